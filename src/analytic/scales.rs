//! Length scales and dimensionless groups (§4.3 and Discussion).
//!
//! * eq. (s0): `s0 = E* Δ / (π (f_s − f_d) p)` — the distance from the stick boundary inside
//!   which the singular JKR traction would exceed `f_s p`;
//! * eq. (Lambda): `Λ = RΔ / ((f_s − f_d) a²)`; with `p = p0`: `s0 = (2/π) Λ a`;
//! * eq. (chi): `χ = RΔ/(f_d a²) = (f_s/f_d − 1) Λ`;
//! * `Ψ = (f_s/f_d − 1) RΔ/(f_d a²) = (f_s/f_d − 1)² Λ` (Discussion, used in Fig. 4).
//!
//! **Small-scale criterion.** The paper requires `s0 ≪ c` without a number. This crate flags
//! the JKR limit as applicable when `s0(c)/c ≤ 0.1` ([`SMALL_SCALE_LIMIT`]), with `s0`
//! evaluated at the local pressure `p(c)`:
//! `s0/c = (2Λ/π) / (c̃ sqrt(1 − c̃²))`, `c̃ = c/a`.

use super::{AnalyticError, Hertz, Result, check_coefficients, non_negative};
use serde::Serialize;
use std::f64::consts::PI;

/// Threshold on `s0/c` below which `s0 ≪ c` is considered satisfied.
pub const SMALL_SCALE_LIMIT: f64 = 0.1;

fn weakening(fs: f64, fd: f64) -> Result<f64> {
    check_coefficients(fs, fd)?;
    if fs == fd {
        return Err(AnalyticError::OutOfRange {
            name: "fs - fd",
            value: 0.0,
            lo: f64::MIN_POSITIVE,
            hi: f64::INFINITY,
        });
    }
    Ok(fs - fd)
}

/// `s0 = E* Δ / (π (f_s − f_d) p)`, eq. (s0). Needs `f_s > f_d`, `p > 0`.
pub fn s0(e_star: f64, delta: f64, fs: f64, fd: f64, p: f64) -> Result<f64> {
    let df = weakening(fs, fd)?;
    super::positive("p", p)?;
    if delta < 0.0 {
        return Err(AnalyticError::NegativeDelta { delta });
    }
    Ok(e_star * delta / (PI * df * p))
}

/// `Λ = RΔ/((f_s − f_d) a²)`, eq. (Lambda).
pub fn lambda(r: f64, delta: f64, fs: f64, fd: f64, a: f64) -> Result<f64> {
    let df = weakening(fs, fd)?;
    if delta < 0.0 {
        return Err(AnalyticError::NegativeDelta { delta });
    }
    Ok(r * delta / (df * a * a))
}

/// `Δ = Λ (f_s − f_d) a²/R` (inverse of eq. Lambda).
pub fn delta_from_lambda(lambda: f64, r: f64, fs: f64, fd: f64, a: f64) -> Result<f64> {
    non_negative("Lambda", lambda)?;
    check_coefficients(fs, fd)?;
    Ok(lambda * (fs - fd) * a * a / r)
}

/// `s0/c` at stick radius `c̃ = c/a` for a given `Λ` (pressure taken at `c`).
pub fn s0_over_c(lambda: f64, c_over_a: f64) -> f64 {
    2.0 * lambda / PI / (c_over_a * (1.0 - c_over_a * c_over_a).sqrt())
}

/// `true` when `s0/c ≤ SMALL_SCALE_LIMIT`.
pub fn small_scale_ok(s0_over_c: f64) -> bool {
    s0_over_c <= SMALL_SCALE_LIMIT
}

/// All scales of a problem (Hertz contact + `f_s > f_d`, `Δ`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Scales {
    pub delta: f64,
    /// eq. (Lambda).
    pub lambda: f64,
    /// eq. (chi).
    pub chi: f64,
    /// `Ψ`.
    pub psi: f64,
    /// `s0` at the centre pressure `p0`, `= (2/π) Λ a`.
    pub s0_centre: f64,
    /// `s0_centre / a`.
    pub s0_centre_over_a: f64,
    /// `W` at `p0`: `(f_s − f_d) p0 Δ`.
    pub w_centre: f64,
    /// `K_II` at `p0`, eq. (KIIa).
    pub k_ii_centre: f64,
}

impl Scales {
    pub fn new(h: &Hertz, fs: f64, fd: f64, delta: f64) -> Result<Self> {
        let lambda = lambda(h.geom.r, delta, fs, fd, h.a)?;
        let s0c = s0(h.geom.e_star, delta, fs, fd, h.p0)?;
        let w = (fs - fd) * h.p0 * delta;
        Ok(Scales {
            delta,
            lambda,
            chi: (fs / fd - 1.0) * lambda,
            psi: (fs / fd - 1.0).powi(2) * lambda,
            s0_centre: s0c,
            s0_centre_over_a: s0c / h.a,
            w_centre: w,
            k_ii_centre: (2.0 * w * h.geom.e_star).sqrt(),
        })
    }
}
