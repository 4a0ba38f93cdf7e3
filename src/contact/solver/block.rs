//! A factorised Delassus block `K = W[unk, unk]` and the store that shares blocks between the
//! runs of one model.

use super::system::PrefixFactor;
use faer::Mat;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor as llt_factor;
use std::sync::Arc;

/// A factorised Delassus block `K = W[unk, unk]`: its Cholesky factor, and the rows of `W`
/// outside it with `W[out_rows, unk]`, contiguous for the product of every iteration.
pub struct Block {
    /// The lower Cholesky factor `L` of `K = L Lᵀ` (its strictly upper part is zero).
    l: BlockFactor,
    pub(super) out_rows: Vec<usize>,
    pub(super) w_out: Mat<f64>,
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
pub(super) const PREFIX_MIN: usize = 256;

/// The length `p` of the leading set of `pf`'s order that holds the unknowns `unk` (distinct
/// μ indices), if it holds few others: at most `p / 64`, the share of unknowns not in the
/// system at which [`LuCache::solve_rows`] refactorises at a new step (each costs a special
/// row, a column of `G` and a row of every capacitance system).
pub(super) fn leading_set(pf: &PrefixFactor, unk: &[usize]) -> Option<usize> {
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
    pub(super) fn prefix(
        w: &Mat<f64>,
        pf: &Arc<PrefixFactor>,
        p: usize,
        parallel: bool,
    ) -> Option<Block> {
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
    pub(super) fn l(&self) -> faer::MatRef<'_, f64> {
        match &self.l {
            BlockFactor::Owned(l) => l.as_ref(),
            BlockFactor::Prefix(pf, p) => pf.c.as_ref().submatrix(0, 0, *p, *p),
        }
    }

    /// Factorises `W[unk, unk]`; `None` if it is singular or not numerically positive definite.
    ///
    /// `parallel`: copy and factorise on rayon's threads. faer's blocked Cholesky
    /// splits the products of its updates by their output, never a sum, so the factor has the
    /// same bits on any number of threads
    /// (`the_block_factor_has_the_same_bits_on_any_number_of_threads`).
    /// Not within a [`BlockStore`]: a rayon worker waiting there for a parallel factorisation
    /// could take up another task that waits on this very block.
    pub(super) fn factorise(w: &Mat<f64>, unk: &[usize], parallel: bool) -> Option<Block> {
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
        let par = if parallel {
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
    pub(super) fn solve_in_place(&self, b: &mut Mat<f64>) {
        self.solve_in_place_below(b, 0);
    }

    /// [`Self::solve_in_place`] for right-hand sides that are zero above row `q0` (columns of
    /// the identity): the forward sweep `L y = b` leaves those rows zero, so it runs on the
    /// trailing block `L[q0.., q0..]` alone (`q0 = 0`: the whole solve). The columns of `G` are
    /// those of slip rows, which (ordered by initial gap, or tangential after normal) sit late
    /// in the block: on Fig. 2 at L7 this takes most of the forward half of their cost.
    pub(super) fn solve_in_place_below(&self, b: &mut Mat<f64>, q0: usize) {
        use faer::linalg::triangular_solve as tri;
        let par = faer::Par::Seq;
        let l = self.l();
        let n = l.nrows();
        let q0 = q0.min(n);
        let lower = l.submatrix(q0, q0, n - q0, n - q0);
        tri::solve_lower_triangular_in_place_with_conj(
            lower,
            faer::Conj::No,
            b.as_mut().subrows_mut(q0, n - q0),
            par,
        );
        tri::solve_upper_triangular_in_place_with_conj(
            l.transpose(),
            faer::Conj::Yes,
            b.as_mut(),
            par,
        );
    }
}

/// Block unknowns from which the columns of `G` skip the zero rows of the forward sweep
/// ([`Block::solve_in_place_below`]). Below, the columns cost little (5 ms in all on Fig. 2 at
/// L5), and the rounding of the whole solve is kept: on L4 the slip-controlled start of
/// `cases/fig2_softening.json`, which crosses the ramp's kink, took five cutbacks instead of
/// none with columns that differed from it by round-off (1e-12 relative) — a step that close
/// to cycling is decided by the last bits.
pub(super) const TRAILING_FROM: usize = 1024;

/// Whether the pivots `L_ii²` of a Cholesky factor are usable: as for an LU, singular when the
/// smallest is below 1e-12 of the largest; and pivots within 2^52 of the smallest normal number
/// have lost digits to underflow (absurd moduli make W that small).
pub(super) fn pivots_ok(pivots: &[f64]) -> bool {
    let lo = pivots.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = pivots.iter().copied().fold(0.0, f64::max);
    !(lo <= 1e-12 * hi || lo < f64::MIN_POSITIVE / f64::EPSILON)
}

/// The rows of `w` outside the unknowns `unk`, and `W[out_rows, unk]`.
pub(super) fn outside(w: &Mat<f64>, unk: &[usize], parallel: bool) -> (Vec<usize>, Mat<f64>) {
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
    pub(super) fn get(&self, w: &Mat<f64>, unk: &[usize]) -> Option<Arc<Block>> {
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
