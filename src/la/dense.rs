//! Dense kernels: the copy of a supernode's trailing part into a dense block, and those of
//! the contact Newton systems: sums of scaled columns of `W`, the product with a block of `W`,
//! the forward sweep with a Cholesky factor, LU solves and GMRES.

use faer::Mat;
use faer::linalg::solvers::Solve;

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

/// `x += a g`.
pub fn axpy(x: &mut [f64], a: f64, g: &[f64]) {
    axpy_with(x, a, g)
}

#[inline(always)]
fn axpy_with(x: &mut [f64], a: f64, g: &[f64]) {
    for (xi, gi) in x.iter_mut().zip(g) {
        *xi += a * gi;
    }
}

/// `y += Σ_j W[:, j] a_j` over the `(j, a_j)` of `terms`, added to each entry in their order
/// (the bits of one column at a time), four columns per pass over `y` (a quarter of the loads
/// and stores of `y`).
pub fn add_columns(y: &mut [f64], w: &Mat<f64>, terms: impl IntoIterator<Item = (usize, f64)>) {
    let m = y.len();
    let cols: Vec<(&[f64], f64)> = terms
        .into_iter()
        .map(|(j, a)| {
            let c = w.col(j).try_as_col_major().expect("contiguous columns");
            (&c.as_slice()[..m], a)
        })
        .collect();
    add_columns_with(y, &cols)
}

#[inline(always)]
fn add_columns_with(y: &mut [f64], cols: &[(&[f64], f64)]) {
    let m = y.len();
    let mut quads = cols.chunks_exact(4);
    for quad in &mut quads {
        let [(c0, a0), (c1, a1), (c2, a2), (c3, a3)] = [quad[0], quad[1], quad[2], quad[3]];
        let (c0, c1, c2, c3) = (&c0[..m], &c1[..m], &c2[..m], &c3[..m]);
        for i in 0..m {
            y[i] = add_four(y[i], [c0[i], c1[i], c2[i], c3[i]], [a0, a1, a2, a3]);
        }
    }
    for &(c, a) in quads.remainder() {
        axpy_with(y, a, c);
    }
}

/// `v + w₀a₀ + w₁a₁ + w₂a₂ + w₃a₃`, added in that order (each product rounded, then added).
#[inline(always)]
fn add_four(mut v: f64, w: [f64; 4], a: [f64; 4]) -> f64 {
    v += w[0] * a[0];
    v += w[1] * a[1];
    v += w[2] * a[2];
    v += w[3] * a[3];
    v
}

/// `y1 += Σ_j W[:, j] a_j` and `y2 += Σ_j W[:, j] b_j` over the nonzero `a_j`, `b_j`, in one
/// pass over the columns of `W`: each output gets its terms in increasing `j`, one after the
/// other, so each is bit for bit what [`add_columns`] gives it alone
/// (`two_products_in_one_pass_give_the_bits_of_one_at_a_time`), and `W` (8 MB on L5) is read
/// once for both.
pub fn add_columns_pair(y1: &mut [f64], y2: &mut [f64], w: &Mat<f64>, a: &[f64], b: &[f64]) {
    let m = y1.len();
    assert!(y2.len() == m && a.len() == b.len() && a.len() <= w.ncols());
    let cols: Vec<(&[f64], f64, f64)> = (0..a.len())
        .filter(|&j| a[j] != 0.0 || b[j] != 0.0)
        .map(|j| {
            let c = w.col(j).try_as_col_major().expect("contiguous columns");
            (&c.as_slice()[..m], a[j], b[j])
        })
        .collect();
    add_columns_pair_with(y1, y2, &cols)
}

#[inline(always)]
fn add_columns_pair_with(y1: &mut [f64], y2: &mut [f64], cols: &[(&[f64], f64, f64)]) {
    let m = y1.len();
    let (y1, y2) = (&mut y1[..m], &mut y2[..m]);
    let mut quads = cols.chunks_exact(4);
    for quad in &mut quads {
        if quad.iter().all(|&(_, a, b)| a != 0.0 && b != 0.0) {
            let [(c0, a0, b0), (c1, a1, b1), (c2, a2, b2), (c3, a3, b3)] =
                [quad[0], quad[1], quad[2], quad[3]];
            let (c0, c1, c2, c3) = (&c0[..m], &c1[..m], &c2[..m], &c3[..m]);
            for i in 0..m {
                let w = [c0[i], c1[i], c2[i], c3[i]];
                y1[i] = add_four(y1[i], w, [a0, a1, a2, a3]);
                y2[i] = add_four(y2[i], w, [b0, b1, b2, b3]);
            }
        } else {
            pair_one_by_one(y1, y2, quad);
        }
    }
    pair_one_by_one(y1, y2, quads.remainder());
}

/// The terms of [`add_columns_pair_with`] one column at a time.
#[inline(always)]
fn pair_one_by_one(y1: &mut [f64], y2: &mut [f64], cols: &[(&[f64], f64, f64)]) {
    for &(c, a, b) in cols {
        if a != 0.0 {
            axpy_with(y1, a, c);
        }
        if b != 0.0 {
            axpy_with(y2, b, c);
        }
    }
}

/// `dst = A x` by faer's matrix-vector product (sequential: the same bits on any number of
/// threads).
pub fn matvec_replace(dst: &mut [f64], a: faer::MatRef<'_, f64>, x: &[f64]) {
    assert!(a.nrows() == dst.len() && a.ncols() == x.len());
    dst.copy_from_slice(&faer_matvec(a, x));
}

/// `A x` by faer's `matmul` (`Accum::Replace`, `alpha = 1`, sequential).
pub fn faer_matvec(a: faer::MatRef<'_, f64>, x: &[f64]) -> Vec<f64> {
    let mut out = faer::Mat::<f64>::zeros(a.nrows(), 1);
    let xm = faer::ColRef::from_slice(x);
    faer::linalg::matmul::matmul(
        out.as_mut(),
        faer::Accum::Replace,
        a,
        xm.as_mat(),
        1.0,
        faer::Par::Seq,
    );
    out.col(0).iter().copied().collect()
}

/// Solves `A x = b` by a fresh LU; `None` when `A` is numerically singular.
pub fn solve_dense(a: &Mat<f64>, b: &Mat<f64>) -> Option<Mat<f64>> {
    let lu = a.partial_piv_lu();
    let x = lu.solve(b);
    (!singular_pivots(&lu)).then_some(x)
}

/// Whether an LU factorisation is numerically singular: its smallest pivot against the largest.
/// A singular system (a body free to slide once every node slips, or a direction nothing holds)
/// still gives a finite answer from a backward-stable LU.
pub fn singular_pivots(lu: &faer::linalg::solvers::PartialPivLu<f64>) -> bool {
    let u = lu.U();
    let n = u.nrows();
    if n == 0 {
        return false;
    }
    let d: Vec<f64> = (0..n).map(|i| u[(i, i)].abs()).collect();
    let lo = d.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = d.iter().cloned().fold(0.0, f64::max);
    lo <= 1e-12 * hi
}

/// Right-preconditioned GMRES (no restart) for `A x = b` with preconditioner `M⁻¹` given by an
/// LU of a nearby matrix, from `x0 = M⁻¹ b`. Returns the solution and the iterations, or
/// `None` if the relative residual is not below `tol` within `max_it` iterations.
pub fn gmres(
    a: &Mat<f64>,
    b: &Mat<f64>,
    m: &faer::linalg::solvers::PartialPivLu<f64>,
    tol: f64,
    max_it: usize,
) -> Option<(Mat<f64>, usize)> {
    let n = a.nrows();
    let bn = b.norm_l2();
    if bn == 0.0 {
        return Some((Mat::zeros(n, 1), 0));
    }
    let x0 = m.solve(b);
    let r0 = b - a * &x0;
    let beta = r0.norm_l2();
    if beta <= tol * bn {
        return Some((x0, 0));
    }
    // Arnoldi on A M⁻¹ with modified Gram–Schmidt; Givens rotations for the least squares.
    let mut v: Vec<Mat<f64>> = vec![&r0 * faer::Scale(1.0 / beta)];
    let mut h = vec![vec![0.0; max_it]; max_it + 1];
    let (mut cs, mut sn) = (vec![0.0; max_it], vec![0.0; max_it]);
    let mut g = vec![0.0; max_it + 1];
    g[0] = beta;
    for k in 0..max_it {
        let z = m.solve(&v[k]);
        let mut w = a * &z;
        for i in 0..=k {
            let hik = (v[i].transpose() * &w)[(0, 0)];
            h[i][k] = hik;
            w -= &v[i] * faer::Scale(hik);
        }
        let hn = w.norm_l2();
        h[k + 1][k] = hn;
        for i in 0..k {
            let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
            h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
            h[i][k] = t;
        }
        let d = h[k][k].hypot(h[k + 1][k]);
        if d == 0.0 {
            return None;
        }
        cs[k] = h[k][k] / d;
        sn[k] = h[k + 1][k] / d;
        h[k][k] = d;
        h[k + 1][k] = 0.0;
        g[k + 1] = -sn[k] * g[k];
        g[k] *= cs[k];
        if g[k + 1].abs() <= tol * bn || hn == 0.0 {
            // y = H⁻¹ g, x = x0 + M⁻¹ V y
            let mut y = vec![0.0; k + 1];
            for i in (0..=k).rev() {
                let s: f64 = (i + 1..=k).map(|j| h[i][j] * y[j]).sum();
                y[i] = (g[i] - s) / h[i][i];
            }
            let mut vy = Mat::<f64>::zeros(n, 1);
            for (i, yi) in y.iter().enumerate() {
                vy += &v[i] * faer::Scale(*yi);
            }
            let x = x0 + m.solve(&vy);
            // Guard against loss of orthogonality: check the true residual.
            let r = (b - a * &x).norm_l2();
            return (r <= 10.0 * tol * bn).then_some((x, k + 1));
        }
        v.push(&w * faer::Scale(1.0 / hn));
    }
    None
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Two products with `W` in one pass give each the bits of its own `add_columns`:
    /// coefficient vectors with zeros in different places (so that some groups of four
    /// columns take the one-by-one path), lengths that are not multiples of four.
    #[test]
    fn two_products_in_one_pass_give_the_bits_of_one_at_a_time() {
        for m in [1, 5, 12, 37, 130] {
            let (w, a) = w_and_mu(m);
            let mut b: Vec<f64> = a.iter().map(|v| 0.7 * v - 0.01).collect();
            let mut a = a;
            for j in (0..m).step_by(3) {
                a[j] = 0.0;
            }
            for j in (1..m).step_by(5) {
                b[j] = 0.0;
            }
            if m > 8 {
                // A run of columns where both are nonzero, for the four-column path.
                for j in 4..8 {
                    a[j] = 0.25 + j as f64;
                    b[j] = -0.5 - j as f64;
                }
            }
            let y0: Vec<f64> = (0..m).map(|i| 1e-3 * i as f64 - 0.02).collect();
            let (mut y1, mut y2) = (y0.clone(), y0.clone());
            add_columns_pair(&mut y1, &mut y2, &w, &a, &b);
            let alone = |c: &[f64]| {
                let mut y = y0.clone();
                let terms = c.iter().enumerate().filter(|&(_, &v)| v != 0.0);
                add_columns(&mut y, &w, terms.map(|(j, &v)| (j, v)));
                y
            };
            let (e1, e2) = (alone(&a), alone(&b));
            for i in 0..m {
                assert_eq!(y1[i].to_bits(), e1[i].to_bits(), "m = {m}, first, row {i}");
                assert_eq!(y2[i].to_bits(), e2[i].to_bits(), "m = {m}, second, row {i}");
            }
        }
    }

    /// A symmetric `m × m` matrix and a vector of forces, both from a fixed sequence.
    pub(crate) fn w_and_mu(m: usize) -> (Mat<f64>, Vec<f64>) {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = move || {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let a = Mat::from_fn(m, m, |_, _| r());
        let w = Mat::from_fn(m, m, |i, j| a[(i, j)] + a[(j, i)]);
        (w, (0..m).map(|_| r()).collect())
    }

    pub(crate) fn product(w: &Mat<f64>, mu: &[f64]) -> Vec<f64> {
        (0..w.nrows())
            .map(|i| (0..mu.len()).map(|j| w[(i, j)] * mu[j]).sum())
            .collect()
    }
}
