//! 6-node quadratic triangle (gmsh type 9, VTK `QUADRATIC_TRIANGLE` = 22).
//!
//! ```text
//!   η
//!   2
//!   |`\
//!   |  `\
//!   5    `4
//!   |      `\
//!   |        `\
//!   0-----3----1  ξ
//! ```
//! Reference coordinates: node 0 (0,0), 1 (1,0), 2 (0,1), 3 (½,0), 4 (½,½), 5 (0,½).
//! With barycentric `L0 = 1 − ξ − η`, `L1 = ξ`, `L2 = η`:
//! `N_i = L_i (2 L_i − 1)` at the vertices and `N = 4 L_i L_j` at the mid-edge nodes.

/// Number of nodes.
pub const NNODE: usize = 6;

/// Local node ids of each edge as (start vertex, end vertex, mid-edge node), counter-clockwise.
pub const EDGE_NODE_IDS: [[usize; 3]; 3] = [[0, 1, 3], [1, 2, 4], [2, 0, 5]];

/// Reference coordinates of the six nodes.
pub const NODE_REF_COORDS: [[f64; 2]; 6] = [
    [0.0, 0.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [0.5, 0.0],
    [0.5, 0.5],
    [0.0, 0.5],
];

/// Shape function values at reference point (ξ, η).
pub fn n(xi: f64, eta: f64) -> [f64; 6] {
    let l0 = 1.0 - xi - eta;
    let (l1, l2) = (xi, eta);
    [
        l0 * (2.0 * l0 - 1.0),
        l1 * (2.0 * l1 - 1.0),
        l2 * (2.0 * l2 - 1.0),
        4.0 * l0 * l1,
        4.0 * l1 * l2,
        4.0 * l2 * l0,
    ]
}

/// Derivatives `[∂N/∂ξ, ∂N/∂η]` of the shape functions at (ξ, η) (`const`: tables of them at
/// the points of a rule are built at compile time, with the same IEEE arithmetic).
pub const fn dn(xi: f64, eta: f64) -> [[f64; 2]; 6] {
    let l0 = 1.0 - xi - eta;
    let (l1, l2) = (xi, eta);
    // ∂L0/∂ξ = ∂L0/∂η = −1; ∂L1/∂ξ = 1; ∂L2/∂η = 1.
    [
        [-(4.0 * l0 - 1.0), -(4.0 * l0 - 1.0)],
        [4.0 * l1 - 1.0, 0.0],
        [0.0, 4.0 * l2 - 1.0],
        [4.0 * (l0 - l1), -4.0 * l1],
        [4.0 * l2, 4.0 * l1],
        [-4.0 * l2, 4.0 * (l0 - l2)],
    ]
}

/// Geometry of the isoparametric map at one reference point.
#[derive(Clone, Copy, Debug)]
pub struct MapPoint {
    /// Physical coordinates x(ξ, η).
    pub x: [f64; 2],
    /// Jacobian determinant `det ∂x/∂ξ`.
    pub det_j: f64,
    /// Physical derivatives `[∂N/∂x, ∂N/∂y]` (valid only when `det_j > 0`).
    pub dndx: [[f64; 2]; 6],
    /// Shape function values.
    pub n: [f64; 6],
}

/// Evaluates the isoparametric map of an element with node coordinates `xe` at (ξ, η).
pub fn map_point(xe: &[[f64; 2]; 6], xi: f64, eta: f64) -> MapPoint {
    let nv = n(xi, eta);
    let d = dn(xi, eta);
    let (x, det_j, dndx) = map_with(xe, &nv, &d);
    MapPoint {
        x,
        det_j,
        dndx,
        n: nv,
    }
}

/// The physical derivatives `[∂N/∂x, ∂N/∂y]` of the shape functions at a reference point
/// where they have the reference derivatives `d` ([`dn`]), and the Jacobian determinant: the
/// arithmetic of [`map_point`] (the same bits) without evaluating the shape functions, for
/// loops over many elements at fixed points.
pub fn gradients(xe: &[[f64; 2]; 6], d: &[[f64; 2]; 6]) -> (f64, [[f64; 2]; 6]) {
    let (_, det_j, dndx) = map_with(xe, &[0.0; 6], d);
    (det_j, dndx)
}

/// The Jacobian determinant alone at a reference point with reference derivatives `d`: the
/// arithmetic of [`map_point`]'s (the same bits).
pub fn jacobian_det(xe: &[[f64; 2]; 6], d: &[[f64; 2]; 6]) -> f64 {
    det2(&jacobian(xe, d))
}

fn det2(j: &[[f64; 2]; 2]) -> f64 {
    j[0][0] * j[1][1] - j[0][1] * j[1][0]
}

/// `J[i][k] = ∂x_i/∂ξ_k` at a reference point with reference derivatives `d`.
#[inline(always)]
fn jacobian(xe: &[[f64; 2]; 6], d: &[[f64; 2]; 6]) -> [[f64; 2]; 2] {
    let mut j = [[0.0; 2]; 2];
    for a in 0..6 {
        for i in 0..2 {
            for k in 0..2 {
                j[i][k] += xe[a][i] * d[a][k];
            }
        }
    }
    j
}

/// The position (from the shape-function values `nv`), Jacobian determinant and physical
/// derivatives at a reference point with reference derivatives `d`.
#[inline(always)]
fn map_with(
    xe: &[[f64; 2]; 6],
    nv: &[f64; 6],
    d: &[[f64; 2]; 6],
) -> ([f64; 2], f64, [[f64; 2]; 6]) {
    let mut x = [0.0; 2];
    for a in 0..6 {
        for i in 0..2 {
            x[i] += nv[a] * xe[a][i];
        }
    }
    let j = jacobian(xe, d);
    let det_j = det2(&j);
    let inv = if det_j != 0.0 {
        [
            [j[1][1] / det_j, -j[0][1] / det_j],
            [-j[1][0] / det_j, j[0][0] / det_j],
        ]
    } else {
        [[0.0; 2]; 2]
    };
    // ∂N/∂x_i = Σ_k ∂N/∂ξ_k ∂ξ_k/∂x_i, with ∂ξ/∂x = J⁻¹.
    let mut dndx = [[0.0; 2]; 6];
    for a in 0..6 {
        for i in 0..2 {
            dndx[a][i] = d[a][0] * inv[0][i] + d[a][1] * inv[1][i];
        }
    }
    (x, det_j, dndx)
}

/// Signed area of the straight triangle through the three vertices (positive when counter-clockwise).
pub fn vertex_area(xe: &[[f64; 2]; 6]) -> f64 {
    let [a, b, c] = [xe[0], xe[1], xe[2]];
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
}

/// Node permutation that reverses the orientation (clockwise ↔ counter-clockwise):
/// swaps vertices 1 and 2 and mid-edge nodes 3 and 5.
pub const REVERSE: [usize; 6] = [0, 2, 1, 5, 4, 3];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronecker_and_partition_of_unity() {
        for (i, p) in NODE_REF_COORDS.iter().enumerate() {
            let v = n(p[0], p[1]);
            for (j, vj) in v.iter().enumerate() {
                let expect = if i == j { 1.0 } else { 0.0 };
                assert!((vj - expect).abs() < 1e-14);
            }
        }
        let d = dn(0.21, 0.37);
        let s: [f64; 2] = d.iter().fold([0.0, 0.0], |s, g| [s[0] + g[0], s[1] + g[1]]);
        assert!(s[0].abs() < 1e-14 && s[1].abs() < 1e-14);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let (xi, eta, h) = (0.23, 0.41, 1e-6);
        let d = dn(xi, eta);
        let (np, nm) = (n(xi + h, eta), n(xi - h, eta));
        let (mp, mm) = (n(xi, eta + h), n(xi, eta - h));
        for a in 0..6 {
            assert!(((np[a] - nm[a]) / (2.0 * h) - d[a][0]).abs() < 1e-8);
            assert!(((mp[a] - mm[a]) / (2.0 * h) - d[a][1]).abs() < 1e-8);
        }
    }
}
