//! Sparse symmetric positive-definite solves with faer's supernodal Cholesky factorisation.
//! The symbolic analysis (ordering, elimination tree, supernodes) is done once per sparsity
//! pattern and reused by every numeric factorisation.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error(
        "the stiffness matrix is not positive definite: a body is not held (add a support or a \
         pilot, or check that every body is connected to one) (pivot {pivot} of {n} in the \
         elimination order is not positive)"
    )]
    NotPositiveDefinite { pivot: usize, n: usize },
    #[error("sparse factorisation: not enough memory for {what} of a matrix of order {n}")]
    OutOfMemory { what: &'static str, n: usize },
    #[error("sparse factorisation: an index of a matrix of order {n} overflows")]
    IndexOverflow { n: usize },
    #[error("sparse factorisation: the symbolic analysis is not supernodal")]
    NotSupernodal,
}

fn sym<'a>(
    n: usize,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
) -> SymbolicSparseColMatRef<'a, usize> {
    SymbolicSparseColMatRef::new_checked(n, n, &col_ptr[..=n], None, &row_idx[..col_ptr[n]])
}

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
    values: Vec<f64>,
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
        use faer::sparse::linalg::{SupernodalThreshold, amd, cholesky};
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
        for k in n_i..n {
            fwd[k] = k;
            inv[k] = k;
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

    /// Numeric factorisation with these values, and extraction of `L_RR`.
    pub fn factorise(
        &self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Result<PartialCholesky, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::cholesky::{SymbolicCholeskyRaw, supernodal::SupernodalLltRef};
        let (n, n_r) = (self.n, self.n_r);
        let n_i = n - n_r;
        let a = SparseColMatRef::new(sym(n, col_ptr, row_idx), &values[..col_ptr[n]]);
        let par = faer::get_global_parallelism();
        let mut l = vec![0.0; self.inner.len_val()];
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
        let mut l_rr = faer::Mat::<f64>::zeros(n_r, n_r);
        if n_r > 0 {
            let SymbolicCholeskyRaw::Supernodal(sn) = self.inner.raw() else {
                return Err(FactorError::NotSupernodal);
            };
            let lref = SupernodalLltRef::new(sn, &l);
            for s in 0..sn.n_supernodes() {
                let node = lref.supernode(s);
                let (start, val, pattern) = (node.start(), node.val(), node.pattern());
                let ncols = val.ncols();
                if start + ncols <= n_i {
                    continue;
                }
                for j in 0..ncols {
                    let col = start + j;
                    if col < n_i {
                        continue;
                    }
                    for i in j..ncols {
                        l_rr[(start + i - n_i, col - n_i)] = val[(i, j)];
                    }
                    for (k, &row) in pattern.iter().enumerate() {
                        l_rr[(row - n_i, col - n_i)] = val[(ncols + k, j)];
                    }
                }
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
