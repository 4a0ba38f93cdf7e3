//! The linear algebra of the contact iteration: the Cholesky factor of a Delassus block with
//! Sherman–Morrison–Woodbury updates for the rows that differ from it, and the LU of a dense
//! Newton matrix reused as a GMRES preconditioner.

use super::{NewtonRows, PrefixFactor, SpecialRow};
use faer::Mat;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor as llt_factor;
use faer::linalg::solvers::Solve;
use std::sync::Arc;
use std::time::Instant;

/// `x += a g`.
fn axpy(x: &mut [f64], a: f64, g: &[f64]) {
    if crate::la::simd::avx2() {
        // SAFETY: the processor has AVX2 (checked above).
        unsafe { axpy_avx2(x, a, g) }
    } else {
        axpy_with(x, a, g)
    }
}

#[inline(always)]
fn axpy_with(x: &mut [f64], a: f64, g: &[f64]) {
    for (xi, gi) in x.iter_mut().zip(g) {
        *xi += a * gi;
    }
}

/// [`axpy_with`] compiled for AVX2 (the same operations in the same order).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn axpy_avx2(x: &mut [f64], a: f64, g: &[f64]) {
    axpy_with(x, a, g)
}

#[cfg(not(target_arch = "x86_64"))]
unsafe fn axpy_avx2(x: &mut [f64], a: f64, g: &[f64]) {
    axpy_with(x, a, g)
}

/// `y += Σ_j W[:, j] a_j` over the `(j, a_j)` of `terms`, added to each entry in their order
/// (the bits of one column at a time), four columns per pass over `y` (a quarter of the loads
/// and stores of `y`; these products were a tenth of the contact solve on L5), compiled for
/// AVX2 where the processor has it (the same operations).
pub(super) fn add_columns(
    y: &mut [f64],
    w: &Mat<f64>,
    terms: impl IntoIterator<Item = (usize, f64)>,
) {
    let m = y.len();
    let cols: Vec<(&[f64], f64)> = terms
        .into_iter()
        .map(|(j, a)| {
            let c = w.col(j).try_as_col_major().expect("contiguous columns");
            (&c.as_slice()[..m], a)
        })
        .collect();
    if crate::la::simd::avx2() {
        // SAFETY: the processor has AVX2 (checked above).
        unsafe { add_columns_avx2(y, &cols) }
    } else {
        add_columns_with(y, &cols)
    }
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

/// [`add_columns_with`] compiled for AVX2 (the same operations in the same order).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_columns_avx2(y: &mut [f64], cols: &[(&[f64], f64)]) {
    add_columns_with(y, cols)
}

#[cfg(not(target_arch = "x86_64"))]
unsafe fn add_columns_avx2(y: &mut [f64], cols: &[(&[f64], f64)]) {
    add_columns_with(y, cols)
}

/// `y1 += Σ_j W[:, j] a_j` and `y2 += Σ_j W[:, j] b_j` over the nonzero `a_j`, `b_j`, in one
/// pass over the columns of `W`: each output gets its terms in increasing `j`, one after the
/// other, so each is bit for bit what [`add_columns`] gives it alone
/// (`two_products_in_one_pass_give_the_bits_of_one_at_a_time`), and `W` (8 MB on L5) is read
/// once for both.
pub(super) fn add_columns_pair(y1: &mut [f64], y2: &mut [f64], w: &Mat<f64>, a: &[f64], b: &[f64]) {
    let m = y1.len();
    assert!(y2.len() == m && a.len() == b.len() && a.len() <= w.ncols());
    let cols: Vec<(&[f64], f64, f64)> = (0..a.len())
        .filter(|&j| a[j] != 0.0 || b[j] != 0.0)
        .map(|j| {
            let c = w.col(j).try_as_col_major().expect("contiguous columns");
            (&c.as_slice()[..m], a[j], b[j])
        })
        .collect();
    if crate::la::simd::avx2() {
        // SAFETY: the processor has AVX2 (checked above).
        unsafe { add_columns_pair_avx2(y1, y2, &cols) }
    } else {
        add_columns_pair_with(y1, y2, &cols)
    }
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

/// [`add_columns_pair_with`] compiled for AVX2 (the same operations in the same order).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn add_columns_pair_avx2(y1: &mut [f64], y2: &mut [f64], cols: &[(&[f64], f64, f64)]) {
    add_columns_pair_with(y1, y2, cols)
}

#[cfg(not(target_arch = "x86_64"))]
unsafe fn add_columns_pair_avx2(y1: &mut [f64], y2: &mut [f64], cols: &[(&[f64], f64, f64)]) {
    add_columns_pair_with(y1, y2, cols)
}

/// `dst = A x` for a column-major `A` (`dst.len()` rows), with the arithmetic of faer's
/// `matmul(dst, Accum::Replace, A, x, 1.0, Par::Seq)` for one column, its column-major
/// matrix-vector kernel: each entry from +0.0, then `fma(A[i, j], x_j, ·)` over the columns in
/// order. Here four columns per pass over `dst` (a quarter of its loads and stores), the same
/// bits (`the_product_with_w_out_has_the_bits_of_faers`). Where the processor lacks AVX2 and
/// FMA, faer's own (whose rounding on such a processor this does not claim to follow).
pub(super) fn matvec_replace(dst: &mut [f64], a: faer::MatRef<'_, f64>, x: &[f64]) {
    assert!(a.nrows() == dst.len() && a.ncols() == x.len());
    #[cfg(target_arch = "x86_64")]
    if crate::la::simd::avx2() && std::arch::is_x86_feature_detected!("fma") {
        let m = dst.len();
        let cols: Vec<&[f64]> = (0..a.ncols())
            .map(|j| {
                let c = a.col(j).try_as_col_major().expect("contiguous columns");
                &c.as_slice()[..m]
            })
            .collect();
        // SAFETY: the processor has AVX2 and FMA (checked above).
        unsafe { matvec_fma(dst, &cols, x) };
        return;
    }
    dst.copy_from_slice(&faer_matvec(a, x));
}

/// `A x` by faer's `matmul` (`Accum::Replace`, `alpha = 1`, sequential).
fn faer_matvec(a: faer::MatRef<'_, f64>, x: &[f64]) -> Vec<f64> {
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

/// The kernel of [`matvec_replace`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn matvec_fma(dst: &mut [f64], cols: &[&[f64]], x: &[f64]) {
    dst.fill(0.0);
    fma_columns(dst, cols.len(), |j| cols[j], |j| x[j]);
}

/// `dst_i = fma(c_j[i], a_j, dst_i)` for the columns `j < count` in order (`c_j = col(j)`, at
/// least as long as `dst`, `a_j = coef(j)`), four columns per pass over `dst`: the same bits as
/// one column at a time.
#[inline(always)]
fn fma_columns<'c>(
    dst: &mut [f64],
    count: usize,
    col: impl Fn(usize) -> &'c [f64],
    coef: impl Fn(usize) -> f64,
) {
    let m = dst.len();
    let mut j = 0;
    while j + 4 <= count {
        let (c0, c1, c2, c3) = (
            &col(j)[..m],
            &col(j + 1)[..m],
            &col(j + 2)[..m],
            &col(j + 3)[..m],
        );
        let (a0, a1, a2, a3) = (coef(j), coef(j + 1), coef(j + 2), coef(j + 3));
        for i in 0..m {
            let mut v = dst[i];
            v = c0[i].mul_add(a0, v);
            v = c1[i].mul_add(a1, v);
            v = c2[i].mul_add(a2, v);
            v = c3[i].mul_add(a3, v);
            dst[i] = v;
        }
        j += 4;
    }
    for j in j..count {
        let (c, a) = (&col(j)[..m], coef(j));
        for (v, &cij) in dst.iter_mut().zip(c) {
            *v = cij.mul_add(a, *v);
        }
    }
}

/// Solves `A x = b` by a fresh LU; `None` when `A` is numerically singular.
pub(super) fn solve_dense(a: &Mat<f64>, b: &Mat<f64>) -> Option<Mat<f64>> {
    let lu = a.partial_piv_lu();
    let x = lu.solve(b);
    (!singular_pivots(&lu)).then_some(x)
}

/// Whether an LU factorisation is numerically singular: its smallest pivot against the largest.
/// A singular system (a body free to slide once every node slips, or a direction nothing holds)
/// still gives a finite answer from a backward-stable LU.
fn singular_pivots(lu: &faer::linalg::solvers::PartialPivLu<f64>) -> bool {
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

/// Factorisations kept across Newton iterations and load steps (see
/// [`super::ContactSystem::solve_step`]).
///
/// The structured path ([`Self::solve_rows`]) keeps the Cholesky factor of a Delassus block
/// `K = W[k_unk, k_unk]` and solves each Newton system `A x = b` whose matrix differs from `K`
/// only in a few rows by the Sherman–Morrison–Woodbury identity; the dense path
/// (`LuCache::solve`) keeps the LU of an earlier Newton matrix as a GMRES preconditioner.
#[derive(Default)]
pub struct LuCache {
    /// Dense path: unknowns and LU of the last factorised Newton matrix.
    unk: Vec<usize>,
    lu: Option<faer::linalg::solvers::PartialPivLu<f64>>,
    /// Structured path: unknowns (μ indices) of the factorised block `K`, the position in it
    /// of each μ index (`usize::MAX`: not in it), its Cholesky factor (`K = Zᵀ Z` restricted to
    /// the unknowns is symmetric positive definite), and the columns `K⁻¹ e_q` computed so far
    /// by position `q` (empty: not yet).
    k_unk: Vec<usize>,
    k_pos: Vec<usize>,
    k_llt: Option<Arc<Block>>,
    k_cols: Vec<Vec<f64>>,
    /// The right-hand side `b̃` (by position in `K`) of the last direct solve with the factor
    /// and `x̃ = K⁻¹ b̃` (empty: none since the factorisation or the last checkpoint).
    bt: Vec<f64>,
    xt: Vec<f64>,
    /// Where factorised blocks are shared with the other simulations of the same model (a
    /// sweep's rows), if anywhere.
    shared: Option<Arc<BlockStore>>,
    /// The batches of columns of `G` solved for since `K` was factorised (positions in `K`),
    /// in order: with `k_unk`, what a resumed run replays to reach the same factors.
    batches: Vec<Vec<usize>>,
    /// Factorisations done (of `K` or of a dense Newton matrix) and GMRES iterations spent (for
    /// the run summary).
    pub factorisations: usize,
    pub gmres_iterations: usize,
    /// Unknowns of the largest Delassus block factorised (or taken from the prefix factor) so far.
    pub largest_block: usize,
    /// Delassus blocks taken from the prefix factor of `W` (not factorised, not counted in
    /// `factorisations`).
    pub prefix_blocks: usize,
    /// Seconds spent in each part of the structured solve (for the run summary).
    pub timings: SolveTimings,
    /// Solve every system directly (no start from the step's last direct solve): set by
    /// [`super::ContactSystem::solve_step`] for small systems and for the second attempt at a
    /// step that failed.
    pub(super) exact: bool,
    /// With the shortcuts: `(μ, W μ)` of the last two converged iterates, the older first,
    /// and the extrapolation factor of the predicted start of the step being solved, if it
    /// has one (see [`Self::recall_w_mu`]).
    products: Vec<(Vec<f64>, Vec<f64>)>,
    prediction: Option<f64>,
    /// Without the shortcuts: `(w0, μ, y = w0 + W μ)` for the predicted start of the next
    /// step, computed with the last step's converged `y` in the same pass over `W` (see
    /// [`Self::take_next_y`]).
    next_y: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    /// With the shortcuts: the special rows (positions in `K`) and the LU of the last
    /// capacitance system factorised, which preconditions GMRES on the next system with the
    /// same rows (see [`CAPACITANCE_REUSE_FROM`]).
    cap_lu: Option<(Vec<usize>, faer::linalg::solvers::PartialPivLu<f64>)>,
}

/// Special rows from which, with the shortcuts, a capacitance system whose rows are those
/// of the last one factorised is solved by GMRES preconditioned with that LU instead of
/// factorised again. Within a load step the slip rows stay and only their coefficients move
/// with the linearisation of μ(slip), so the LU of the step's first iteration serves the
/// others; Fig. 2 on L7 ends with some 700 slip rows, whose LU (6 ms) each Newton iteration
/// had repeated. Below, the LU costs little and the rounding of the direct solve is kept.
const CAPACITANCE_REUSE_FROM: usize = 256;

/// Seconds spent in the parts of the structured contact solve, summed over a run.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SolveTimings {
    /// Cholesky factorisations of Delassus blocks `K`.
    pub factorise: f64,
    /// Columns `K⁻¹ e_q` of the rows that differ from `K`.
    pub columns: f64,
    /// Direct solves with the factor (one per load step, or when a plain row's right-hand side
    /// changes).
    pub direct: f64,
    /// The capacitance system and the Woodbury correction.
    pub woodbury: f64,
    /// Products with `W` for the rows outside the system.
    pub products: f64,
}

/// A factorised Delassus block `K = W[unk, unk]`: its Cholesky factor, and the rows of `W`
/// outside it with `W[out_rows, unk]`, contiguous for the product of every iteration.
pub struct Block {
    /// The lower Cholesky factor `L` of `K = L Lᵀ` (its strictly upper part is zero).
    l: BlockFactor,
    out_rows: Vec<usize>,
    w_out: Mat<f64>,
}

/// Where a block's Cholesky factor is.
enum BlockFactor {
    /// Factorised from `W`.
    Owned(Mat<f64>),
    /// The leading `p × p` block of a [`PrefixFactor`] (the block's unknowns are the first
    /// `p` of its order).
    Prefix(Arc<PrefixFactor>, usize),
}

/// Unknowns from which a Delassus block is taken from the [`PrefixFactor`] when it is nearly
/// a leading set of its order (smaller blocks cost little to factorise).
const PREFIX_MIN: usize = 256;

/// The length `p` of the leading set of `pf`'s order that holds the unknowns `unk` (distinct
/// μ indices), if it holds few others: at most `p / 64`, the share of unknowns not in the
/// system at which [`LuCache::solve_rows`] refactorises at a new step (each costs a special
/// row, a column of `G` and a row of every capacitance system).
fn leading_set(pf: &PrefixFactor, unk: &[usize]) -> Option<usize> {
    if unk.len() < PREFIX_MIN {
        return None;
    }
    let p = unk.iter().map(|&u| pf.pos[u]).max()? + 1;
    (p.checked_sub(unk.len())? <= p / 64).then_some(p)
}

impl Block {
    /// The block of the first `p` unknowns of `pf`'s order (`W[order[..p], order[..p]]`),
    /// whose factor is the leading block of `pf`'s: no factorisation. `None` under the same
    /// pivot test as [`Self::factorise`]; `parallel` as there.
    fn prefix(w: &Mat<f64>, pf: &Arc<PrefixFactor>, p: usize, parallel: bool) -> Option<Block> {
        let pivots: Vec<f64> = (0..p).map(|i| pf.c[(i, i)].powi(2)).collect();
        if !pivots_ok(&pivots) {
            return None;
        }
        let (out_rows, w_out) = outside(w, &pf.order[..p], parallel);
        Some(Block {
            l: BlockFactor::Prefix(pf.clone(), p),
            out_rows,
            w_out,
        })
    }

    /// The lower Cholesky factor.
    fn l(&self) -> faer::MatRef<'_, f64> {
        match &self.l {
            BlockFactor::Owned(l) => l.as_ref(),
            BlockFactor::Prefix(pf, p) => pf.c.as_ref().submatrix(0, 0, *p, *p),
        }
    }

    /// Factorises `W[unk, unk]`; `None` if it is singular or not numerically positive definite.
    ///
    /// `parallel`: copy and factorise on rayon's threads (the factorisation on one while a
    /// model-cache entry is written, [`crate::cache::writing`]). faer's blocked Cholesky
    /// splits the products of its updates by their output, never a sum, so the factor has the
    /// same bits on any number of threads
    /// (`the_block_factor_has_the_same_bits_on_any_number_of_threads`).
    /// Not within a [`BlockStore`]: a rayon worker waiting there for a parallel factorisation
    /// could take up another task that waits on this very block.
    fn factorise(w: &Mat<f64>, unk: &[usize], parallel: bool) -> Option<Block> {
        // Factorised in place from the lower half of K (faer's `Llt` would copy K into a
        // second array of the same size first: 87 MB at L7, in fresh memory).
        let n = unk.len();
        let lower = |j: usize, col: &mut [f64]| {
            let wj = w.col(unk[j]);
            for i in j..n {
                col[i] = wj[unk[i]];
            }
        };
        let mut l = crate::la::par::mat_filled(n, n, parallel, lower);
        let par = if parallel && !crate::cache::writing() {
            crate::la::par::factor_parallelism()
        } else {
            faer::Par::Seq
        };
        let mut mem = MemBuffer::new(llt_factor::cholesky_in_place_scratch::<f64>(
            n,
            par,
            Default::default(),
        ));
        llt_factor::cholesky_in_place(
            l.as_mut(),
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .ok()?;
        let pivots: Vec<f64> = (0..n).map(|i| l[(i, i)].powi(2)).collect();
        if !pivots_ok(&pivots) {
            return None;
        }
        let (out_rows, w_out) = outside(w, unk, parallel);
        Some(Block {
            l: BlockFactor::Owned(l),
            out_rows,
            w_out,
        })
    }

    /// Solves `K X = B` in place for the columns of `b` (sequential; the forward and backward
    /// sweeps of faer's `llt::solve::solve_in_place_with_conj`, the same arithmetic).
    fn solve_in_place(&self, b: &mut Mat<f64>) {
        self.solve_in_place_below(b, 0);
    }

    /// [`Self::solve_in_place`] for right-hand sides that are zero above row `q0` (columns of
    /// the identity): the forward sweep `L y = b` leaves those rows zero, so it runs on the
    /// trailing block `L[q0.., q0..]` alone (`q0 = 0`: the whole solve). The columns of `G` are
    /// those of slip rows, which (ordered by initial gap, or tangential after normal) sit late
    /// in the block: on Fig. 2 at L7 this takes most of the forward half of their cost.
    /// One right-hand side (a direct solve) takes its forward sweep from [`forward_one`],
    /// faer's arithmetic four columns per pass: the 50-law sweep 2.071 → 1.967 s, faster in
    /// 8 of 8 pairs (`SWEEP_AB_SINGLE=0 benches/sweep_ab.sh 8`). The backward sweep written
    /// the same way (faer's dot products, bit for bit) gained nothing measurable (1.995 →
    /// 1.987 s, 3 of 8 pairs) and is faer's.
    fn solve_in_place_below(&self, b: &mut Mat<f64>, q0: usize) {
        use faer::linalg::triangular_solve as tri;
        let par = faer::Par::Seq;
        let l = self.l();
        let n = l.nrows();
        let q0 = q0.min(n);
        let lower = l.submatrix(q0, q0, n - q0, n - q0);
        if b.ncols() != 1 || !forward_one(lower, b.col_mut(0).subrows_mut(q0, n - q0)) {
            tri::solve_lower_triangular_in_place_with_conj(
                lower,
                faer::Conj::No,
                b.as_mut().subrows_mut(q0, n - q0),
                par,
            );
        }
        tri::solve_upper_triangular_in_place_with_conj(
            l.transpose(),
            faer::Conj::Yes,
            b.as_mut(),
            par,
        );
    }
}

/// Solves `L y = b` in place for one right-hand side with the arithmetic of faer's
/// `solve_lower_triangular_in_place` (sequential, one column): the same recursive halving
/// (`faer_block_size`), the same closed forms on blocks of at most four rows, and each
/// off-diagonal block applied as faer's column-major matrix-vector product does it, every entry
/// `fma(L[i, j], −y_j, b_i)` over the columns in order; here four columns per pass over `b`
/// (a quarter of its loads and stores), the same bits
/// (`the_forward_sweep_has_the_bits_of_faers`). `false` (nothing done) where the processor lacks
/// AVX2 and FMA, or `L` or `b` is not contiguous by columns: faer's own then.
fn forward_one(l: faer::MatRef<'_, f64>, b: faer::ColMut<'_, f64>) -> bool {
    #[cfg(target_arch = "x86_64")]
    if crate::la::simd::avx2()
        && std::arch::is_x86_feature_detected!("fma")
        && l.row_stride() == 1
        && l.nrows() > 0
        && b.row_stride() == 1
    {
        let b = b.try_as_col_major_mut().expect("unit row stride");
        let n = l.nrows();
        let ld = l.col_stride() as usize;
        // SAFETY: column-major with leading dimension `ld`, `n` columns of `n` rows.
        let data = unsafe { std::slice::from_raw_parts(l.as_ptr(), ld * (n - 1) + n) };
        // SAFETY: the processor has AVX2 and FMA (checked above).
        unsafe { forward_fma(data, ld, 0, b.as_slice_mut()) };
        return true;
    }
    let _ = (l, b);
    false
}

/// The split of faer's recursive triangular solve: the rows of the leading block of `n`.
fn faer_block_size(n: usize) -> usize {
    let half = n / 2;
    n - if n >= 32 {
        half.div_ceil(16) * 16
    } else if n >= 16 {
        half.div_ceil(8) * 8
    } else if n >= 8 {
        half.div_ceil(4) * 4
    } else {
        half
    }
}

/// [`forward_one`] on the diagonal block of `L` (column-major in `l`, leading dimension `ld`)
/// that starts at row and column `off`, of order `x.len()`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn forward_fma(l: &[f64], ld: usize, off: usize, x: &mut [f64]) {
    let n = x.len();
    let at = |i: usize, j: usize| l[(off + j) * ld + off + i];
    if n <= 4 {
        // faer's closed forms, with their order of operations.
        let inv: [f64; 4] = std::array::from_fn(|i| if i < n { at(i, i).recip() } else { 0.0 });
        let y0 = x[0] * inv[0];
        x[0] = y0;
        if n == 1 {
            return;
        }
        let y1 = x[1] * inv[1] + (-at(1, 0) * inv[1]) * y0;
        x[1] = y1;
        if n == 2 {
            return;
        }
        let y2 = x[2] * inv[2] + (-at(2, 0) * inv[2]) * y0 + (-at(2, 1) * inv[2]) * y1;
        x[2] = y2;
        if n == 3 {
            return;
        }
        x[3] = x[3] * inv[3]
            + (-at(3, 0) * inv[3]) * y0
            + (-at(3, 1) * inv[3]) * y1
            + (-at(3, 2) * inv[3]) * y2;
        return;
    }
    let bs = faer_block_size(n);
    // SAFETY: the caller's (AVX2 and FMA).
    unsafe { forward_fma(l, ld, off, &mut x[..bs]) };
    let (top, bot) = x.split_at_mut(bs);
    let m = bot.len();
    let col = |j: usize| {
        let s = (off + j) * ld + off + bs;
        &l[s..s + m]
    };
    fma_columns(bot, bs, col, |j| -top[j]);
    // SAFETY: the caller's (AVX2 and FMA).
    unsafe { forward_fma(l, ld, off + bs, bot) };
}

/// Block unknowns from which the columns of `G` skip the zero rows of the forward sweep
/// ([`Block::solve_in_place_below`]). Below, the columns cost little (5 ms in all on Fig. 2 at
/// L5), and the rounding of the whole solve is kept: on L4 the slip-controlled start of
/// `cases/fig2_softening.json`, which crosses the ramp's kink, took five cutbacks instead of
/// none with columns that differed from it by round-off (1e-12 relative) — a step that close
/// to cycling is decided by the last bits.
const TRAILING_FROM: usize = 1024;

/// Whether the pivots `L_ii²` of a Cholesky factor are usable: as for an LU, singular when the
/// smallest is below 1e-12 of the largest; and pivots within 2^52 of the smallest normal number
/// have lost digits to underflow (absurd moduli make W that small).
fn pivots_ok(pivots: &[f64]) -> bool {
    let lo = pivots.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = pivots.iter().copied().fold(0.0, f64::max);
    !(lo <= 1e-12 * hi || lo < f64::MIN_POSITIVE / f64::EPSILON)
}

/// The rows of `w` outside the unknowns `unk`, and `W[out_rows, unk]`.
fn outside(w: &Mat<f64>, unk: &[usize], parallel: bool) -> (Vec<usize>, Mat<f64>) {
    let mut inside = vec![false; w.nrows()];
    unk.iter().for_each(|&u| inside[u] = true);
    let out_rows: Vec<usize> = (0..w.nrows()).filter(|&i| !inside[i]).collect();
    let column = |q: usize, col: &mut [f64]| {
        let wq = w.col(unk[q]);
        for (c, &r) in col.iter_mut().zip(&out_rows) {
            *c = wq[r];
        }
    };
    let w_out = crate::la::par::mat_filled(out_rows.len(), unk.len(), parallel, column);
    (out_rows, w_out)
}

/// Factorised Delassus blocks shared by the simulations of one model that run side by side (a
/// sweep's rows, which through the same loads factorise the same blocks: Fig. 2's 50-law sweep
/// on L5 needs 4 distinct blocks for its 200 factorisations). The first simulation to need a
/// block factorises it and the others wait for it and reuse it. A factorisation is sequential
/// and depends only on `W` and the unknowns, so each simulation's results are bit for bit
/// those it gets alone. Blocks beyond [`BlockStore::MAX_BYTES`] are not kept: each simulation
/// factorises those itself.
#[derive(Default)]
pub struct BlockStore {
    /// The bytes of the blocks taken in, and the blocks by their unknowns.
    blocks: std::sync::Mutex<(usize, BlockMap)>,
}

/// The blocks of a [`BlockStore`] by their unknowns.
type BlockMap = std::collections::HashMap<Vec<usize>, Arc<BlockSlot>>;

/// One block of a [`BlockStore`]: factorised once (`None`: singular).
type BlockSlot = std::sync::OnceLock<Option<Arc<Block>>>;

impl BlockStore {
    /// Bytes of factors a store keeps at most (about 16 blocks of 1 000 unknowns, or 2 of
    /// 4 000 as on L7).
    pub const MAX_BYTES: usize = 256 << 20;

    /// The factorised block `W[unk, unk]`, from the store or factorised now.
    fn get(&self, w: &Mat<f64>, unk: &[usize]) -> Option<Arc<Block>> {
        // The factor and W[out_rows, unk].
        let estimate = 8 * unk.len() * w.nrows();
        let slot = {
            let mut guard = self.blocks.lock().unwrap_or_else(|e| e.into_inner());
            let (bytes, map) = &mut *guard;
            match map.get(unk) {
                Some(slot) => Some(slot.clone()),
                None if *bytes + estimate <= Self::MAX_BYTES => {
                    *bytes += estimate;
                    let slot = Arc::new(BlockSlot::new());
                    map.insert(unk.to_vec(), slot.clone());
                    Some(slot)
                }
                None => None,
            }
        };
        match slot {
            Some(slot) => slot
                .get_or_init(|| Block::factorise(w, unk, false).map(Arc::new))
                .clone(),
            None => Block::factorise(w, unk, false).map(Arc::new),
        }
    }
}

/// The factorised Delassus block and the columns of `G` computed from it, by what produced
/// them: saved with a restart state, so that a resumed run factorises the same block and
/// solves for the same columns in the same batches (the same arithmetic, hence the same bits).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BlockRecord {
    /// μ indices of the block's unknowns.
    pub unk: Vec<usize>,
    /// Positions in the block of the columns solved for, batch by batch.
    pub batches: Vec<Vec<usize>>,
    /// The last direct solve `x̃ = K⁻¹ b̃` and its right-hand side (empty: none).
    #[serde(default)]
    pub bt: Vec<f64>,
    #[serde(default)]
    pub xt: Vec<f64>,
    /// `(μ, W μ)` of the last two converged iterates, the older first.
    #[serde(default)]
    pub products: Vec<(Vec<f64>, Vec<f64>)>,
}

/// Contact systems with fewer candidate unknowns than this are solved through the dense Newton
/// matrix even with a cache. There it costs microseconds, and such small systems are where the
/// degenerate cases live (a few nodes touching at zero load, whose active sets are decided by
/// the round-off in forces that are zero in exact arithmetic): the dense path keeps the
/// rounding of the reference solve for them.
pub(super) const STRUCTURED_MIN: usize = 64;

/// Columns of `G` solved for ahead of need with each batch: those of the stick nodes nearest
/// their friction limit, which are the next to slip as a tangential load grows. A solve with
/// the cached factor reads the whole factor (tens of MB at L7) whatever the number of
/// right-hand sides, so a few dozen columns cost little more than one. Fig. 2 on L7 spends
/// 2.35 s on columns without, 0.97 s with 16, 0.88 s with 32, 0.80 s with 64 and 0.79 s with
/// 128 (one run each).
const PREFETCH: usize = 64;

/// GMRES iterations before giving up on the cached factorisation and refactorising.
const GMRES_MAX: usize = 12;

impl LuCache {
    /// A cache that shares its factorised Delassus blocks through `store` (see [`BlockStore`]).
    pub fn sharing(store: Option<Arc<BlockStore>>) -> LuCache {
        LuCache {
            shared: store,
            ..Default::default()
        }
    }

    /// Forgets the factorisations.
    pub fn clear(&mut self) {
        self.lu = None;
        self.unk.clear();
        self.forget_block();
        self.products.clear();
        self.next_y = None;
    }

    /// The start of the next step is extrapolated from the last two converged states by `t`
    /// (`μ = μ₁ + t (μ₁ − μ₀)`, normal forces clipped at zero), or not extrapolated (`None`).
    pub fn predict_with(&mut self, t: Option<f64>) {
        self.prediction = t;
    }

    /// The extrapolation factor announced for the step being solved ([`Self::predict_with`]),
    /// if it has not been used.
    pub(super) fn prediction(&self) -> Option<f64> {
        self.prediction
    }

    /// Keeps `y = w0 + W μ` at the predicted start `μ` of the next step (see
    /// [`Self::take_next_y`]).
    pub(super) fn keep_next_y(&mut self, w0: &[f64], mu: Vec<f64>, y: Vec<f64>) {
        self.next_y = Some((w0.to_vec(), mu, y));
    }

    /// `y = w0 + W μ` if [`Self::keep_next_y`] kept it for exactly these `w0` and `μ` (bit for
    /// bit: a product of its own would give the same bits), once.
    pub(super) fn take_next_y(&mut self, w0: &[f64], mu: &[f64]) -> Option<Vec<f64>> {
        let same = |a: &[f64], b: &[f64]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
        };
        let (w, m, y) = self.next_y.take()?;
        (same(&w, w0) && same(&m, mu)).then_some(y)
    }

    /// Keeps `W μ` of a converged iterate `μ` (with the shortcuts, from the last solve).
    pub(super) fn remember_w_mu(&mut self, mu: Vec<f64>, w_mu: Vec<f64>) {
        if self.products.len() == 2 {
            self.products.remove(0);
        }
        self.products.push((mu, w_mu));
    }

    /// `W μ` without a product with the whole of `w` where the products of the last two
    /// converged iterates give it: `μ` is the last of them, or the extrapolation announced by
    /// [`Self::predict_with`], `W μ = p₁ + t (p₁ − p₀) + W δ` with `δ` the entries of `μ` that
    /// differ from `μ₁ + t (μ₁ − μ₀)` (the clipped normal forces). At L7 a product with `W`
    /// reads 130 MB: it was a fifth of the contact solve's time at the start of the steps.
    /// `None` when neither applies (or `δ` has more than an eighth of the entries).
    pub(super) fn recall_w_mu(&mut self, mu: &[f64], w: &Mat<f64>) -> Option<Vec<f64>> {
        let t = self.prediction.take();
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        let [.., (mu1, p1)] = &self.products[..] else {
            return None;
        };
        if mu1.len() != mu.len() {
            return None;
        }
        if same(mu1, mu) {
            return Some(p1.clone());
        }
        let (t, [(mu0, p0), _]) = (t?, &self.products[..]) else {
            return None;
        };
        // The predictor's own arithmetic (`crate::driver`), entry by entry.
        let mut delta = Vec::new();
        for (j, ((a, b), m)) in mu1.iter().zip(mu0).zip(mu).enumerate() {
            let e = a + t * (a - b);
            if e.to_bits() != m.to_bits() {
                delta.push((j, m - e));
            }
        }
        if delta.len() > mu.len() / 8 {
            return None;
        }
        let mut p: Vec<f64> = p1.iter().zip(p0).map(|(a, b)| a + t * (a - b)).collect();
        add_columns(&mut p, w, delta);
        Some(p)
    }

    /// Forgets the factorised block `K` and everything computed from it.
    fn forget_block(&mut self) {
        self.cap_lu = None;
        self.k_llt = None;
        self.k_unk.clear();
        self.k_pos.clear();
        self.k_cols.clear();
        self.forget_direct();
        self.batches.clear();
    }

    /// Forgets the last direct solve (the next system is solved directly).
    pub(super) fn forget_direct(&mut self) {
        self.bt.clear();
        self.xt.clear();
    }

    /// At the end of every converged step: forgets the factorisations of this step's own
    /// matrices (the dense LU and the capacitance LU), which a resumed run could not rebuild
    /// bit for bit. What is kept — the factorised block `K`, the columns solved from it, the
    /// last direct solve and the products of the last two converged iterates — is what
    /// [`Self::checkpoint`] records, so a run computes the same whichever of its steps are
    /// checkpoints (written steps) and a run resumed from any of them computes what the
    /// uninterrupted run computes.
    pub fn end_step(&mut self) {
        self.lu = None;
        self.cap_lu = None;
        self.unk.clear();
    }

    /// What a resumed run needs to rebuild the state kept by [`Self::end_step`] (see
    /// [`BlockRecord`]; the block's unknowns and batches are empty when none is factorised);
    /// `None` when nothing is kept.
    pub fn checkpoint(&self) -> Option<BlockRecord> {
        (self.k_llt.is_some() || !self.products.is_empty()).then(|| BlockRecord {
            unk: self.k_unk.clone(),
            batches: self.batches.clone(),
            bt: self.bt.clone(),
            xt: self.xt.clone(),
            products: self.products.clone(),
        })
    }

    /// Rebuilds the state [`Self::checkpoint`] recorded: factorises the same block of `w` and
    /// solves for the same columns in the same batches. The work is not counted in the
    /// factorisations (the uninterrupted run counted it once). `false` if the block does not
    /// factorise (the record is not from this model).
    pub fn replay(
        &mut self,
        w: &Mat<f64>,
        prefix: Option<&Arc<PrefixFactor>>,
        rec: &BlockRecord,
    ) -> bool {
        let (count, taken) = (self.factorisations, self.prefix_blocks);
        let ok = rec.unk.is_empty()
            || self.factorise_block(w, prefix, &rec.unk).is_some()
                && rec.batches.iter().all(|b| {
                    b.iter().all(|&q| q < self.k_unk.len())
                        && self.solve_columns(b.clone()).is_some()
                });
        self.factorisations = count;
        self.prefix_blocks = taken;
        if !ok {
            self.clear();
            return false;
        }
        self.bt = rec.bt.clone();
        self.xt = rec.xt.clone();
        self.products = rec.products.clone();
        true
    }

    /// Solves the structured Newton system `rows` (see [`super::ContactSystem::newton_rows`]) with the
    /// cached Cholesky factor of a Delassus block `K` whose unknowns include those of `rows`;
    /// `w` is the whole Delassus operator. Returns the unknowns (ordered as `rows.unk`) and
    /// `W μ` at the new iterate (all rows of `W`; on the system's own rows it is taken from the
    /// equations, which saves most of a product with `W` per iteration). `None` if `K` or the
    /// system is numerically singular, or the answer is not finite (the caller then assembles
    /// the dense system, whose LU decides).
    ///
    /// Why: through a load history the contact set changes little, and the Newton matrix
    /// differs from `K = W[unk, unk]` only in the rows of slip nodes and force-driven anchors
    /// (`p` of them, `p ≪ n`). Unknowns of `K` that left the contact are more such rows
    /// (`x_q = 0`), so `K` is refactorised only when a node outside it comes into contact or
    /// too many of its unknowns have left. With `A = K + E_P B` (`E_P` the special rows'
    /// unit vectors, `B = A_P − K_P`):
    /// ```text
    ///   x0 = K⁻¹ b,   G = K⁻¹ E_P,   C = I + B G = A_P G,   C y = B x0,   x = x0 − G y,
    /// ```
    /// where `A_P G` has the entries `α G_rj + γ G_qj + β δ_rj` (because `K G = E_P`) and
    /// `B x0 = α x0_r + γ x0_q + (β − 1) b_r` (because `K x0 = b`). Each iteration costs one
    /// solve with the cached factor and a `p × p` factorisation; the columns of `G` are kept
    /// until `K` is refactorised, so a node that starts to slip costs one more solve, once.
    ///
    /// `new_step`: the first iteration of a load step. While the contact set settles within a
    /// step, `K` is kept until a quarter of its unknowns have left; at the start of a step it
    /// is refactorised for the current set once more than 1/64 have, since those rows would
    /// otherwise enlarge the capacitance system of every iteration of the steps to come.
    pub fn solve_rows(
        &mut self,
        w: &Mat<f64>,
        prefix: Option<&Arc<PrefixFactor>>,
        rows: &NewtonRows,
        new_step: bool,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let covered = self.k_llt.is_some()
            && rows
                .unk
                .iter()
                .all(|&u| self.k_pos.get(u).is_some_and(|&q| q != usize::MAX));
        // Unknowns of K not in this system: each costs a special row (and a column of G).
        let left = self.k_unk.len().saturating_sub(rows.unk.len());
        let limit = self.k_unk.len() / if new_step { 64 } else { 4 };
        if !covered || left > limit {
            let t = Instant::now();
            let done = self.factorise_block(w, prefix, &rows.unk);
            self.timings.factorise += t.elapsed().as_secs_f64();
            done?;
        }
        let nk = self.k_unk.len();
        let (b, special) = self.on_block(rows);
        let likely: Vec<usize> = rows
            .likely
            .iter()
            .map(|&r| self.k_pos[rows.unk[r]])
            .collect();
        let t = Instant::now();
        let cols = self.solve_g_columns(&special, &likely);
        self.timings.columns += t.elapsed().as_secs_f64();
        cols?;
        // x0 = K⁻¹ b. The rows of K keep their right-hand side through the iterations of a
        // step, so with b = b̃ + E_P d (d nonzero on special rows only) x0 = x̃ + G d from the
        // last direct solve x̃ = K⁻¹ b̃ and the columns of G: no pass over the factor.
        let t = Instant::now();
        let mut is_special = vec![false; nk];
        for s in &special {
            is_special[s.row] = true;
        }
        let reuse = !self.exact
            && self.xt.len() == nk
            && (0..nk).all(|q| is_special[q] || b[q].to_bits() == self.bt[q].to_bits());
        if !reuse {
            let block = self.k_llt.as_ref()?;
            let mut x0 = Mat::from_fn(nk, 1, |i, _| b[i]);
            block.solve_in_place(&mut x0);
            self.bt = b.clone();
            self.xt = x0.col(0).iter().copied().collect();
        }
        let mut x = self.xt.clone();
        if reuse {
            for s in &special {
                let d = b[s.row] - self.bt[s.row];
                if d != 0.0 {
                    axpy(&mut x, d, &self.k_cols[s.row]);
                }
            }
        }
        self.timings.direct += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let y_cap = if special.is_empty() {
            Vec::new()
        } else {
            let y = self.woodbury_correction(&special, &b, &mut x);
            self.timings.woodbury += t.elapsed().as_secs_f64();
            y?
        };
        let t = Instant::now();
        let (xs, w_mu) = self.new_w_mu(w, rows, &b, &x, &special, &y_cap);
        self.timings.products += t.elapsed().as_secs_f64();
        xs.iter().all(|v| v.is_finite()).then_some((xs, w_mu))
    }

    /// The system `rows` in the positions of the factorised block `K`: the right-hand side `b`
    /// (zero on unknowns of `K` not in the system) and the special rows, followed by a row
    /// `x_q = 0` for each unknown `q` of `K` not in the system.
    fn on_block(&self, rows: &NewtonRows) -> (Vec<f64>, Vec<SpecialRow>) {
        let nk = self.k_unk.len();
        let mut b = vec![0.0; nk];
        let mut in_system = vec![false; nk];
        for (r, &u) in rows.unk.iter().enumerate() {
            b[self.k_pos[u]] = rows.b[r];
            in_system[self.k_pos[u]] = true;
        }
        let mut special: Vec<SpecialRow> = rows
            .special
            .iter()
            .map(|s| SpecialRow {
                row: self.k_pos[rows.unk[s.row]],
                col: self.k_pos[rows.unk[s.col]],
                combo: s
                    .combo
                    .iter()
                    .map(|&(t, c)| (self.k_pos[rows.unk[t]], c))
                    .collect(),
                ..*s
            })
            .collect();
        special.extend((0..nk).filter(|&q| !in_system[q]).map(|q| SpecialRow {
            row: q,
            alpha: 1.0,
            beta: 0.0,
            gamma: 0.0,
            col: q,
            combo: Vec::new(),
        }));
        (b, special)
    }

    /// Computes the columns `G = K⁻¹ e_q` of the special rows not computed yet, and with them
    /// (when any is missing) those of up to [`PREFETCH`] positions of `likely` not computed
    /// yet; `None` if `K` is not factorised.
    fn solve_g_columns(&mut self, special: &[SpecialRow], likely: &[usize]) -> Option<()> {
        let mut missing: Vec<usize> = special
            .iter()
            .map(|s| s.row)
            .filter(|&q| self.k_cols[q].is_empty())
            .collect();
        if missing.is_empty() {
            return self.k_llt.as_ref().map(|_| ());
        }
        let mut taken = std::collections::HashSet::<usize>::from_iter(missing.iter().copied());
        missing.extend(
            likely
                .iter()
                .copied()
                .filter(|&q| self.k_cols[q].is_empty() && taken.insert(q))
                .take(PREFETCH),
        );
        self.solve_columns(missing)
    }

    /// Solves for the columns `G = K⁻¹ e_q` at positions `qs` in one solve with several
    /// right-hand sides, and records the batch; `None` if `K` is not factorised.
    fn solve_columns(&mut self, qs: Vec<usize>) -> Option<()> {
        let block = self.k_llt.as_ref()?;
        let nk = self.k_unk.len();
        let mut e = Mat::<f64>::zeros(nk, qs.len());
        for (c, &q) in qs.iter().enumerate() {
            e[(q, c)] = 1.0;
        }
        let q0 = if nk >= TRAILING_FROM {
            qs.iter().copied().min().unwrap_or(nk)
        } else {
            0
        };
        block.solve_in_place_below(&mut e, q0);
        for (c, &q) in qs.iter().enumerate() {
            self.k_cols[q] = e.col(c).iter().copied().collect();
        }
        self.batches.push(qs);
        Some(())
    }

    /// The Woodbury step from `x = x0 = K⁻¹ b`: solves `C y = B x0` and sets `x = x0 − G y`;
    /// returns `y`, or `None` if `C` is near-singular.
    fn woodbury_correction(
        &mut self,
        special: &[SpecialRow],
        b: &[f64],
        x: &mut [f64],
    ) -> Option<Vec<f64>> {
        let p = special.len();
        let (cap, rhs) = self.capacitance_system(special, b, x);
        let reuse = !self.exact && p >= CAPACITANCE_REUSE_FROM;
        let rows: Vec<usize> = special.iter().map(|s| s.row).collect();
        let iterated = match &self.cap_lu {
            Some((r, lu)) if reuse && *r == rows => {
                gmres(&cap, &rhs, lu, 1e-13, GMRES_MAX).map(|(y, its)| {
                    self.gmres_iterations += its;
                    y
                })
            }
            _ => None,
        };
        let y = match iterated {
            Some(y) => y,
            None => {
                let clu = cap.partial_piv_lu();
                // Near-singular (gross sliding, a free direction): the dense system decides.
                if (0..p).any(|i| clu.U()[(i, i)].abs() <= 1e-10) {
                    self.cap_lu = None;
                    return None;
                }
                let y = clu.solve(&rhs);
                self.cap_lu = reuse.then_some((rows, clu));
                y
            }
        };
        let y_cap: Vec<f64> = (0..p).map(|j| y[(j, 0)]).collect();
        for (sj, yj) in special.iter().zip(&y_cap) {
            axpy(x, -yj, &self.k_cols[sj.row]);
        }
        Some(y_cap)
    }

    /// The capacitance system `C y = B x0` (`C = A_P G`, `x0` = `x`), each row scaled by the
    /// size of its terms.
    fn capacitance_system(
        &self,
        special: &[SpecialRow],
        b: &[f64],
        x: &[f64],
    ) -> (Mat<f64>, Mat<f64>) {
        let nk = self.k_unk.len();
        let p = special.len();
        let mut cap = Mat::<f64>::zeros(p, p);
        // Index in `special` of each row of K that is special.
        let mut special_at = vec![None; nk];
        for (i, si) in special.iter().enumerate() {
            special_at[si.row] = Some(i);
        }
        let mut rhs = Mat::<f64>::zeros(p, 1);
        // Size of the terms of each row: C is singular when A is, often by cancellation
        // between large terms (a direction nothing holds), which its own pivots relative
        // to each other do not show; relative to the terms they do.
        let mut size = vec![0.0f64; p];
        // Each special row's (row, col, α, γ) side by side, read p times below.
        let at: Vec<(usize, usize, f64, f64)> = special
            .iter()
            .map(|s| (s.row, s.col, s.alpha, s.gamma))
            .collect();
        for (j, sj) in special.iter().enumerate() {
            let g = &self.k_cols[sj.row];
            let col = cap
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous columns")
                .as_slice_mut();
            for ((c, sz), &(row, other, alpha, gamma)) in col.iter_mut().zip(&mut size).zip(&at) {
                let (t1, t2) = (alpha * g[row], gamma * g[other]);
                *c = t1 + t2;
                *sz = sz.max(t1.abs() + t2.abs());
            }
            if sj.combo.is_empty() {
                cap[(j, j)] += sj.beta;
                rhs[(j, 0)] =
                    sj.alpha * x[sj.row] + sj.gamma * x[sj.col] + (sj.beta - 1.0) * b[sj.row];
            } else {
                // Σ c K_t G = Σ c (E_P)_t: unit entries where t is a special row.
                for &(t, c) in &sj.combo {
                    if let Some(i) = special_at[t] {
                        cap[(j, i)] += c;
                    }
                }
                rhs[(j, 0)] = sj.alpha * x[sj.row]
                    + sj.gamma * x[sj.col]
                    + sj.combo.iter().map(|&(t, c)| c * b[t]).sum::<f64>()
                    - b[sj.row];
            }
        }
        let scale: Vec<f64> = special
            .iter()
            .zip(&size)
            .map(|(si, sz)| {
                let k_part = if si.combo.is_empty() {
                    si.beta.abs()
                } else {
                    si.combo.iter().map(|(_, c)| c.abs()).sum()
                };
                1.0 / (sz + k_part).max(f64::MIN_POSITIVE)
            })
            .collect();
        for j in 0..p {
            let col = cap
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous columns")
                .as_slice_mut();
            for (c, s) in col.iter_mut().zip(&scale) {
                *c *= s;
            }
        }
        for (i, s) in scale.iter().enumerate() {
            rhs[(i, 0)] *= s;
        }
        (cap, rhs)
    }

    /// The unknowns of `rows` (in its order) from the block solution `x`, and `W μ` of the new
    /// iterate (all rows of `W`).
    fn new_w_mu(
        &self,
        w: &Mat<f64>,
        rows: &NewtonRows,
        b: &[f64],
        x: &[f64],
        special: &[SpecialRow],
        y_cap: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        // W μ of the new iterate, for the next iteration's sets: on this system's rows it is
        // what the rows impose, `K x = b − E_P y`, the others are products with W.
        let mut w_mu = vec![0.0; w.nrows()];
        let xs: Vec<f64> = rows.unk.iter().map(|&u| x[self.k_pos[u]]).collect();
        let mut in_unk = vec![false; w.nrows()];
        for &u in &rows.unk {
            in_unk[u] = true;
            w_mu[u] = b[self.k_pos[u]];
        }
        for (sj, yj) in special.iter().zip(y_cap) {
            let u = self.k_unk[sj.row];
            if in_unk[u] {
                w_mu[u] -= yj;
            }
        }
        // Rows outside K: one product with the block W[out, K] kept with the factor, at the
        // iterate (zero on the unknowns of K not in this system). Sequential, so that the
        // sums do not depend on the number of threads.
        let mut xk = vec![0.0; self.k_unk.len()];
        for (&u, &xu) in rows.unk.iter().zip(&xs) {
            xk[self.k_pos[u]] = xu;
        }
        let block = self.k_llt.as_ref().expect("solved with the factor");
        let mut prod = vec![0.0; block.out_rows.len()];
        matvec_replace(&mut prod, block.w_out.as_ref(), &xk);
        for (&p, &i) in prod.iter().zip(&block.out_rows) {
            w_mu[i] = p;
        }
        // Rows of K not in this system (nodes that left the contact): dot products.
        for &i in &self.k_unk {
            if !in_unk[i] {
                let col = w.col(i);
                w_mu[i] = rows.unk.iter().zip(&xs).map(|(&u, xu)| col[u] * xu).sum();
            }
        }
        (xs, w_mu)
    }

    /// Factorises `K = W[unk, unk]` for [`Self::solve_rows`]; `None` if it is singular or not
    /// numerically positive definite.
    ///
    /// With a [`PrefixFactor`] (`prefix`), a set of unknowns that is nearly a leading set of its
    /// order ([`leading_set`]) takes that whole leading set as the block, whose factor is read
    /// from the prefix factor instead of computed; its unknowns not in `unk` become special
    /// rows of the systems (`x_q = 0`), as those that leave the contact do.
    fn factorise_block(
        &mut self,
        w: &Mat<f64>,
        prefix: Option<&Arc<PrefixFactor>>,
        unk: &[usize],
    ) -> Option<()> {
        self.forget_block();
        let lead = prefix.and_then(|pf| leading_set(pf, unk).map(|p| (pf, p)));
        let (unk, block) = match lead {
            Some((pf, p)) => {
                self.prefix_blocks += 1;
                (
                    &pf.order[..p],
                    Block::prefix(w, pf, p, self.shared.is_none()).map(Arc::new),
                )
            }
            None => {
                self.factorisations += 1;
                let block = match &self.shared {
                    Some(store) => store.get(w, unk),
                    None => Block::factorise(w, unk, true).map(Arc::new),
                };
                (unk, block)
            }
        };
        self.largest_block = self.largest_block.max(unk.len());
        let block = block?;
        self.k_pos = vec![usize::MAX; w.nrows()];
        for (q, &u) in unk.iter().enumerate() {
            self.k_pos[u] = q;
        }
        self.k_unk = unk.to_vec();
        self.k_cols = vec![Vec::new(); unk.len()];
        self.k_llt = Some(block);
        Some(())
    }

    /// Solves `A x = b` for the unknowns `unk`: by GMRES preconditioned with the cached LU when
    /// it is for the same unknowns, else (or if GMRES stalls) with a new LU, which is kept.
    /// `None` when the system is singular.
    pub(super) fn solve(&mut self, unk: &[usize], a: &Mat<f64>, b: &Mat<f64>) -> Option<Mat<f64>> {
        if self.unk == unk
            && let Some(lu) = &self.lu
            && let Some((x, its)) = gmres(a, b, lu, 1e-13, GMRES_MAX)
        {
            self.gmres_iterations += its;
            return Some(x);
        }
        let lu = a.partial_piv_lu();
        self.factorisations += 1;
        if singular_pivots(&lu) {
            self.clear();
            return None;
        }
        let x = lu.solve(b);
        self.unk = unk.to_vec();
        self.lu = Some(lu);
        Some(x)
    }
}

/// Right-preconditioned GMRES (no restart) for `A x = b` with preconditioner `M⁻¹` given by an
/// LU of a nearby matrix, from `x0 = M⁻¹ b`. Returns the solution and the iterations, or
/// `None` if the relative residual is not below `tol` within `max_it` iterations.
fn gmres(
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
mod tests {
    use super::*;

    /// A set of unknowns is served by the prefix factor when it fills its leading set but for
    /// at most one in 64, and is large enough.
    #[test]
    fn the_leading_set_of_a_prefix_factor_holds_the_unknowns_with_few_others() {
        let m = 1000;
        let order: Vec<usize> = (0..m).rev().collect();
        let pf = PrefixFactor::new(Mat::zeros(1, 1), order.clone());
        let first = |p: usize| order[..p].to_vec();
        assert_eq!(leading_set(&pf, &first(640)), Some(640));
        // Ten holes in 640: 640 / 64 = 10 allowed; eleven are not.
        let holes = |k: usize| -> Vec<usize> { first(640).into_iter().skip(k).collect() };
        assert_eq!(leading_set(&pf, &holes(10)), Some(640));
        assert_eq!(leading_set(&pf, &holes(11)), None);
        // Too small to be worth it.
        assert_eq!(leading_set(&pf, &first(PREFIX_MIN - 1)), None);
        assert_eq!(leading_set(&pf, &first(PREFIX_MIN)), Some(PREFIX_MIN));
    }

    /// `matvec_replace` gives faer's product bit for bit (the rows of `W` outside a block
    /// times the iterate): shapes whose columns are not a multiple of four and whose rows are
    /// not of the vector width, with zeros of both signs in `x`.
    #[test]
    fn the_product_with_w_out_has_the_bits_of_faers() {
        for (rows, cols) in [(1, 1), (3, 5), (7, 4), (33, 17), (200, 123), (64, 256)] {
            let (w, mut x) = w_and_mu(rows.max(cols));
            x.truncate(cols);
            x[0] = -0.0;
            if cols > 2 {
                x[2] = 0.0;
            }
            let a = w.as_ref().submatrix(0, 0, rows, cols);
            let mut ours = vec![f64::NAN; rows];
            matvec_replace(&mut ours, a, &x);
            let theirs = faer_matvec(a, &x);
            for i in 0..rows {
                assert_eq!(
                    ours[i].to_bits(),
                    theirs[i].to_bits(),
                    "{rows} x {cols}, row {i}"
                );
            }
        }
    }

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

    /// The forward sweep of one right-hand side gives faer's bits: orders that take every
    /// branch of the recursive split (below 8, 8–15, 16–31, 32 and up) and each closed form
    /// (blocks of 1–4 rows), on a trailing block of a larger factor (a leading dimension
    /// larger than the order), with a zero and a negative zero in the right-hand side.
    #[test]
    fn the_forward_sweep_has_the_bits_of_faers() {
        let (w, b0) = w_and_mu(300);
        // A well-conditioned lower triangle: W's lower part with a heavy diagonal.
        let big = Mat::from_fn(300, 300, |i, j| {
            if i == j {
                4.0 + w[(i, j)].abs()
            } else if i > j {
                w[(i, j)]
            } else {
                0.0
            }
        });
        for n in [
            1, 2, 3, 4, 5, 7, 8, 11, 15, 16, 23, 31, 32, 33, 47, 64, 100, 257,
        ] {
            let off = 300 - n;
            let l = big.as_ref().submatrix(off, off, n, n);
            let mut rhs = Mat::from_fn(n, 1, |i, _| b0[i]);
            rhs[(0, 0)] = -0.0;
            if n > 2 {
                rhs[(2, 0)] = 0.0;
            }
            let mut theirs = rhs.clone();
            faer::linalg::triangular_solve::solve_lower_triangular_in_place_with_conj(
                l,
                faer::Conj::No,
                theirs.as_mut(),
                faer::Par::Seq,
            );
            if !forward_one(l, rhs.col_mut(0)) {
                // No AVX2 and FMA here: faer's own runs, nothing to compare.
                return;
            }
            for i in 0..n {
                assert_eq!(
                    rhs[(i, 0)].to_bits(),
                    theirs[(i, 0)].to_bits(),
                    "order {n}, row {i}"
                );
            }
        }
    }

    /// A symmetric `m × m` matrix and a vector of forces, both from a fixed sequence.
    fn w_and_mu(m: usize) -> (Mat<f64>, Vec<f64>) {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = move || {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let a = Mat::from_fn(m, m, |_, _| r());
        let w = Mat::from_fn(m, m, |i, j| a[(i, j)] + a[(j, i)]);
        (w, (0..m).map(|_| r()).collect())
    }

    fn product(w: &Mat<f64>, mu: &[f64]) -> Vec<f64> {
        (0..w.nrows())
            .map(|i| (0..mu.len()).map(|j| w[(i, j)] * mu[j]).sum())
            .collect()
    }

    /// A block factorised on rayon's threads has the bits of the sequential factorisation, in
    /// pools of 2, 3 and 4 threads, at sizes that cross faer's blocking thresholds, with a
    /// subset of the unknowns (so the copy gathers rows and columns) and the rows outside.
    #[test]
    fn the_block_factor_has_the_same_bits_on_any_number_of_threads() {
        for n in [60usize, 700, 1300] {
            let (a, _) = w_and_mu(n);
            let mut w = &a * &a;
            for i in 0..n {
                w[(i, i)] += 1.0;
            }
            let unk: Vec<usize> = (0..n).filter(|i| i % 7 != 3).rev().collect();
            let seq = Block::factorise(&w, &unk, false).expect("positive definite");
            for threads in [2, 3, 4] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("a pool");
                let par = pool
                    .install(|| Block::factorise(&w, &unk, true))
                    .expect("positive definite");
                let (ls, lp) = (seq.l(), par.l());
                for j in 0..unk.len() {
                    for i in j..unk.len() {
                        assert_eq!(ls[(i, j)].to_bits(), lp[(i, j)].to_bits(), "n {n}");
                    }
                }
                assert_eq!(seq.out_rows, par.out_rows);
                assert_eq!(seq.w_out, par.w_out);
            }
        }
    }

    /// Columns of the identity solved with the forward sweep on the trailing block only (from
    /// the first column's position) are `K⁻¹ e_q` as the whole solve gives them, to round-off,
    /// and checked against `K` itself; from position 0 it is the whole solve, bit for bit.
    #[test]
    fn unit_columns_solved_below_their_first_row_are_the_columns_of_the_inverse() {
        let n = 300;
        let (a, _) = w_and_mu(n);
        // Symmetric positive definite: A² plus a multiple of the identity.
        let mut w = &a * &a;
        for i in 0..n {
            w[(i, i)] += 1.0;
        }
        let unk: Vec<usize> = (0..n).collect();
        let block = Block::factorise(&w, &unk, false).expect("positive definite");
        let qs = [180usize, 211, 250, 299];
        let unit = || {
            let mut e = Mat::<f64>::zeros(n, qs.len());
            for (c, &q) in qs.iter().enumerate() {
                e[(q, c)] = 1.0;
            }
            e
        };
        let (mut whole, mut below, mut from0) = (unit(), unit(), unit());
        block.solve_in_place(&mut whole);
        block.solve_in_place_below(&mut below, 180);
        block.solve_in_place_below(&mut from0, 0);
        let scale = (0..n).fold(0.0f64, |m, i| m.max(whole[(i, 0)].abs()));
        for c in 0..qs.len() {
            for i in 0..n {
                assert_eq!(whole[(i, c)].to_bits(), from0[(i, c)].to_bits());
                assert!((whole[(i, c)] - below[(i, c)]).abs() <= 1e-12 * scale);
            }
            // K g = e_q.
            for i in 0..n {
                let r: f64 = (0..n).map(|j| w[(i, j)] * below[(j, c)]).sum();
                let e = if i == qs[c] { 1.0 } else { 0.0 };
                assert!((r - e).abs() <= 1e-9, "row {i} of K g_{}: {r}", qs[c]);
            }
        }
    }

    #[test]
    fn recalled_products_are_those_of_the_predicted_forces_and_refused_otherwise() {
        let m = 40;
        let (w, mu0) = w_and_mu(m);
        let mu1: Vec<f64> = mu0.iter().map(|v| 1.1 * v + 0.05).collect();
        let mut cache = LuCache::default();
        // Nothing kept: no recall.
        assert!(cache.recall_w_mu(&mu1, &w).is_none());
        cache.remember_w_mu(mu0.clone(), product(&w, &mu0));
        cache.remember_w_mu(mu1.clone(), product(&w, &mu1));
        // The last converged forces themselves: their product as kept.
        assert_eq!(cache.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
        // The predictor's start, with the first three entries clipped to zero.
        let t = 0.75;
        let mut mu: Vec<f64> = mu1.iter().zip(&mu0).map(|(a, b)| a + t * (a - b)).collect();
        mu[..3].iter_mut().for_each(|v| *v = 0.0);
        // Without the announced factor it is not recognised.
        assert!(cache.recall_w_mu(&mu, &w).is_none());
        cache.predict_with(Some(t));
        let got = cache.recall_w_mu(&mu, &w).expect("recalled");
        let want = product(&w, &mu);
        let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (g, x) in got.iter().zip(&want) {
            assert!((g - x).abs() <= 1e-13 * scale, "{g} against {x}");
        }
        // The factor is used once.
        assert!(cache.recall_w_mu(&mu, &w).is_none());
        // Forces off the prediction in more than an eighth of the entries: not recalled.
        let mut off = mu.clone();
        off[..m / 8 + 1].iter_mut().for_each(|v| *v += 1e-3);
        cache.predict_with(Some(t));
        assert!(cache.recall_w_mu(&off, &w).is_none());
        // A checkpoint records them and a replay of the record restores them: a resumed run
        // recalls what the uninterrupted one does.
        let rec = cache.checkpoint().expect("products kept");
        let mut resumed = LuCache::default();
        assert!(resumed.replay(&w, None, &rec));
        assert_eq!(resumed.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
        // A step's end keeps them too.
        cache.end_step();
        assert_eq!(cache.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
    }
}
