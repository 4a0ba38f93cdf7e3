//! Mortar contact between two curved faces: the pairing and the candidate zone
//! ([`geometry`]), the mortar integrals ([`mortar`]) and the contact solver on the condensed
//! system ([`solver`]).
//!
//! Pairing, normals and initial gaps are taken in the reference configuration (small
//! deformation), so the constraint operator is linear in the displacements and is built once.

pub mod geometry;
pub mod mortar;
pub mod search;
pub mod solver;

pub use geometry::{Pair, PairError, build_pair, default_candidate_gap, oriented_edges};

/// A contact pair on a condensed model: the mortar operator expressed in the retained DOFs
/// and the Delassus operator of the solver.
pub struct ContactModel {
    pub pair: Pair,
    pub system: solver::ContactSystem,
    /// Rows of `Y` over the retained DOFs (index into R, coefficient), in the order of μ.
    pub y_rows: Vec<Vec<(usize, f64)>>,
    /// Composite plane-strain modulus of the pair.
    pub e_star: f64,
}

/// The constraint rows `Y` of a pair over the retained DOFs (retained index, coefficient), in
/// the order of μ: gap rows, slip rows, then one unit row per grounded retained DOF; with the
/// nodal initial gaps and tangential offsets that prescribed displacements add.
pub struct ConstraintRows {
    pub rows: Vec<Vec<(usize, f64)>>,
    pub gap0: Vec<f64>,
    pub v0: Vec<f64>,
}

impl ConstraintRows {
    /// Expresses the pair's mortar operator in the retained DOFs of `dofs`; `grounded` are the
    /// retained indices of the anchors (the pilot's first).
    pub fn new(pair: &Pair, dofs: &crate::dofs::DofMap, grounded: &[usize]) -> ConstraintRows {
        use crate::dofs::Dof;
        let m0 = &pair.mortar;
        let ns = m0.slave_nodes.len();
        let n_i = dofs.n_interior;
        let mut gap0 = m0.gap0.clone();
        let mut v0 = vec![0.0; ns];
        let mut rows = Vec::with_capacity(2 * ns + grounded.len());
        let to_r = |row: &mortar::Row, constant: &mut f64| -> Vec<(usize, f64)> {
            let mut out = Vec::new();
            for (node, coef) in row {
                for c in 0..2 {
                    match dofs.node[*node][c] {
                        Dof::Free(i) if i >= n_i => out.push((i - n_i, coef[c])),
                        Dof::Fixed(q) => *constant += coef[c] * dofs.prescribed[q],
                        Dof::Free(_) | Dof::Unused => panic!("contact node {node} is not retained"),
                    }
                }
            }
            out
        };
        for j in 0..ns {
            rows.push(to_r(&m0.g_rows[j], &mut gap0[j]));
        }
        for j in 0..ns {
            rows.push(to_r(&m0.t_rows[j], &mut v0[j]));
        }
        for &r in grounded {
            rows.push(vec![(r, 1.0)]);
        }
        ConstraintRows { rows, gap0, v0 }
    }

    /// The rows in free-DOF indices (retained index + `n_i`).
    pub fn free(&self, n_i: usize) -> Vec<Vec<(usize, f64)>> {
        self.rows
            .iter()
            .map(|r| r.iter().map(|&(k, v)| (n_i + k, v)).collect())
            .collect()
    }
}

impl ContactModel {
    /// The contact model of `pair` on the condensed system `cond`, whose grounding springs are
    /// the last rows of `y`: the Delassus operator `W = Y K̂⁻¹ Yᵀ` from the trailing block of
    /// the saddle-point factorisation, or (when that block is not negative definite to
    /// working precision, a rank-deficient `Y`) by one solve per row.
    ///
    /// `order`: the order of the constraint rows in the saddle-point factorisation
    /// ([`solver::prefix_order`]; `None`: the order of μ). With it, the trailing block also
    /// gives the Cholesky factor of `W` in that order ([`solver::PrefixFactor`]).
    pub fn new(
        pair: Pair,
        y: ConstraintRows,
        has_pilot: bool,
        cond: &crate::condense::Condensed,
        e_star: f64,
        order: Option<Vec<usize>>,
    ) -> ContactModel {
        let (w, prefix) = match &cond.chol {
            crate::condense::Factor::Saddle(f) => f.delassus(order.is_some()),
            crate::condense::Factor::Partial(_) => None,
        }
        .map(|(w, c)| match (c, order) {
            (Some(c), Some(order)) => {
                crate::trace::mark("delassus: C");
                let (mut w, pf) = (w, solver::PrefixFactor::new(c, order));
                to_mu_order(&mut w, &pf.pos);
                crate::trace::mark("delassus: in μ order");
                (w, Some(pf))
            }
            (_, _) => (w, None),
        })
        .unwrap_or_else(|| (delassus_by_solves(&y.rows, cond), None));
        Self::with_w(pair, y, has_pilot, cond, e_star, w, prefix)
    }

    /// As [`ContactModel::new`] with the Delassus operator `w` of an earlier build of the same
    /// model (the model cache, [`crate::cache`]).
    pub fn with_w(
        pair: Pair,
        y: ConstraintRows,
        has_pilot: bool,
        cond: &crate::condense::Condensed,
        e_star: f64,
        w: faer::Mat<f64>,
        prefix: Option<solver::PrefixFactor>,
    ) -> ContactModel {
        let m0 = &pair.mortar;
        let ns = m0.slave_nodes.len();
        let kg: Vec<f64> = cond.grounding.iter().map(|g| g.1).collect();
        let eps_unit = (0..ns).map(|j| e_star * m0.weight[j] / m0.h[j]).collect();
        // Orientation of the mean slip: its response to a pilot force in +x.
        let slip_orient = if has_pilot {
            let s: f64 = (0..ns).map(|j| m0.weight[j] * w[(ns + j, 2 * ns)]).sum();
            if s < 0.0 { -1.0 } else { 1.0 }
        } else {
            1.0
        };
        let system = solver::ContactSystem {
            ns,
            has_pilot,
            w: std::sync::Arc::new(w),
            gap0: y.gap0,
            v0: y.v0,
            c: e_star,
            eps_unit,
            kg,
            weight: m0.weight.clone(),
            slip_orient,
            floating_pilot: false,
            prefix: prefix.map(std::sync::Arc::new),
        };
        ContactModel {
            pair,
            system,
            y_rows: y.rows,
            e_star,
        }
    }

    /// `w0 = Y K̂⁻¹ f` for a free load vector `f` (zero without a solve when `f` is zero, as
    /// the loads of zero prescribed displacements or of no tractions are).
    pub fn w0(&self, cond: &crate::condense::Condensed, f: &[f64]) -> Vec<f64> {
        if f.iter().all(|v| *v == 0.0) {
            return vec![0.0; self.y_rows.len()];
        }
        let mut x = f.to_vec();
        cond.chol.solve_in_place(&mut x);
        self.y_rows
            .iter()
            .map(|row| row.iter().map(|&(r, v)| v * x[cond.n_i + r]).sum())
            .collect()
    }

    /// The forces on the retained DOFs, `r = Yᵀ μ`, of a contact state.
    pub fn retained_forces(&self, st: &solver::State, n_r: usize) -> Vec<f64> {
        let ns = self.system.ns;
        let mut r = vec![0.0; n_r];
        for (i, row) in self.y_rows.iter().enumerate() {
            let mu = if i < ns {
                st.f_n[i]
            } else if i < 2 * ns {
                st.f_t[i - ns]
            } else {
                st.z[i - 2 * ns]
            };
            if mu != 0.0 {
                for &(k, v) in row {
                    r[k] += v * mu;
                }
            }
        }
        r
    }
}

/// Reorders in place a symmetric `w` given in an order of its unknowns (`w[a, b]` the entry
/// of the unknowns at positions `a`, `b`; `pos[i]` the position of unknown `i`) into their
/// natural order: the rows of each column first, then the columns by the cycles of the
/// permutation (one spare column: the Delassus operator is 130 MB at L7, and a second copy
/// would raise the run's peak memory).
fn to_mu_order(w: &mut faer::Mat<f64>, pos: &[usize]) {
    use rayon::prelude::*;
    let m = pos.len();
    // The rows of each column permuted, the columns on rayon's threads.
    w.par_col_chunks_mut(64).for_each(|cols| {
        let mut cols = cols;
        let mut tmp = vec![0.0; m];
        for c in 0..cols.ncols() {
            for (t, &p) in tmp.iter_mut().zip(pos) {
                *t = cols[(p, c)];
            }
            for (i, t) in tmp.iter().enumerate() {
                cols[(i, c)] = *t;
            }
        }
    });
    let mut tmp = vec![0.0; m];
    // Column j of the result is column pos[j] of the row-permuted array.
    let mut done = vec![false; m];
    for start in 0..m {
        if done[start] {
            continue;
        }
        tmp.iter_mut()
            .zip(w.col(start).iter())
            .for_each(|(t, x)| *t = *x);
        let mut j = start;
        loop {
            done[j] = true;
            let k = pos[j];
            if k == start {
                w.col_mut(j).iter_mut().zip(&tmp).for_each(|(x, t)| *x = *t);
                break;
            }
            for i in 0..m {
                let v = w[(i, k)];
                w[(i, j)] = v;
            }
            j = k;
        }
    }
}

/// `W = Y K̂⁻¹ Yᵀ` by one solve with `K̂` per row of `Y` (a block solve).
fn delassus_by_solves(
    rows: &[Vec<(usize, f64)>],
    cond: &crate::condense::Condensed,
) -> faer::Mat<f64> {
    let n = cond.n_i + cond.n_r;
    let m = rows.len();
    let mut x = vec![0.0; n * m];
    for (j, row) in rows.iter().enumerate() {
        for &(r, v) in row {
            x[j * n + cond.n_i + r] += v;
        }
    }
    cond.chol.solve_block_in_place(&mut x, m);
    let mut w = faer::Mat::<f64>::zeros(m, m);
    for (i, row) in rows.iter().enumerate() {
        for j in 0..m {
            w[(i, j)] = row.iter().map(|&(r, v)| v * x[j * n + cond.n_i + r]).sum();
        }
    }
    // Symmetric to round-off; make it exactly so.
    for i in 0..m {
        for j in 0..i {
            let a = 0.5 * (w[(i, j)] + w[(j, i)]);
            w[(i, j)] = a;
            w[(j, i)] = a;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    /// The in-place reordering of a symmetric matrix from an order of its unknowns into theirs,
    /// against the gathered copy, for a permutation with cycles of several lengths.
    #[test]
    fn a_matrix_in_another_order_of_its_unknowns_comes_back_in_theirs() {
        let m = 9;
        let order = [4, 0, 8, 2, 1, 3, 7, 6, 5];
        let natural = faer::Mat::from_fn(m, m, |i, j| {
            (1 + i.min(j)) as f64 * 10.0 + (i.max(j)) as f64
        });
        let mut w = faer::Mat::from_fn(m, m, |a, b| natural[(order[a], order[b])]);
        let pos = super::solver::PrefixFactor::new(faer::Mat::zeros(1, 1), order.to_vec()).pos;
        super::to_mu_order(&mut w, &pos);
        for i in 0..m {
            for j in 0..m {
                assert_eq!(w[(i, j)], natural[(i, j)], "({i}, {j})");
            }
        }
    }
}
