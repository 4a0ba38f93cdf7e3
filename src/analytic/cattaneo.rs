//! Cattaneo–Mindlin partial slip with a constant friction coefficient, eq. (C-M):
//! `q(x) = f [p(x) − p*(x)]`, `p*` the Hertz pressure of a load `P* = P − Q/f`, so the stick
//! zone is `|x| < c` with `c = a sqrt(1 − Q/(fP))`.
//!
//! §3 of the paper: with an **abrupt** static→dynamic transition (`Δ = 0`) the solution is this
//! one with `f = f_d` ([`CattaneoMindlin::abrupt`]), whatever `f_s ≥ f_d`.

use super::{AnalyticError, Hertz, Result, check_coefficients, non_negative, positive};

/// Cattaneo–Mindlin solution with coefficient `f` on a Hertz contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CattaneoMindlin {
    pub hertz: Hertz,
    pub f: f64,
}

impl CattaneoMindlin {
    /// Constant coefficient `f > 0`.
    pub fn new(hertz: Hertz, f: f64) -> Result<Self> {
        Ok(CattaneoMindlin {
            hertz,
            f: positive("f", f)?,
        })
    }

    /// §3: abrupt transition from `f_s` to `f_d` — the C–M solution with `f = f_d`.
    /// Errors if `f_d > f_s`.
    pub fn abrupt(hertz: Hertz, fs: f64, fd: f64) -> Result<Self> {
        check_coefficients(fs, fd)?;
        Self::new(hertz, fd)
    }

    /// Stick semi-width `c = a sqrt(1 − Q/(fP))` for `0 ≤ Q ≤ fP`, eq. (C-M).
    pub fn stick_half_width(&self, q: f64) -> Result<f64> {
        non_negative("Q", q)?;
        let limit = self.f * self.hertz.p_load;
        if q > limit {
            return Err(AnalyticError::QAboveLimit {
                q,
                limit: "f P",
                limit_value: limit,
            });
        }
        Ok(self.hertz.a * (1.0 - q / limit).max(0.0).sqrt())
    }

    /// Tangential force for stick semi-width `c`: `Q = f (P − P(c)) = fP (1 − c²/a²)`.
    pub fn tangential_force(&self, c: f64) -> f64 {
        self.f * (self.hertz.p_load - self.hertz.load_for_half_width(c.min(self.hertz.a)))
    }

    /// Shear traction `q(x) = f [p(x) − p*(x)]`, eq. (C-M), stick semi-width `c`.
    pub fn traction(&self, x: f64, c: f64) -> f64 {
        self.f * (self.hertz.pressure(x) - self.hertz.half_width_pressure(x, c))
    }
}
