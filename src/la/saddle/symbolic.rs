//! The symbolic analysis of the contact saddle-point matrix and its numeric factorisation.

use super::factor::SaddleFactor;
use super::layout::Supernodes;
use crate::la::base::{FactorError, supernodal, sym};
use crate::la::ordering::ordering_choice;
use crate::la::par::{factor_parallelism, vec_in_parallel};
use crate::la::values::{FactorValues, SharedValues, ValuesDestination};
use faer::Side;
use faer::sparse::SparseColMatRef;

/// Whether the saddle-point factorisations run on the elimination tree's schedule
/// ([`crate::supernodal`]): where its kernel is available, unless `STICKSLIP_FACTOR=faer`
/// asks for faer's own loop (for comparisons: the same factor, but `W` formed by the product
/// rather than copied from the factorisation, so different last bits downstream).
pub fn tree_scheduled() -> bool {
    std::env::var("STICKSLIP_FACTOR").map_or(true, |v| v != "faer")
}

/// The sparsity pattern and symbolic analysis of the saddle-point matrix of a contact model,
/// ```text
///   A = [K̂  Yᵀ]     (n + m) × (n + m),
///       [Y   0 ]
/// ```
/// with the `m` constraint rows `Y` (mortar gap and slip rows, anchors) ordered after the `n`
/// free DOFs. Eliminating the free DOFs leaves `−W = −Y K̂⁻¹ Yᵀ` in the trailing block, so an
/// `L D Lᵀ` factorisation without pivoting (A is quasi-definite in this order: `K̂` positive
/// definite, `W` positive definite when `Y` has full row rank) gives both the factor of `K̂`
/// (its leading block) and the Delassus operator `W = −L_MM D_MM L_MMᵀ`, with a dense block of
/// order `m` only — instead of the dense Schur complement on every contact DOF (about `2m`)
/// followed by `m` triangular solves with it.
#[derive(Clone)]
pub struct SaddleSymbolic {
    pub(super) inner: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    pub(super) layout: std::sync::Arc<Supernodes>,
    pub(super) col_ptr: Vec<usize>,
    pub(super) row_idx: Vec<usize>,
    pub(super) n: usize,
    pub(super) m: usize,
}

impl SaddleSymbolic {
    /// The pattern of `A` from the upper CSC pattern of `K̂` (order `n`) and the rows of `Y`
    /// (free-DOF index, coefficient), and its symbolic analysis: the free DOFs ordered by a
    /// fill-reducing ordering, the constraint rows last in their own order.
    pub fn analyse(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        y_rows: &[Vec<(usize, f64)>],
    ) -> Result<SaddleSymbolic, FactorError> {
        let fwd = match ordering_choice(n) {
            crate::la::ordering::Ordering::Amd => {
                crate::la::ordering::try_amd_order(n, col_ptr, row_idx).map_err(|e| match e {
                    faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow {
                        n: n + y_rows.len(),
                    },
                    _ => FactorError::OutOfMemory {
                        what: "the ordering",
                        n: n + y_rows.len(),
                    },
                })?
            }
            crate::la::ordering::Ordering::NestedDissection => {
                crate::la::ordering::nested_dissection(n, col_ptr, row_idx)
            }
        };
        crate::trace::mark("ordered");
        Self::with_ordering(n, col_ptr, row_idx, y_rows, &fwd)
    }

    /// As [`Self::analyse`] with a given ordering of the free DOFs (`fwd[new] = old`, a
    /// permutation of `0..n`), such as [`Self::ordering`] of an earlier analysis.
    pub fn with_ordering(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        y_rows: &[Vec<(usize, f64)>],
        ordering: &[usize],
    ) -> Result<SaddleSymbolic, FactorError> {
        use faer::sparse::linalg::{SupernodalThreshold, cholesky};
        let m = y_rows.len();
        let size = n + m;
        let mut cp = col_ptr[..=n].to_vec();
        let mut ri = row_idx[..col_ptr[n]].to_vec();
        for row in y_rows {
            let mut rows: Vec<usize> = row.iter().map(|&(r, _)| r).collect();
            rows.sort_unstable();
            rows.dedup();
            ri.extend(rows);
            ri.push(cp.len() - 1); // the (zero) diagonal of the constraint column
            cp.push(ri.len());
        }
        let mut fwd = ordering.to_vec();
        fwd.extend(n..size);
        let mut inv = vec![0usize; size];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, size);
        let params = cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let inner = cholesky::factorize_symbolic_cholesky(
            sym(size, &cp, &ri),
            Side::Upper,
            cholesky::SymmetricOrdering::Custom(perm),
            params,
        );
        let inner = inner.map_err(|e| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n: size },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n: size,
            },
        })?;
        crate::trace::mark("symbolic");
        let layout = std::sync::Arc::new(Supernodes::of(&inner)?);
        Ok(SaddleSymbolic {
            inner: std::sync::Arc::new(inner),
            layout,
            col_ptr: cp,
            row_idx: ri,
            n,
            m,
        })
    }

    /// The ordering of the free DOFs (`fwd[new] = old`; the constraint rows follow in order).
    pub fn ordering(&self) -> Vec<usize> {
        let perm = self.inner.perm().expect("custom ordering");
        perm.arrays().0[..self.n].to_vec()
    }

    /// Number of nonzeros of the factor `L` (supernodal storage).
    pub fn factor_len(&self) -> usize {
        self.inner.len_val()
    }

    /// Estimated floating-point operations of the numeric factorisation, split into the
    /// elimination of `K̂` itself, its updates of the constraint rows (the fill that couples
    /// `Y` to the separators) and the dense constraint block: `(k, k_to_m, m)`.
    pub fn flops(&self) -> (f64, f64, f64) {
        let sn = supernodal(&self.inner).expect("analysed supernodal");
        let n = self.n;
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        let ptr = sn.col_ptr_for_row_idx();
        let (mut fk, mut fkm, mut fm) = (0.0, 0.0, 0.0);
        for s in 0..sn.n_supernodes() {
            let pattern = &sn.row_idx()[ptr[s]..ptr[s + 1]];
            let w = (end[s] - begin[s]) as f64;
            let wk = (end[s].min(n).saturating_sub(begin[s])) as f64;
            let wm = w - wk;
            let pk = pattern.iter().filter(|&&r| r < n).count() as f64;
            let pm = pattern.len() as f64 - pk;
            // Columns of K̂: their own block and updates of K̂ rows, then of constraint rows.
            fk += wk * wk * wk / 3.0 + wk * wk * pk + wk * pk * pk;
            fkm += wk * wk * (pm + wm) + wk * (pm + wm) * (pm + wm + 2.0 * pk);
            // Constraint columns (all after K̂'s).
            fm += wm * wm * wm / 3.0 + wm * wm * pm + wm * pm * pm;
        }
        (fk, fkm, fm)
    }

    /// Numeric `L D Lᵀ` factorisation with the values of `K̂` (in the pattern given to
    /// [`Self::analyse`]) and the same `Y` rows, in fresh memory.
    pub fn factorise(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
    ) -> Result<SaddleFactor, FactorError> {
        self.factorise_in(k_values, y_rows, None)
    }

    /// Length of the factor's values.
    pub fn len_val(&self) -> usize {
        self.inner.len_val()
    }

    /// [`Self::factorise`] with the values computed in `dest` when given (a new model-cache
    /// entry's file mapped for writing; [`Self::len_val`] floats), the same bits.
    pub fn factorise_in(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
        dest: Option<Box<dyn ValuesDestination>>,
    ) -> Result<SaddleFactor, FactorError> {
        self.factorise_using(k_values, y_rows, dest, tree_scheduled())
    }

    /// [`Self::factorise_in`] on the elimination tree's schedule with `tree`, else with
    /// faer's own loop.
    pub(super) fn factorise_using(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
        mut dest: Option<Box<dyn ValuesDestination>>,
        tree: bool,
    ) -> Result<SaddleFactor, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        let (n, m) = (self.n, self.m);
        let size = n + m;
        // The values of the constraint columns (those of K̂ are `k_values` as they are).
        let kn = self.col_ptr[n];
        let mut y_values = Vec::with_capacity(self.row_idx.len() - kn);
        for (i, row) in y_rows.iter().enumerate() {
            let rows = &self.row_idx[self.col_ptr[n + i]..self.col_ptr[n + i + 1]];
            let start = y_values.len();
            y_values.resize(start + rows.len(), 0.0);
            for &(r, v) in row {
                let p = rows[..rows.len() - 1]
                    .binary_search(&r)
                    .expect("row in the analysed pattern");
                y_values[start + p] += v;
            }
        }
        let par = factor_parallelism();
        crate::trace::mark("factor: values gathered");
        let mut owned = Vec::new();
        let l: &mut [f64] = match &mut dest {
            Some(d) => {
                // Its pages faulted in on all cores, as `vec_in_parallel` does: those of a new
                // file read as zeros, so populating them is enough where the kernel can.
                let populated = tree && d.populate();
                let v = d.as_mut_f64();
                assert_eq!(
                    v.len(),
                    self.inner.len_val(),
                    "a factor's destination of another length"
                );
                if !populated {
                    use rayon::prelude::*;
                    v.par_chunks_mut(1 << 16).for_each(|c| c.fill(0.0));
                }
                v
            }
            None => {
                owned = vec_in_parallel(self.inner.len_val());
                &mut owned
            }
        };
        crate::trace::mark("factor: values cleared");
        let mut schur = None;
        if tree {
            let lower = crate::la::supernodal::LowerCsc::permuted(
                &self.col_ptr,
                &self.row_idx,
                |p| {
                    if p < kn {
                        k_values[p]
                    } else {
                        y_values[p - kn]
                    }
                },
                &self.layout.fwd,
            );
            crate::trace::mark("factor: lower triangle permuted");
            let st = crate::la::supernodal::Structure {
                begin: &self.layout.begin,
                row_ptr: &self.layout.row_ptr,
                rows: &self.layout.rows,
                val_ptr: &self.layout.val_ptr,
            };
            schur = crate::la::supernodal::factorise(&st, lower, l, par, Some(n))
                .map_err(|pivot| FactorError::NotPositiveDefinite { pivot, n })?;
            if schur.is_none() {
                crate::trace::mark("factor: constraint block not in the root (W by the product)");
            }
        } else {
            let mut values = Vec::with_capacity(self.row_idx.len());
            values.extend_from_slice(&k_values[..kn]);
            values.extend_from_slice(&y_values);
            let a = SparseColMatRef::new(sym(size, &self.col_ptr, &self.row_idx), &values);
            let mut mem = MemBuffer::try_new(
                self.inner
                    .factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            )
            .map_err(|_| FactorError::OutOfMemory {
                what: "the numeric factorisation",
                n: size,
            })?;
            self.inner
                .factorize_numeric_ldlt(
                    l,
                    a,
                    Side::Upper,
                    Default::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .map_err(|e| match e {
                    faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                        FactorError::NotPositiveDefinite { pivot: index, n }
                    }
                })?;
        }
        let values = match dest {
            Some(d) => FactorValues::Stored(d.into_stored()),
            None => FactorValues::Owned(owned),
        };
        let mut f = self.from_values(std::sync::Arc::new(values))?;
        if let Some((w, seconds)) = schur {
            f.constraint_block_s = seconds;
            *f.schur.lock().unwrap_or_else(|p| p.into_inner()) = Some(w);
        }
        let values = f.values();
        // K̂ must be positive definite: every pivot of its block positive (a body that nothing
        // holds gives a vanishing or negative one).
        let mut dmax: f64 = 0.0;
        for s in 0..f.layout.n_supernodes() {
            let node = f.layout.node(s, &values);
            for j in 0..node.ncols {
                let col = node.start + j;
                if col >= n {
                    break;
                }
                let d = node.at(j, j);
                dmax = dmax.max(d.abs());
                if d.partial_cmp(&(1e-14 * dmax)) != Some(std::cmp::Ordering::Greater) {
                    return Err(FactorError::NotPositiveDefinite { pivot: col, n });
                }
            }
        }
        Ok(f)
    }

    /// The factorisation with the values of an earlier numeric factorisation on this analysis
    /// ([`SaddleFactor::values`]).
    pub fn from_values(&self, l: SharedValues) -> Result<SaddleFactor, FactorError> {
        SaddleFactor::from_layout(self.layout.clone(), l, self.n, self.m)
    }
}
