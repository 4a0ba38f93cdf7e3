//! Time integration: the generalised-α scheme of Chung & Hulbert with the mortar contact and
//! friction Newton of the quasi-static steps in every time step.
//!
//! | module | content |
//! |---|---|
//! | this file | [`Scheme`]: the scheme's parameters from its spectral radius ρ∞ |
//! | `masses` | [`Masses`]: the consistent mass of the model's elements, `M x` and `½ vᵀ M v` |
//! | `integrator` | [`Integrator`]: one time step on the model of `K + c M` |
//! | `flux` | the fronts of weakening of a time step and the energy release rate reaching each (dynamic J-integral) |
//!
//! **The equations.** With `u, v, a` the free DOFs' displacement, velocity and acceleration,
//! `k(u)` the elastic forces, `T` the tractions and `r` the forces on the retained DOFs (the
//! pilot and the contact), each step satisfies the balance at the intermediate times
//! ```text
//!   M a_{n+1−αm} + (1−αf) [k(u_{n+1}) − T_{n+1} − r_{n+1}] + αf [k(u_n) − T_n − r_n] = 0,
//!   a_{n+1−αm} = (1−αm) a_{n+1} + αm a_n,
//! ```
//! with Newmark's updates
//! ```text
//!   u_{n+1} = u_n + Δt v_n + Δt² [(½ − β) a_n + β a_{n+1}],
//!   v_{n+1} = v_n + Δt [(1 − γ) a_n + γ a_{n+1}].
//! ```
//! The contact conditions (non-penetration, Coulomb friction with the slip-dependent μ) are
//! imposed on `u_{n+1}` and the contact forces `r_{n+1}` are those at `t_{n+1}`. Eliminating
//! `a_{n+1}` leaves, per step, the quasi-static contact problem
//! `(K + c M) u_{n+1} = f + r_{n+1}` with `c = (1−αm) / ((1−αf) β Δt²)` and a load `f` known
//! from step `n`: the contact Newton of [`crate::contact::solver`] on the Delassus operator
//! of `K + c M`, factorised once per time step size.
//!
//! **Energy.** For ρ∞ = 1 (αm = αf = ½, β = ¼, γ = ½) the scheme is the trapezoidal rule
//! on the balance at mid-step, and for a linear elastic body without contact
//! `Δ(½ vᵀMv + ½ uᵀKu) = ½ (f_{n+1} + f_n)·Δu` exactly: the trapezoidal work of
//! [`crate::energy`]. For ρ∞ < 1 the balance's residual is the scheme's own dissipation.
//! The contact forces are weighed like every force (`1 − αf`, `αf`); booked with the
//! trapezoid, a node that closes does `−½ F_n Δg ≤ 0`, one that stays closed or stuck does
//! none, and only a node that opens (`+½ F_n^old Δg`) or a slip that reverses can give energy
//! back: reported in `normal_work` and `dissipation` (`docs/dynamics.md` has the measured
//! figures).

pub mod flux;
mod integrator;
mod masses;

pub use integrator::{Integrator, TimeState};
pub use masses::Masses;

/// The parameters of the generalised-α scheme (Chung & Hulbert 1993) of spectral radius ρ∞:
/// second-order accurate, unconditionally stable for linear problems, with the largest high-
/// frequency dissipation for the least low-frequency dissipation:
/// ```text
///   αm = (2ρ∞ − 1)/(ρ∞ + 1),  αf = ρ∞/(ρ∞ + 1),  γ = ½ − αm + αf,  β = ¼ (1 − αm + αf)².
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Scheme {
    pub rho_inf: f64,
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub beta: f64,
    pub gamma: f64,
}

impl Scheme {
    /// The scheme of spectral radius `rho_inf` ∈ [0, 1].
    pub fn new(rho_inf: f64) -> Scheme {
        let r = rho_inf;
        let alpha_m = (2.0 * r - 1.0) / (r + 1.0);
        let alpha_f = r / (r + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        Scheme {
            rho_inf,
            alpha_m,
            alpha_f,
            beta,
            gamma,
        }
    }

    /// The mass coefficient of the step's matrix `K + c M`: `c = (1−αm)/((1−αf) β Δt²)`.
    pub fn mass_shift(&self, dt: f64) -> f64 {
        (1.0 - self.alpha_m) / ((1.0 - self.alpha_f) * self.beta * dt * dt)
    }

    /// One step of the scheme on the oscillator `ü + ω² u = 0` from `(u, v, a)`: the
    /// single-mode form of [`Integrator::step`], for checking the scheme's properties.
    pub fn oscillator_step(&self, omega: f64, dt: f64, (u, v, a): (f64, f64, f64)) -> [f64; 3] {
        let (am, af, b, g) = (self.alpha_m, self.alpha_f, self.beta, self.gamma);
        let k = omega * omega;
        // (1−αm) a1 + αm a + (1−αf) k u1 + αf k u = 0 with u1 = u + Δt v + Δt²((½−β) a + β a1).
        let pred = u + dt * v + dt * dt * (0.5 - b) * a;
        let a1 = -(am * a + (1.0 - af) * k * pred + af * k * u)
            / ((1.0 - am) + (1.0 - af) * k * b * dt * dt);
        let u1 = pred + b * dt * dt * a1;
        let v1 = v + dt * ((1.0 - g) * a + g * a1);
        [u1, v1, a1]
    }
}

#[cfg(test)]
mod tests {
    use super::Scheme;

    #[test]
    fn rho_one_is_the_trapezoidal_rule_and_conserves_the_oscillators_energy() {
        let s = Scheme::new(1.0);
        assert_eq!(
            (s.alpha_m, s.alpha_f, s.beta, s.gamma),
            (0.5, 0.5, 0.25, 0.5)
        );
        let (w, dt) = (3.0, 0.37);
        let mut x = (1.0, 0.0, -9.0);
        let e0 = 0.5 * (x.1 * x.1 + w * w * x.0 * x.0);
        for _ in 0..1000 {
            let [u, v, a] = s.oscillator_step(w, dt, x);
            x = (u, v, a);
        }
        let e = 0.5 * (x.1 * x.1 + w * w * x.0 * x.0);
        assert!((e - e0).abs() <= 1e-12 * e0, "{e} vs {e0}");
    }

    /// The spectral radius of the one-step amplification matrix of `(u, v, a)` at `ωΔt`.
    fn spectral_radius(s: &Scheme, omega_dt: f64) -> f64 {
        let cols: Vec<[f64; 3]> = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
            .into_iter()
            .map(|x| s.oscillator_step(omega_dt, 1.0, x))
            .collect();
        let a = |i: usize, j: usize| cols[j][i];
        // det(λI − A) = λ³ − c2 λ² + c1 λ − c0.
        let c2 = a(0, 0) + a(1, 1) + a(2, 2);
        let c1 = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0) + a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0)
            + a(1, 1) * a(2, 2)
            - a(1, 2) * a(2, 1);
        let c0 = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
            - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
            + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
        // Durand–Kerner on the complex roots.
        type C = (f64, f64);
        let mul = |x: C, y: C| (x.0 * y.0 - x.1 * y.1, x.0 * y.1 + x.1 * y.0);
        let sub = |x: C, y: C| (x.0 - y.0, x.1 - y.1);
        let div = |x: C, y: C| {
            let d = y.0 * y.0 + y.1 * y.1;
            ((x.0 * y.0 + x.1 * y.1) / d, (x.1 * y.0 - x.0 * y.1) / d)
        };
        let p = |z: C| {
            let z2 = mul(z, z);
            let z3 = mul(z2, z);
            (
                z3.0 - c2 * z2.0 + c1 * z.0 - c0,
                z3.1 - c2 * z2.1 + c1 * z.1,
            )
        };
        let mut r: [C; 3] = [(0.4, 0.9), (-0.7, 0.3), (0.2, -0.8)];
        for _ in 0..2000 {
            for i in 0..3 {
                let mut d = (1.0, 0.0);
                for j in 0..3 {
                    if j != i {
                        d = mul(d, sub(r[i], r[j]));
                    }
                }
                r[i] = sub(r[i], div(p(r[i]), d));
            }
        }
        r.iter().map(|z| z.0.hypot(z.1)).fold(0.0, f64::max)
    }

    /// The spectral radius is ρ∞ at ωΔt → ∞ and tends to 1 at ωΔt → 0.
    #[test]
    fn the_high_frequency_spectral_radius_is_rho_inf() {
        for rho in [0.0, 0.5, 0.8, 0.9, 1.0] {
            let s = Scheme::new(rho);
            let r = spectral_radius(&s, 1e5);
            assert!((r - rho).abs() <= 1e-3, "ρ∞ {rho}: {r}");
            let r = spectral_radius(&s, 1e-3);
            assert!((r - 1.0).abs() <= 1e-6, "ρ∞ {rho} at ωΔt = 1e-3: {r}");
        }
        // A slow mode keeps its energy to second order.
        let s = Scheme::new(0.8);
        let (w, dt) = (1.0, 0.01);
        let mut x = (1.0, 0.0, -1.0);
        for _ in 0..628 {
            let [u, v, a] = s.oscillator_step(w, dt, x);
            x = (u, v, a);
        }
        let e = 0.5 * (x.1 * x.1 + x.0 * x.0);
        assert!((e - 0.5).abs() < 1e-4 * 0.5, "{e}");
    }
}
