//! `stickslip analytic …`: the closed forms from the command line.
//!
//! Scalars are printed as pretty JSON, curves as CSV with a header row (the CSV writers are in
//! `curves`). Geometry defaults to VM272 (two cylinders of 8 mm, E = 200 N/mm², ν = 0.3,
//! P = 10 N/mm); every subcommand that needs it accepts `--r1 --r2 --e1 --nu1 --e2 --nu2 --load`,
//! and `--case CASE` takes the radii, moduli, load and friction law from a case file
//! ([`crate::analytic::case_scene`]), each flag given as well overriding the case's value. See
//! `docs/analytic.md`.
//!
//! | module | content |
//! |---|---|
//! | `args` | the clap arguments of each subcommand |
//! | `inputs` | what the flags resolve to (scene, law, force, a case's numbers); [`CliError`] |
//! | `curves` | the CSV curve writers |
//! | this file | the dispatch and the JSON writers |

mod args;
mod curves;
mod inputs;

pub use args::*;
pub use inputs::CliError;

use crate::analytic::AnalyticError;
use crate::analytic::apparent::apparent;
use crate::analytic::cattaneo::CattaneoMindlin;
use crate::analytic::dcm::{DoubleCm, Weakening};
use crate::analytic::hertz::dundurs_beta;
use crate::analytic::jkr::{Jkr, JkrCurve, k_ii};
use crate::analytic::scales::{self, Scales, s0_over_c, small_scale_ok};
use crate::friction::PRESETS;
use inputs::{CliResult, given_or_case};
use serde_json::{Value, json};
use std::io::Write;

/// Writes `v` as pretty JSON followed by a newline.
fn print_json(out: &mut dyn Write, v: &Value) -> CliResult<()> {
    serde_json::to_writer_pretty(&mut *out, v)?;
    writeln!(out)?;
    Ok(())
}

/// Runs one `analytic` subcommand, writing JSON or CSV to `out`.
pub fn run(args: &AnalyticArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.cmd {
        AnalyticCmd::Hertz(g) => run_hertz(g, out),
        AnalyticCmd::Cm(c) => run_cm(c, out),
        AnalyticCmd::Abrupt(c) => run_abrupt(c, out),
        AnalyticCmd::Dcm(d) => run_dcm(d, out),
        AnalyticCmd::DcmCurve(d) => curves::dcm_curve(d, out),
        AnalyticCmd::Traction(t) => curves::traction(t, out),
        AnalyticCmd::Jkr(j) => run_jkr(j, out),
        AnalyticCmd::JkrCurve(j) => curves::jkr_curve(j, out),
        AnalyticCmd::Scales(s) => run_scales(s, out),
        AnalyticCmd::Law(l) => run_law(l, out),
        AnalyticCmd::LawCurve(l) => curves::law_curve(l, out),
        AnalyticCmd::Presets => run_presets(out),
        AnalyticCmd::ImpliedLaw(i) => curves::implied_law(i, out),
        AnalyticCmd::Apparent(a) => run_apparent(a, out),
        AnalyticCmd::ApparentCurve(a) => curves::apparent_curve(a, out),
    }
}

/// `hertz`: R, E*, a, p0 and Dundurs' β as JSON.
fn run_hertz(g: &GeomArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = g.scene()?;
    let h = sc.hertz()?;
    print_json(
        out,
        &sc.annotate(json!({
            "r_eff": h.geom.r, "e_star": h.geom.e_star, "load": h.p_load,
            "a": h.a, "p0": h.p0,
            "dundurs_beta": dundurs_beta(sc.e1, sc.nu1, sc.e2, sc.nu2),
        })),
    )
}

/// `cm`: the Cattaneo–Mindlin stick semi-width for constant f as JSON.
fn run_cm(c: &CmArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = c.geom.scene()?;
    let h = sc.hertz()?;
    let mu = match (c.mu, sc.law()) {
        (Some(mu), _) => mu,
        (None, Some(law)) => match law.f_dynamic() {
            Ok(fd) if fd == law.f_static() => fd,
            _ => {
                return Err(CliError::Usage(format!(
                    "the case's friction law is not constant (f_s = {}): --mu is required",
                    law.f_static()
                )));
            }
        },
        (None, None) => {
            return Err(CliError::Usage(
                "--mu is required (or --case with a case that has a friction law)".into(),
            ));
        }
    };
    let cm = CattaneoMindlin::new(h, mu)?;
    let q = c.force.force(mu, h.p_load);
    let cc = cm.stick_half_width(q)?;
    print_json(
        out,
        &sc.annotate(json!({
            "mu": mu, "q": q, "q_over_mu_p": q / (mu * h.p_load),
            "a": h.a, "p0": h.p0, "c": cc, "c_over_a": cc / h.a,
        })),
    )
}

/// `abrupt`: the abrupt static→dynamic transition (C–M with f = f_d) as JSON.
fn run_abrupt(c: &AbruptArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = c.geom.scene()?;
    let h = sc.hertz()?;
    let (fs, fd) = sc.coefficients(c.fs, c.fd)?;
    let cm = CattaneoMindlin::abrupt(h, fs, fd)?;
    let q = c.force.force(fd, h.p_load);
    let cc = cm.stick_half_width(q)?;
    print_json(
        out,
        &sc.annotate(json!({
            "fs": fs, "fd": fd, "q": q, "q_over_fd_p": q / (fd * h.p_load),
            "a": h.a, "c": cc, "c_over_a": cc / h.a,
            "note": "abrupt transition (Delta = 0): Cattaneo-Mindlin with f = f_d",
        })),
    )
}

/// `jkr`: the JKR maximum, optionally the stable c/a at a force and the small-scale check, as JSON.
fn run_jkr(j: &JkrArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = j.case.scales()?;
    let psi = given_or_case(j.psi, case.as_ref().map(|c| c.0.psi), "--psi")?;
    let lambda = j.lambda.or(case.as_ref().map(|c| c.0.lambda));
    let cur = JkrCurve::new(psi)?;
    let m = cur.maximum();
    let mut v = json!({
        "psi": psi, "q_max_ratio": m.q_ratio, "c_max_over_a": m.c_over_a,
    });
    if let Some((_, _, _, scene)) = &case {
        v["scene"] = scene.clone();
    }
    if let Some(q) = j.q_ratio {
        v["q_ratio"] = json!(q);
        v["c_over_a"] = json!(cur.stick_half_width(q)?);
    }
    if let Some(l) = lambda {
        crate::analytic::non_negative("Lambda", l)?;
        let s = (m.c_over_a > 0.0).then(|| s0_over_c(l, m.c_over_a));
        v["lambda"] = json!(l);
        v["s0_over_c_at_max"] = json!(s);
        v["small_scale_ok"] = json!(s.is_some_and(small_scale_ok));
    }
    print_json(out, &v)
}

/// `scales`: the length scales as JSON, plus the values at a stick radius if `--c-over-a` is given.
fn run_scales(s: &ScalesArgs, out: &mut dyn Write) -> CliResult<()> {
    let scene = s.geom.scene()?;
    let h = scene.hertz()?;
    let (fs, fd) = scene.coefficients(s.fs, s.fd)?;
    let delta = scene.delta(s.len.delta, s.len.lambda, &h, fs, fd)?;
    let sc = Scales::new(&h, fs, fd, delta)?;
    let mut v = scene.annotate(serde_json::to_value(sc)?);
    v["a"] = json!(h.a);
    v["p0"] = json!(h.p0);
    v["small_scale_limit"] = json!(scales::SMALL_SCALE_LIMIT);
    if let Some(ct) = s.c_over_a {
        if !(ct > 0.0 && ct < 1.0) {
            return Err(AnalyticError::OutOfRange {
                name: "c/a",
                value: ct,
                lo: 0.0,
                hi: 1.0,
            }
            .into());
        }
        let c = ct * h.a;
        let jkr = Jkr::new(h, fs, fd, delta)?;
        let pc = h.pressure(c);
        let s0c = scales::s0(h.geom.e_star, delta, fs, fd, pc)?;
        v["c_over_a"] = json!(ct);
        v["p_c"] = json!(pc);
        v["s0_c"] = json!(s0c);
        v["s0_over_c"] = json!(s0c / c);
        v["small_scale_ok"] = json!(small_scale_ok(s0c / c));
        v["w_c"] = json!(jkr.energy(c));
        v["k_ii_c"] = json!(k_ii(jkr.energy(c), h.geom.e_star));
        v["jkr_zone_width_c"] = json!(jkr.transition_width(c));
    }
    print_json(out, &v)
}

/// `law`: a friction law with f_s, f_d, W/p and Δ, optionally f(u) and df/du at a slip, as JSON.
fn run_law(l: &LawArgs, out: &mut dyn Write) -> CliResult<()> {
    let law = l.spec.law()?;
    let mut v = json!({
        "law": serde_json::to_value(&law)?,
        "f_static": law.f_static(),
    });
    match law.f_dynamic() {
        Ok(fd) => {
            v["f_dynamic"] = json!(fd);
            v["w_over_p"] = json!(law.w_over_p()?);
            v["delta"] = json!(law.delta().ok());
        }
        Err(e) => {
            v["f_dynamic"] = Value::Null;
            v["note"] = json!(e.to_string());
        }
    }
    if let Some(u) = l.u {
        v["u"] = json!(u);
        v["mu_u"] = json!(law.mu(u));
        v["dmu_du"] = json!(law.dmu_du(u));
    }
    let weakens = law.f_dynamic().is_ok_and(|fd| fd < law.f_static());
    let (name, note) = match (l.history, weakens) {
        (_, false) => (
            "accumulated",
            "the law does not weaken: the history makes no difference".to_string(),
        ),
        (HistoryArg::Accumulated, true) => (
            "accumulated",
            "u is the total slip path of a point: weakening is permanent".to_string(),
        ),
        (HistoryArg::SinceStick, true) => (
            "since_stick",
            format!(
                "u is the slip since the point last stuck or was out of contact: a point that \
                 sticks regains f_s = {}; under monotonic loading the same as accumulated",
                law.f_static()
            ),
        ),
    };
    v["history"] = json!(name);
    v["history_note"] = json!(note);
    print_json(out, &v)
}

/// `presets`: the Table 1 presets as a JSON array.
fn run_presets(out: &mut dyn Write) -> CliResult<()> {
    let v: Vec<Value> = PRESETS
        .iter()
        .map(
            |p| json!({"name": p.0, "fs": p.1, "fd": p.2, "delta_um": p.3, "delta_mm": p.3 * 1e-3}),
        )
        .collect();
    print_json(out, &json!(v))
}

/// `apparent`: the apparent static friction for given χ and f_s/f_d as JSON.
fn run_apparent(a: &ApparentArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = a.case.scales()?;
    let chi = given_or_case(a.chi, case.as_ref().map(|c| c.0.chi), "--chi")?;
    let ratio = given_or_case(
        a.fs_over_fd,
        case.as_ref().map(|c| c.1 / c.2),
        "--fs-over-fd",
    )?;
    let p = apparent(chi, ratio, !a.no_dcm)?;
    let mut v = serde_json::to_value(p)?;
    if let Some((_, _, _, scene)) = case {
        v["scene"] = scene;
    }
    print_json(out, &v)
}

/// `dcm`: the double Cattaneo–Mindlin state (c, b, W) with the JKR and C–M comparisons as JSON.
fn run_dcm(d: &DcmArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = d.geom.scene()?;
    let h = sc.hertz()?;
    let (fs, fd) = sc.coefficients(d.fs, d.fd)?;
    let m = DoubleCm::new(h, fs, fd)?;
    let q = d.force.force(fd, h.p_load);
    let weak = match (d.weak.w, d.weak.delta, d.weak.lambda, sc.law()) {
        (Some(w), _, _, _) => Weakening::Energy(w),
        (None, None, None, None) => {
            return Err(CliError::Usage(
                "--delta, --lambda or --w is required (or --case with a case that has a \
                 friction law)"
                    .into(),
            ));
        }
        _ => Weakening::SlipLength(sc.delta(d.weak.delta, d.weak.lambda, &h, fs, fd)?),
    };
    let st = m.solve(q, weak)?;
    let mut v = sc.annotate(json!({
        "fs": fs, "fd": fd, "load": h.p_load, "a": h.a,
        "q": q, "q_over_fd_p": q / (fd * h.p_load),
        "c": st.c, "b": st.b, "c_over_a": st.c / h.a, "b_over_a": st.b / h.a,
        "w": st.w, "p_c": st.p_c,
    }));
    if let Weakening::SlipLength(delta) = weak {
        v["delta"] = json!(delta);
        if fs > fd {
            v["lambda"] = json!(scales::lambda(h.geom.r, delta, fs, fd, h.a)?);
            let jkr = JkrCurve::new(Jkr::new(h, fs, fd, delta)?.psi())?;
            v["psi"] = json!(jkr.psi);
            v["jkr_c_over_a"] = json!(jkr.stick_half_width(q / (fd * h.p_load)).ok());
        }
    }
    v["cm_fd_c_over_a"] = json!(
        CattaneoMindlin::new(h, fd)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    v["cm_fs_c_over_a"] = json!(
        CattaneoMindlin::new(h, fs)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    print_json(out, &v)
}
