//! A numeric factorisation of the contact saddle-point matrix: its solves with `K̂` and its
//! Delassus operator `W`.

use super::layout::{Node, Supernodes, sweep_columns};
use crate::la::base::FactorError;
use crate::la::dense::copy_trailing;
use crate::la::par::{SharedMat, TILE, factor_parallelism, for_tiles_below, mat_filled};
use crate::la::values::SharedValues;

/// A numeric `L D Lᵀ` factorisation of a saddle-point matrix (see [`SaddleSymbolic`]).
pub struct SaddleFactor {
    pub(super) layout: std::sync::Arc<Supernodes>,
    /// The factor's values, shared with a model-cache writer ([`crate::cache`]); `None` once
    /// released ([`Self::release`]).
    pub(super) values: std::sync::Mutex<Option<SharedValues>>,
    pub(super) n: usize,
    pub(super) m: usize,
    /// Per supernode with columns of `K̂`, the supernode, its columns of `K̂` and its pattern
    /// rows of `K̂` (the solves' plan, found at the first solve: 0.5 ms per solve on L5).
    pub(super) plan: std::sync::OnceLock<Vec<(usize, usize, usize)>>,
    /// `W = Y K̂⁻¹ Yᵀ` (its lower triangle) as the factorisation found it, the Schur
    /// complement of the constraint block, until [`Self::delassus`] takes it.
    pub(super) schur: std::sync::Mutex<Option<faer::Mat<f64>>>,
    /// Wall time of the constraint block within the numeric factorisation (its updates, the
    /// elimination of the top separator's columns from it and its `L D Lᵀ`), seconds; zero
    /// where it was not timed apart (faer's loop, a factor from the model cache).
    pub constraint_block_s: f64,
}

impl SaddleFactor {
    /// The factorisation of a saddle-point matrix with `n` free DOFs and `m` constraint rows
    /// from its supernodal layout and values (a model-cache hit: no symbolic analysis).
    pub fn from_layout(
        layout: std::sync::Arc<Supernodes>,
        values: SharedValues,
        n: usize,
        m: usize,
    ) -> Result<SaddleFactor, FactorError> {
        if values.len() != layout.len_val() {
            return Err(FactorError::FactorLength {
                len: values.len(),
                expected: layout.len_val(),
            });
        }
        Ok(SaddleFactor {
            layout,
            values: std::sync::Mutex::new(Some(values)),
            n,
            m,
            plan: std::sync::OnceLock::new(),
            schur: std::sync::Mutex::new(None),
            constraint_block_s: 0.0,
        })
    }

    /// The supernodal layout (shared, not copied).
    pub fn layout(&self) -> std::sync::Arc<Supernodes> {
        self.layout.clone()
    }

    /// The values of the factor (shared, not copied).
    ///
    /// # Panics
    /// Once the values are released ([`Self::release`]).
    pub fn values(&self) -> SharedValues {
        self.values
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
            .expect("a saddle factor's values used after their release")
    }

    /// Gives up this factor's hold on its values: once the solves that started before have
    /// ended (and a model-cache writer has written them), the memory can be freed, on the
    /// caller's schedule, while the rest of the model is still in use (a run releases the
    /// factor once its last field is recovered, so that freeing hundreds of MB overlaps the
    /// output and the summary instead of following them). Any later solve panics.
    pub fn release(&self) -> Option<SharedValues> {
        self.values.lock().unwrap_or_else(|p| p.into_inner()).take()
    }

    /// Order of `K̂`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Solves `K̂ X = B` in place for a column-major block of `ncols` right-hand sides: the
    /// sweeps of the leading block of the factor only, the columns split over rayon's threads.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        self.solve_block(b, ncols, true);
    }

    /// As [`Self::solve_block_in_place`] in one sweep on the calling thread, which reads the
    /// factor once for all the columns (the output writer's recoveries: two columns cost 1.3
    /// times one on L7, `examples/recovery_timing`, where two threads would read it twice and
    /// take the core the contact solve runs on). The same bits.
    pub fn solve_block_in_place_one_sweep(&self, b: &mut [f64], ncols: usize) {
        self.solve_block(b, ncols, false);
    }

    fn solve_block(&self, b: &mut [f64], ncols: usize, split: bool) {
        let (n, m) = (self.n, self.m);
        let size = n + m;
        if n == 0 || ncols == 0 {
            return;
        }
        let values = self.values();
        let fwd = &self.layout.fwd;
        // Permuted copy, constraint rows zero (they are never read below).
        let mut x = vec![0.0; size * ncols];
        for j in 0..ncols {
            for i in 0..n {
                x[j * size + i] = b[j * n + fwd[i]];
            }
        }
        let nodes = self.leading_nodes(&values);
        // Each column sees the same operations in the same order whether it is solved alone
        // or with others, on any thread: the columns are split over the threads in groups of
        // up to eight, each group one read of the factor with its columns interleaved
        // (`sweep_columns`). Fewer columns stay together on this thread: two interleaved cost
        // 18 ms on L5 against 14 ms for one alone (`examples/recovery_timing`), where two
        // threads with one each read the factor twice, both memory-bound, and take the core
        // that the other preparations of the end of a run need.
        let threads = if split {
            rayon::current_num_threads().clamp(1, ncols.div_ceil(8).max(1))
        } else {
            1
        };
        let per = ncols.div_ceil(threads).max(1);
        if threads > 1 {
            use rayon::prelude::*;
            x.par_chunks_mut(size * per)
                .for_each(|cols| sweep_columns(&nodes, cols, size));
        } else {
            sweep_columns(&nodes, &mut x, size);
        }
        // Back in the original order (`fwd` maps the first n positions onto the free DOFs).
        for j in 0..ncols {
            for i in 0..n {
                b[j * n + fwd[i]] = x[j * size + i];
            }
        }
    }

    /// Per supernode of K: its first column, the columns of K in it, the pattern rows of K
    /// (the constraint rows come last in every pattern) and its `values`.
    pub(super) fn leading_nodes<'a>(
        &'a self,
        values: &'a [f64],
    ) -> Vec<(usize, usize, usize, Node<'a>)> {
        let n = self.n;
        let plan = self.plan.get_or_init(|| {
            (0..self.layout.n_supernodes())
                .map(|s| (s, self.layout.node(s, values)))
                .take_while(|(_, node)| node.start < n)
                .map(|(s, node)| {
                    let kp = node.pattern.partition_point(|&r| r < n);
                    (s, node.ncols.min(n - node.start), kp)
                })
                .collect()
        });
        plan.iter()
            .map(|&(s, wk, kp)| {
                let node = self.layout.node(s, values);
                (node.start, wk, kp, node)
            })
            .collect()
    }

    /// Solves `K̂ x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_block_in_place(b, 1);
    }

    /// The Delassus operator `W = Y K̂⁻¹ Yᵀ = −L_MM D_MM L_MMᵀ` (dense, `m × m`, in the order
    /// of the constraint rows), or `None` when a pivot of the constraint block is not negative
    /// (`Y` is rank-deficient, or `W` is too ill-conditioned for the unpivoted factorisation
    /// to be trusted). With `keep_factor`, also `C = L_MM (−D_MM)^½`, a lower Cholesky factor
    /// of `W` (`W = C Cᵀ`, its strictly upper part zero): the leading `p × p` block of `C` is
    /// the Cholesky factor of the leading block `W[..p, ..p]`, for every `p`, with no
    /// factorisation (see `contact::PrefixFactor`).
    pub fn delassus(&self, keep_factor: bool) -> Option<(faer::Mat<f64>, Option<faer::Mat<f64>>)> {
        use faer::linalg::matmul::triangular::{BlockStructure, matmul};
        let m = self.m;
        let schur = self.schur.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(mut w) = schur {
            // W as the factorisation found it (its lower triangle): no product.
            let values = self.values();
            if !negative_pivots(&self.d_mm(&values)) {
                return None;
            }
            let ws = SharedMat::of(&mut w);
            // SAFETY: (j, i) is above the diagonal in this task's rows, (i, j) below it in
            // its columns: no task writes what another reads or writes.
            for_tiles_below(m, |i, j| unsafe { ws.set(j, i, ws.get(i, j)) });
            crate::trace::mark("delassus: from the factorisation");
            if !keep_factor {
                return Some((w, None));
            }
            // The factorisation copies W only where the constraint columns end the root.
            let c = self
                .c_from_root(&values)
                .expect("W copied from the root supernode");
            return Some((w, Some(c)));
        }
        let mut l = self.l_mm();
        crate::trace::mark("delassus: L_MM gathered");
        if !negative_pivots(&(0..m).map(|i| l[(i, i)]).collect::<Vec<_>>()) {
            return None;
        }
        // One array holds both operands of W = −B Lᵀ: B = L D in its lower half (D on the
        // diagonal) and Lᵀ in its strict upper half, which the product reads as unit upper
        // triangular (a copy of L for B would cost another m × m array: 130 MB at L7). On
        // rayon's threads: 3.9 → 2.4 ms on L5 (medians of 8 runs) against a loop by columns on
        // one thread.
        let ls = SharedMat::of(&mut l);
        for_tiles_below(m, |i, j| {
            // SAFETY: (i, j) is below the diagonal in this task's columns, (j, i) above it in
            // its rows, and no task writes the diagonal.
            unsafe {
                let v = ls.get(i, j);
                ls.set(j, i, v);
                ls.set(i, j, v * ls.get(j, j));
            }
        });
        crate::trace::mark("delassus: L D");
        let mut w = faer::Mat::zeros(m, m);
        matmul(
            w.as_mut(),
            BlockStructure::TriangularLower,
            faer::Accum::Replace,
            l.as_ref(),
            BlockStructure::TriangularLower,
            l.as_ref(),
            BlockStructure::UnitTriangularUpper,
            -1.0,
            factor_parallelism(),
        );
        crate::trace::mark("delassus: product");
        // The upper half from the lower.
        let ws = SharedMat::of(&mut w);
        // SAFETY: (j, i) is above the diagonal in this task's rows, (i, j) below it in its
        // columns: no task writes what another reads or writes.
        for_tiles_below(m, |i, j| unsafe { ws.set(j, i, ws.get(i, j)) });
        crate::trace::mark("delassus: symmetric");
        if !keep_factor {
            return Some((w, None));
        }
        Some((w, Some(cholesky_of_w(l))))
    }

    /// `L_MM` (dense, lower) with `D_MM` on its diagonal, from the constraint columns'
    /// supernodes.
    fn l_mm(&self) -> faer::Mat<f64> {
        let (n, m) = (self.n, self.m);
        let values = self.values();
        let mut l = faer::Mat::zeros(m, m);
        for s in 0..self.layout.n_supernodes() {
            let node = self.layout.node(s, &values);
            copy_trailing(&mut l, n, node.start, node.ncols, node.pattern, |i, j| {
                node.at(i, j)
            });
        }
        l
    }

    /// `C = L_MM (−D_MM)^½` (lower, as [`cholesky_of_w`] gives it, the same bits) read
    /// straight from the last supernode when it holds every constraint column (as on every
    /// mesh of the ladder), else `None`.
    fn c_from_root(&self, values: &[f64]) -> Option<faer::Mat<f64>> {
        let (n, m) = (self.n, self.m);
        let node = self
            .layout
            .node(self.layout.n_supernodes().checked_sub(1)?, values);
        if node.start > n || !node.pattern.is_empty() || node.start + node.ncols != n + m {
            return None;
        }
        let kk = n - node.start;
        Some(mat_filled(m, m, true, |j, col| {
            let sj = (-node.at(kk + j, kk + j)).sqrt();
            col[j] = sj;
            for i in j + 1..m {
                col[i] = node.at(kk + i, kk + j) * sj;
            }
        }))
    }

    /// `D_MM`, the pivots of the constraint columns.
    fn d_mm(&self, values: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut d = Vec::with_capacity(self.m);
        for s in 0..self.layout.n_supernodes() {
            let node = self.layout.node(s, values);
            for j in 0..node.ncols {
                if node.start + j >= n {
                    d.push(node.at(j, j));
                }
            }
        }
        d
    }
}

/// Whether the constraint block's pivots `d` are all negative to working precision (`W`
/// positive definite, `Y` of full row rank).
fn negative_pivots(d: &[f64]) -> bool {
    let dmax = d.iter().map(|x| x.abs()).fold(0.0, f64::max);
    d.iter()
        .all(|x| x.partial_cmp(&(-1e-13 * dmax)) == Some(std::cmp::Ordering::Less))
}

/// `C = L_MM (−D_MM)^½` from `l`, which holds `D_MM` on its diagonal and `L_MMᵀ` (unit
/// diagonal) in its strict upper half: a lower Cholesky factor of `W`.
fn cholesky_of_w(mut l: faer::Mat<f64>) -> faer::Mat<f64> {
    let m = l.nrows();
    // C from the same array: column j of L (unit diagonal) is the strict upper half's row
    // j, scaled by (−d_j)^½; the strict upper half is cleared.
    let s: Vec<f64> = (0..m).map(|j| (-l[(j, j)]).sqrt()).collect();
    let ls = SharedMat::of(&mut l);
    // SAFETY: (i, j) is below the diagonal in this task's columns, (j, i) above it in its
    // rows: no task writes what another reads or writes.
    for_tiles_below(m, |i, j| unsafe { ls.set(i, j, ls.get(j, i) * s[j]) });
    for (j, &sj) in s.iter().enumerate() {
        l[(j, j)] = sj;
    }
    {
        use rayon::prelude::*;
        l.par_col_chunks_mut(TILE)
            .enumerate()
            .for_each(|(b, cols)| {
                let mut cols = cols;
                for c in 0..cols.ncols() {
                    let j = b * TILE + c;
                    for i in 0..j {
                        cols[(i, c)] = 0.0;
                    }
                }
            });
    }
    l
}
