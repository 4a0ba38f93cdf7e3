//! What the sparse factorisations share: their error, faer's view of an upper CSC pattern,
//! and the supernodal structure of a symbolic analysis.

use faer::sparse::SymbolicSparseColMatRef;

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
    #[error("sparse factorisation: {len} factor values given for an analysis with {expected}")]
    FactorLength { len: usize, expected: usize },
}

/// faer's symbolic view of the upper CSC pattern of an `n × n` matrix.
pub(crate) fn sym<'a>(
    n: usize,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
) -> SymbolicSparseColMatRef<'a, usize> {
    SymbolicSparseColMatRef::new_checked(n, n, &col_ptr[..=n], None, &row_idx[..col_ptr[n]])
}

/// The supernodal structure of a symbolic factorisation (forced supernodal at analysis).
pub(crate) fn supernodal(
    s: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
) -> Result<
    &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    FactorError,
> {
    match s.raw() {
        faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(sn) => Ok(sn),
        _ => Err(FactorError::NotSupernodal),
    }
}
