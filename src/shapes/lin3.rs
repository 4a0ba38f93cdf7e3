//! 3-node quadratic line (gmsh type 8, VTK `QUADRATIC_EDGE` = 21).
//!
//! ```text
//!   0-----2-----1     s ∈ [−1, 1]: node 0 at s = −1, node 1 at s = +1, node 2 at s = 0
//! ```
//! `N0 = s(s − 1)/2`, `N1 = s(s + 1)/2`, `N2 = 1 − s²`.

/// Number of nodes.
pub const NNODE: usize = 3;

/// Shape function values at `s`.
pub fn n(s: f64) -> [f64; 3] {
    [0.5 * s * (s - 1.0), 0.5 * s * (s + 1.0), 1.0 - s * s]
}

/// Shape function derivatives `dN/ds` at `s`.
pub fn dn(s: f64) -> [f64; 3] {
    [s - 0.5, s + 0.5, -2.0 * s]
}

/// Second derivatives `d²N/ds²` (constant).
pub const D2N: [f64; 3] = [1.0, 1.0, -2.0];

/// Position `x(s)` on an edge with node coordinates `xe`.
pub fn point(xe: &[[f64; 2]; 3], s: f64) -> [f64; 2] {
    let v = n(s);
    [
        v[0] * xe[0][0] + v[1] * xe[1][0] + v[2] * xe[2][0],
        v[0] * xe[0][1] + v[1] * xe[1][1] + v[2] * xe[2][1],
    ]
}

/// Tangent `dx/ds` on an edge with node coordinates `xe`.
pub fn tangent(xe: &[[f64; 2]; 3], s: f64) -> [f64; 2] {
    let d = dn(s);
    [
        d[0] * xe[0][0] + d[1] * xe[1][0] + d[2] * xe[2][0],
        d[0] * xe[0][1] + d[1] * xe[1][1] + d[2] * xe[2][1],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_properties() {
        for (i, s) in [-1.0, 1.0, 0.0].iter().enumerate() {
            let v = n(*s);
            for (j, vj) in v.iter().enumerate() {
                assert_eq!(*vj, if i == j { 1.0 } else { 0.0 });
            }
        }
        let h = 1e-6;
        let (p, m) = (n(0.3 + h), n(0.3 - h));
        let d = dn(0.3);
        for a in 0..3 {
            assert!(((p[a] - m[a]) / (2.0 * h) - d[a]).abs() < 1e-9);
        }
    }
}
