//! Two-dimensional Hertz contact of a cylinder (effective radius `R`) on a half-space.
//!
//! `p(x) = E* sqrt(a² − x²) / (2R)`, `P = π E* a² / (4R)` (the paper's pressure equation
//! before (Maugis)), so `a = sqrt(4PR/(πE*))` and `p0 = E* a/(2R) = 2P/(πa)`.

use super::{AnalyticError, Result, finite, positive};
use std::f64::consts::PI;

/// Effective radius and composite plane-strain modulus of a contact pair.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Geometry {
    /// Effective radius `R`, `1/R = 1/R1 + 1/R2`.
    pub r: f64,
    /// Composite modulus `E*`, `1/E* = (1 − ν1²)/E1 + (1 − ν2²)/E2`.
    pub e_star: f64,
}

fn poisson(name: &'static str, nu: f64) -> Result<f64> {
    finite(name, nu)?;
    if nu <= -1.0 || nu > 0.5 {
        return Err(AnalyticError::BadPoisson { name, value: nu });
    }
    Ok(nu)
}

impl Geometry {
    /// From `R` and `E*` directly (both positive).
    pub fn new(r: f64, e_star: f64) -> Result<Self> {
        Ok(Geometry {
            r: positive("R", r)?,
            e_star: positive("E*", e_star)?,
        })
    }

    /// From two convex cylinders (radii `r1`, `r2`; either may be `f64::INFINITY`, a flat, but
    /// not both) and their Young's moduli and Poisson's ratios (plane strain).
    pub fn from_bodies(r1: f64, r2: f64, e1: f64, nu1: f64, e2: f64, nu2: f64) -> Result<Self> {
        // Either body may be a flat (R = ∞), not both.
        for (name, r) in [("R1", r1), ("R2", r2)] {
            if r.is_nan() || r <= 0.0 {
                return Err(AnalyticError::NotPositive { name, value: r });
            }
        }
        if r1.is_infinite() && r2.is_infinite() {
            return Err(AnalyticError::NotFinite {
                name: "R1",
                value: r1,
            });
        }
        positive("E1", e1)?;
        positive("E2", e2)?;
        poisson("nu1", nu1)?;
        poisson("nu2", nu2)?;
        let r = 1.0 / (1.0 / r1 + 1.0 / r2);
        let e_star = 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2);
        Geometry::new(r, e_star)
    }

    /// The VM272 pair: two cylinders of 8 mm, E = 200 N/mm², ν = 0.3 (`R = 4`, `E* = 109.89`).
    pub fn vm272() -> Self {
        Geometry::from_bodies(8.0, 8.0, 200.0, 0.3, 200.0, 0.3).expect("valid constants")
    }
}

/// Dundurs' parameter β (plane strain) of two materials. The paper assumes β = 0 (identical
/// materials give exactly 0); a non-zero value means normal–tangential coupling that the closed
/// forms ignore.
pub fn dundurs_beta(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    let g1 = e1 / (2.0 * (1.0 + nu1));
    let g2 = e2 / (2.0 * (1.0 + nu2));
    let num = (1.0 - 2.0 * nu1) / g1 - (1.0 - 2.0 * nu2) / g2;
    let den = 2.0 * ((1.0 - nu1) / g1 + (1.0 - nu2) / g2);
    num / den
}

/// Hertz solution for a normal load `P` per unit thickness.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Hertz {
    pub geom: Geometry,
    /// Normal load per unit thickness `P`.
    pub p_load: f64,
    /// Contact semi-width `a = sqrt(4PR/(πE*))`.
    pub a: f64,
    /// Peak pressure `p0 = 2P/(πa)`.
    pub p0: f64,
}

impl Hertz {
    /// Hertz contact under load `p_load > 0`.
    pub fn new(geom: Geometry, p_load: f64) -> Result<Self> {
        positive("P", p_load)?;
        let a = (4.0 * p_load * geom.r / (PI * geom.e_star)).sqrt();
        Ok(Hertz {
            geom,
            p_load,
            a,
            p0: 2.0 * p_load / (PI * a),
        })
    }

    /// Contact with semi-width `a` (the load follows from `P = π E* a²/(4R)`).
    pub fn with_half_width(geom: Geometry, a: f64) -> Result<Self> {
        positive("a", a)?;
        Hertz::new(geom, PI * geom.e_star * a * a / (4.0 * geom.r))
    }

    /// Unit problem `R = E* = a = 1` (`P = π/4`), convenient for dimensionless curves.
    pub fn unit() -> Self {
        Hertz::with_half_width(
            Geometry {
                r: 1.0,
                e_star: 1.0,
            },
            1.0,
        )
        .expect("valid constants")
    }

    /// Pressure `p(x) = p0 sqrt(1 − x²/a²)`, zero outside the contact.
    pub fn pressure(&self, x: f64) -> f64 {
        self.half_width_pressure(x, self.a)
    }

    /// `E* sqrt(c² − x²)/(2R)`: the Hertz pressure of a contact of semi-width `c` (zero for
    /// `|x| ≥ c`). This is `p*` of eq. (C-M) and `(E*/2R) · sqrt` terms of eq. (CM-q).
    pub fn half_width_pressure(&self, x: f64, c: f64) -> f64 {
        let s = c * c - x * x;
        if s <= 0.0 {
            0.0
        } else {
            self.geom.e_star * s.sqrt() / (2.0 * self.geom.r)
        }
    }

    /// Load `P(c) = π E* c²/(4R)` of a Hertz contact of semi-width `c`.
    pub fn load_for_half_width(&self, c: f64) -> f64 {
        PI * self.geom.e_star * c * c / (4.0 * self.geom.r)
    }
}
