//! The consistent mass of the 6-node triangle.
//!
//! Per unit thickness and density `ρ`, the element mass couples the nodes' displacements
//! component by component:
//! ```text
//!   M_e = ρ ∫_e Nᵀ N dA ⊗ I₂,   (m_e)_ab = ρ Σ_q w_q N_a(ξ_q) N_b(ξ_q) |J(ξ_q)|
//! ```
//! with the 7-point rule of degree 5 ([`crate::quadrature::TRI_7`]): exact for a straight-sided
//! element (`N_a N_b` of degree 4, `|J|` constant). Since `Σ_a N_a = 1`, the entries of `m_e`
//! sum to `ρ ∫_e |J| dξ`, the element's mass (exact for `|J|` up to degree 5, so for curved
//! elements too); a uniform velocity `v` gives the kinetic energy `½ m |v|²` exactly, and a
//! rigid rotation (velocity linear in x) gives `½ ρ ∫ |v|² dA` exactly on straight-sided
//! elements.

use crate::quadrature::TRI_7;
use crate::shapes::tri6;

/// The scalar block `m_e` (6 × 6, row-major, symmetric) of the consistent mass of an element
/// with node coordinates `xe` and density `rho`: the mass matrix on the element's twelve
/// DOFs (x then y per node) is `M[2a+c][2b+d] = m_e[a][b] δ_cd`.
pub fn element_mass(xe: &[[f64; 2]; 6], rho: f64) -> [f64; 36] {
    let mut m = [0.0; 36];
    for &([xi, eta], w) in &TRI_7 {
        let mp = tri6::map_point(xe, xi, eta);
        let f = rho * w * mp.det_j;
        for a in 0..6 {
            for b in a..6 {
                m[a * 6 + b] += f * mp.n[a] * mp.n[b];
            }
        }
    }
    // Exactly symmetric.
    for a in 0..6 {
        for b in 0..a {
            m[a * 6 + b] = m[b * 6 + a];
        }
    }
    m
}

/// `M_e x_e` for the element's twelve DOFs (x then y per node) with scalar block `m`.
pub fn apply(m: &[f64; 36], x: &[f64; 12]) -> [f64; 12] {
    let mut y = [0.0; 12];
    for a in 0..6 {
        for b in 0..6 {
            let mab = m[a * 6 + b];
            y[2 * a] += mab * x[2 * b];
            y[2 * a + 1] += mab * x[2 * b + 1];
        }
    }
    y
}

/// The full 12 × 12 matrix (row-major) of scalar block `m`.
pub fn expand(m: &[f64; 36]) -> [f64; 144] {
    let mut full = [0.0; 144];
    for a in 0..6 {
        for b in 0..6 {
            for c in 0..2 {
                full[(2 * a + c) * 12 + 2 * b + c] = m[a * 6 + b];
            }
        }
    }
    full
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight-sided triangle with its mid-side nodes at the midpoints.
    fn straight(v: [[f64; 2]; 3]) -> [[f64; 2]; 6] {
        let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
        [
            v[0],
            v[1],
            v[2],
            mid(v[0], v[1]),
            mid(v[1], v[2]),
            mid(v[2], v[0]),
        ]
    }

    fn area(v: [[f64; 2]; 3]) -> f64 {
        0.5 * ((v[1][0] - v[0][0]) * (v[2][1] - v[0][1])
            - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]))
    }

    #[test]
    fn the_entries_sum_to_the_mass_and_match_the_closed_form_of_the_straight_triangle() {
        let v = [[0.3, -0.2], [2.1, 0.4], [0.7, 1.9]];
        let (rho, a) = (7.8, area(v));
        let m = element_mass(&straight(v), rho);
        let total: f64 = m.iter().sum();
        assert!(
            (total - rho * a).abs() <= 1e-14 * rho * a,
            "{total} vs {}",
            rho * a
        );
        // The closed form of the P2 triangle: vertex–vertex (6, −1), vertex–mid (0, −4 for the
        // opposite side), mid–mid (32, 16), over 180, times ρA.
        let exact = |i: usize, j: usize| -> f64 {
            let vertex = |k| k < 3;
            let r = match (vertex(i), vertex(j)) {
                (true, true) => {
                    if i == j {
                        6.0
                    } else {
                        -1.0
                    }
                }
                (true, false) | (false, true) => {
                    let (vx, mid) = if vertex(i) { (i, j) } else { (j, i) };
                    // mid-side node k+3 joins vertices k and k+1; opposite vertex is k+2.
                    if (mid - 3 + 2) % 3 == vx { -4.0 } else { 0.0 }
                }
                (false, false) => {
                    if i == j {
                        32.0
                    } else {
                        16.0
                    }
                }
            };
            r * rho * a / 180.0
        };
        for i in 0..6 {
            for j in 0..6 {
                let d = (m[i * 6 + j] - exact(i, j)).abs();
                assert!(
                    d <= 1e-14 * rho * a,
                    "({i},{j}): {} vs {}",
                    m[i * 6 + j],
                    exact(i, j)
                );
            }
        }
    }

    #[test]
    fn rigid_motions_have_their_exact_kinetic_energy() {
        let v = [[1.0, 0.5], [3.0, 1.0], [1.5, 2.5]];
        let xe = straight(v);
        let rho = 2.5;
        let m = element_mass(&xe, rho);
        let a = area(v);
        // Translation (vx, vy): ½ ρ A |v|².
        let mut vel = [0.0; 12];
        for k in 0..6 {
            vel[2 * k] = 0.7;
            vel[2 * k + 1] = -1.3;
        }
        let ke = 0.5
            * vel
                .iter()
                .zip(apply(&m, &vel))
                .map(|(a, b)| a * b)
                .sum::<f64>();
        let exact = 0.5 * rho * a * (0.7f64.powi(2) + 1.3f64.powi(2));
        assert!((ke - exact).abs() <= 1e-14 * exact, "{ke} vs {exact}");
        // Rotation ω about the origin: v = ω (−y, x); ½ ρ ω² ∫ (x² + y²) dA, with the polar
        // moment of the triangle about the origin from its vertices.
        let w = 0.9;
        for k in 0..6 {
            vel[2 * k] = -w * xe[k][1];
            vel[2 * k + 1] = w * xe[k][0];
        }
        let ke = 0.5
            * vel
                .iter()
                .zip(apply(&m, &vel))
                .map(|(a, b)| a * b)
                .sum::<f64>();
        let second = |c: usize| {
            let s: f64 = (0..3).map(|i| v[i][c] * v[i][c]).sum::<f64>();
            let t: f64 = (0..3).map(|i| v[i][c]).sum::<f64>();
            a / 12.0 * (s + t * t)
        };
        let exact = 0.5 * rho * w * w * (second(0) + second(1));
        assert!((ke - exact).abs() <= 1e-13 * exact, "{ke} vs {exact}");
    }

    #[test]
    fn the_expanded_matrix_is_symmetric_and_applies_as_the_block() {
        let xe = straight([[0.0, 0.0], [1.0, 0.2], [0.1, 0.8]]);
        let m = element_mass(&xe, 1.3);
        let full = expand(&m);
        let x: [f64; 12] = std::array::from_fn(|i| (i as f64 * 0.37).sin());
        let y = apply(&m, &x);
        for i in 0..12 {
            let yi: f64 = (0..12).map(|j| full[i * 12 + j] * x[j]).sum();
            assert!((yi - y[i]).abs() <= 1e-15 * 10.0);
            for j in 0..12 {
                assert_eq!(full[i * 12 + j], full[j * 12 + i]);
            }
        }
    }
}
