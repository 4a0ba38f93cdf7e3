//! The CSV curves of `stickslip analytic …`: one writer per curve subcommand, each printing a
//! header row and then one row per point. The arguments are defined in [`super::args`].

use super::args::{
    ApparentCurveArgs, DcmCurveArgs, ImpliedLawArgs, JkrCurveArgs, LawCurveArgs, TractionArgs,
};
use super::inputs::{CliResult, given_or_case};
use crate::analytic::AnalyticError;
use crate::analytic::apparent;
use crate::analytic::cattaneo::CattaneoMindlin;
use crate::analytic::dcm::{DoubleCm, implied_law_normalized};
use crate::analytic::jkr::{Jkr, JkrCurve};
use crate::friction::FrictionLaw;
use std::io::Write;

/// `dcm-curve`: Q/(f_d P) vs c/a of the double C–M solution at fixed Λ (Fig. 5).
pub(super) fn dcm_curve(d: &DcmCurveArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = d.case.scales()?;
    let lambda = given_or_case(d.lambda, case.as_ref().map(|c| c.0.lambda), "--lambda")?;
    let r = match (d.ratio.psi, d.ratio.fs_over_fd) {
        (Some(psi), _) => {
            JkrCurve::new(psi)?;
            if lambda <= 0.0 {
                return Err(AnalyticError::NotPositive {
                    name: "Lambda",
                    value: lambda,
                }
                .into());
            }
            1.0 + (psi / lambda).sqrt()
        }
        (_, Some(r)) => r,
        (None, None) => given_or_case(
            None,
            case.as_ref().map(|c| c.1 / c.2),
            "--psi or --fs-over-fd",
        )?,
    };
    let (m, weak) = DoubleCm::normalized(r, lambda)?;
    let pts = m.curve(weak, d.n)?;
    writeln!(out, "c_over_a,b_over_a,mid_over_a,q_ratio,branch,stable")?;
    for p in pts {
        writeln!(
            out,
            "{},{},{},{},{},{}",
            p.c,
            p.b,
            0.5 * (p.c + p.b),
            p.q / (m.fd * m.hertz.p_load),
            match p.branch {
                crate::analytic::dcm::Branch::Dcm => "dcm",
                crate::analytic::dcm::Branch::CmFs => "cm_fs",
            },
            p.stable
        )?;
    }
    Ok(())
}

/// `traction`: p(x) and the shear tractions q(x) of double C–M, C–M with f_d and the JKR limit
/// across the contact (Figs. 2–3).
pub(super) fn traction(t: &TractionArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = t.geom.scene()?;
    let h = sc.hertz()?;
    let (fs, fd) = sc.coefficients(t.fs, t.fd)?;
    let delta = sc.delta(t.len.delta, t.len.lambda, &h, fs, fd)?;
    let dcm = DoubleCm::new(h, fs, fd)?;
    let q = t.force.force(fd, h.p_load);
    let st = dcm.solve_delta(q, delta)?;
    let cm = CattaneoMindlin::new(h, fd)?;
    let c_cm = cm.stick_half_width(q).ok();
    let jkr = Jkr::new(h, fs, fd, delta)?;
    let c_jkr = jkr
        .curve()
        .stick_half_width(q / (fd * h.p_load))
        .ok()
        .map(|x| x * h.a);
    writeln!(out, "x,x_over_a,p,q_dcm,q_cm_fd,q_jkr,f_dcm")?;
    let n = t.n.max(2);
    for i in 0..n {
        let x = -h.a + 2.0 * h.a * i as f64 / (n - 1) as f64;
        let p = h.pressure(x);
        let qd = dcm.traction(x, st.c, st.b);
        let f = if p > 0.0 { Some(qd / p) } else { None };
        let qj = c_jkr.map(|c| jkr.traction(x, c)).filter(|v| v.is_finite());
        writeln!(
            out,
            "{},{},{},{},{},{},{}",
            x,
            x / h.a,
            p,
            qd,
            csv_opt(c_cm.map(|c| cm.traction(x, c))),
            csv_opt(qj),
            csv_opt(f)
        )?;
    }
    Ok(())
}

/// `jkr-curve`: Q/(f_d P) vs c/a of the JKR limit for given Ψ (Fig. 4).
pub(super) fn jkr_curve(j: &JkrCurveArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = j.case.scales()?;
    let cur = JkrCurve::new(given_or_case(j.psi, case.map(|c| c.0.psi), "--psi")?)?;
    writeln!(out, "c_over_a,q_ratio,stable")?;
    for (c, q, s) in cur.curve(j.n) {
        writeln!(out, "{c},{q},{s}")?;
    }
    Ok(())
}

/// `law-curve`: samples of f(u) and df/du from zero to `--u-max` (by default 3Δ, or 1.5 × the
/// last table slip).
pub(super) fn law_curve(l: &LawCurveArgs, out: &mut dyn Write) -> CliResult<()> {
    let law = l.spec.law()?;
    let u_max = match l.u_max {
        Some(u) if u.is_finite() && u > 0.0 => u,
        Some(u) => {
            return Err(AnalyticError::NotPositive {
                name: "u-max",
                value: u,
            }
            .into());
        }
        None => match &law {
            FrictionLaw::Table(t) => 1.5 * t.rows().last().map(|r| r[0]).unwrap_or(1.0),
            _ => 3.0 * law.delta().unwrap_or(0.0),
        }
        .max(1e-12),
    };
    writeln!(out, "u,mu,dmu_du")?;
    let n = l.n.max(2);
    for i in 0..n {
        let u = u_max * i as f64 / (n - 1) as f64;
        writeln!(out, "{},{},{}", u, law.mu(u), csv_opt(law.dmu_du(u)))?;
    }
    Ok(())
}

/// `implied-law`: the friction law implied by the double C–M solution for a/c, b/c (Fig. 1).
pub(super) fn implied_law(i: &ImpliedLawArgs, out: &mut dyn Write) -> CliResult<()> {
    let pts = implied_law_normalized(i.a_over_c, i.b_over_c, i.n)?;
    writeln!(out, "u_over_delta,f_norm")?;
    for p in pts {
        writeln!(out, "{},{}", p[0], p[1])?;
    }
    Ok(())
}

/// `apparent-curve`: Q_max/(f_d P) vs f_s/f_d for given χ, optionally with the double C–M
/// columns (Fig. 6).
pub(super) fn apparent_curve(a: &ApparentCurveArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = a.case.scales()?;
    let chi = given_or_case(a.chi, case.map(|c| c.0.chi), "--chi")?;
    let pts = apparent::apparent_curve(chi, a.ratio_max, a.n, a.dcm)?;
    writeln!(
        out,
        "fs_over_fd,q_max_jkr,c_max_jkr,s0_over_c,small_scale_ok,q_max_dcm,c_max_dcm,b_max_dcm"
    )?;
    for p in pts {
        writeln!(
            out,
            "{},{},{},{},{},{},{},{}",
            p.fs_over_fd,
            p.q_max_jkr,
            p.c_max_jkr,
            csv_opt(p.s0_over_c),
            p.small_scale_ok,
            csv_opt(p.q_max_dcm),
            csv_opt(p.c_max_dcm),
            csv_opt(p.b_max_dcm)
        )?;
    }
    Ok(())
}

/// A CSV cell: the number, or empty for `None`.
fn csv_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}
