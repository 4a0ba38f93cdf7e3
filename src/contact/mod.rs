//! Mortar contact between two curved faces: the pairing and the candidate zone
//! ([`geometry`]), the mortar integrals ([`mortar`]) and the contact solver on the condensed
//! system ([`solver`]).
//!
//! Pairing, normals and initial gaps are taken in the reference configuration (small
//! deformation), so the constraint operator is linear in the displacements and is built once.

pub mod geometry;
pub mod mortar;
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

impl ContactModel {
    /// Expresses the pair's mortar operator in the retained DOFs of `dofs` and builds the
    /// Delassus operator from the condensed stiffness.
    pub fn new(
        pair: Pair,
        dofs: &crate::dofs::DofMap,
        cond: &crate::condense::Condensed,
        e_star: f64,
    ) -> ContactModel {
        use crate::dofs::Dof;
        let m0 = &pair.mortar;
        let ns = m0.slave_nodes.len();
        let n_i = dofs.n_interior;
        let n_r = dofs.n_retained;
        let has_pilot = dofs.pilot.is_some();
        let m = 2 * ns + cond.grounding.len();
        let mut gap0 = m0.gap0.clone();
        let mut v0 = vec![0.0; ns];
        let mut y_rows = Vec::with_capacity(m);
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
            let r = to_r(&m0.g_rows[j], &mut gap0[j]);
            y_rows.push(r);
        }
        for j in 0..ns {
            let r = to_r(&m0.t_rows[j], &mut v0[j]);
            y_rows.push(r);
        }
        // Anchors: every grounded retained DOF (the pilot's first).
        for &(r, _) in &cond.grounding {
            y_rows.push(vec![(r, 1.0)]);
        }
        // Z = L_RR⁻¹ Yᵀ, W = Zᵀ Z.
        let mut z = faer::Mat::<f64>::zeros(n_r, m);
        for (col, row) in y_rows.iter().enumerate() {
            for &(r, v) in row {
                z[(r, col)] += v;
            }
        }
        let par = faer::get_global_parallelism();
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            cond.chol.l_rr(),
            z.as_mut(),
            par,
        );
        let mut w = faer::Mat::<f64>::zeros(m, m);
        faer::linalg::matmul::matmul(
            w.as_mut(),
            faer::Accum::Replace,
            z.transpose(),
            z.as_ref(),
            1.0,
            par,
        );
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
            w,
            z,
            gap0,
            v0,
            c: e_star,
            eps_unit,
            kg,
            weight: m0.weight.clone(),
            slip_orient,
            floating_pilot: false,
        };
        ContactModel {
            pair,
            system,
            y_rows,
            e_star,
        }
    }

    /// `w0 = Zᵀ L_RR⁻¹ g` for a condensed load `g`.
    pub fn w0(&self, cond: &crate::condense::Condensed, g: &[f64]) -> Vec<f64> {
        let n_r = g.len();
        let mut x = faer::Mat::<f64>::zeros(n_r, 1);
        for i in 0..n_r {
            x[(i, 0)] = g[i];
        }
        let par = faer::get_global_parallelism();
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            cond.chol.l_rr(),
            x.as_mut(),
            par,
        );
        let m = self.system.z.ncols();
        let mut out = faer::Mat::<f64>::zeros(m, 1);
        faer::linalg::matmul::matmul(
            out.as_mut(),
            faer::Accum::Replace,
            self.system.z.transpose(),
            x.as_ref(),
            1.0,
            par,
        );
        (0..m).map(|i| out[(i, 0)]).collect()
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
