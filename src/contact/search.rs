//! A uniform grid over the bounding boxes of a face's edges, for the pairing's searches
//! (nearest master edge along a slave normal, master edges facing a slave edge).
//!
//! A query returns, in increasing index order, every edge whose box meets the query box (and
//! possibly a few more): callers keep their own exact test and visit candidates in the order a
//! scan over all edges would, so the results are bit-identical to that scan. Without the grid
//! those scans cost O(slave edges × master edges), about 1.3 s of the L7 Fig. 2 run.

/// An axis-aligned box: (lower corner, upper corner).
pub type Aabb = ([f64; 2], [f64; 2]);

/// Edges binned by the grid cells their boxes overlap (compressed rows: the edges of cell `k`
/// are `items[start[k]..start[k + 1]]`, increasing).
pub struct EdgeGrid {
    lo: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<usize>,
    items: Vec<u32>,
    /// Number of edges.
    len: usize,
    /// The largest side of any box.
    max_side: f64,
}

impl EdgeGrid {
    /// The grid of `boxes`. The cell side is the larger of the mean box extent and the side
    /// that gives about four cells per edge over the boxes' extent, so that the grid's size
    /// stays linear in the number of edges.
    pub fn new(boxes: &[Aabb]) -> EdgeGrid {
        let n = boxes.len();
        let max_side = boxes
            .iter()
            .map(|(lo, hi)| (hi[0] - lo[0]).max(hi[1] - lo[1]))
            .fold(0.0, f64::max);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut mean = 0.0;
        for (a, b) in boxes {
            for i in 0..2 {
                lo[i] = lo[i].min(a[i]);
                hi[i] = hi[i].max(b[i]);
            }
            mean += (b[0] - a[0]).max(b[1] - a[1]);
        }
        if n == 0
            || !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite())
        {
            // One cell holding every edge: queries return all of them.
            return EdgeGrid {
                lo: [0.0; 2],
                cell: f64::INFINITY,
                nx: 1,
                ny: 1,
                start: vec![0, n],
                items: (0..n as u32).collect(),
                len: n,
                max_side,
            };
        }
        mean /= n as f64;
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        let by_count =
            (w.max(f64::MIN_POSITIVE) * h.max(f64::MIN_POSITIVE) / (4.0 * n as f64)).sqrt();
        let cell = mean
            .max(by_count)
            .max(1e-12 * w.max(h))
            .max(f64::MIN_POSITIVE);
        let nx = ((w / cell) as usize + 1).min(4 * n + 1);
        let ny = ((h / cell) as usize + 1).min(4 * n + 1);
        let mut grid = EdgeGrid {
            lo,
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
            len: n,
            max_side,
        };
        // Two passes: count the edges of each cell, then fill (in increasing edge order).
        let mut counts = vec![0usize; nx * ny];
        for b in boxes {
            let (ix, iy) = grid.span(b);
            for y in iy.0..=iy.1 {
                for x in ix.0..=ix.1 {
                    counts[y * nx + x] += 1;
                }
            }
        }
        let mut acc = 0;
        for (k, c) in counts.iter().enumerate() {
            grid.start[k] = acc;
            acc += c;
        }
        grid.start[nx * ny] = acc;
        grid.items = vec![0; acc];
        let mut next = grid.start[..nx * ny].to_vec();
        for (e, b) in boxes.iter().enumerate() {
            let (ix, iy) = grid.span(b);
            for y in iy.0..=iy.1 {
                for x in ix.0..=ix.1 {
                    let k = y * nx + x;
                    grid.items[next[k]] = e as u32;
                    next[k] += 1;
                }
            }
        }
        grid
    }

    /// The largest side of the boxes the grid was built on (callers widen their queries by it
    /// when their own test allows for the size of each edge).
    pub fn max_side(&self) -> f64 {
        self.max_side
    }

    /// The cell index range along one axis covering [a, b] (clamped to the grid).
    fn axis(&self, a: f64, b: f64, i: usize, n: usize) -> (usize, usize) {
        let to = |v: f64| {
            let t = ((v - self.lo[i]) / self.cell).floor();
            if t.is_nan() || t < 0.0 {
                0
            } else {
                (t as usize).min(n - 1)
            }
        };
        (to(a), to(b))
    }

    /// The cells a box overlaps: (x range, y range), inclusive.
    fn span(&self, b: &Aabb) -> ((usize, usize), (usize, usize)) {
        (
            self.axis(b.0[0], b.1[0], 0, self.nx),
            self.axis(b.0[1], b.1[1], 1, self.ny),
        )
    }

    /// The edges whose cells overlap box `q` (a superset of those whose box meets `q`), in
    /// increasing order, into `out` (cleared first).
    pub fn query(&self, q: &Aabb, out: &mut Vec<usize>) {
        out.clear();
        if !(q.0[0] <= q.1[0] && q.0[1] <= q.1[1] && self.cell.is_finite()) {
            // An empty, unbounded or NaN query, or a grid of one cell: every edge.
            out.extend(0..self.len);
            return;
        }
        let (ix, iy) = self.span(q);
        for y in iy.0..=iy.1 {
            for x in ix.0..=ix.1 {
                let k = y * self.nx + x;
                out.extend(
                    self.items[self.start[k]..self.start[k + 1]]
                        .iter()
                        .map(|&e| e as usize),
                );
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// The edges whose cells overlap the segment from `a` to `b` widened by `margin` on every
    /// side (a superset of those whose box comes within `margin` of the segment), in
    /// increasing order, into `out` (cleared first). The segment is covered by pieces no
    /// longer than a cell, each queried by its box: a normal line through a fine face meets a
    /// few cells where the square around its reach holds hundreds of edges.
    pub fn query_segment(&self, a: [f64; 2], b: [f64; 2], margin: f64, out: &mut Vec<usize>) {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let pieces = (len / self.cell).ceil();
        if !(pieces.is_finite() && margin.is_finite() && margin >= 0.0)
            || pieces > (self.nx + self.ny) as f64
        {
            // A grid of one cell, a segment that crosses most of the grid, or bad input: the
            // segment's box.
            let q = (
                [a[0].min(b[0]) - margin, a[1].min(b[1]) - margin],
                [a[0].max(b[0]) + margin, a[1].max(b[1]) + margin],
            );
            return self.query(&q, out);
        }
        out.clear();
        let k = (pieces as usize).max(1);
        let at = |i: usize| {
            let t = i as f64 / k as f64;
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        };
        for i in 0..k {
            let (p, q) = (
                if i == 0 { a } else { at(i) },
                if i + 1 == k { b } else { at(i + 1) },
            );
            let piece = (
                [p[0].min(q[0]) - margin, p[1].min(q[1]) - margin],
                [p[0].max(q[0]) + margin, p[1].max(q[1]) + margin],
            );
            // Cells shared with the neighbouring pieces give repeats, removed below.
            let (ix, iy) = self.span(&piece);
            for y in iy.0..=iy.1 {
                for x in ix.0..=ix.1 {
                    let c = y * self.nx + x;
                    out.extend(
                        self.items[self.start[c]..self.start[c + 1]]
                            .iter()
                            .map(|&e| e as usize),
                    );
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift) for the test's boxes.
    fn rng(seed: &mut u64) -> f64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    fn meets(a: &Aabb, b: &Aabb) -> bool {
        a.0[0] <= b.1[0] && b.0[0] <= a.1[0] && a.0[1] <= b.1[1] && b.0[1] <= a.1[1]
    }

    #[test]
    fn queries_hold_every_box_that_meets_them_in_increasing_order() {
        let mut seed = 0x9e37_79b9_7f4a_7c15;
        // Edges along an arc (as a contact face is), and scattered ones.
        let mut boxes: Vec<Aabb> = (0..400)
            .map(|i| {
                let (t0, t1) = (i as f64 / 400.0 * 3.0, (i + 1) as f64 / 400.0 * 3.0);
                let (p, q) = ([t0.cos(), t0.sin()], [t1.cos(), t1.sin()]);
                (
                    [p[0].min(q[0]), p[1].min(q[1])],
                    [p[0].max(q[0]), p[1].max(q[1])],
                )
            })
            .collect();
        for _ in 0..100 {
            let (x, y, w, h) = (
                rng(&mut seed) * 4.0 - 2.0,
                rng(&mut seed) * 4.0 - 2.0,
                rng(&mut seed),
                rng(&mut seed) * 0.01,
            );
            boxes.push(([x, y], [x + w, y + h]));
        }
        let grid = EdgeGrid::new(&boxes);
        let mut out = Vec::new();
        for k in 0..2000 {
            let (x, y) = (rng(&mut seed) * 5.0 - 2.5, rng(&mut seed) * 5.0 - 2.5);
            let r = if k % 100 == 0 {
                f64::INFINITY
            } else {
                rng(&mut seed) * 0.3
            };
            let q = ([x - r, y - r], [x + r, y + r]);
            grid.query(&q, &mut out);
            assert!(
                out.windows(2).all(|w| w[0] < w[1]),
                "increasing, no repeats"
            );
            for (i, b) in boxes.iter().enumerate() {
                if meets(b, &q) {
                    assert!(
                        out.binary_search(&i).is_ok(),
                        "box {i} meets query {k} but is missing"
                    );
                }
            }
        }
        // Segments: every box within the margin of one is returned.
        let near_segment = |bx: &Aabb, a: [f64; 2], b: [f64; 2], m: f64| {
            // The distance from the segment to the box, by sampling the segment finely
            // (an overestimate by at most half a sample step).
            let steps = 2000;
            (0..=steps).any(|i| {
                let t = i as f64 / steps as f64;
                let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
                let dx = (bx.0[0] - p[0]).max(p[0] - bx.1[0]).max(0.0);
                let dy = (bx.0[1] - p[1]).max(p[1] - bx.1[1]).max(0.0);
                dx.hypot(dy) <= m
            })
        };
        for k in 0..300 {
            let a = [rng(&mut seed) * 5.0 - 2.5, rng(&mut seed) * 5.0 - 2.5];
            let (th, l) = (
                rng(&mut seed) * 6.3,
                rng(&mut seed) * if k % 10 == 0 { 6.0 } else { 0.4 },
            );
            let b = [a[0] + l * th.cos(), a[1] + l * th.sin()];
            let m = rng(&mut seed) * 0.02;
            grid.query_segment(a, b, m, &mut out);
            assert!(
                out.windows(2).all(|w| w[0] < w[1]),
                "increasing, no repeats"
            );
            for (i, bx) in boxes.iter().enumerate() {
                if near_segment(bx, a, b, m) {
                    assert!(
                        out.binary_search(&i).is_ok(),
                        "box {i} near segment {k} but missing"
                    );
                }
            }
        }
        // Degenerate inputs: no boxes, one point.
        EdgeGrid::new(&[]).query(&([0.0; 2], [1.0; 2]), &mut out);
        assert!(out.is_empty());
        EdgeGrid::new(&[([1.0, 1.0], [1.0, 1.0])]).query(&([0.0; 2], [1.0; 2]), &mut out);
        assert_eq!(out, vec![0]);
    }
}
