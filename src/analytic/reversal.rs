//! Load reversal after Cattaneo–Mindlin loading (Mindlin & Deresiewicz), for a constant
//! coefficient `f` on a 2-D Hertz contact, the tangential load cycling between `+Q*` and
//! `−Q*` (`0 < Q* < fP`).
//!
//! Unloading from `Q*` to `Q` reverses the slip in an outer band `c′ < |x| < a` and adds to the
//! traction twice a Cattaneo–Mindlin distribution of the opposite sign:
//! ```text
//!   q(x) = q_CM(x; c*) − 2 q_CM(x; c′),   c′ = a sqrt(1 − (Q* − Q)/(2fP)),
//! ```
//! (`q_CM(x; c) = f [p(x) − p_c(x)]`, [`CattaneoMindlin::traction`]); the force of the added
//! term is `2fP(1 − c′²/a²) = Q* − Q`, and at `Q = −Q*` it gives `c′ = c*` and `q = −q*`. The
//! reloading branch from `−Q*` is the mirror image, `q = −q_CM(x; c*) + 2 q_CM(x; c″)` with
//! `c″ = a sqrt(1 − (Q + Q*)/(2fP))`. Every later cycle repeats the first loop (the contact
//! shakes down to a steady hysteresis). The stick zone during either branch is `|x| < c′`.

use super::{AnalyticError, CattaneoMindlin, Result};

/// The fretting loop between `+q_star` and `−q_star` after first loading to `q_star`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    pub cm: CattaneoMindlin,
    pub q_star: f64,
    /// Stick half-width at the turning points, `c* = a sqrt(1 − Q*/(fP))`.
    pub c_star: f64,
}

/// Which branch of the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Branch {
    /// From `+Q*` down to `−Q*`.
    Unloading,
    /// From `−Q*` up to `+Q*`.
    Reloading,
}

impl Reversal {
    /// The loop of amplitude `q_star` (`0 < Q* < fP`).
    pub fn new(cm: CattaneoMindlin, q_star: f64) -> Result<Self> {
        let c_star = cm.stick_half_width(q_star)?;
        Ok(Reversal { cm, q_star, c_star })
    }

    /// The stick half-width `c′` at load `q` on `branch` (`−Q* ≤ Q ≤ Q*`).
    pub fn stick_half_width(&self, branch: Branch, q: f64) -> Result<f64> {
        // A load within 1e-9 of the turning point is the turning point (solver round-off).
        if q.abs() > self.q_star * (1.0 + 1e-9) {
            return Err(AnalyticError::QAboveLimit {
                q,
                limit: "Q*",
                limit_value: self.q_star,
            });
        }
        let q = q.clamp(-self.q_star, self.q_star);
        let change = match branch {
            Branch::Unloading => self.q_star - q,
            Branch::Reloading => q + self.q_star,
        };
        let fp = self.cm.f * self.cm.hertz.p_load;
        Ok(self.cm.hertz.a * (1.0 - change / (2.0 * fp)).max(0.0).sqrt())
    }

    /// The shear traction at `x` and load `q` on `branch`.
    pub fn traction(&self, branch: Branch, q: f64, x: f64) -> Result<f64> {
        let c = self.stick_half_width(branch, q)?;
        let first = self.cm.traction(x, self.c_star);
        Ok(match branch {
            Branch::Unloading => first - 2.0 * self.cm.traction(x, c),
            Branch::Reloading => -first + 2.0 * self.cm.traction(x, c),
        })
    }
}
