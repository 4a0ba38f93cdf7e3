//! Dense kernels: the copy of a supernode's trailing part into a dense block, and the
//! products, triangular solves and LU solves of the contact Newton systems.

/// Copies the part of a supernode (first column `start`, `ncols` columns, off-diagonal rows
/// `pattern`, entry `(i, j)` of its columns by `at`) at and after row and column `from` into
/// the dense lower triangle `out` of the trailing block (`out[(r − from, c − from)]`).
pub fn copy_trailing(
    out: &mut faer::Mat<f64>,
    from: usize,
    start: usize,
    ncols: usize,
    pattern: &[usize],
    at: impl Fn(usize, usize) -> f64,
) {
    for j in start.max(from) - start..ncols {
        let col = start + j - from;
        for i in j..ncols {
            out[(start + i - from, col)] = at(i, j);
        }
        for (k, &row) in pattern.iter().enumerate() {
            out[(row - from, col)] = at(ncols + k, j);
        }
    }
}
