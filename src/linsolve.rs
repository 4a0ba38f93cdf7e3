//! Sparse symmetric positive-definite solves with faer's supernodal Cholesky factorisation.
//! The symbolic analysis (ordering, elimination tree, supernodes) is done once per sparsity
//! pattern and reused by every numeric factorisation.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error(
        "the stiffness matrix is not positive definite: a body is not held (add a support or a \
         pilot, or check that every body is connected to one) ({0})"
    )]
    NotPositiveDefinite(String),
    #[error("sparse factorisation failed: {0}")]
    Other(String),
}

/// The symbolic analysis of a pattern.
#[derive(Clone)]
pub struct Symbolic {
    inner: SymbolicLlt<usize>,
    n: usize,
}

/// A Cholesky factorisation `K = L Lᵀ` of an upper-triangular CSC matrix.
#[derive(Clone)]
pub struct Cholesky {
    llt: Llt<usize, f64>,
    n: usize,
}

fn sym<'a>(
    n: usize,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
) -> SymbolicSparseColMatRef<'a, usize> {
    SymbolicSparseColMatRef::new_checked(n, n, &col_ptr[..=n], None, &row_idx[..col_ptr[n]])
}

impl Symbolic {
    /// Analyses the leading `n` columns of an upper-triangular CSC pattern.
    pub fn analyse(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<Symbolic, FactorError> {
        let inner = SymbolicLlt::try_new(sym(n, col_ptr, row_idx), Side::Upper)
            .map_err(|e| FactorError::Other(format!("{e:?}")))?;
        Ok(Symbolic { inner, n })
    }

    /// Numeric factorisation of the leading `n` columns with these values.
    pub fn factorise(
        &self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Result<Cholesky, FactorError> {
        let n = self.n;
        let a = SparseColMatRef::new(sym(n, col_ptr, row_idx), &values[..col_ptr[n]]);
        let llt =
            Llt::try_new_with_symbolic(self.inner.clone(), a, Side::Upper).map_err(
                |e| match e {
                    faer::sparse::linalg::LltError::Numeric(x) => {
                        FactorError::NotPositiveDefinite(format!("{x:?}"))
                    }
                    other => FactorError::Other(format!("{other:?}")),
                },
            )?;
        Ok(Cholesky { llt, n })
    }
}

impl Cholesky {
    pub fn n(&self) -> usize {
        self.n
    }

    /// Solves `K x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let m = MatMut::from_column_major_slice_mut(b, self.n, 1);
        self.llt.solve_in_place(m);
    }

    /// Solves `K X = B` in place for a column-major block of right-hand sides.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        let m = MatMut::from_column_major_slice_mut(b, self.n, ncols);
        self.llt.solve_in_place(m);
    }
}
