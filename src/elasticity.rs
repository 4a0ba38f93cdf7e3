//! Plane-strain isotropic linear elasticity on isoparametric 6-node triangles.
//!
//! Strain `ε = (εxx, εyy, γxy)`, stress `σ = D ε` with the plane-strain matrix
//! `D = [[λ+2μ, λ, 0], [λ, λ+2μ, 0], [0, 0, μ]]`, `λ = Eν/((1+ν)(1−2ν))`, `μ = E/(2(1+ν))`,
//! and `σzz = ν (σxx + σyy)`.
//!
//! Element matrices integrate with the 6-point degree-4 rule: exact for straight-sided
//! elements (the integrand is of degree 2) and accurate for curved ones.
//!
//! **Nearly incompressible bodies** (ν ≥ [`NEARLY_INCOMPRESSIBLE`]): the quadratic
//! displacement field cannot keep its divergence near zero at every quadrature point, and the
//! `λ θ²` energy locks it (on VM272 L3 the Hertz a comes out 2.3 % small at ν = 0.4999).
//! Those bodies use the mixed P2/P0 element in its B-bar form: the dilatation in the λ term is
//! the element mean `θ̄ = (1/A) ∫ θ dA`, a constant pressure per element (inf-sup stable with
//! quadratic displacements), so `σ = 2μ ε + λ θ̄ I` (and `σzz = λ θ̄`) and
//! `K = ∫ Bᵀ (μ D₀) B dA + λ A b̄ b̄ᵀ` with `D₀ = diag(2, 2, 1)` and `b̄` the mean divergence
//! row. Bodies with ν below the threshold keep the standard element, bit for bit.

use crate::quadrature::{TRI_3, TRI_6};
use crate::shapes::tri6::{self, MapPoint};

/// Poisson's ratio from which a body uses the mixed P2/P0 (B-bar) element.
pub const NEARLY_INCOMPRESSIBLE: f64 = 0.49;

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

    /// Whether this material uses the mixed P2/P0 (B-bar) element (see the module docs).
    pub fn is_mixed(&self) -> bool {
        self.nu >= NEARLY_INCOMPRESSIBLE
    }

    /// Stress (σxx, σyy, σxy, σzz) from the strain and the dilatation of the λ term: the
    /// element mean θ̄ for a mixed element, `εxx + εyy` otherwise.
    pub fn stress4(&self, eps: [f64; 3], theta: f64) -> [f64; 4] {
        if self.is_mixed() {
            let (l, m) = self.lame();
            [
                2.0 * m * eps[0] + l * theta,
                2.0 * m * eps[1] + l * theta,
                m * eps[2],
                l * theta,
            ]
        } else {
            let s = self.stress(eps);
            [s[0], s[1], s[2], self.sigma_zz(s)]
        }
    }
}

/// The reference derivatives of the shape functions at the points of [`TRI_6`] (for
/// [`tri6::gradients`]: the element loops over the rule then map only the gradients, with the
/// bits of [`tri6::map_point`]).
const TRI_6_DN: [[[f64; 2]; 6]; 6] = {
    let mut d = [[[0.0; 2]; 6]; 6];
    let mut q = 0;
    while q < 6 {
        d[q] = tri6::dn(TRI_6[q].0[0], TRI_6[q].0[1]);
        q += 1;
    }
    d
};

/// The element mean of the divergence row, `b̄ = (1/A) ∫ (N_a,x, N_a,y) dA` (12 entries),
/// and the element area A.
pub fn mean_divergence(xe: &[[f64; 2]; 6]) -> ([f64; 12], f64) {
    let mut b = [0.0; 12];
    let mut area = 0.0;
    for ((_, w), d) in TRI_6.iter().zip(&TRI_6_DN) {
        let (det_j, dndx) = tri6::gradients(xe, d);
        let s = w * det_j;
        area += s;
        for a in 0..6 {
            b[2 * a] += s * dndx[a][0];
            b[2 * a + 1] += s * dndx[a][1];
        }
    }
    b.iter_mut().for_each(|v| *v /= area);
    (b, area)
}

/// The dilatation of the λ term for an element: θ̄ for a mixed material, NaN (unused) else.
fn element_theta(xe: &[[f64; 2]; 6], ue: &[f64; 12], mat: &Material) -> f64 {
    if mat.is_mixed() {
        let (b, _) = mean_divergence(xe);
        b.iter().zip(ue).map(|(b, u)| b * u).sum()
    } else {
        f64::NAN
    }
}

/// Stress (σxx, σyy, σxy, σzz) at a mapped point of an element with displacements `ue`.
pub fn stress_at_point(
    xe: &[[f64; 2]; 6],
    mp: &MapPoint,
    ue: &[f64; 12],
    mat: &Material,
) -> [f64; 4] {
    mat.stress4(strain(mp, ue), element_theta(xe, ue, mat))
}

/// Element stiffness (12 × 12, row-major; DOF order `[u0x, u0y, u1x, …]`).
///
/// `K_ab = Σ_q w_q det J_q [[(λ+2μ) Na,x Nb,x + μ Na,y Nb,y, λ Na,x Nb,y + μ Na,y Nb,x],
///                          [λ Na,y Nb,x + μ Na,x Nb,y, (λ+2μ) Na,y Nb,y + μ Na,x Nb,x]]`
pub fn element_stiffness(xe: &[[f64; 2]; 6], mat: &Material) -> [f64; 144] {
    if mat.is_mixed() {
        return mixed_element_stiffness(xe, mat);
    }
    let (l, m) = mat.lame();
    let mut k = [0.0; 144];
    for ((_, w), d) in TRI_6.iter().zip(&TRI_6_DN) {
        let (det_j, g) = tri6::gradients(xe, d);
        let s = w * det_j;
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

/// The mixed P2/P0 (B-bar) stiffness `∫ Bᵀ (μ D₀) B dA + λ A b̄ b̄ᵀ` (see the module docs).
fn mixed_element_stiffness(xe: &[[f64; 2]; 6], mat: &Material) -> [f64; 144] {
    let (l, m) = mat.lame();
    let mut k = [0.0; 144];
    for ((_, w), d) in TRI_6.iter().zip(&TRI_6_DN) {
        let (det_j, g) = tri6::gradients(xe, d);
        let s = w * det_j;
        for a in 0..6 {
            for b in 0..6 {
                let (ax, ay, bx, by) = (g[a][0], g[a][1], g[b][0], g[b][1]);
                k[(2 * a) * 12 + 2 * b] += s * m * (2.0 * ax * bx + ay * by);
                k[(2 * a) * 12 + 2 * b + 1] += s * m * ay * bx;
                k[(2 * a + 1) * 12 + 2 * b] += s * m * ax * by;
                k[(2 * a + 1) * 12 + 2 * b + 1] += s * m * (2.0 * ay * by + ax * bx);
            }
        }
    }
    let (bbar, area) = mean_divergence(xe);
    for i in 0..12 {
        for j in 0..12 {
            k[i * 12 + j] += l * area * bbar[i] * bbar[j];
        }
    }
    k
}

/// What [`element_forces`] reads of an element's geometry and material: per point of the rule,
/// `w det J` and the shape-function gradients; the largest entry of `K_e` in magnitude (its
/// largest diagonal entry: `K_e` is positive semi-definite, `|K_ij| ≤ √(K_ii K_jj)`); and
/// for a mixed element its mean divergence and area. Kept per element by a model whose
/// element forces are wanted many times (a sweep's checks, one per row).
pub struct ForceGeometry {
    s: [f64; 6],
    dndx: [[[f64; 2]; 6]; 6],
    kmax: f64,
    mean_divergence: Option<Box<([f64; 12], f64)>>,
}

impl ForceGeometry {
    /// The largest entry of the element's `K_e` in magnitude.
    pub fn kmax(&self) -> f64 {
        self.kmax
    }
}

/// The [`ForceGeometry`] of an element.
pub fn force_geometry(xe: &[[f64; 2]; 6], mat: &Material) -> ForceGeometry {
    let (l, m) = mat.lame();
    let mixed = mat.is_mixed();
    let mut s = [0.0; 6];
    let mut dndx = [[[0.0; 2]; 6]; 6];
    let mut diag = [0.0; 12];
    let (a_xx, a_yy) = if mixed {
        (2.0 * m, m)
    } else {
        (l + 2.0 * m, m)
    };
    for (q, ((_, w), d)) in TRI_6.iter().zip(&TRI_6_DN).enumerate() {
        let (det_j, g6) = tri6::gradients(xe, d);
        s[q] = w * det_j;
        dndx[q] = g6;
        for (a, g) in g6.iter().enumerate() {
            let (ax, ay) = (g[0], g[1]);
            diag[2 * a] += s[q] * (a_xx * ax * ax + a_yy * ay * ay);
            diag[2 * a + 1] += s[q] * (a_xx * ay * ay + a_yy * ax * ax);
        }
    }
    let mean_divergence = mixed.then(|| {
        let (bbar, area) = mean_divergence(xe);
        for i in 0..12 {
            diag[i] += l * area * bbar[i] * bbar[i];
        }
        Box::new((bbar, area))
    });
    ForceGeometry {
        s,
        dndx,
        kmax: diag.iter().fold(0.0f64, |a, d| a.max(d.abs())),
        mean_divergence,
    }
}

/// The internal nodal forces `K_e u_e` of an element with displacements `ue`, integrated like
/// [`element_stiffness`] (the same rule) without forming `K_e`: `Σ_q w_q det J_q B_qᵀ σ_q`, plus
/// `λ A b̄ (b̄ · u_e)` for a mixed element. Also the largest entry of `K_e` in magnitude.
pub fn element_forces(xe: &[[f64; 2]; 6], ue: &[f64; 12], mat: &Material) -> ([f64; 12], f64) {
    element_forces_with(&force_geometry(xe, mat), ue, mat)
}

/// [`element_forces`] from the element's [`ForceGeometry`] (the same arithmetic):
/// [`element_forces_lanes`] of one set.
pub fn element_forces_with(
    geo: &ForceGeometry,
    ue: &[f64; 12],
    mat: &Material,
) -> ([f64; 12], f64) {
    debug_assert_eq!(
        geo.mean_divergence.is_some(),
        mat.is_mixed(),
        "the geometry of another material"
    );
    let f = element_forces_lanes(geo, &ue.map(|v| [v]), mat);
    (f.map(|[v]| v), geo.kmax)
}

/// [`strain_of`] of `R` displacement sets at once (lane by lane, the same operations).
#[inline(always)]
fn strain_lanes<const R: usize>(dndx: &[[f64; 2]; 6], ue: &[[f64; R]; 12]) -> [[f64; R]; 3] {
    let mut e = [[0.0; R]; 3];
    for a in 0..6 {
        let (gx, gy) = (dndx[a][0], dndx[a][1]);
        for j in 0..R {
            e[0][j] += gx * ue[2 * a][j];
            e[1][j] += gy * ue[2 * a + 1][j];
            e[2][j] += gy * ue[2 * a][j] + gx * ue[2 * a + 1][j];
        }
    }
    e
}

/// [`element_forces_with`] of `R` displacement sets at once (entry `[k][j]`: DOF `k` of set
/// `j`): the geometry read once for all of them, each lane the same operations in the same
/// order as the one-set function, so the same bits.
#[inline(always)]
pub fn element_forces_lanes<const R: usize>(
    geo: &ForceGeometry,
    ue: &[[f64; R]; 12],
    mat: &Material,
) -> [[f64; R]; 12] {
    let (l, m) = mat.lame();
    let mixed = geo.mean_divergence.is_some();
    let mut f = [[0.0; R]; 12];
    for (s, dndx) in geo.s.iter().zip(&geo.dndx) {
        let e = strain_lanes(dndx, ue);
        // `Material::stress`, or the B part of a mixed element.
        let mut sig = [[0.0; R]; 3];
        for j in 0..R {
            if mixed {
                sig[0][j] = 2.0 * m * e[0][j];
                sig[1][j] = 2.0 * m * e[1][j];
                sig[2][j] = m * e[2][j];
            } else {
                sig[0][j] = (l + 2.0 * m) * e[0][j] + l * e[1][j];
                sig[1][j] = l * e[0][j] + (l + 2.0 * m) * e[1][j];
                sig[2][j] = m * e[2][j];
            }
        }
        for (a, g) in dndx.iter().enumerate() {
            let (ax, ay) = (g[0], g[1]);
            for j in 0..R {
                f[2 * a][j] += s * (ax * sig[0][j] + ay * sig[2][j]);
                f[2 * a + 1][j] += s * (ay * sig[1][j] + ax * sig[2][j]);
            }
        }
    }
    if let Some(md) = &geo.mean_divergence {
        let (bbar, area) = (&md.0, md.1);
        for j in 0..R {
            let theta: f64 = bbar.iter().zip(ue).map(|(b, u)| b * u[j]).sum();
            for i in 0..12 {
                f[i][j] += l * area * bbar[i] * theta;
            }
        }
    }
    f
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
    strain_of(&mp.dndx, ue)
}

/// Strain from the shape-function gradients `dndx` at a point.
fn strain_of(dndx: &[[f64; 2]; 6], ue: &[f64; 12]) -> [f64; 3] {
    let mut e = [0.0; 3];
    for a in 0..6 {
        let (gx, gy) = (dndx[a][0], dndx[a][1]);
        e[0] += gx * ue[2 * a];
        e[1] += gy * ue[2 * a + 1];
        e[2] += gy * ue[2 * a] + gx * ue[2 * a + 1];
    }
    e
}

/// Stress (σxx, σyy, σxy, σzz) at the six nodes of an element, recovered from the three
/// degree-2 quadrature points (ξ, η ∈ {1/6, 2/3}) by the linear field through them.
pub fn nodal_stress(xe: &[[f64; 2]; 6], ue: &[f64; 12], mat: &Material) -> [[f64; 4]; 6] {
    nodal_stress_at(xe, ue, mat, &stress_point_gradients())
}

/// The reference derivatives of the shape functions at the three points of
/// [`nodal_stress`], for [`nodal_stress_at`].
pub fn stress_point_gradients() -> [[[f64; 2]; 6]; 3] {
    std::array::from_fn(|q| tri6::dn(TRI_3[q].0[0], TRI_3[q].0[1]))
}

/// [`nodal_stress`] with the reference derivatives `d3` of [`stress_point_gradients`]
/// evaluated once for a loop over elements (the same bits): [`nodal_stress_lanes`] of one set.
pub fn nodal_stress_at(
    xe: &[[f64; 2]; 6],
    ue: &[f64; 12],
    mat: &Material,
    d3: &[[[f64; 2]; 6]; 3],
) -> [[f64; 4]; 6] {
    nodal_stress_lanes(xe, &ue.map(|v| [v]), mat, d3).map(|a| a.map(|[v]| v))
}

/// [`nodal_stress_at`] of `R` displacement sets at once (`ue[k][j]`: DOF `k` of set `j`;
/// the result `[a][i][j]`: component `i` at node `a` of set `j`): the element's gradients
/// mapped once for all of them, each lane the same operations in the same order as the
/// one-set function, so the same bits.
#[inline(always)]
pub fn nodal_stress_lanes<const R: usize>(
    xe: &[[f64; 2]; 6],
    ue: &[[f64; R]; 12],
    mat: &Material,
    d3: &[[[f64; 2]; 6]; 3],
) -> [[[f64; R]; 4]; 6] {
    let mixed = mat.is_mixed();
    let (l, m) = mat.lame();
    // `element_theta`, lane by lane.
    let theta: [f64; R] = if mixed {
        let (b, _) = mean_divergence(xe);
        std::array::from_fn(|j| b.iter().zip(ue).map(|(b, u)| b * u[j]).sum())
    } else {
        [f64::NAN; R]
    };
    let g: [[[f64; R]; 4]; 3] = std::array::from_fn(|q| {
        let (_, dndx) = tri6::gradients(xe, &d3[q]);
        // `strain_of`, then `Material::stress4`, lane by lane.
        let e = strain_lanes(&dndx, ue);
        let mut s = [[0.0; R]; 4];
        for j in 0..R {
            if mixed {
                s[0][j] = 2.0 * m * e[0][j] + l * theta[j];
                s[1][j] = 2.0 * m * e[1][j] + l * theta[j];
                s[2][j] = m * e[2][j];
                s[3][j] = l * theta[j];
            } else {
                s[0][j] = (l + 2.0 * m) * e[0][j] + l * e[1][j];
                s[1][j] = l * e[0][j] + (l + 2.0 * m) * e[1][j];
                s[2][j] = m * e[2][j];
                s[3][j] = mat.nu * (s[0][j] + s[1][j]);
            }
        }
        s
    });
    let mut out = [[[0.0; R]; 4]; 6];
    for (a, r) in tri6::NODE_REF_COORDS.iter().enumerate() {
        // Local coordinates in the triangle of the quadrature points.
        let s = (r[0] - 1.0 / 6.0) * 2.0;
        let t = (r[1] - 1.0 / 6.0) * 2.0;
        let c = [1.0 - s - t, s, t];
        for j in 0..R {
            for i in 0..3 {
                out[a][i][j] = c[0] * g[0][i][j] + c[1] * g[1][i][j] + c[2] * g[2][i][j];
            }
            out[a][3][j] = if mixed {
                g[0][3][j]
            } else {
                mat.nu * (out[a][0][j] + out[a][1][j])
            };
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
        for nu in [0.3, 0.4999] {
            symmetric_with_rigid_body_null_space(Material { e: 200.0, nu });
        }
    }

    fn symmetric_with_rigid_body_null_space(mat: Material) {
        let xe = curved_element();
        let k = element_stiffness(&xe, &mat);
        let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..12 {
            for j in 0..12 {
                assert!((k[i * 12 + j] - k[j * 12 + i]).abs() < 1e-12 * scale);
            }
        }
        // Translations and the infinitesimal rotation give no force.
        let modes: [fn([f64; 2]) -> [f64; 2]; 3] =
            [|_| [1.0, 0.0], |_| [0.0, 1.0], |x| [-x[1], x[0]]];
        for m in modes.iter() {
            let u: Vec<f64> = xe.iter().flat_map(|x| m(*x)).collect();
            for i in 0..12 {
                let f: f64 = (0..12).map(|j| k[i * 12 + j] * u[j]).sum();
                assert!(f.abs() < 1e-11 * scale, "{f}");
            }
        }
    }

    #[test]
    fn element_forces_are_k_times_u_and_kmax_the_largest_entry() {
        let xe = curved_element();
        let ue: [f64; 12] = std::array::from_fn(|i| ((i * 37 % 11) as f64 - 5.0) * 1e-3);
        for mat in [
            Material { e: 3.0, nu: 0.25 },
            Material { e: 2.0, nu: 0.4995 },
        ] {
            let k = element_stiffness(&xe, &mat);
            let (f, kmax) = element_forces(&xe, &ue, &mat);
            let kmax_k = k.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(
                (kmax - kmax_k).abs() <= 1e-14 * kmax_k,
                "{kmax} against {kmax_k}"
            );
            for i in 0..12 {
                let ku: f64 = (0..12).map(|j| k[i * 12 + j] * ue[j]).sum();
                let size: f64 = (0..12).map(|j| (k[i * 12 + j] * ue[j]).abs()).sum();
                assert!(
                    (f[i] - ku).abs() <= 1e-13 * size,
                    "row {i}: {} against {ku}",
                    f[i]
                );
            }
        }
    }

    /// One set's element forces and nodal stresses written out plainly (the arithmetic the
    /// lanes must repeat, operation for operation): the oracle of the test below.
    fn forces_one_set(geo: &ForceGeometry, ue: &[f64; 12], mat: &Material) -> [f64; 12] {
        let (l, m) = mat.lame();
        let mut f = [0.0; 12];
        for (s, dndx) in geo.s.iter().zip(&geo.dndx) {
            let e = strain_of(dndx, ue);
            let sig = if geo.mean_divergence.is_some() {
                [2.0 * m * e[0], 2.0 * m * e[1], m * e[2]]
            } else {
                mat.stress(e)
            };
            for (a, g) in dndx.iter().enumerate() {
                let (ax, ay) = (g[0], g[1]);
                f[2 * a] += s * (ax * sig[0] + ay * sig[2]);
                f[2 * a + 1] += s * (ay * sig[1] + ax * sig[2]);
            }
        }
        if let Some(md) = &geo.mean_divergence {
            let (bbar, area) = (&md.0, md.1);
            let theta: f64 = bbar.iter().zip(ue).map(|(b, u)| b * u).sum();
            for i in 0..12 {
                f[i] += l * area * bbar[i] * theta;
            }
        }
        f
    }

    fn stress_one_set(xe: &[[f64; 2]; 6], ue: &[f64; 12], mat: &Material) -> [[f64; 4]; 6] {
        let theta = element_theta(xe, ue, mat);
        let d3 = stress_point_gradients();
        let g: [[f64; 4]; 3] = std::array::from_fn(|q| {
            let (_, dndx) = tri6::gradients(xe, &d3[q]);
            mat.stress4(strain_of(&dndx, ue), theta)
        });
        let mut out = [[0.0; 4]; 6];
        for (a, r) in tri6::NODE_REF_COORDS.iter().enumerate() {
            let s = (r[0] - 1.0 / 6.0) * 2.0;
            let t = (r[1] - 1.0 / 6.0) * 2.0;
            let c = [1.0 - s - t, s, t];
            for i in 0..3 {
                out[a][i] = c[0] * g[0][i] + c[1] * g[1][i] + c[2] * g[2][i];
            }
            out[a][3] = if mat.is_mixed() {
                g[0][3]
            } else {
                mat.sigma_zz([out[a][0], out[a][1], out[a][2]])
            };
        }
        out
    }

    /// Element forces and nodal stresses of several displacement sets at once (lanes; one
    /// set is the library's one-set path) are each set's own as written out plainly above,
    /// bit for bit, for either kind of element; a zero set gives zeros.
    #[test]
    fn lanes_give_the_bits_of_one_set_at_a_time() {
        fn check<const R: usize>(xe: &[[f64; 2]; 6], mat: &Material) {
            let sets: [[f64; 12]; R] = std::array::from_fn(|j| {
                std::array::from_fn(|i| {
                    if j == 1 {
                        0.0
                    } else {
                        ((i * 37 + j * 13) % 11) as f64 * 1e-3 - 5e-3 + 1e-4 * j as f64
                    }
                })
            });
            let ue: [[f64; R]; 12] = std::array::from_fn(|k| std::array::from_fn(|j| sets[j][k]));
            let geo = force_geometry(xe, mat);
            let fl = element_forces_lanes(&geo, &ue, mat);
            let d3 = stress_point_gradients();
            let sl = nodal_stress_lanes(xe, &ue, mat, &d3);
            for (j, set) in sets.iter().enumerate() {
                let f = forces_one_set(&geo, set, mat);
                for k in 0..12 {
                    assert_eq!(
                        f[k].to_bits(),
                        fl[k][j].to_bits(),
                        "force {k} of set {j} of {R}"
                    );
                }
                let s = stress_one_set(xe, set, mat);
                for a in 0..6 {
                    for i in 0..4 {
                        assert_eq!(
                            s[a][i].to_bits(),
                            sl[a][i][j].to_bits(),
                            "stress {i} at node {a} of set {j} of {R}"
                        );
                    }
                }
            }
        }
        let xe = curved_element();
        for mat in [
            Material { e: 3.0, nu: 0.25 },
            Material { e: 2.0, nu: 0.4995 },
        ] {
            check::<1>(&xe, &mat);
            check::<2>(&xe, &mat);
            check::<4>(&xe, &mat);
            check::<8>(&xe, &mat);
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
