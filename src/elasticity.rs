//! Plane-strain isotropic linear elasticity on isoparametric 6-node triangles.
//!
//! Strain `ε = (εxx, εyy, γxy)`, stress `σ = D ε` with the plane-strain matrix
//! `D = [[λ+2μ, λ, 0], [λ, λ+2μ, 0], [0, 0, μ]]`, `λ = Eν/((1+ν)(1−2ν))`, `μ = E/(2(1+ν))`,
//! and `σzz = ν (σxx + σyy)`.
//!
//! Element matrices integrate with the 6-point degree-4 rule: exact for straight-sided
//! elements (the integrand is of degree 2) and accurate for curved ones.

use crate::quadrature::{TRI_3, TRI_6};
use crate::shapes::tri6::{self, MapPoint};

/// An isotropic linear elastic material.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Material {
    /// Young's modulus.
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
}

impl Material {
    /// Lamé constants (λ, μ) of plane strain.
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.e, self.nu);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// Plane-strain modulus `E/(1 − ν²)`.
    pub fn plane_strain_modulus(&self) -> f64 {
        self.e / (1.0 - self.nu * self.nu)
    }

    /// Stress (σxx, σyy, σxy) from strain (εxx, εyy, γxy).
    pub fn stress(&self, eps: [f64; 3]) -> [f64; 3] {
        let (l, m) = self.lame();
        [
            (l + 2.0 * m) * eps[0] + l * eps[1],
            l * eps[0] + (l + 2.0 * m) * eps[1],
            m * eps[2],
        ]
    }

    /// Out-of-plane stress σzz of plane strain.
    pub fn sigma_zz(&self, s: [f64; 3]) -> f64 {
        self.nu * (s[0] + s[1])
    }
}

/// Element stiffness (12 × 12, row-major; DOF order `[u0x, u0y, u1x, …]`).
///
/// `K_ab = Σ_q w_q det J_q [[(λ+2μ) Na,x Nb,x + μ Na,y Nb,y, λ Na,x Nb,y + μ Na,y Nb,x],
///                          [λ Na,y Nb,x + μ Na,x Nb,y, (λ+2μ) Na,y Nb,y + μ Na,x Nb,x]]`
pub fn element_stiffness(xe: &[[f64; 2]; 6], mat: &Material) -> [f64; 144] {
    let (l, m) = mat.lame();
    let mut k = [0.0; 144];
    for (p, w) in TRI_6.iter() {
        let mp = tri6::map_point(xe, p[0], p[1]);
        let s = w * mp.det_j;
        let g = &mp.dndx;
        for a in 0..6 {
            for b in 0..6 {
                let (ax, ay, bx, by) = (g[a][0], g[a][1], g[b][0], g[b][1]);
                k[(2 * a) * 12 + 2 * b] += s * ((l + 2.0 * m) * ax * bx + m * ay * by);
                k[(2 * a) * 12 + 2 * b + 1] += s * (l * ax * by + m * ay * bx);
                k[(2 * a + 1) * 12 + 2 * b] += s * (l * ay * bx + m * ax * by);
                k[(2 * a + 1) * 12 + 2 * b + 1] += s * ((l + 2.0 * m) * ay * by + m * ax * bx);
            }
        }
    }
    k
}

/// Consistent nodal forces of a body force `b(x)` per unit volume (12 entries).
pub fn element_body_force(xe: &[[f64; 2]; 6], b: &dyn Fn([f64; 2]) -> [f64; 2]) -> [f64; 12] {
    let mut f = [0.0; 12];
    for (p, w) in crate::quadrature::TRI_7.iter() {
        let mp = tri6::map_point(xe, p[0], p[1]);
        let bv = b(mp.x);
        for a in 0..6 {
            f[2 * a] += w * mp.det_j * mp.n[a] * bv[0];
            f[2 * a + 1] += w * mp.det_j * mp.n[a] * bv[1];
        }
    }
    f
}

/// Strain (εxx, εyy, γxy) at a mapped point from element displacements `ue` (12 entries).
pub fn strain(mp: &MapPoint, ue: &[f64; 12]) -> [f64; 3] {
    let mut e = [0.0; 3];
    for a in 0..6 {
        let (gx, gy) = (mp.dndx[a][0], mp.dndx[a][1]);
        e[0] += gx * ue[2 * a];
        e[1] += gy * ue[2 * a + 1];
        e[2] += gy * ue[2 * a] + gx * ue[2 * a + 1];
    }
    e
}

/// Stress (σxx, σyy, σxy) at the six nodes of an element, recovered from the three
/// degree-2 quadrature points (ξ, η ∈ {1/6, 2/3}) by the linear field through them.
pub fn nodal_stress(xe: &[[f64; 2]; 6], ue: &[f64; 12], mat: &Material) -> [[f64; 3]; 6] {
    let g: Vec<[f64; 3]> = TRI_3
        .iter()
        .map(|(p, _)| {
            let mp = tri6::map_point(xe, p[0], p[1]);
            mat.stress(strain(&mp, ue))
        })
        .collect();
    let mut out = [[0.0; 3]; 6];
    for (a, r) in tri6::NODE_REF_COORDS.iter().enumerate() {
        // Local coordinates in the triangle of the quadrature points.
        let s = (r[0] - 1.0 / 6.0) * 2.0;
        let t = (r[1] - 1.0 / 6.0) * 2.0;
        let c = [1.0 - s - t, s, t];
        for i in 0..3 {
            out[a][i] = c[0] * g[0][i] + c[1] * g[1][i] + c[2] * g[2][i];
        }
    }
    out
}

/// von Mises equivalent stress including σzz.
pub fn von_mises(sxx: f64, syy: f64, sxy: f64, szz: f64) -> f64 {
    (0.5 * ((sxx - syy).powi(2) + (syy - szz).powi(2) + (szz - sxx).powi(2)) + 3.0 * sxy * sxy)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curved_element() -> [[f64; 2]; 6] {
        [
            [0.0, 0.0],
            [1.0, 0.1],
            [0.2, 0.9],
            [0.5, -0.05],
            [0.65, 0.55],
            [0.05, 0.45],
        ]
    }

    #[test]
    fn stiffness_is_symmetric_with_rigid_body_null_space() {
        let xe = curved_element();
        let mat = Material { e: 200.0, nu: 0.3 };
        let k = element_stiffness(&xe, &mat);
        let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..12 {
            for j in 0..12 {
                assert!((k[i * 12 + j] - k[j * 12 + i]).abs() < 1e-12 * scale);
            }
        }
        // Translations and the infinitesimal rotation give no force.
        let modes: [Box<dyn Fn([f64; 2]) -> [f64; 2]>; 3] = [
            Box::new(|_| [1.0, 0.0]),
            Box::new(|_| [0.0, 1.0]),
            Box::new(|x| [-x[1], x[0]]),
        ];
        for m in modes.iter() {
            let u: Vec<f64> = xe.iter().flat_map(|x| m(*x)).collect();
            for i in 0..12 {
                let f: f64 = (0..12).map(|j| k[i * 12 + j] * u[j]).sum();
                assert!(f.abs() < 1e-11 * scale, "{f}");
            }
        }
    }

    #[test]
    fn nodal_stress_of_a_linear_field_is_exact() {
        let xe = curved_element();
        let mat = Material { e: 3.0, nu: 0.25 };
        // u = (a x + b y, c x + d y): constant strain.
        let (a, b, c, d) = (1e-3, 2e-3, -5e-4, 7e-4);
        let ue: [f64; 12] = std::array::from_fn(|i| {
            let x = xe[i / 2];
            if i % 2 == 0 {
                a * x[0] + b * x[1]
            } else {
                c * x[0] + d * x[1]
            }
        });
        let exact = mat.stress([a, d, b + c]);
        for s in nodal_stress(&xe, &ue, &mat) {
            for i in 0..3 {
                assert!((s[i] - exact[i]).abs() < 1e-14);
            }
        }
    }
}
