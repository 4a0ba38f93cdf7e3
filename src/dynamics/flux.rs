//! The energy release rate at a moving front of weakening, measured from the bulk fields by the
//! dynamic J-integral in its domain form.
//!
//! # The integral
//!
//! For a front moving along `e₁ = (s, 0)` (`s = ±1`) at the point `x_t` of the contact line, with
//! `W = ½ σ:ε` the strain energy and `T = ½ ρ |u̇|²` the kinetic energy densities, the energy
//! flux into a contour `C` around the front, `J_C = ∫_C [(W + T) n₁ − σ_ij n_j u_i,₁] ds`, equals
//! over the region `A` between `C` and an outer contour (Moran & Shih 1987)
//!
//! ```text
//!   J_C = ∫_A [σ_ij u_i,₁ − (W + T) δ_1j] q,_j dA + ∫_A ρ [ü_i u_i,₁ − u̇_i u̇_i,₁] q dA
//!         + ∫_faces τ v̂,₁ q dx₁
//! ```
//!
//! with a weight `q` that is 1 on `C` and 0 on the outer contour. The last term is the work of
//! the contact's shear traction `τ` (on the slave body, along its tangent) on the gradient of
//! the relative tangential displacement `v̂` (master minus slave, along the same tangent)
//! between the two faces; the pressure does no work on a closed contact. The identity uses only
//! the balance of momentum `σ_ij,j = ρ ü_i` and `W,₁ = σ_ij u_i,j1`: it holds for any motion,
//! steady or not.
//!
//! A slip-weakening front has no singularity: the flux into a vanishing contour is zero, and all
//! the energy arrives at the faces. Splitting the shear into the residual friction `τ_r =
//! sign(τ) f_d p` and the excess `τ − τ_r`, the energy spent on weakening per unit advance is
//!
//! ```text
//!   G = −∫ (τ − τ_r) v̂,₁ q dx₁ = J_bulk + ∫_faces τ_r v̂,₁ q dx₁
//! ```
//!
//! where `J_bulk` is the two area terms. With `q = 1` over the whole process zone and a front
//! moving steadily, `G` is the fracture energy `Γ = ∫ (τ − τ_r) dδ` of the law, whatever the
//! speed: [`release_rate`] measures the left side from the bodies' strains, velocities and
//! accelerations, which is what makes the comparison with `Γ` a test of the fields around the
//! front (and the quantity an experiment infers from strains near a rupture front).
//!
//! # The weight
//!
//! `q(r) = 1` for `r ≤ r_in`, `(r_out − r)/(r_out − r_in)` up to `r_out`, 0 beyond (`r` the
//! distance to the front), evaluated exactly at each quadrature point of the degree-4 rule.

use crate::contact::solver::{State, Status};
use crate::elasticity::Material;
use crate::friction::FrictionLaw;
use crate::model::Model;
use crate::model::fronts::{WeakeningFront, process_slip, weakening_fronts};
use crate::quadrature::TRI_6;
use crate::record::FrontFigures;
use crate::shapes::tri6;

use super::TimeState;

/// The region of a domain integral: the front at `tip`, moving along `(dir, 0)`, `q = 1`
/// within `r_in` and 0 beyond `r_out` (`0 < r_in < r_out`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Domain {
    pub tip: [f64; 2],
    pub dir: f64,
    pub r_in: f64,
    pub r_out: f64,
}

impl Domain {
    /// `q` and its gradient at `x`.
    pub fn q(&self, x: [f64; 2]) -> (f64, [f64; 2]) {
        let d = [x[0] - self.tip[0], x[1] - self.tip[1]];
        let r = d[0].hypot(d[1]);
        if r <= self.r_in {
            (1.0, [0.0; 2])
        } else if r >= self.r_out {
            (0.0, [0.0; 2])
        } else {
            let w = self.r_out - self.r_in;
            ((self.r_out - r) / w, [-d[0] / (r * w), -d[1] / (r * w)])
        }
    }

    /// Whether an element with nodes `xe` can reach into the region (its bounding box is
    /// within `r_out` of the front).
    pub fn touches(&self, xe: &[[f64; 2]; 6]) -> bool {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in xe {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let gap = |k: usize| (lo[k] - self.tip[k]).max(self.tip[k] - hi[k]).max(0.0);
        gap(0).hypot(gap(1)) < self.r_out
    }
}

/// One element's fields for the domain integral: node coordinates, nodal displacement, velocity
/// and acceleration (x, y per node, in node order), material and density.
pub struct ElementFields {
    pub xe: [[f64; 2]; 6],
    pub u: [f64; 12],
    pub v: [f64; 12],
    pub a: [f64; 12],
    pub mat: Material,
    pub rho: f64,
}

/// The area terms `J_bulk` of the domain integral over `elements` (see the module docs).
pub fn bulk_integral(elements: impl IntoIterator<Item = ElementFields>, d: &Domain) -> f64 {
    let mut total = 0.0;
    for el in elements {
        for &([xi, eta], w) in &TRI_6 {
            let mp = tri6::map_point(&el.xe, xi, eta);
            let (q, dq) = d.q(mp.x);
            if q == 0.0 && dq == [0.0; 2] {
                continue;
            }
            // Gradients ∂u_i/∂x_j of the displacement and of the velocity; the point's
            // velocity and acceleration.
            let (mut gu, mut gv) = ([[0.0; 2]; 2], [[0.0; 2]; 2]);
            let (mut vel, mut acc) = ([0.0; 2], [0.0; 2]);
            for n in 0..6 {
                for i in 0..2 {
                    for j in 0..2 {
                        gu[i][j] += mp.dndx[n][j] * el.u[2 * n + i];
                        gv[i][j] += mp.dndx[n][j] * el.v[2 * n + i];
                    }
                    vel[i] += mp.n[n] * el.v[2 * n + i];
                    acc[i] += mp.n[n] * el.a[2 * n + i];
                }
            }
            let eps = [gu[0][0], gu[1][1], gu[0][1] + gu[1][0]];
            let s = el.mat.stress(eps);
            let sigma = [[s[0], s[2]], [s[2], s[1]]];
            let energy = 0.5 * (s[0] * eps[0] + s[1] * eps[1] + s[2] * eps[2])
                + 0.5 * el.rho * (vel[0] * vel[0] + vel[1] * vel[1]);
            // Derivatives along the front's direction e₁ = (dir, 0).
            let u1 = [d.dir * gu[0][0], d.dir * gu[1][0]];
            let v1 = [d.dir * gv[0][0], d.dir * gv[1][0]];
            let mut f = -energy * d.dir * dq[0];
            for i in 0..2 {
                f += u1[i] * (sigma[i][0] * dq[0] + sigma[i][1] * dq[1]);
                f += el.rho * (acc[i] * u1[i] - vel[i] * v1[i]) * q;
            }
            total += f * mp.det_j * w;
        }
    }
    total
}

/// The face term `∫ τ_r v̂,₁ q dx₁` along the contact line: `x` the slave nodes' abscissae in
/// increasing order, `v_hat` their relative tangential displacement and `tau_r` the residual
/// shear they carry (signed as the shear), the contact line at the height of the front. Each
/// interval between two nodes contributes `τ_r (v̂_{k+1} − v̂_k) s q` at its middle.
pub fn face_integral(x: &[f64], v_hat: &[f64], tau_r: &[f64], d: &Domain) -> f64 {
    (0..x.len().saturating_sub(1))
        .map(|k| {
            let xm = 0.5 * (x[k] + x[k + 1]);
            let (q, _) = d.q([xm, d.tip[1]]);
            0.5 * (tau_r[k] + tau_r[k + 1]) * (v_hat[k + 1] - v_hat[k]) * d.dir * q
        })
        .sum()
}

/// The energy release rate `G = J_bulk + ∫ τ_r v̂,₁ q dx₁` of the front of domain `d`.
pub fn release_rate(
    elements: impl IntoIterator<Item = ElementFields>,
    face: (&[f64], &[f64], &[f64]),
    d: &Domain,
) -> f64 {
    bulk_integral(elements, d) + face_integral(face.0, face.1, face.2, d)
}

/// The fronts of weakening of a state integrated in time (`now`, contact state `st`, friction
/// law `law`, bodies of density `density[b]`, the elements `near` the slave face
/// ([`near_face`])): their positions, energy release rates `G`
/// ([`release_rate`]) and the fracture energies `Γ = (W/p) p̄` of their process zones (`p̄` the
/// mean pressure on its nodes). No front without weakening.
pub fn front_figures(
    model: &Model,
    (density, near): (&[f64], &[usize]),
    now: &TimeState,
    st: &State,
    law: &FrictionLaw,
) -> FrontFigures {
    let mut out = FrontFigures::default();
    let (Some(cm), Ok(fd), Some(ps), Ok(w_p)) = (
        &model.contact,
        law.f_dynamic(),
        process_slip(law),
        law.w_over_p(),
    ) else {
        return out;
    };
    let m = &cm.pair.mortar;
    let mut order: Vec<usize> = (0..m.slave_nodes.len()).collect();
    let pos = |j: usize| model.mesh.nodes[m.slave_nodes[j]];
    order.sort_by(|&a, &b| pos(a)[0].total_cmp(&pos(b)[0]));
    let x: Vec<f64> = order.iter().map(|&j| pos(j)[0]).collect();
    let on: Vec<bool> = order
        .iter()
        .map(|&j| st.status[j] != Status::Open)
        .collect();
    let fs = law.f_static();
    let weak: Vec<bool> = order
        .iter()
        .map(|&j| law.mu(st.slip_mu[j]) < fs - 1e-9 * (fs - fd))
        .collect();
    let slip: Vec<f64> = order.iter().map(|&j| st.slip_mu[j]).collect();
    let p: Vec<f64> = order.iter().map(|&j| st.f_n[j] / m.weight[j]).collect();
    let v_hat: Vec<f64> = order.iter().map(|&j| st.v[j]).collect();
    let tau_r: Vec<f64> = order
        .iter()
        .zip(&on)
        .map(|(&j, &c)| {
            if c {
                (-st.f_t[j]).signum() * fd * st.f_n[j] / m.weight[j]
            } else {
                0.0
            }
        })
        .collect();
    let fronts = weakening_fronts(&x, &on, &weak, &slip, ps);
    let ends = [x[0], x[x.len() - 1]];
    for side in 0..2 {
        let Some(f) = fronts[side] else { continue };
        out.front[side] = Some(f.x);
        let (lo, hi) = f.nodes;
        out.gamma[side] = Some(w_p * p[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64);
        let other = fronts[1 - side].map(|o| o.x);
        let y = pos(order[f.nodes.0])[1];
        if let Some(d) = domain_of(&f, y, ends, other) {
            out.g[side] = bulk_fields(model, (density, near), now, &d)
                .map(|els| release_rate(els, (&x, &v_hat, &tau_r), &d));
        }
    }
    out
}

/// The elements (indices into `model.elems`) that a front's domain can reach: those within half
/// the slave face's extent of its bounding box. A domain fits between the face's ends
/// ([`domain_of`]), so its radius is below half the face's extent along x.
pub fn near_face(model: &Model) -> Vec<usize> {
    let Some(cm) = &model.contact else {
        return Vec::new();
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &n in &cm.pair.mortar.slave_nodes {
        for k in 0..2 {
            lo[k] = lo[k].min(model.mesh.nodes[n][k]);
            hi[k] = hi[k].max(model.mesh.nodes[n][k]);
        }
    }
    let reach = 0.5 * (hi[0] - lo[0]);
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let half = [0.5 * (hi[0] - lo[0]) + reach, 0.5 * (hi[1] - lo[1]) + reach];
    (0..model.elems.len())
        .filter(|&i| {
            let xe = model.mesh.tri_coords(model.elems[i].0);
            (0..2).all(|k| {
                let (a, b) = xe
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                        (a.min(p[k]), b.max(p[k]))
                    });
                b >= centre[k] - half[k] && a <= centre[k] + half[k]
            })
        })
        .collect()
}

/// The domain of front `f` on the contact line at height `y` with ends `ends` and the other
/// front at `other` (see the module docs); `None` where it does not fit.
fn domain_of(f: &WeakeningFront, y: f64, ends: [f64; 2], other: Option<f64>) -> Option<Domain> {
    let h_e = 2.0 * f.spacing;
    let r_in = (1.25 * f.process + h_e).max(4.0 * h_e);
    let r_out = 2.0 * r_in;
    let room = (f.x - ends[0]).min(ends[1] - f.x);
    let apart = other.map_or(f64::INFINITY, |o| 0.5 * (o - f.x).abs());
    (r_out < room && r_out < apart).then_some(Domain {
        tip: [f.x, y],
        dir: f.dir,
        r_in,
        r_out,
    })
}

/// The fields of the elements that reach into `d`; `None` if one of them is of the mixed
/// (nearly incompressible) formulation, whose stress the integrand does not take.
fn bulk_fields(
    model: &Model,
    (density, near): (&[f64], &[usize]),
    now: &TimeState,
    d: &Domain,
) -> Option<Vec<ElementFields>> {
    let table = model.element_dof_table();
    let n_free = model.dofs.n_free();
    let mut out = Vec::new();
    for &i in near {
        let (e, mat) = &model.elems[i];
        let xe = model.mesh.tri_coords(*e);
        if !d.touches(&xe) {
            continue;
        }
        if mat.is_mixed() {
            return None;
        }
        let free = |f: &[f64]| {
            table[i].map(|k| {
                let k = k as usize;
                if k < n_free { f[k] } else { 0.0 }
            })
        };
        out.push(ElementFields {
            xe,
            u: model.element_u(i, &now.u),
            v: free(&now.v),
            a: free(&now.a),
            mat: *mat,
            rho: density[model.elem_body[i]],
        });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane-strain mode-II displacement field of a crack along `x < 0` (tip at the
    /// origin) of intensity `k`, on the side `upper` of the crack (θ = ±π on its faces).
    fn mode_ii(p: [f64; 2], upper: bool, k: f64, mat: &Material) -> [f64; 2] {
        let (_, mu) = mat.lame();
        let kappa = 3.0 - 4.0 * mat.nu;
        let r = p[0].hypot(p[1]);
        let mut th = p[1].atan2(p[0]);
        if p[1] == 0.0 && p[0] < 0.0 {
            th = if upper {
                std::f64::consts::PI
            } else {
                -std::f64::consts::PI
            };
        }
        let c = k / (2.0 * mu) * (r / (2.0 * std::f64::consts::PI)).sqrt();
        let (s2, c2) = (0.5 * th).sin_cos();
        [
            c * s2 * (kappa + 1.0 + 2.0 * c2 * c2),
            -c * c2 * (kappa - 1.0 - 2.0 * s2 * s2),
        ]
    }

    /// 6-node triangles of a structured n × n grid over `[x0, x0 + w] × [y0, y0 + h]`.
    fn grid(n: usize, [x0, y0]: [f64; 2], w: f64, h: f64) -> Vec<[[f64; 2]; 6]> {
        let at = |i: f64, j: f64| [x0 + w * i / n as f64, y0 + h * j / n as f64];
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (i, j) = (i as f64, j as f64);
                let (a, b, c, d) = (
                    at(i, j),
                    at(i + 1.0, j),
                    at(i + 1.0, j + 1.0),
                    at(i, j + 1.0),
                );
                let mid = |p: [f64; 2], q: [f64; 2]| [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                out.push([a, b, c, mid(a, b), mid(b, c), mid(c, a)]);
                out.push([a, c, d, mid(a, c), mid(c, d), mid(d, a)]);
            }
        }
        out
    }

    /// The domain integral of the static mode-II field over two half-squares meeting along
    /// the crack line, each with its own nodes there, for a front moving along `dir`.
    fn static_j(n: usize, dir: f64, velocity: [f64; 2]) -> f64 {
        let mat = Material {
            e: 5650.0,
            nu: 0.35,
        };
        let k = 2.0;
        let half = 10.0;
        let d = Domain {
            tip: [0.0, 0.0],
            dir,
            r_in: 3.0,
            r_out: 8.0,
        };
        let mut els = Vec::new();
        for (upper, y0) in [(true, 0.0), (false, -half)] {
            for xe in grid(n, [-half, y0], 2.0 * half, half) {
                let mut u = [0.0; 12];
                let mut v = [0.0; 12];
                for (m, p) in xe.iter().enumerate() {
                    // The field of a crack behind the front: mirrored for a front moving in −x.
                    let q = [dir * p[0], p[1]];
                    let w = mode_ii(q, upper, k, &mat);
                    u[2 * m] = dir * w[0];
                    u[2 * m + 1] = w[1];
                    v[2 * m] = velocity[0];
                    v[2 * m + 1] = velocity[1];
                }
                els.push(ElementFields {
                    xe,
                    u,
                    v,
                    a: [0.0; 12],
                    mat,
                    rho: 1.17e-9,
                });
            }
        }
        let g = k * k / mat.plane_strain_modulus();
        bulk_integral(els, &d) / g
    }

    #[test]
    fn the_domain_integral_of_the_mode_ii_field_is_its_energy_release_rate_in_either_direction() {
        // G = K²(1 − ν²)/E: the integral converges to it at second order as the grid is refined
        // (measured 1.4e-2, 2.8e-3, 7.0e-4 at 8, 16, 32 cells a side), for a front
        // moving in +x or in −x, and a uniform velocity adds nothing.
        let e: Vec<f64> = [8, 16, 32]
            .iter()
            .map(|&n| (static_j(n, 1.0, [0.0; 2]) - 1.0).abs())
            .collect();
        assert!(e[2] < 1e-3, "J/G − 1 = {e:?}");
        assert!(
            e[1] / e[2] > 3.5 && e[0] / e[1] > 3.5,
            "errors {e:?} do not converge"
        );
        let left = static_j(32, -1.0, [0.0; 2]);
        assert!(
            (left - 1.0).abs() < 1e-3,
            "front moving in −x: J/G = {left}"
        );
        let moving = static_j(32, 1.0, [3.0e3, -1.0e3]);
        assert!(
            (moving - static_j(32, 1.0, [0.0; 2])).abs() < 1e-12,
            "J/G = {moving}"
        );
    }

    #[test]
    fn the_weight_is_one_inside_zero_outside_and_linear_between() {
        let d = Domain {
            tip: [1.0, 0.0],
            dir: 1.0,
            r_in: 1.0,
            r_out: 3.0,
        };
        assert_eq!(d.q([1.5, 0.0]), (1.0, [0.0; 2]));
        assert_eq!(d.q([5.0, 0.0]), (0.0, [0.0; 2]));
        let (q, g) = d.q([3.0, 0.0]);
        assert!((q - 0.5).abs() < 1e-15 && (g[0] + 0.5).abs() < 1e-15 && g[1] == 0.0);
        let far = [
            [10.0, 10.0],
            [11.0, 10.0],
            [10.0, 11.0],
            [10.5, 10.0],
            [10.5, 10.5],
            [10.0, 10.5],
        ];
        assert!(!d.touches(&far));
        let near = far.map(|p| [p[0] - 8.5, p[1] - 10.0]);
        assert!(d.touches(&near));
    }

    #[test]
    fn the_face_term_is_the_residual_shear_times_the_slip_gradient_inside_the_weight() {
        // v̂ falling linearly by 1 per unit length towards a front moving in +x at x = 0,
        // residual shear 2: the integral over q is 2 × (−1) × (r_in + (r_out − r_in)/2).
        let d = Domain {
            tip: [0.0, 0.0],
            dir: 1.0,
            r_in: 2.0,
            r_out: 4.0,
        };
        let x: Vec<f64> = (0..=100).map(|k| -5.0 + 0.1 * k as f64).collect();
        let v: Vec<f64> = x.iter().map(|&x| if x < 0.0 { -x } else { 0.0 }).collect();
        let t = vec![2.0; x.len()];
        let f = face_integral(&x, &v, &t, &d);
        assert!((f + 2.0 * 3.0).abs() < 1e-12, "{f}");
    }
}
