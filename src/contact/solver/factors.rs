//! The linear algebra of the contact iteration: the Cholesky factor of a Delassus block with
//! Sherman–Morrison–Woodbury updates for the rows that differ from it, and the LU of a dense
//! Newton matrix reused as a GMRES preconditioner.

use super::block::{Block, BlockRecord, BlockStore, TRAILING_FROM, leading_set};
use super::enforce::{NewtonRows, SpecialRow};
use super::system::PrefixFactor;
use crate::la::dense::{add_columns, axpy, gmres, matvec_replace, singular_pivots};
use faer::Mat;
use faer::linalg::solvers::Solve;
use std::sync::Arc;
use std::time::Instant;

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
