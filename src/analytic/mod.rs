//! Closed-form solutions of the paper for the two-dimensional Hertzian geometry
//! (cylinder of effective radius `R` on a half-space, composite modulus `E*`, normal load `P`
//! per unit thickness, Dundurs' β = 0 so that the pressure is unaffected by friction).
//!
//! Equation labels refer to the LaTeX source of Papangelo, Ciavarella & Barber
//! (the paper, see `docs/reference.md`):
//!
//! | module | content |
//! |---|---|
//! | [`hertz`] | `a`, `p0`, `p(x)`; building `R`, `E*` from two bodies |
//! | [`cattaneo`] | eq. (C-M) with constant `f`; the abrupt case of §3 (`f = f_d`) |
//! | [`dcm`] | double Cattaneo–Mindlin: (qx2CM), (Qx), (W1), (C); solve for `(c, b)`; implied `f(u)` (Fig. 1) |
//! | [`jkr`] | JKR limit: (delta), (qxJKRDelta), (QJKR), (KII), (KIIa); `Q_max` (Fig. 4) |
//! | [`scales`] | `s0` (s0), `Λ` (Lambda), `χ` (chi), `Ψ`; small-scale criterion |
//! | [`apparent`] | apparent static friction `Q_max/(f_d P)` vs `f_s/f_d` (Fig. 6) |
//! | [`elliptic`] | complete elliptic integrals `K(m)`, `E(m)` by the AGM |
//! | [`cli`] | the `stickslip analytic …` subcommands: their arguments, JSON and CSV writers |
//! | [`case_scene`] | the radii, moduli, load and law of a case file, for `--case` |
//!
//! Units are whatever the caller uses consistently (the VM272 defaults are mm, N/mm², N/mm).

pub mod apparent;
pub mod case_scene;
pub mod cattaneo;
pub mod cli;
pub mod dcm;
pub mod elliptic;
pub mod hertz;
pub mod jkr;
pub mod reversal;
pub(crate) mod roots;
pub mod scales;

pub use cattaneo::CattaneoMindlin;
pub use dcm::{DcmState, DoubleCm};
pub use hertz::{Geometry, Hertz};
pub use jkr::{Jkr, JkrCurve};
pub use reversal::{Branch, Reversal};

use thiserror::Error;

/// Errors of the closed-form module. Each variant carries the offending values.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AnalyticError {
    /// A parameter that must be finite is NaN or infinite.
    #[error("parameter `{name}` must be finite, got {value}")]
    NotFinite { name: &'static str, value: f64 },
    /// A parameter that must be strictly positive is not.
    #[error("parameter `{name}` must be positive, got {value}")]
    NotPositive { name: &'static str, value: f64 },
    /// A parameter that must be non-negative is negative.
    #[error("parameter `{name}` must be non-negative, got {value}")]
    Negative { name: &'static str, value: f64 },
    /// A parameter is outside its admissible interval.
    #[error("parameter `{name}` = {value} is outside [{lo}, {hi}]")]
    OutOfRange {
        name: &'static str,
        value: f64,
        lo: f64,
        hi: f64,
    },
    /// Poisson's ratio outside (−1, 0.5].
    #[error("Poisson's ratio `{name}` = {value} is outside (-1, 0.5]")]
    BadPoisson { name: &'static str, value: f64 },
    /// The dynamic friction coefficient exceeds the static one.
    #[error("f_d = {fd} exceeds f_s = {fs}: the theory assumes slip weakening (f_s >= f_d)")]
    FdExceedsFs { fs: f64, fd: f64 },
    /// Negative slip length.
    #[error("slip length delta must be non-negative, got {delta}")]
    NegativeDelta { delta: f64 },
    /// Negative Ψ.
    #[error("Psi must be non-negative, got {psi}")]
    NegativePsi { psi: f64 },
    /// The tangential force exceeds the largest value the theory allows (gross sliding).
    #[error(
        "tangential force Q = {q} exceeds {limit} = {limit_value}: no stick zone (gross sliding)"
    )]
    QAboveLimit {
        q: f64,
        limit: &'static str,
        limit_value: f64,
    },
    /// The outer transition boundary `b` would exceed `a`: the solution has become the
    /// Cattaneo–Mindlin solution with `f = f_s` (whose stick semi-width is `c_cm_fs`).
    #[error(
        "double Cattaneo-Mindlin: b would exceed a (need W = {w_needed:e} at c = {c:e}, but b = a gives only {w_at_b_eq_a:e}); the solution has become Cattaneo-Mindlin with f = f_s, c = {c_cm_fs:e}"
    )]
    BExceedsA {
        c: f64,
        w_needed: f64,
        w_at_b_eq_a: f64,
        c_cm_fs: f64,
    },
    /// Friction coefficients equal but a positive fracture energy demanded.
    #[error("f_s = f_d = {f} cannot carry a fracture energy W = {w} > 0")]
    NoWeakening { f: f64, w: f64 },
}

pub type Result<T> = std::result::Result<T, AnalyticError>;

pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(AnalyticError::NotFinite { name, value })
    }
}

pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(AnalyticError::NotPositive { name, value })
    }
}

pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64> {
    finite(name, value)?;
    if value >= 0.0 {
        Ok(value)
    } else {
        Err(AnalyticError::Negative { name, value })
    }
}

/// Checks `f_s ≥ f_d > 0` (finite).
pub(crate) fn check_coefficients(fs: f64, fd: f64) -> Result<()> {
    positive("fs", fs)?;
    positive("fd", fd)?;
    if fd > fs {
        return Err(AnalyticError::FdExceedsFs { fs, fd });
    }
    Ok(())
}
