//! The sparse Cholesky factorisation of a model without contact, with its retained unknowns
//! (the pilot's DOFs) ordered last.

use super::base::{FactorError, sym};
use super::dense::copy_trailing;
use super::par::{factor_parallelism, vec_in_parallel};
use super::values::{FactorValues, SharedValues};
use faer::sparse::SparseColMatRef;
use faer::{MatMut, Side};

/// A sparse Cholesky factorisation `K = L Lᵀ` whose ordering puts a chosen set of *retained*
/// unknowns last, so that the trailing block of `L` is the Cholesky factor of the Schur
/// complement on them:
/// ```text
///   L = [L_II 0; L_RI L_RR],   S = K_RR − K_RI K_II⁻¹ K_IR = L_RR L_RRᵀ .
/// ```
/// The interior unknowns are ordered by AMD; the retained ones keep their order at the end.
/// This gives the condensed stiffness at the cost of one factorisation plus a dense block,
/// instead of one solve per retained unknown.
pub struct PartialCholesky {
    symbolic: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    /// The factor's values, shared with a model-cache writer ([`crate::cache`]).
    values: SharedValues,
    n: usize,
    n_r: usize,
    /// `L_RR`, dense lower triangular, column-major `n_r × n_r`.
    l_rr: faer::Mat<f64>,
}

/// The symbolic analysis of a [`PartialCholesky`], reusable across numeric factorisations.
#[derive(Clone)]
pub struct PartialSymbolic {
    inner: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    n: usize,
    n_r: usize,
}

impl PartialSymbolic {
    /// Orders and analyses an upper-triangular CSC pattern of size `n` whose last `n_r`
    /// unknowns are retained.
    pub fn analyse(
        n: usize,
        n_r: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<PartialSymbolic, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::amd;
        let other = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n,
            },
        };
        let n_i = n - n_r;
        // AMD on the interior block (its leading columns are a valid upper CSC matrix).
        let mut fwd = vec![0usize; n];
        let mut inv = vec![0usize; n];
        if n_i > 0 {
            let a_ii = sym(n_i, col_ptr, row_idx);
            let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
                n_i,
                col_ptr[n_i],
            ))
            .map_err(|_| FactorError::OutOfMemory {
                what: "the ordering",
                n,
            })?;
            amd::order_maybe_unsorted(
                &mut fwd[..n_i],
                &mut inv[..n_i],
                a_ii,
                Default::default(),
                MemStack::new(&mut mem),
            )
            .map_err(other)?;
        }
        Self::with_ordering(n, n_r, col_ptr, row_idx, &fwd[..n_i])
    }

    /// As [`Self::analyse`] with a given ordering of the interior unknowns (`fwd[new] = old`,
    /// a permutation of `0..n − n_r`), such as [`Self::ordering`] of an earlier analysis.
    pub fn with_ordering(
        n: usize,
        n_r: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        interior: &[usize],
    ) -> Result<PartialSymbolic, FactorError> {
        use faer::sparse::linalg::{SupernodalThreshold, cholesky};
        let other = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n,
            },
        };
        let mut fwd = interior.to_vec();
        fwd.extend(n - n_r..n);
        let mut inv = vec![0usize; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
        let params = cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let inner = cholesky::factorize_symbolic_cholesky(
            sym(n, col_ptr, row_idx),
            Side::Upper,
            cholesky::SymmetricOrdering::Custom(perm),
            params,
        )
        .map_err(other)?;
        Ok(PartialSymbolic {
            inner: std::sync::Arc::new(inner),
            n,
            n_r,
        })
    }

    /// The ordering of the interior unknowns (`fwd[new] = old`).
    pub fn ordering(&self) -> Vec<usize> {
        let perm = self.inner.perm().expect("custom ordering");
        perm.arrays().0[..self.n - self.n_r].to_vec()
    }

    /// Numeric factorisation with these values, and extraction of `L_RR`.
    pub fn factorise(
        &self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Result<PartialCholesky, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        let n = self.n;
        let a = SparseColMatRef::new(sym(n, col_ptr, row_idx), &values[..col_ptr[n]]);
        let par = factor_parallelism();
        let mut l = vec_in_parallel(self.inner.len_val());
        let mut mem = MemBuffer::try_new(
            self.inner
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| FactorError::OutOfMemory {
            what: "the numeric factorisation",
            n,
        })?;
        self.inner
            .factorize_numeric_llt(
                &mut l,
                a,
                Side::Upper,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    FactorError::NotPositiveDefinite { pivot: index, n }
                }
            })?;
        self.from_values(std::sync::Arc::new(FactorValues::Owned(l)))
    }

    /// The factorisation with the values of an earlier numeric factorisation on this
    /// analysis ([`PartialCholesky::values`]), and extraction of `L_RR`.
    pub fn from_values(&self, l: SharedValues) -> Result<PartialCholesky, FactorError> {
        use faer::sparse::linalg::cholesky::{SymbolicCholeskyRaw, supernodal::SupernodalLltRef};
        let (n, n_r) = (self.n, self.n_r);
        let n_i = n - n_r;
        if l.len() != self.inner.len_val() {
            return Err(FactorError::FactorLength {
                len: l.len(),
                expected: self.inner.len_val(),
            });
        }
        let mut l_rr = faer::Mat::<f64>::zeros(n_r, n_r);
        if n_r > 0 {
            let SymbolicCholeskyRaw::Supernodal(sn) = self.inner.raw() else {
                return Err(FactorError::NotSupernodal);
            };
            let lref = SupernodalLltRef::new(sn, &l);
            for s in 0..sn.n_supernodes() {
                let node = lref.supernode(s);
                let val = node.val();
                copy_trailing(
                    &mut l_rr,
                    n_i,
                    node.start(),
                    val.ncols(),
                    node.pattern(),
                    |i, j| val[(i, j)],
                );
            }
        }
        Ok(PartialCholesky {
            symbolic: self.inner.clone(),
            values: l,
            n,
            n_r,
            l_rr,
        })
    }
}

impl PartialCholesky {
    pub fn n(&self) -> usize {
        self.n
    }

    pub fn n_retained(&self) -> usize {
        self.n_r
    }

    /// The values of the factor (shared, not copied).
    pub fn values(&self) -> SharedValues {
        self.values.clone()
    }

    /// `L_RR` (dense, lower triangular): `S = L_RR L_RRᵀ`.
    pub fn l_rr(&self) -> faer::MatRef<'_, f64> {
        self.l_rr.as_ref()
    }

    /// Solves `K X = B` in place for a column-major block of `ncols` right-hand sides.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::cholesky::LltRef;
        let par = faer::get_global_parallelism();
        let lref = LltRef::new(&self.symbolic, &self.values);
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(ncols, par));
        let m = MatMut::from_column_major_slice_mut(b, self.n, ncols);
        lref.solve_in_place_with_conj(faer::Conj::No, m, par, MemStack::new(&mut mem));
    }

    /// Solves `K x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_block_in_place(b, 1);
    }
}
