//! The `JKR` limit (§4.2): transition zone condensed to a line at `x = ±c`.
//!
//! * eq. (delta): width `δ ≈ 16R²W / (πE*(f_s − f_d)²(a² − c²))` of the transition zone;
//! * eq. (qxJKRDelta): `q_x ≈ (E* f_d/2R) q(x,a,c) + E* sqrt((f_s − f_d)Δ c sqrt(a² − c²) / (πR(c² − x²)))`;
//! * eq. (QJKR): `Q_x/(f_d P) ≈ 1 − c²/a² + (4/(f_d a²)) sqrt((f_s − f_d) R Δ c sqrt(a² − c²)/π)`,
//!   which in terms of `c̃ = c/a` and `Ψ` is `1 − c̃² + 4 sqrt(Ψ c̃ sqrt(1 − c̃²)/π)`;
//! * eq. (KII): `K_II = lim q_x sqrt(2π(c − x)) = sqrt(2 W E*)`;
//! * eq. (KIIa): `K_II = sqrt(2E*(f_s − f_d) p Δ)`.
//!
//! Here `W = (f_s − f_d) p(c) Δ` (eq. Maugis10 with the pressure at the stick boundary).
//! Under force control the branch `c > c_max` (right of the maximum) is stable and
//! `c < c_max` unstable (the paper's dotted lines in Fig. 4).

use super::roots::bisect;
use super::{AnalyticError, Hertz, Result, check_coefficients, non_negative};
use serde::Serialize;
use std::f64::consts::PI;

/// `K_II = sqrt(2 W E*)`, eq. (KII).
pub fn k_ii(w: f64, e_star: f64) -> f64 {
    (2.0 * w * e_star).sqrt()
}

/// Dimensionless JKR curve `Q_x/(f_d P)` vs `c/a` for a given `Ψ ≥ 0`, eq. (QJKR).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JkrCurve {
    pub psi: f64,
}

/// Location and value of the maximum of a JKR curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JkrMax {
    /// `c/a` at the maximum.
    pub c_over_a: f64,
    /// `Q_max/(f_d P)`.
    pub q_ratio: f64,
}

impl JkrCurve {
    /// Errors with [`AnalyticError::NegativePsi`] for `Ψ < 0`.
    pub fn new(psi: f64) -> Result<Self> {
        super::finite("Psi", psi)?;
        if psi < 0.0 {
            return Err(AnalyticError::NegativePsi { psi });
        }
        Ok(JkrCurve { psi })
    }

    /// `Q_x/(f_d P)` at `c/a = ct ∈ [0, 1]`, eq. (QJKR).
    pub fn q_ratio(&self, ct: f64) -> f64 {
        let ct = ct.clamp(0.0, 1.0);
        1.0 - ct * ct + 4.0 * (self.psi * ct * (1.0 - ct * ct).sqrt() / PI).sqrt()
    }

    /// `d(Q_x/(f_d P))/d(c/a)` for `0 < ct < 1`.
    pub fn dq_ratio(&self, ct: f64) -> f64 {
        let h = ct * ct * (1.0 - ct * ct);
        let dh = (2.0 * ct - 4.0 * ct * ct * ct) / (4.0 * h.powf(0.75));
        -2.0 * ct + 4.0 * (self.psi / PI).sqrt() * dh
    }

    /// The maximum `Q_max/(f_d P)` and its `c/a` (the root of the derivative in
    /// `(0, 1/√2)`, by bisection). `Ψ = 0` gives `(0, 1)`.
    pub fn maximum(&self) -> JkrMax {
        if self.psi == 0.0 {
            return JkrMax {
                c_over_a: 0.0,
                q_ratio: 1.0,
            };
        }
        let lo = 1e-100;
        let hi = std::f64::consts::FRAC_1_SQRT_2;
        let ct = bisect(|x| self.dq_ratio(x), lo, hi, 1e-16);
        JkrMax {
            c_over_a: ct,
            q_ratio: self.q_ratio(ct),
        }
    }

    /// Stable stick semi-width `c/a` at `Q_x/(f_d P) = q_ratio` (the root right of the
    /// maximum). Errors when `q_ratio` exceeds `Q_max/(f_d P)` or is negative.
    pub fn stick_half_width(&self, q_ratio: f64) -> Result<f64> {
        non_negative("Q/(f_d P)", q_ratio)?;
        let m = self.maximum();
        if q_ratio > m.q_ratio {
            return Err(AnalyticError::QAboveLimit {
                q: q_ratio,
                limit: "Q_max/(f_d P) of the JKR limit",
                limit_value: m.q_ratio,
            });
        }
        if q_ratio == 0.0 {
            return Ok(1.0);
        }
        Ok(bisect(
            |x| self.q_ratio(x) - q_ratio,
            m.c_over_a,
            1.0,
            1e-16,
        ))
    }

    /// `n` points `(c/a, Q/(f_d P), stable)` with `c/a` uniform in `[0, 1]`.
    pub fn curve(&self, n: usize) -> Vec<(f64, f64, bool)> {
        let m = self.maximum();
        let n = n.max(2);
        (0..n)
            .map(|i| {
                let ct = i as f64 / (n - 1) as f64;
                (ct, self.q_ratio(ct), ct >= m.c_over_a)
            })
            .collect()
    }
}

/// Dimensional JKR solution for a law with `f_s ≥ f_d > 0` and slip length `Δ ≥ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jkr {
    pub hertz: Hertz,
    pub fs: f64,
    pub fd: f64,
    pub delta: f64,
}

impl Jkr {
    pub fn new(hertz: Hertz, fs: f64, fd: f64, delta: f64) -> Result<Self> {
        check_coefficients(fs, fd)?;
        super::finite("delta", delta)?;
        if delta < 0.0 {
            return Err(AnalyticError::NegativeDelta { delta });
        }
        Ok(Jkr {
            hertz,
            fs,
            fd,
            delta,
        })
    }

    /// `Ψ = (f_s/f_d − 1) RΔ/(f_d a²)`.
    pub fn psi(&self) -> f64 {
        (self.fs - self.fd) * self.hertz.geom.r * self.delta
            / (self.fd * self.fd * self.hertz.a.powi(2))
    }

    /// The dimensionless curve of this problem.
    pub fn curve(&self) -> JkrCurve {
        JkrCurve { psi: self.psi() }
    }

    /// Fracture energy at the stick boundary, `W = (f_s − f_d) p(c) Δ`.
    pub fn energy(&self, c: f64) -> f64 {
        (self.fs - self.fd) * self.hertz.pressure(c) * self.delta
    }

    /// `K_II = sqrt(2E*(f_s − f_d) p(c) Δ)`, eq. (KIIa).
    pub fn k_ii(&self, c: f64) -> f64 {
        (2.0 * self.hertz.geom.e_star * (self.fs - self.fd) * self.hertz.pressure(c) * self.delta)
            .sqrt()
    }

    /// Transition-zone width `δ` of eq. (delta) (infinite for `c → a`).
    pub fn transition_width(&self, c: f64) -> f64 {
        let (r, es, a) = (self.hertz.geom.r, self.hertz.geom.e_star, self.hertz.a);
        16.0 * r * r * self.energy(c) / (PI * es * (self.fs - self.fd).powi(2) * (a * a - c * c))
    }

    /// Shear traction, eq. (qxJKRDelta); singular (infinite) at `|x| = c`, `f_d p` outside.
    pub fn traction(&self, x: f64, c: f64) -> f64 {
        let h = &self.hertz;
        let (r, es, a) = (h.geom.r, h.geom.e_star, h.a);
        let base = self.fd * (h.pressure(x) - h.half_width_pressure(x, c));
        if x.abs() >= c {
            return base;
        }
        let sing = es
            * ((self.fs - self.fd) * self.delta * c * (a * a - c * c).max(0.0).sqrt()
                / (PI * r * (c * c - x * x)))
                .sqrt();
        base + sing
    }

    /// Tangential force `Q_x`, eq. (QJKR) times `f_d P`.
    pub fn tangential_force(&self, c: f64) -> f64 {
        self.fd * self.hertz.p_load * self.curve().q_ratio(c / self.hertz.a)
    }
}
