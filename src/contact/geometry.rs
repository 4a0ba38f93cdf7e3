//! The geometry of a contact pair in the reference configuration: the slave and master faces,
//! the candidate zone and its ends, and the mortar operator built on it.

use super::mortar::{self, Mortar};
use super::search::{Aabb, EdgeGrid};
use crate::loads::EdgeOrientation;
use crate::mesh::Mesh;

/// The geometric part of a contact pair: the candidate zone and its mortar operator.
pub struct Pair {
    pub mortar: Mortar,
    /// Slave edges of the candidate zone (nodes ordered with the slave body on the left).
    pub zone_edges: Vec<[usize; 3]>,
    /// Nodes of the zone edges next to slave edges outside the zone: contact there means the
    /// zone may clip it.
    pub rim_nodes: Vec<usize>,
    /// Nodes of zone edges that project (in part) beyond the end of the master face, or
    /// that end the slave face: contact there is held by a face too short for it.
    pub face_ends: Vec<usize>,
    /// Candidate gap used.
    pub candidate_gap: f64,
    /// The common normal, if the pair uses one.
    pub common_normal: Option<[f64; 2]>,
    /// The slave's outward normal at the first touch (the common normal when there is one).
    pub first_touch: [f64; 2],
}

/// What stops a pair from being built.
#[derive(Debug, thiserror::Error)]
pub enum PairError {
    #[error(
        "contact: boundary element {tag} of group `{group}` is not an edge of any triangle of the bodies in use"
    )]
    Dangling { tag: u64, group: String },
    #[error(
        "contact: no slave node of `{slave}` is within the candidate gap {gap:e} of `{master}` (smallest initial gap {min:e}); \
         the faces do not face each other, or raise `contact.candidate_gap`"
    )]
    EmptyZone {
        slave: String,
        master: String,
        gap: f64,
        min: f64,
    },
    #[error(
        "contact: the mortar operator of `{slave}` lost the slave point ({x:.6}, {y:.6}): {why}; \
         this is a defect of the contact search, please report it with the mesh"
    )]
    Dropped {
        slave: String,
        x: f64,
        y: f64,
        why: String,
    },
    #[error(
        "contact: slave `{slave}` and master `{master}` penetrate initially, by up to {depth:e} at ({x:.6}, {y:.6}); move the bodies apart"
    )]
    Penetration {
        slave: String,
        master: String,
        depth: f64,
        x: f64,
        y: f64,
    },
}

/// Oriented edges of a curve group.
pub fn oriented_edges(
    mesh: &Mesh,
    orient: &EdgeOrientation,
    group: &str,
) -> Result<Vec<[usize; 3]>, PairError> {
    let g = mesh.group(group).expect("checked");
    g.elements
        .iter()
        .map(|&l| {
            orient.oriented_nodes(mesh, l).ok_or(PairError::Dangling {
                tag: mesh.lines[l].tag,
                group: group.into(),
            })
        })
        .collect()
}

/// Default candidate gap: 0.5 % of the diagonal of the slave face's bounding box.
pub fn default_candidate_gap(mesh: &Mesh, slave: &[[usize; 3]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for e in slave {
        for &n in e {
            for i in 0..2 {
                lo[i] = lo[i].min(mesh.nodes[n][i]);
                hi[i] = hi[i].max(mesh.nodes[n][i]);
            }
        }
    }
    0.005 * (hi[0] - lo[0]).hypot(hi[1] - lo[1])
}

/// The master face indexed for [`point_gap`]: its edges' coordinates and a grid of the boxes
/// of their Bézier control points.
struct MasterIndex {
    coords: Vec<[[f64; 2]; 3]>,
    grid: EdgeGrid,
}

impl MasterIndex {
    fn new(mesh: &Mesh, master: &[[usize; 3]]) -> MasterIndex {
        let coords: Vec<[[f64; 2]; 3]> = master.iter().map(|e| e.map(|k| mesh.nodes[k])).collect();
        let boxes: Vec<Aabb> = coords.iter().map(control_box).collect();
        MasterIndex {
            grid: EdgeGrid::new(&boxes),
            coords,
        }
    }
}

/// The master parameters a hit of [`point_gap`] may have: the edge and round-off.
const R_MAX: f64 = 1.0 + 1e-9;

/// Initial gap of a slave point along its normal: the smallest |g| over master edges hit
/// within their parameter range, ignoring hits farther than `reach` (a normal line far from the
/// contact can cross the other face behind the point without any overlap). The master edges
/// are visited in order, as a scan of the whole face would; the grid only skips edges that
/// [`within_reach`] rejects.
fn point_gap(
    master: &MasterIndex,
    x: [f64; 2],
    n: [f64; 2],
    reach: f64,
    near: &mut Vec<usize>,
) -> Option<f64> {
    // A hit `x + g n` with |g| ≤ reach lies on its edge, within the edge's control box: the
    // box comes within round-off of the segment of the normal line out to `reach` (the margin
    // is far above it, and above the 1e-9 of the parameter range `R_MAX` allows past the ends).
    let nn = n[0].hypot(n[1]);
    let margin = 1e-6 * (reach * nn + x[0].abs() + x[1].abs() + 2.0 * master.grid.max_side());
    master.grid.query_segment(
        [x[0] - reach * n[0], x[1] - reach * n[1]],
        [x[0] + reach * n[0], x[1] + reach * n[1]],
        margin,
        near,
    );
    let mut best: Option<f64> = None;
    for &i in near.iter() {
        let xm = &master.coords[i];
        if !within_reach(xm, x, reach) || !mortar::may_hit_within(xm, x, n, R_MAX) {
            continue;
        }
        if let Some((r, g)) = mortar::project_along(xm, x, n)
            && (-R_MAX..=R_MAX).contains(&r)
            && g.abs() <= reach
            && best.is_none_or(|b| g.abs() < b.abs())
        {
            best = Some(g);
        }
    }
    best
}

/// The box of the Bézier control points of a quadratic edge (end, end, middle node), which
/// contains the curve.
fn control_box(xm: &[[f64; 2]; 3]) -> Aabb {
    let c = [
        2.0 * xm[2][0] - 0.5 * (xm[0][0] + xm[1][0]),
        2.0 * xm[2][1] - 0.5 * (xm[0][1] + xm[1][1]),
    ];
    let mut lo = [0.0; 2];
    let mut hi = [0.0; 2];
    for i in 0..2 {
        lo[i] = xm[0][i].min(xm[1][i]).min(c[i]);
        hi[i] = xm[0][i].max(xm[1][i]).max(c[i]);
    }
    (lo, hi)
}

/// Whether a master edge may hold a hit within `reach` of `x`: the distance from `x` to the
/// bounding box of the edge's Bézier control points (which contains the curve) is at most
/// `reach`, with a margin far above the round-off of [`mortar::project_along`]. Edges that fail
/// cannot give an accepted hit in [`point_gap`]; skipping them saves the projections, which
/// otherwise take most of the time of building a pair on a fine mesh.
fn within_reach(xm: &[[f64; 2]; 3], x: [f64; 2], reach: f64) -> bool {
    let (lo, hi) = control_box(xm);
    let mut d2 = 0.0;
    let mut scale = reach + x[0].abs() + x[1].abs();
    for i in 0..2 {
        let (lo, hi) = (lo[i], hi[i]);
        let d = (lo - x[i]).max(x[i] - hi).max(0.0);
        d2 += d * d;
        scale += hi - lo;
    }
    d2.sqrt() <= reach + 1e-6 * scale
}

/// Chooses the candidate zone (slave edges with a node whose initial gap is at most
/// `candidate_gap`) and builds the mortar operator on it.
///
/// `common`: use one normal for the whole pair, the slave normal at the point of smallest
/// initial gap (see [`mortar::build`]).
pub fn build_pair(
    mesh: &Mesh,
    slave_name: &str,
    master_name: &str,
    slave: &[[usize; 3]],
    master: &[[usize; 3]],
    candidate_gap: f64,
    common: bool,
) -> Result<Pair, PairError> {
    let ZoneScan {
        zone,
        min_gap,
        samples,
        deepest,
        zone_gap,
    } = scan_slave(mesh, slave, master, candidate_gap);
    if let Some((depth, x)) = deepest {
        return Err(PairError::Penetration {
            slave: slave_name.into(),
            master: master_name.into(),
            depth,
            x: x[0],
            y: x[1],
        });
    }
    if zone.is_empty() {
        return Err(PairError::EmptyZone {
            slave: slave_name.into(),
            master: master_name.into(),
            gap: candidate_gap,
            min: min_gap,
        });
    }
    // The first touch: the normals of the points of smallest gap (averaged over ties, such as
    // the two edges meeting at the touching node).
    let tie = min_gap + 1e-6 * candidate_gap;
    let sum = samples
        .iter()
        .filter(|(g, _)| *g <= tie)
        .fold([0.0, 0.0], |s, (_, n)| [s[0] + n[0], s[1] + n[1]]);
    let len = sum[0].hypot(sum[1]);
    let first_touch = [sum[0] / len, sum[1] / len];
    let zone_edges: Vec<[usize; 3]> = zone.iter().map(|&i| slave[i]).collect();
    let near = master_near_zone(mesh, master, &zone_edges, zone_gap);
    let normal = common.then_some(first_touch);
    let mortar = mortar::build(&mesh.nodes, &zone_edges, &near, normal, 2.0 * zone_gap);
    let face_ends = check_coverage(
        mesh,
        slave_name,
        (slave, &zone_edges),
        master,
        normal,
        &mortar,
    )?;
    let rim_nodes = zone_rim(slave, &zone, &zone_edges);
    // The guard against clipping must see every rim node: each carries a multiplier.
    if let Some(&n) = rim_nodes
        .iter()
        .find(|n| !mortar.slave_nodes.contains(n) && !face_ends.contains(n))
    {
        return Err(PairError::Dropped {
            slave: slave_name.into(),
            x: mesh.nodes[n][0],
            y: mesh.nodes[n][1],
            why: "a node on the rim of the candidate zone carries no contact unknown".into(),
        });
    }
    Ok(Pair {
        mortar,
        zone_edges,
        rim_nodes,
        face_ends,
        candidate_gap,
        common_normal: common.then_some(first_touch),
        first_touch,
    })
}

/// What [`scan_slave`] finds on the slave face.
struct ZoneScan {
    /// Indices of the slave edges in the candidate zone.
    zone: Vec<usize>,
    /// The smallest initial gap sampled.
    min_gap: f64,
    /// (initial gap, slave normal) at every sampled point that projects onto the master face.
    samples: Vec<(f64, [f64; 2])>,
    /// The deepest initial penetration, if any (reported, not resolved): (depth, point).
    deepest: Option<(f64, [f64; 2])>,
    /// The largest initial gap sampled on a zone edge (bounds the mortar's search).
    zone_gap: f64,
}

/// One gap sample of a slave edge: (gap, slave normal, point).
type Sample = (f64, [f64; 2], [f64; 2]);

/// Samples the initial gap at the ends and middle of every slave edge; an edge with a sample
/// within `candidate_gap` is in the zone.
fn scan_slave(
    mesh: &Mesh,
    slave: &[[usize; 3]],
    master: &[[usize; 3]],
    candidate_gap: f64,
) -> ZoneScan {
    let mut zone = Vec::new();
    let mut min_gap = f64::INFINITY;
    let mut samples: Vec<(f64, [f64; 2])> = Vec::new();
    // The deepest initial penetration, if any (reported, not resolved).
    let mut deepest: Option<(f64, [f64; 2])> = None;
    // The largest initial gap sampled on a zone edge (bounds the mortar's search).
    let mut zone_gap: f64 = candidate_gap;
    let index = MasterIndex::new(mesh, master);
    // The gaps of each edge's three samples, found in parallel and merged in edge order (the
    // result does not depend on the threads).
    use rayon::prelude::*;
    // Per edge: its chord and its samples.
    let sampled: Vec<(f64, [Option<Sample>; 3])> = slave
        .par_iter()
        .map_init(Vec::new, |near, e| {
            let xs = e.map(|k| mesh.nodes[k]);
            let h = (xs[0][0] - xs[1][0]).hypot(xs[0][1] - xs[1][1]);
            let found = [-1.0, 0.0, 1.0].map(|s| {
                let (x, n, _, _) = mortar::frame(&xs, s);
                point_gap(&index, x, n, 10.0 * (candidate_gap + h), near).map(|g| (g, n, x))
            });
            (h, found)
        })
        .collect();
    for (i, (h, found)) in sampled.into_iter().enumerate() {
        let mut in_zone = false;
        let mut edge_gap: f64 = 0.0;
        for &(g, n, x) in found.iter().flatten() {
            min_gap = min_gap.min(g);
            samples.push((g, n));
            if g < -1e-9 * h && deepest.is_none_or(|d: (f64, [f64; 2])| -g > d.0) {
                deepest = Some((-g, x));
            }
            if g <= candidate_gap {
                in_zone = true;
            }
            edge_gap = edge_gap.max(g.abs());
        }
        if in_zone {
            zone.push(i);
            zone_gap = zone_gap.max(edge_gap);
        }
    }
    ZoneScan {
        zone,
        min_gap,
        samples,
        deepest,
        zone_gap,
    }
}

/// Master edges near the zone: those with a node within `2 zone_gap + 2 h_max` of the zone's
/// bounding box.
fn master_near_zone(
    mesh: &Mesh,
    master: &[[usize; 3]],
    zone_edges: &[[usize; 3]],
    zone_gap: f64,
) -> Vec<[usize; 3]> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut hmax: f64 = 0.0;
    for e in zone_edges {
        let a = mesh.nodes[e[0]];
        let b = mesh.nodes[e[1]];
        hmax = hmax.max((a[0] - b[0]).hypot(a[1] - b[1]));
        for &n in e {
            for i in 0..2 {
                lo[i] = lo[i].min(mesh.nodes[n][i]);
                hi[i] = hi[i].max(mesh.nodes[n][i]);
            }
        }
    }
    let reach = 2.0 * zone_gap + 2.0 * hmax;
    master
        .iter()
        .filter(|e| {
            e.iter().any(|&k| {
                let p = mesh.nodes[k];
                p[0] >= lo[0] - reach
                    && p[0] <= hi[0] + reach
                    && p[1] >= lo[1] - reach
                    && p[1] <= hi[1] + reach
            })
        })
        .copied()
        .collect()
}

/// The rim: zone vertices shared with a slave edge outside the zone (with the other nodes of
/// their zone edges), sorted. Contact there means the zone may clip it (a zone that is the
/// whole slave face has no rim).
fn zone_rim(slave: &[[usize; 3]], zone: &[usize], zone_edges: &[[usize; 3]]) -> Vec<usize> {
    let in_zone: std::collections::HashSet<usize> = zone.iter().copied().collect();
    let outside: std::collections::HashSet<usize> = slave
        .iter()
        .enumerate()
        .filter(|(i, _)| !in_zone.contains(i))
        .flat_map(|(_, e)| [e[0], e[1]])
        .collect();
    let mut rim_nodes = Vec::new();
    for e in zone_edges {
        if outside.contains(&e[0]) || outside.contains(&e[1]) {
            rim_nodes.extend_from_slice(e);
        }
    }
    rim_nodes.sort_unstable();
    rim_nodes.dedup();
    rim_nodes
}

/// Verifies that the mortar operator covers every zone edge wherever the edge faces the
/// master face: an edge that is covered only in part is checked again against the whole master
/// face with an unbounded search, and any difference is an error (a slave point silently
/// dropped from the contact). Returns the nodes of edges that reach past the master face's end
/// and the two end nodes of the slave face when they are in the zone.
fn check_coverage(
    mesh: &Mesh,
    slave_name: &str,
    (slave, zone_edges): (&[[usize; 3]], &[[usize; 3]]),
    master: &[[usize; 3]],
    normal: Option<[f64; 2]>,
    mortar: &Mortar,
) -> Result<Vec<usize>, PairError> {
    let dropped = |e: &[usize; 3], why: String| PairError::Dropped {
        slave: slave_name.into(),
        x: mesh.nodes[e[2]][0],
        y: mesh.nodes[e[2]][1],
        why,
    };
    if mortar.lost_points > 0 {
        return Err(dropped(
            &zone_edges[0],
            format!(
                "{} integration points could not be projected",
                mortar.lost_points
            ),
        ));
    }
    let mut ends = Vec::new();
    for (e, &cov) in zone_edges.iter().zip(&mortar.coverage) {
        if cov >= 2.0 - 1e-9 {
            continue;
        }
        let full = mortar::build(&mesh.nodes, &[*e], master, normal, f64::INFINITY);
        if full.coverage[0] > cov + 1e-9 {
            return Err(dropped(
                e,
                format!(
                    "its edge is covered over {:.3} of its length by the search, {:.3} by all master edges",
                    cov / 2.0,
                    full.coverage[0] / 2.0
                ),
            ));
        }
        ends.extend_from_slice(e);
    }
    // Vertices that end the slave face (used by one edge of the face only).
    let mut count = std::collections::HashMap::new();
    for e in slave {
        for v in [e[0], e[1]] {
            *count.entry(v).or_insert(0usize) += 1;
        }
    }
    for e in zone_edges {
        ends.extend([e[0], e[1]].into_iter().filter(|v| count[v] == 1));
    }
    ends.sort_unstable();
    ends.dedup();
    Ok(ends)
}
