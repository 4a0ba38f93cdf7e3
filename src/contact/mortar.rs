//! Segment-to-segment mortar integrals on quadratic (3-node) edges, in the reference
//! configuration (small deformation: the constraint operator is linear in the displacements).
//!
//! For a slave point `X(s)` with outward unit normal `n(s)` and tangent `τ(s)` (n rotated by
//! −90°), the master point `Y` is where the normal line `X + g n` meets the master surface;
//! `g0 = (Y − X)·n` is the initial gap. With the multiplier basis `Φ_j = N_j` (the standard
//! quadratic basis of the slave edges), the nodal quantities are
//! ```text
//!   w_j  = ∫ Φ_j dΓ                                   (nodal weight)
//!   ĝ_j  = (1/w_j) ∫ Φ_j [g0 + (u_m(Y) − u_s(X))·n] dΓ   (nodal gap)
//!   v̂_j  = (1/w_j) ∫ Φ_j (u_m(Y) − u_s(X))·τ dΓ         (nodal relative tangential displacement)
//! ```
//! i.e. `ĝ = g0 + Ĝ u` and `v̂ = T̂ u`, with rows `Ĝ_j`, `T̂_j` over the slave and master nodes
//! (the D and M blocks of the mortar method, divided by `w_j`). The nodal contact forces
//! `F_n,j = w_j p_j`, `F_t,j` act on the displacements through `Ĝᵀ F_n + T̂ᵀ F_t`.
//!
//! The integrals are split into segments: the pieces of a slave edge whose points project
//! onto one master edge. Each segment is integrated with 5-point Gauss.

use crate::quadrature::gauss_legendre;
use crate::shapes::lin3;
use std::collections::{BTreeMap, BTreeSet};

/// A row of the mortar operator: (mesh node, coefficient vector for (ux, uy)).
pub type Row = Vec<(usize, [f64; 2])>;

/// The mortar operator of one contact pair.
#[derive(Clone, Debug, Default)]
pub struct Mortar {
    /// Slave nodes carrying a multiplier (mesh node indices), sorted by position along the face.
    pub slave_nodes: Vec<usize>,
    /// Nodal weights `w_j = ∫ Φ_j`.
    pub weight: Vec<f64>,
    /// Nodal initial gaps.
    pub gap0: Vec<f64>,
    /// Rows of `Ĝ` (nodal gap per unit displacement).
    pub g_rows: Vec<Row>,
    /// Rows of `T̂` (nodal tangential relative displacement).
    pub t_rows: Vec<Row>,
    /// Unit normal and tangent at each slave node (from the edge geometry).
    pub normal: Vec<[f64; 2]>,
    pub tangent: Vec<[f64; 2]>,
    /// Mesh nodes of the master side that appear in the rows.
    pub master_nodes: Vec<usize>,
    /// A representative element size at each slave node (edge chord).
    pub h: Vec<f64>,
    /// Per slave edge (in the order given to [`build`]): the length of its parameter interval
    /// [−1, 1] covered by segments, 2 when the whole edge projects onto the master face.
    pub coverage: Vec<f64>,
    /// Integration points whose projection failed inside a segment (should be none).
    pub lost_points: usize,
}

/// Projects `x` along direction `n` onto the quadratic edge `xm`: returns `(r, g)` with
/// `xm(r) = x + g n`; `r` may lie outside [−1, 1] (the edge's quadratic extension).
pub fn project_along(xm: &[[f64; 2]; 3], x: [f64; 2], n: [f64; 2]) -> Option<(f64, f64)> {
    let size = len2(xm[0][0] - xm[1][0], xm[0][1] - xm[1][1]);
    let mut r = 0.0;
    let p = lin3::point(xm, 0.0);
    let mut g = (p[0] - x[0]) * n[0] + (p[1] - x[1]) * n[1];
    for _ in 0..50 {
        let p = lin3::point(xm, r);
        let t = lin3::tangent(xm, r);
        let f = [p[0] - x[0] - g * n[0], p[1] - x[1] - g * n[1]];
        // Converged when the two curves meet to round-off of the coordinates.
        if len2(f[0], f[1]) <= 1e-12 * (size + x[0].abs() + x[1].abs()) {
            return Some((r, g));
        }
        // J = [t, −n]
        let det = t[0] * (-n[1]) - (-n[0]) * t[1];
        if det.abs() < 1e-300 {
            return None;
        }
        let dr = (f[0] * (-n[1]) - (-n[0]) * f[1]) / det;
        let dg = (t[0] * f[1] - t[1] * f[0]) / det;
        r -= dr;
        g -= dg;
        if !r.is_finite() || r.abs() > 1e3 {
            return None;
        }
    }
    None
}

/// `√(x² + y²)` without `hypot`'s guards against overflow and underflow, which make it several
/// times slower (the pairing calls these two functions for every candidate edge, and `hypot`
/// had taken most of the pairing's time at L7); coordinates of a mesh are far from either.
fn len2(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// Whether [`project_along`] may return an `r` in `[−r_max, r_max]`: `false` only when it
/// provably cannot. Its iteration stops on a residual `f = xm(r) − x − g n` below
/// `1e−12 (size + |x|)`, and `|f| |n| ≥ |f × n| = |h(r)|` with `h(r) = (xm(r) − x) × n =
/// a r² + b r + c`; so when `|h|` stays above a thousand times that tolerance over the whole
/// interval (checked at its ends and at the vertex of `h`, where the extremes of a quadratic
/// are), no converged `r` lies in it. Callers that reject hits outside the interval skip the
/// iteration there and get the same results; on a fine mesh most projections of the pairing's
/// search are of that kind.
pub fn may_hit_within(xm: &[[f64; 2]; 3], x: [f64; 2], n: [f64; 2], r_max: f64) -> bool {
    let cross = |u: [f64; 2]| u[0] * n[1] - u[1] * n[0];
    // xm(r) = m + r d + r² q (end nodes at r = ∓1, middle node m at r = 0).
    let q = [
        0.5 * (xm[0][0] + xm[1][0]) - xm[2][0],
        0.5 * (xm[0][1] + xm[1][1]) - xm[2][1],
    ];
    let d = [0.5 * (xm[1][0] - xm[0][0]), 0.5 * (xm[1][1] - xm[0][1])];
    let (a, b, c) = (
        cross(q),
        cross(d),
        cross([xm[2][0] - x[0], xm[2][1] - x[1]]),
    );
    if !(a.is_finite() && b.is_finite() && c.is_finite() && r_max.is_finite()) {
        return true;
    }
    let size = len2(xm[0][0] - xm[1][0], xm[0][1] - xm[1][1]);
    let tol = 1e-12 * (size + x[0].abs() + x[1].abs());
    let nn = len2(n[0], n[1]);
    // Round-off of the coefficients (before their cancellation) and of evaluating h on the
    // interval, and of the iteration's residual, which grows with the distance |x_m − x|:
    // far below the margin.
    let norm = |u: [f64; 2]| len2(u[0], u[1]);
    let slack = 1e-12
        * nn
        * (norm(q) * r_max * r_max + norm(d) * r_max + norm([xm[2][0] - x[0], xm[2][1] - x[1]]));
    let margin = 1e3 * tol * nn + slack;
    let h = |r: f64| (a * r + b) * r + c;
    let (lo, hi) = (h(-r_max), h(r_max));
    // The vertex, when inside the interval (else the ends again).
    let rv = -b / (2.0 * a);
    let mid = if a != 0.0 && rv.abs() < r_max {
        h(rv)
    } else {
        lo
    };
    let clear = (lo > margin && hi > margin && mid > margin)
        || (lo < -margin && hi < -margin && mid < -margin);
    !clear
}

/// Position, unit outward normal, unit tangent and length element of a slave edge at `s`.
/// The edge is oriented with its body on the left, so the outward normal is `(t_y, −t_x)/|t|`.
pub fn frame(xs: &[[f64; 2]; 3], s: f64) -> ([f64; 2], [f64; 2], [f64; 2], f64) {
    let x = lin3::point(xs, s);
    let t = lin3::tangent(xs, s);
    let j = t[0].hypot(t[1]);
    let n = [t[1] / j, -t[0] / j];
    (x, n, [n[1], -n[0]], j)
}

/// The frame used by the mortar integrals at slave parameter `s`: the edge's own normal and
/// tangent, or a common normal `n0` for the whole pair (see [`build`]).
fn frame_with(
    xs: &[[f64; 2]; 3],
    s: f64,
    n0: Option<[f64; 2]>,
) -> ([f64; 2], [f64; 2], [f64; 2], f64) {
    let (x, n, tau, j) = frame(xs, s);
    match n0 {
        Some(c) => (x, c, [c[1], -c[0]], j),
        None => (x, n, tau, j),
    }
}

/// The master parameter hit by the normal from slave parameter `s`.
fn r_of_s(xs: &[[f64; 2]; 3], xm: &[[f64; 2]; 3], s: f64, n0: Option<[f64; 2]>) -> Option<f64> {
    let (x, n, _, _) = frame_with(xs, s, n0);
    project_along(xm, x, n).map(|(r, _)| r)
}

/// Slave parameter in [lo, hi] where `r(s) = target`, by bisection (r is monotone in s).
fn solve_r(
    xs: &[[f64; 2]; 3],
    xm: &[[f64; 2]; 3],
    target: f64,
    mut lo: f64,
    mut hi: f64,
    n0: Option<[f64; 2]>,
) -> Option<f64> {
    let mut flo = r_of_s(xs, xm, lo, n0)? - target;
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        let fm = r_of_s(xs, xm, mid, n0)? - target;
        if (fm < 0.0) == (flo < 0.0) {
            lo = mid;
            flo = fm;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-15 {
            break;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Builds the mortar operator for the slave edges `slave` and master edges `master`, each given
/// by its three mesh nodes ordered with its body on the left, over node coordinates `x`.
///
/// `common_normal`: `None` projects along, and splits the relative displacement into, each
/// slave point's own normal and tangent. `Some(n0)` uses one direction `n0` for the whole pair:
/// the classical small-strain contact of two curved bodies (Johnson §4.1, the paper's theory),
/// where gaps are measured and forces transmitted along the common normal of the first touch.
/// With local normals the rigid approach `δ` of the bodies has a component `δ·x/R` along the
/// tilted tangents, which appears as spurious slip of the order of the elastic slip when
/// `a/R` is not small against `μ`.
///
/// `max_gap` bounds the initial gap of any point of the slave edges: master edges are searched
/// within the slave edge's reach along its normals (its chord, the gap and the master edge's
/// size), so no slave edge misses a master segment because its gap is large against its size.
pub fn build(
    x: &[[f64; 2]],
    slave: &[[usize; 3]],
    master: &[[usize; 3]],
    common_normal: Option<[f64; 2]>,
    max_gap: f64,
) -> Mortar {
    let n0 = common_normal;
    let mut sums = Sums::default();
    let coords = |e: &[usize; 3]| e.map(|k| x[k]);
    // Bounding boxes of the master edges for a quick search.
    let mboxes: Vec<([f64; 2], [f64; 2])> =
        master.iter().map(|e| bounding_box(&coords(e))).collect();
    let grid = super::search::EdgeGrid::new(&mboxes);
    // The segments of each slave edge (the search and projections) in parallel; the sums
    // below add them in edge order, so the operator does not depend on the threads.
    use rayon::prelude::*;
    let found: Vec<(SlaveEdge, Vec<Segment>, usize)> = slave
        .par_iter()
        .map_init(Vec::new, |near, se| {
            let xs = coords(se);
            let chord = (xs[0][0] - xs[1][0]).hypot(xs[0][1] - xs[1][1]);
            // Master edges near this slave edge: the normals from the edge travel at most
            // `max_gap` (plus a margin of a few chords for the curvature of both faces).
            let (lo, hi) = bounding_box(&xs);
            let mut segments: Vec<Segment> = Vec::new();
            let mut lost = 0;
            // Every master edge the test below keeps has its box within this distance of the
            // slave edge's box; the grid gives them in increasing order, as a scan would.
            let r = (2.0 * max_gap.abs() + 10.0 * chord + grid.max_side()) * (1.0 + 1e-9);
            grid.query(&([lo[0] - r, lo[1] - r], [hi[0] + r, hi[1] + r]), near);
            for &mi in near.iter() {
                let me = &master[mi];
                let (mlo, mhi) = mboxes[mi];
                let reach =
                    2.0 * max_gap.abs() + 10.0 * chord + (mhi[0] - mlo[0]).max(mhi[1] - mlo[1]);
                if mlo[0] > hi[0] + reach
                    || mhi[0] < lo[0] - reach
                    || mlo[1] > hi[1] + reach
                    || mhi[1] < lo[1] - reach
                {
                    continue;
                }
                let xm = coords(me);
                if n0.is_some_and(|n| !shadows_overlap(&xs, &xm, n)) {
                    continue;
                }
                if let Some((s_lo, s_hi)) = segment_on(&xs, &xm, n0, &mut lost) {
                    segments.push((s_lo, s_hi, mi));
                }
            }
            let edge = SlaveEdge {
                nodes: se,
                xs,
                chord,
            };
            (edge, segments, lost)
        })
        .collect();
    let mut coverage = Vec::with_capacity(slave.len());
    for (edge, segments, lost) in found {
        sums.lost_points += lost;
        coverage.push(segments.iter().map(|(lo, hi, _)| hi - lo).sum::<f64>());
        for (s_lo, s_hi, mi) in segments {
            let xm = coords(&master[mi]);
            sums.add_segment(&edge, &master[mi], &xm, (s_lo, s_hi), n0);
        }
        sums.add_nodal_frame(&edge, n0);
    }
    sums.into_mortar(x, coverage)
}

/// Whether the shadows of two quadratic edges along the direction `n` may overlap (`false`
/// only when they provably do not). Along one projection direction a slave point and its hit
/// on the master edge share their coordinate across `n` (to the round-off of
/// [`project_along`]), and a quadratic edge over `[−1, 1]` lies in the hull of its Bézier
/// control points; [`segment_on`] finds a segment, or counts a lost crossing, only where a
/// point of the slave edge hits the master edge over `[−1, 1]` (to `1e−9`). So when the
/// ranges of the control points across `n` are apart by more than a margin far above that
/// round-off, `segment_on` returns `None` and counts nothing: skipping it changes no result.
/// On a fine mesh nearly all of the search's candidates are of that kind (L7: 445 000 pairs of
/// edges, two projections each, for 2 000 slave edges).
fn shadows_overlap(xs: &[[f64; 2]; 3], xm: &[[f64; 2]; 3], n: [f64; 2]) -> bool {
    let range = |e: &[[f64; 2]; 3]| {
        let across = |p: [f64; 2]| p[0] * n[1] - p[1] * n[0];
        let c = [
            2.0 * e[2][0] - 0.5 * (e[0][0] + e[1][0]),
            2.0 * e[2][1] - 0.5 * (e[0][1] + e[1][1]),
        ];
        let v = [across(e[0]), across(e[1]), across(c)];
        let size = e
            .iter()
            .chain([&c])
            .map(|p| p[0].abs() + p[1].abs())
            .fold(0.0, f64::max);
        (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]), size)
    };
    let (slo, shi, ss) = range(xs);
    let (mlo, mhi, ms) = range(xm);
    let margin = 1e-6 * (ss + ms + (shi - slo) + (mhi - mlo));
    if !(margin.is_finite() && slo.is_finite() && mlo.is_finite()) {
        return true;
    }
    mlo <= shi + margin && slo <= mhi + margin
}

/// A segment `(s_lo, s_hi, master edge)` of a slave edge that projects onto a master edge.
type Segment = (f64, f64, usize);

/// Lower and upper corners of the bounding box of `points`.
fn bounding_box(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}

/// The segment of slave edge `xs` that projects onto master edge `xm`: the s-interval where
/// `r(s) ∈ [−1, 1]`, or `None` when the edges do not face each other over a positive length.
/// A crossing whose bisection fails is counted in `lost_points`.
fn segment_on(
    xs: &[[f64; 2]; 3],
    xm: &[[f64; 2]; 3],
    n0: Option<[f64; 2]>,
    lost_points: &mut usize,
) -> Option<(f64, f64)> {
    let (Some(ra), Some(rb)) = (r_of_s(xs, xm, -1.0, n0), r_of_s(xs, xm, 1.0, n0)) else {
        return None;
    };
    if ra.max(rb) < -1.0 || ra.min(rb) > 1.0 {
        return None;
    }
    // The s-interval where r(s) ∈ [−1, 1].
    let mut s_lo: f64 = -1.0;
    let mut s_hi: f64 = 1.0;
    for target in [-1.0, 1.0] {
        if (ra - target) * (rb - target) < 0.0 {
            let Some(s) = solve_r(xs, xm, target, -1.0, 1.0, n0) else {
                // Cannot happen for faces that face each other; counted, never hidden.
                *lost_points += 1;
                continue;
            };
            // Which side of s is inside?
            // r(s) is monotone: the left part (s < s*) is inside iff r(−1) is.
            let inside_left = if target < 0.0 { ra > -1.0 } else { ra < 1.0 };
            if inside_left {
                s_hi = s_hi.min(s);
            } else {
                s_lo = s_lo.max(s);
            }
        }
    }
    // A slave edge whose image only touches this master edge at an end gives no segment.
    let inside = r_of_s(xs, xm, 0.5 * (s_lo + s_hi), n0).is_some_and(|r| r.abs() <= 1.0 + 1e-9);
    (s_hi - s_lo > 1e-14 && inside).then_some((s_lo, s_hi))
}

/// A slave edge: its three mesh nodes, their coordinates and its chord.
struct SlaveEdge<'a> {
    nodes: &'a [usize; 3],
    xs: [[f64; 2]; 3],
    chord: f64,
}

/// The integrals accumulated at one slave node.
#[derive(Default)]
struct Acc {
    w: f64,
    g0: f64,
    g: BTreeMap<usize, [f64; 2]>,
    t: BTreeMap<usize, [f64; 2]>,
    h: f64,
    n: [f64; 2],
    tau: [f64; 2],
}

/// The running sums of [`build`]: the integrals per slave node, the master nodes met and the
/// integration points lost.
#[derive(Default)]
struct Sums {
    acc: BTreeMap<usize, Acc>,
    master_nodes: BTreeSet<usize>,
    lost_points: usize,
}

impl Sums {
    /// Adds the integrals over the segment `[s_lo, s_hi]` of `edge` that projects onto the
    /// master edge `me` (coordinates `xm`), by 5-point Gauss.
    fn add_segment(
        &mut self,
        edge: &SlaveEdge,
        me: &[usize; 3],
        xm: &[[f64; 2]; 3],
        (s_lo, s_hi): (f64, f64),
        n0: Option<[f64; 2]>,
    ) {
        let (se, xs, chord) = (edge.nodes, &edge.xs, edge.chord);
        let half = 0.5 * (s_hi - s_lo);
        for &(gq, wq) in gauss_legendre(5) {
            let s = s_lo + half * (gq + 1.0);
            let (xp, n, tau, j) = frame_with(xs, s, n0);
            let Some((r, g0)) = project_along(xm, xp, n) else {
                self.lost_points += 1;
                continue;
            };
            let ns = lin3::n(s);
            let nm = lin3::n(r.clamp(-1.0, 1.0));
            let dw = wq * half * j;
            for a in 0..3 {
                let e = self.acc.entry(se[a]).or_default();
                let fa = ns[a] * dw;
                e.w += fa;
                e.g0 += fa * g0;
                e.h = e.h.max(chord);
                for i in 0..3 {
                    let v = e.g.entry(se[i]).or_insert([0.0; 2]);
                    v[0] -= fa * ns[i] * n[0];
                    v[1] -= fa * ns[i] * n[1];
                    let v = e.t.entry(se[i]).or_insert([0.0; 2]);
                    v[0] -= fa * ns[i] * tau[0];
                    v[1] -= fa * ns[i] * tau[1];
                }
                for k in 0..3 {
                    let v = e.g.entry(me[k]).or_insert([0.0; 2]);
                    v[0] += fa * nm[k] * n[0];
                    v[1] += fa * nm[k] * n[1];
                    let v = e.t.entry(me[k]).or_insert([0.0; 2]);
                    v[0] += fa * nm[k] * tau[0];
                    v[1] += fa * nm[k] * tau[1];
                    self.master_nodes.insert(me[k]);
                }
            }
        }
    }

    /// Nodal frame: adds the normal and tangent of `edge` at its nodes (averaged over edges).
    fn add_nodal_frame(&mut self, edge: &SlaveEdge, n0: Option<[f64; 2]>) {
        for (a, s) in [(0usize, -1.0), (1, 1.0), (2, 0.0)] {
            let (_, n, tau, _) = frame_with(&edge.xs, s, n0);
            let e = self.acc.entry(edge.nodes[a]).or_default();
            e.n = [e.n[0] + n[0], e.n[1] + n[1]];
            e.tau = [e.tau[0] + tau[0], e.tau[1] + tau[1]];
        }
    }

    /// The operator: nodes with positive weight ordered along the face, rows divided by the
    /// weights (exact zeros dropped), unit nodal frames.
    fn into_mortar(self, x: &[[f64; 2]], coverage: Vec<f64>) -> Mortar {
        let mut m = Mortar::default();
        let mut entries: Vec<(usize, Acc)> =
            self.acc.into_iter().filter(|(_, a)| a.w > 0.0).collect();
        // Order along the face by the tangent direction of the first node (x for the VM272 arcs).
        entries.sort_by(|a, b| {
            let (pa, pb) = (x[a.0], x[b.0]);
            let t = a.1.tau;
            (pa[0] * t[0] + pa[1] * t[1])
                .partial_cmp(&(pb[0] * t[0] + pb[1] * t[1]))
                .expect("finite")
        });
        for (node, a) in entries {
            let unit = |v: [f64; 2]| {
                let l = v[0].hypot(v[1]);
                [v[0] / l, v[1] / l]
            };
            m.slave_nodes.push(node);
            m.weight.push(a.w);
            m.gap0.push(a.g0 / a.w);
            m.g_rows.push(
                a.g.into_iter()
                    .map(|(k, v)| (k, [v[0] / a.w, v[1] / a.w]))
                    .filter(|(_, v)| v[0] != 0.0 || v[1] != 0.0)
                    .collect(),
            );
            m.t_rows.push(
                a.t.into_iter()
                    .map(|(k, v)| (k, [v[0] / a.w, v[1] / a.w]))
                    .filter(|(_, v)| v[0] != 0.0 || v[1] != 0.0)
                    .collect(),
            );
            m.normal.push(unit(a.n));
            m.tangent.push(unit(a.tau));
            m.h.push(a.h);
        }
        m.master_nodes = self.master_nodes.into_iter().collect();
        m.coverage = coverage;
        m.lost_points = self.lost_points;
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A xorshift stream of numbers uniform in [−1, 1).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// `shadows_overlap` says `false` only where `segment_on` along that direction finds no
    /// segment and counts no lost crossing: random curved edge pairs, many of them near each
    /// other's shadow, at three scales.
    #[test]
    fn skipped_edge_pairs_have_no_segment() {
        let mut rng = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut skipped, mut segments) = (0, 0);
        for k in 0..100_000 {
            let scale = [1e-3, 1.0, 30.0][k % 3];
            let bow = [0.0, 0.05, 0.4][k % 3];
            let at = [2.0 * scale * rng(), scale * (0.5 + rng())];
            let mut edge = |at: [f64; 2]| {
                let (p, q) = (
                    [at[0] + rng() * scale, at[1] + 0.2 * rng() * scale],
                    [at[0] + rng() * scale, at[1] + 0.2 * rng() * scale],
                );
                let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                [
                    p,
                    q,
                    [mid[0] + bow * (q[1] - p[1]), mid[1] - bow * (q[0] - p[0])],
                ]
            };
            let xs = edge([0.0, 0.0]);
            let xm = edge(at);
            let th = 0.5 * std::f64::consts::PI + 0.3 * rng();
            let n = [th.cos(), th.sin()];
            let mut lost = 0;
            let found = segment_on(&xs, &xm, Some(n), &mut lost);
            if found.is_some() {
                segments += 1;
            }
            if !shadows_overlap(&xs, &xm, n) {
                skipped += 1;
                assert!(
                    found.is_none() && lost == 0,
                    "case {k}: {found:?}, lost {lost}"
                );
            }
        }
        // The test means something: both kinds occur often.
        assert!(
            skipped > 20_000 && segments > 20_000,
            "skipped {skipped}, segments {segments}"
        );
    }

    /// `may_hit_within` says `false` only where `project_along` finds no hit in the interval:
    /// checked over random curved edges and lines, many of them near tangency or far off.
    #[test]
    fn skipped_projections_never_land_on_the_interval() {
        let mut rng = uniform(0x2545_f491_4f6c_dd1d);
        let (mut skipped, mut hits) = (0, 0);
        for k in 0..200_000 {
            let scale = [1e-3, 1.0, 30.0][k % 3];
            let bow = [0.0, 1e-9, 0.05, 0.4][k % 4];
            let (p, q) = (
                [rng() * scale, rng() * scale],
                [rng() * scale, rng() * scale],
            );
            let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
            let xm = [
                p,
                q,
                [mid[0] + bow * (q[1] - p[1]), mid[1] - bow * (q[0] - p[0])],
            ];
            let x = [mid[0] + rng() * scale, mid[1] + rng() * scale];
            let th = rng() * std::f64::consts::PI;
            let n = [th.cos(), th.sin()];
            for r_max in [1.0 + 1e-9, 1.5] {
                let hit = project_along(&xm, x, n).is_some_and(|(r, _)| r.abs() <= r_max);
                if hit {
                    hits += 1;
                }
                if !may_hit_within(&xm, x, n, r_max) {
                    skipped += 1;
                    assert!(!hit, "case {k}: a hit in [-{r_max}, {r_max}] was skipped");
                }
            }
        }
        // The test means something: both kinds occur often.
        assert!(
            skipped > 100_000 && hits > 50_000,
            "skipped {skipped}, hits {hits}"
        );
    }
}
