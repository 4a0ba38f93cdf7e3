//! The supernodal layout of a saddle factor and the triangular sweeps that solve with it.

use crate::la::base::{FactorError, supernodal};

/// The supernodal layout of a saddle factor, which its solves and its Delassus operator read:
/// copied out of faer's symbolic analysis, or restored from the model cache (so that a cache hit
/// needs no symbolic analysis). Supernode `s` has the columns `begin[s]..begin[s + 1]`, the
/// off-diagonal rows `rows[row_ptr[s]..row_ptr[s + 1]]` (ascending) and its values at
/// `val_ptr[s]..val_ptr[s + 1]` of the factor's values, column-major with its columns' rows
/// then the off-diagonal rows (the diagonal block holds `D` on its diagonal under a unit
/// lower triangle). `fwd[new] = old` is the ordering of the saddle-point matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Supernodes {
    pub begin: Vec<usize>,
    pub row_ptr: Vec<usize>,
    pub rows: Vec<usize>,
    pub val_ptr: Vec<usize>,
    pub fwd: Vec<usize>,
}

/// One supernode of a [`Supernodes`] layout with its values.
pub(super) struct Node<'a> {
    pub(super) start: usize,
    pub(super) ncols: usize,
    pub(super) nrows: usize,
    pub(super) pattern: &'a [usize],
    pub(super) val: &'a [f64],
}

impl Node<'_> {
    /// Column `c` (all `nrows` rows).
    pub(super) fn col(&self, c: usize) -> &[f64] {
        &self.val[c * self.nrows..(c + 1) * self.nrows]
    }

    pub(super) fn at(&self, i: usize, j: usize) -> f64 {
        self.val[j * self.nrows + i]
    }
}

impl Supernodes {
    /// The layout of a supernodal symbolic analysis with a custom ordering.
    pub(super) fn of(
        s: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    ) -> Result<Supernodes, FactorError> {
        let sn = supernodal(s)?;
        let nsup = sn.n_supernodes();
        let mut begin = sn.supernode_begin().to_vec();
        begin.push(sn.supernode_end().last().copied().unwrap_or(0));
        let mut row_ptr = Vec::with_capacity(nsup + 1);
        let mut rows = Vec::new();
        row_ptr.push(0);
        for k in 0..nsup {
            rows.extend_from_slice(sn.supernode(k).pattern());
            row_ptr.push(rows.len());
        }
        let fwd = s.perm().expect("custom ordering").arrays().0.to_vec();
        Ok(Supernodes {
            begin,
            row_ptr,
            rows,
            val_ptr: sn.col_ptr_for_val().to_vec(),
            fwd,
        })
    }

    pub(super) fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    /// Length of the factor's values.
    pub fn len_val(&self) -> usize {
        self.val_ptr.last().copied().unwrap_or(0)
    }

    /// Supernode `s` with the factor's `values`.
    pub(super) fn node<'a>(&'a self, s: usize, values: &'a [f64]) -> Node<'a> {
        let (start, end) = (self.begin[s], self.begin[s + 1]);
        let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
        Node {
            start,
            ncols: end - start,
            nrows: end - start + pattern.len(),
            pattern,
            val: &values[self.val_ptr[s]..self.val_ptr[s + 1]],
        }
    }

    /// `Err` with what is wrong if this is not the layout of a saddle factor with `n` free DOFs
    /// and `m` constraint rows (supernodes that tile `0..n + m`, value ranges that fit their
    /// shapes, ascending
    /// off-diagonal rows below each supernode, an ordering that is a permutation with the free
    /// DOFs first); the length of the values is checked against [`Self::len_val`] by
    /// [`SaddleFactor::from_layout`], whose layout must pass this.
    pub fn check(&self, n: usize, m: usize) -> Result<(), String> {
        let size = n + m;
        let nsup = self.begin.len().saturating_sub(1);
        if self.begin.last() != Some(&size) {
            return Err("supernodes do not tile the columns".into());
        }
        if self.begin.first() != Some(&0) || self.begin.windows(2).any(|w| w[0] >= w[1]) {
            return Err("supernodes do not tile the columns".into());
        }
        if self.row_ptr.len() != nsup + 1
            || self.val_ptr.len() != nsup + 1
            || self.row_ptr[0] != 0
            || self.val_ptr[0] != 0
            || self.row_ptr[nsup] != self.rows.len()
        {
            return Err("supernode pointers".into());
        }
        for s in 0..nsup {
            let pattern = self
                .rows
                .get(self.row_ptr[s]..self.row_ptr[s + 1])
                .ok_or("supernode pointers")?;
            let ncols = self.begin[s + 1] - self.begin[s];
            if self.val_ptr[s + 1].checked_sub(self.val_ptr[s])
                != Some((ncols + pattern.len()) * ncols)
            {
                return Err("supernode values".into());
            }
            if pattern.first().is_some_and(|&r| r < self.begin[s + 1])
                || pattern.last().is_some_and(|&r| r >= size)
                || pattern.windows(2).any(|w| w[0] >= w[1])
            {
                return Err("supernode rows".into());
            }
        }
        let mut seen = vec![false; size];
        if self.fwd.len() != size
            || !self.fwd.iter().enumerate().all(|(k, &i)| {
                (i < n) == (k < n) && i < size && !std::mem::replace(&mut seen[i], true)
            })
        {
            return Err("ordering".into());
        }
        Ok(())
    }
}

/// `Σ a_i b_i` in four interleaved partial sums (which the compiler vectorises).
#[inline(always)]
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Asks for the cache lines of `v`, to be read once (a hint: no effect on results).
///
/// Non-temporal (`NTA`): the recovery sweeps stream the factor's 132 MB (L5) through the
/// caches while the contact Newton, on the other core, works on a Delassus operator and block
/// factor of a few MB that otherwise lose their place in the shared L3 to it. With `T0`
/// against `NTA` (a switch in a build not kept, the same binary in alternating runs of
/// `benches/ab.sh`, Fig. 2 on L5): wall − floor 0.282 → 0.266 s (`cold`, 14 pairs) and 0.311
/// → 0.294 s (`first`, 16 pairs); the sweep alone unchanged (`examples/recovery_timing`,
/// 18–20 ms for one column either way); L7 `cold` 1.427 against 1.422 (4 pairs).
///
/// From the last line to the first: the backward sweep goes down the factor's memory, and
/// requests that go down with it all the way (not up within each supernode) let the
/// processor's own stream prefetch follow. The backward loop alone on L5 (a scratch program
/// timing it on the factor of Fig. 2, not kept): 12.4–13.0 ms with the lines requested
/// upwards, 10.8–10.9 ms downwards with the pattern-row sums first (below); a plain read of
/// the same bytes, supernodes from the last, 9.6–10.0 ms going up within each and 4.3 ms
/// going down throughout.
#[inline(always)]
pub(super) fn prefetch(v: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for line in v.chunks(8).rev() {
        // SAFETY: a prefetch reads nothing and cannot fault; the address is in `v`.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_NTA }>(
                line.as_ptr().cast(),
            )
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

/// The downward prefetch of the backward sweeps (see [`sweep_leading_body`]): the values of the
/// supernodes solved next, requested up to 8 KB below the one being solved.
pub(super) struct Ahead {
    /// The first supernode requested so far.
    next: usize,
    /// Bytes requested below the supernode being solved.
    fetched: usize,
}

impl Ahead {
    const BYTES: usize = 8 << 10;

    pub(super) fn new(nsup: usize) -> Ahead {
        Ahead {
            next: nsup,
            fetched: 0,
        }
    }

    /// Supernode `i` (of `nodes`, going down) is solved next: requests what follows it.
    #[inline(always)]
    pub(super) fn at(&mut self, nodes: &[(usize, usize, usize, Node<'_>)], i: usize) {
        let bytes = |(_, wk, _, node): &(usize, usize, usize, Node<'_>)| wk * node.nrows * 8;
        if self.next > i {
            (self.next, self.fetched) = (i, 0);
        } else {
            self.fetched -= bytes(&nodes[i]);
        }
        while self.next > 0 && self.fetched < Self::BYTES {
            self.next -= 1;
            let (_, wk, _, next) = &nodes[self.next];
            prefetch(&next.val[..wk * next.nrows]);
            self.fetched += bytes(&nodes[self.next]);
        }
    }
}

/// The forward, diagonal and backward sweeps of `K̂ X = B` with the leading block of a saddle
/// factor (`nodes`: per supernode of K its first column, its columns of K, the pattern rows of
/// K and its values), in place on the permuted columns `x` of length `size` each.
pub(super) fn sweep_leading(nodes: &[(usize, usize, usize, Node<'_>)], x: &mut [f64], size: usize) {
    sweep_leading_body(nodes, x, size)
}

#[inline(always)]
pub(super) fn sweep_leading_body(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [f64],
    size: usize,
) {
    // Each supernode is read once for all the columns (the factor is tens to hundreds of MB
    // and the sweeps are memory-bound); each column sees the same operations in the same
    // order as when it is solved alone.
    let mut t = Vec::new();
    // Forward: L_KK y = b; the off-diagonal rows of a supernode are gathered into `t` and
    // scattered once.
    for (start, wk, kp, node) in nodes {
        let (pat, w) = (&node.pattern[..*kp], node.ncols);
        for x in x.chunks_exact_mut(size) {
            // A supernode whose entries are all zero changes nothing (the right-hand sides of
            // recoveries are zero outside the retained DOFs, and so stay most supernodes).
            if x[*start..start + wk].iter().all(|&v| v == 0.0) {
                continue;
            }
            t.clear();
            t.resize(*kp, 0.0);
            for c in 0..*wk {
                let xc = x[start + c];
                if xc == 0.0 {
                    continue;
                }
                let col = node.col(c);
                for r in c + 1..*wk {
                    x[start + r] -= col[r] * xc;
                }
                for (tk, lk) in t.iter_mut().zip(&col[w..w + kp]) {
                    *tk += lk * xc;
                }
            }
            for (&row, tk) in pat.iter().zip(&t) {
                x[row] -= tk;
            }
        }
    }
    // D and backward: x = L_KK⁻ᵀ D⁻¹ y, supernode by supernode from the last; the pattern's
    // values gathered into `t` once. Each entry is divided by its pivot just before its own
    // column is read (a pass of its own over the diagonals cost a cache miss per column).
    // The values of the supernodes solved next are requested 8 KB ahead: the sweep goes down
    // the factor's memory, a few KB per supernode, and the hardware's prefetch does not follow
    // it from one supernode to the one before (without: 17.4 ms for this loop on L5, with:
    // 11.6 ms; [`Ahead`]). Within a supernode the sums over its pattern rows (most of its
    // values) are formed first, column after column in memory order, and the dependent
    // diagonal-block sums after: one column's recovery 17.4 → 15.2 ms on L5 with the
    // downward prefetch (`examples/recovery_timing`, five alternating runs each). The same
    // operations on each entry, so the same bits.
    let mut ahead = Ahead::new(nodes.len());
    let mut below = Vec::new();
    for (i, (start, wk, kp, node)) in nodes.iter().enumerate().rev() {
        let (pat, w) = (&node.pattern[..*kp], node.ncols);
        ahead.at(nodes, i);
        for x in x.chunks_exact_mut(size) {
            // Gather the pattern rows of this column, then the dot products with them.
            t.clear();
            for &row in pat {
                t.push(x[row]);
            }
            // The sums over the pattern rows first, from the first column (the supernode's
            // memory in order), then the diagonal block's, which depend on the columns after.
            below.clear();
            for c in 0..*wk {
                below.push(dot(&node.col(c)[w..w + kp], &t));
            }
            for c in (0..*wk).rev() {
                let col = node.col(c);
                // Both sums as (vectorised) dot products: the one over the diagonal block
                // was a chain of dependent scalar updates, most of the sweep's time.
                let mut acc = x[start + c] / col[c];
                acc -= dot(&col[c + 1..*wk], &x[start + c + 1..start + wk]);
                acc -= below[c];
                x[start + c] = acc;
            }
        }
    }
}

/// [`sweep_leading`] of `R` columns at once, interleaved (`x[i][j]`: entry `i` of column `j`):
/// the gathers and scatters of a supernode's pattern rows touch one cache line for all the
/// columns instead of one per column, and the loops run across the columns in vector
/// registers. Each column sees the operations of [`sweep_leading_body`] in its order, so the
/// same bits as solved alone: the skipped columns of the forward sweep (a zero multiplier)
/// keep their entries by a select, and the sums are [`dot`]'s, lane by lane.
pub(super) fn sweep_leading_lanes<const R: usize>(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [[f64; R]],
) {
    sweep_leading_lanes_body(nodes, x)
}

/// [`dot`] of `a` with each lane of `b`.
#[inline(always)]
pub(super) fn dot_lanes<const R: usize>(a: &[f64], b: &[[f64; R]]) -> [f64; R] {
    let mut acc = [[0.0; R]; 4];
    let n4 = a.len() / 4 * 4;
    for (x, y) in a[..n4].chunks_exact(4).zip(b[..n4].chunks_exact(4)) {
        for k in 0..4 {
            for j in 0..R {
                acc[k][j] += x[k] * y[k][j];
            }
        }
    }
    std::array::from_fn(|j| {
        let tail: f64 = a[n4..].iter().zip(&b[n4..]).map(|(x, y)| x * y[j]).sum();
        (acc[0][j] + acc[1][j]) + (acc[2][j] + acc[3][j]) + tail
    })
}

#[inline(always)]
pub(super) fn sweep_leading_lanes_body<const R: usize>(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [[f64; R]],
) {
    let mut t: Vec<[f64; R]> = Vec::new();
    // Forward, as in `sweep_leading_body`: a lane whose multiplier is zero is skipped there,
    // so its entries are kept here (`t` starts at +0 and can only stay +0 or move away from
    // zero, so adding a zero product to it changes nothing).
    for (start, wk, kp, node) in nodes {
        let (start, wk, kp) = (*start, *wk, *kp);
        let (pat, w) = (&node.pattern[..kp], node.ncols);
        if x[start..start + wk].iter().flatten().all(|&v| v == 0.0) {
            continue;
        }
        t.clear();
        t.resize(kp, [0.0; R]);
        for c in 0..wk {
            let xc = x[start + c];
            if xc.iter().all(|&v| v == 0.0) {
                continue;
            }
            let col = node.col(c);
            for (xr, &l) in x[start + c + 1..start + wk].iter_mut().zip(&col[c + 1..wk]) {
                for j in 0..R {
                    let v = xr[j] - l * xc[j];
                    xr[j] = if xc[j] == 0.0 { xr[j] } else { v };
                }
            }
            for (tk, &lk) in t.iter_mut().zip(&col[w..w + kp]) {
                for j in 0..R {
                    tk[j] += lk * xc[j];
                }
            }
        }
        for (&row, tk) in pat.iter().zip(&t) {
            for j in 0..R {
                x[row][j] -= tk[j];
            }
        }
    }
    // D and backward, with the prefetch of `sweep_leading_body`.
    let mut ahead = Ahead::new(nodes.len());
    let mut below: Vec<[f64; R]> = Vec::new();
    for (i, (start, wk, kp, node)) in nodes.iter().enumerate().rev() {
        let (start, wk, kp) = (*start, *wk, *kp);
        let (pat, w) = (&node.pattern[..kp], node.ncols);
        ahead.at(nodes, i);
        t.clear();
        for &row in pat {
            t.push(x[row]);
        }
        below.clear();
        for c in 0..wk {
            below.push(dot_lanes(&node.col(c)[w..w + kp], &t));
        }
        for c in (0..wk).rev() {
            let col = node.col(c);
            let d = dot_lanes(&col[c + 1..wk], &x[start + c + 1..start + wk]);
            let xc = &mut x[start + c];
            for j in 0..R {
                let mut acc = xc[j] / col[c];
                acc -= d[j];
                acc -= below[c][j];
                xc[j] = acc;
            }
        }
    }
}

/// Solves the permuted columns `cols` (column-major, `size` each) with the leading block:
/// one column alone, more `R` at a time interleaved (the same bits).
pub(super) fn sweep_columns(
    nodes: &[(usize, usize, usize, Node<'_>)],
    cols: &mut [f64],
    size: usize,
) {
    pub(super) fn group<const R: usize>(
        nodes: &[(usize, usize, usize, Node<'_>)],
        cols: &mut [f64],
        size: usize,
    ) {
        let k = cols.len() / size;
        let mut x = vec![[0.0; R]; size];
        for (j, c) in cols.chunks_exact(size).enumerate() {
            for (xi, v) in x.iter_mut().zip(c) {
                xi[j] = *v;
            }
        }
        sweep_leading_lanes(nodes, &mut x);
        for (j, c) in cols.chunks_exact_mut(size).enumerate().take(k) {
            for (xi, v) in x.iter().zip(c) {
                *v = xi[j];
            }
        }
    }
    for g in cols.chunks_mut(8 * size) {
        match g.len() / size {
            1 => sweep_leading(nodes, g, size),
            2 => group::<2>(nodes, g, size),
            3 | 4 => group::<4>(nodes, g, size),
            _ => group::<8>(nodes, g, size),
        }
    }
}
