//! Distributed tractions on boundary groups, integrated into consistent nodal forces.
//!
//! On a 3-node edge with position `x(s)`, `s ∈ [−1, 1]`, the nodal force of node `a` is
//! `f_a = ∫ N_a(s) t(x(s)) |x'(s)| ds`. A pressure `p` acts against the outward normal:
//! `t |x'| = −p (x'_y, −x'_x)` for an edge traversed with its body on the left.
//! Where the load has a kink inside an edge (the ends `x0 ± a` of a Hertzian profile), the
//! parameter interval is split there, and each piece is integrated with 5-point Gauss in a
//! variable graded towards its ends, where the profile has a square-root behaviour.

use crate::mesh::Mesh;
use crate::quadrature::gauss_legendre;
use crate::shapes::{lin3, tri6};
use std::collections::HashMap;

/// A distributed load on a boundary.
#[derive(Clone, Debug, PartialEq)]
pub enum Traction {
    /// Uniform traction vector (force per unit length and unit thickness).
    Uniform { tx: f64, ty: f64 },
    /// Uniform pressure, positive when it pushes into the body.
    Pressure { p: f64 },
    /// Hertzian pressure `p0 sqrt(1 − (x − x0)²/a²)` for `|x − x0| < a`, zero elsewhere,
    /// pushing into the body.
    Hertz { p0: f64, a: f64, x0: f64 },
}

impl Traction {
    /// Pressure at abscissa x (for pressure-type loads).
    fn pressure(&self, x: f64) -> f64 {
        match *self {
            Traction::Pressure { p } => p,
            Traction::Hertz { p0, a, x0 } => {
                let r = (x - x0) / a;
                if r.abs() < 1.0 {
                    p0 * (1.0 - r * r).sqrt()
                } else {
                    0.0
                }
            }
            Traction::Uniform { .. } => 0.0,
        }
    }

    /// Abscissae where the load has a kink.
    fn kinks(&self) -> Vec<f64> {
        match *self {
            Traction::Hertz { a, x0, .. } => vec![x0 - a, x0 + a],
            _ => Vec::new(),
        }
    }
}

/// An edge that belongs to no triangle of the active bodies.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "boundary element {tag} of group `{group}` is not an edge of any triangle of the bodies in use"
)]
pub struct DanglingEdge {
    pub tag: u64,
    pub group: String,
}

/// Orientation of boundary lines: for each line, whether its node order runs with the body
/// on its left (the counter-clockwise sense of the adjacent triangle).
pub struct EdgeOrientation {
    map: HashMap<(usize, usize), (usize, usize), std::hash::BuildHasherDefault<NodePairHasher>>,
}

/// A multiplicative hash of node indices for the edge map, which every run builds over all
/// triangles: the default (SipHash, proof against crafted keys) took a quarter of its time,
/// and mesh node numbers need no such proof.
#[derive(Default, Clone, Copy)]
pub struct NodePairHasher(u64);

impl std::hash::Hasher for NodePairHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x517c_c1b7_2722_0a95);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

impl EdgeOrientation {
    /// Indexes the edges of the active triangles.
    pub fn new(mesh: &Mesh, active_tris: &[usize]) -> Self {
        let mut map = HashMap::with_capacity_and_hasher(active_tris.len() * 3, Default::default());
        for &e in active_tris {
            let t = &mesh.triangles[e];
            for ed in tri6::EDGE_NODE_IDS.iter() {
                map.insert((t.nodes[ed[0]], t.nodes[ed[1]]), (e, 0));
            }
        }
        EdgeOrientation { map }
    }

    /// [`Self::new`] for the lines of the groups `groups` only: the directed edges of the
    /// active triangles that are one of those lines' (either way), so every query about those
    /// lines answers as with the whole index. The index of every edge took 5 ms on L5 and
    /// 17 ms on L7, before the model's first parallel phase; a case asks about a few thousand.
    pub fn for_groups(mesh: &Mesh, active_tris: &[usize], groups: &[&str]) -> Self {
        let mut wanted: HashMap<(usize, usize), (), _> =
            HashMap::with_hasher(std::hash::BuildHasherDefault::<NodePairHasher>::default());
        for g in groups.iter().filter_map(|name| mesh.group(name)) {
            for &l in &g.elements {
                let n = mesh.lines[l].nodes;
                wanted.insert((n[0], n[1]), ());
                wanted.insert((n[1], n[0]), ());
            }
        }
        let mut map = HashMap::with_capacity_and_hasher(wanted.len() / 2, Default::default());
        for &e in active_tris {
            let t = &mesh.triangles[e];
            for ed in tri6::EDGE_NODE_IDS.iter() {
                let key = (t.nodes[ed[0]], t.nodes[ed[1]]);
                if wanted.contains_key(&key) {
                    map.insert(key, (e, 0));
                }
            }
        }
        EdgeOrientation { map }
    }

    /// Node coordinates of line `l` ordered with the body on the left.
    pub fn oriented_coords(
        &self,
        mesh: &Mesh,
        l: usize,
        group: &str,
    ) -> Result<[[f64; 2]; 3], DanglingEdge> {
        let n = mesh.lines[l].nodes;
        if self.map.contains_key(&(n[0], n[1])) {
            Ok(mesh.line_coords(l))
        } else if self.map.contains_key(&(n[1], n[0])) {
            Ok([mesh.nodes[n[1]], mesh.nodes[n[0]], mesh.nodes[n[2]]])
        } else {
            Err(DanglingEdge {
                tag: mesh.lines[l].tag,
                group: group.into(),
            })
        }
    }

    /// The triangle that has the directed edge (a, b) of its counter-clockwise boundary.
    pub fn edge_triangle(&self, a: usize, b: usize) -> Option<usize> {
        self.map.get(&(a, b)).map(|v| v.0)
    }

    /// Node indices of line `l` ordered with the body on the left.
    pub fn oriented_nodes(&self, mesh: &Mesh, l: usize) -> Option<[usize; 3]> {
        let n = mesh.lines[l].nodes;
        if self.map.contains_key(&(n[0], n[1])) {
            Some(n)
        } else if self.map.contains_key(&(n[1], n[0])) {
            Some([n[1], n[0], n[2]])
        } else {
            None
        }
    }
}

/// Parameters `s ∈ (−1, 1)` where the edge's abscissa x(s) equals `xk`.
fn crossings(xe: &[[f64; 2]; 3], xk: f64) -> Vec<f64> {
    // x(s) = A s² + B s + C
    let (x0, x1, x2) = (xe[0][0], xe[1][0], xe[2][0]);
    let a = 0.5 * (x0 + x1) - x2;
    let b = 0.5 * (x1 - x0);
    let c = x2 - xk;
    let mut r = Vec::new();
    if a.abs() < 1e-14 * (b.abs() + c.abs() + 1e-300) {
        if b != 0.0 {
            r.push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            if q != 0.0 {
                r.push(q / a);
                r.push(c / q);
            }
        }
    }
    r.retain(|s| *s > -1.0 && *s < 1.0);
    r
}

/// Nodal forces (3 nodes × 2 components) of a traction on an edge oriented with the body on
/// the left.
pub fn edge_forces(xe: &[[f64; 2]; 3], load: &Traction) -> [[f64; 2]; 3] {
    let mut cuts = vec![-1.0, 1.0];
    for xk in load.kinks() {
        cuts.extend(crossings(xe, xk));
    }
    cuts.sort_by(|a, b| a.partial_cmp(b).expect("finite"));
    let graded = !load.kinks().is_empty();
    let mut f = [[0.0; 2]; 3];
    let mut add = |s: f64, weight: f64| {
        let n = lin3::n(s);
        let t = lin3::tangent(xe, s);
        let tl = match *load {
            Traction::Uniform { tx, ty } => {
                let j = t[0].hypot(t[1]);
                [tx * j, ty * j]
            }
            _ => {
                let p = load.pressure(lin3::point(xe, s)[0]);
                // outward normal × |x'| = (t_y, −t_x)
                [-p * t[1], p * t[0]]
            }
        };
        for a in 0..3 {
            f[a][0] += weight * n[a] * tl[0];
            f[a][1] += weight * n[a] * tl[1];
        }
    };
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        if hi <= lo {
            continue;
        }
        if graded {
            // The Hertzian profile behaves like sqrt(distance) at its ends: integrate each half
            // of the piece with s = end ∓ L τ², which makes the integrand smooth in τ.
            let mid = 0.5 * (lo + hi);
            for &(g, wg) in gauss_legendre(5) {
                let tau = 0.5 * (g + 1.0);
                let l = mid - lo;
                add(lo + l * tau * tau, 0.5 * wg * 2.0 * l * tau);
                add(hi - l * tau * tau, 0.5 * wg * 2.0 * l * tau);
            }
        } else {
            let half = 0.5 * (hi - lo);
            for &(g, wg) in gauss_legendre(5) {
                add(lo + half * (g + 1.0), wg * half);
            }
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hertz_load_on_a_straight_edge_integrates_to_the_hertz_force() {
        // Edge along y = 0 from x = 2 to x = −2, body below (on the left when going −x).
        let xe = [[2.0, 0.0], [-2.0, 0.0], [0.0, 0.0]];
        let (p0, a) = (3.0, 1.3);
        let f = edge_forces(&xe, &Traction::Hertz { p0, a, x0: 0.0 });
        let fy: f64 = f.iter().map(|v| v[1]).sum();
        // ∫ p0 sqrt(1 − x²/a²) dx = π a p0 / 2, pushing down (−y).
        // One edge spans the whole profile: 5 graded Gauss points per half-piece give ~1e-6.
        assert!(
            (fy + std::f64::consts::PI * a * p0 / 2.0).abs() < 1e-5 * p0,
            "{fy}"
        );
        assert!(f.iter().map(|v| v[0]).sum::<f64>().abs() < 1e-14);
    }

    #[test]
    fn uniform_pressure_on_an_arc_gives_the_chord_resultant() {
        // Quarter arc of radius 1 from (1,0) to (0,1), body inside (left going counter-clockwise).
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let xe = [[1.0, 0.0], [0.0, 1.0], [c, c]];
        let f = edge_forces(&xe, &Traction::Pressure { p: 2.0 });
        // The resultant of a pressure on any curve is p × (chord rotated), here −p (1, 1).
        let (fx, fy) = f.iter().fold((0.0, 0.0), |s, v| (s.0 + v[0], s.1 + v[1]));
        assert!(
            (fx + 2.0).abs() < 1e-12 && (fy + 2.0).abs() < 1e-12,
            "{fx} {fy}"
        );
    }
}
