//! Apparent static friction (Discussion, Fig. 6): the ratio `Q_max/(f_d P)` that a
//! force-controlled experiment would report as `f_s/f_d`, for a given `χ = RΔ/(f_d a²)`.
//!
//! With `r = f_s/f_d`: `Ψ = (r − 1) χ` and `Λ = χ/(r − 1)`. The JKR value is the maximum of
//! eq. (QJKR); the double C–M value is the maximum of the composite curve of eqs. (Qx), (W1)
//! with `W = (f_s − f_d) p(c) Δ` (continued by C–M with `f_s` where `b` would exceed `a`).
//! The small-scale criterion is evaluated at the JKR maximum (see [`super::scales`]).

use super::dcm::{Branch, DoubleCm};
use super::jkr::JkrCurve;
use super::scales::{s0_over_c, small_scale_ok};
use super::{AnalyticError, Result, non_negative};
use serde::Serialize;
use std::f64::consts::PI;

/// One point of Fig. 6.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ApparentPoint {
    pub chi: f64,
    /// `f_s/f_d`.
    pub fs_over_fd: f64,
    /// `Ψ = (f_s/f_d − 1) χ`.
    pub psi: f64,
    /// `Λ = χ/(f_s/f_d − 1)` (`None` for `f_s = f_d`).
    pub lambda: Option<f64>,
    /// `Q_max/(f_d P)` from the JKR limit.
    pub q_max_jkr: f64,
    /// `c/a` at the JKR maximum.
    pub c_max_jkr: f64,
    /// `s0/c` at the JKR maximum (`None` if undefined: `f_s = f_d` or `c = 0`).
    pub s0_over_c: Option<f64>,
    /// Small-scale criterion `s0/c ≤ 0.1` at the JKR maximum.
    pub small_scale_ok: bool,
    /// `Q_max/(f_d P)` of the double C–M solution (if requested).
    pub q_max_dcm: Option<f64>,
    /// `c/a` at the double C–M maximum.
    pub c_max_dcm: Option<f64>,
    /// `b/a` at the double C–M maximum.
    pub b_max_dcm: Option<f64>,
    /// `true` if the double C–M maximum lies on the C–M (`f = f_s`) continuation.
    pub dcm_max_truncated: Option<bool>,
}

/// Fig. 6 point for given `χ ≥ 0` and `f_s/f_d ≥ 1`; `with_dcm` adds the double C–M value.
pub fn apparent(chi: f64, fs_over_fd: f64, with_dcm: bool) -> Result<ApparentPoint> {
    non_negative("chi", chi)?;
    super::finite("fs/fd", fs_over_fd)?;
    if fs_over_fd < 1.0 {
        return Err(AnalyticError::FdExceedsFs {
            fs: fs_over_fd,
            fd: 1.0,
        });
    }
    let psi = (fs_over_fd - 1.0) * chi;
    let m = JkrCurve::new(psi)?.maximum();
    let lambda = (fs_over_fd > 1.0).then(|| chi / (fs_over_fd - 1.0));
    let s0c = match lambda {
        Some(l) if m.c_over_a > 0.0 => Some(s0_over_c(l, m.c_over_a)),
        _ => None,
    };
    let mut pt = ApparentPoint {
        chi,
        fs_over_fd,
        psi,
        lambda,
        q_max_jkr: m.q_ratio,
        c_max_jkr: m.c_over_a,
        s0_over_c: s0c,
        small_scale_ok: s0c.is_some_and(small_scale_ok),
        q_max_dcm: None,
        c_max_dcm: None,
        b_max_dcm: None,
        dcm_max_truncated: None,
    };
    if with_dcm {
        let (model, weak) = DoubleCm::normalized(fs_over_fd, lambda.unwrap_or(0.0))?;
        let (br, st) = model.max_force(weak)?;
        pt.q_max_dcm = Some(st.q / (PI / 4.0));
        pt.c_max_dcm = Some(st.c);
        pt.b_max_dcm = Some(st.b);
        pt.dcm_max_truncated = Some(br == Branch::CmFs);
    }
    Ok(pt)
}

/// `n` points of a Fig. 6 curve, `f_s/f_d` uniform in `[1, ratio_max]`.
pub fn apparent_curve(
    chi: f64,
    ratio_max: f64,
    n: usize,
    with_dcm: bool,
) -> Result<Vec<ApparentPoint>> {
    super::finite("ratio-max", ratio_max)?;
    if ratio_max <= 1.0 {
        return Err(AnalyticError::OutOfRange {
            name: "ratio-max",
            value: ratio_max,
            lo: 1.0,
            hi: f64::INFINITY,
        });
    }
    let n = n.max(2);
    (0..n)
        .map(|i| {
            apparent(
                chi,
                1.0 + (ratio_max - 1.0) * i as f64 / (n - 1) as f64,
                with_dcm,
            )
        })
        .collect()
}
