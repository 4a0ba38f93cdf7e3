//! What a run reports: the friction summary (Q_max, Λ, χ, Ψ, s0 and the closed forms through
//! [`crate::analytic`]), the self-checks of the last converged step, `summary.json`,
//! `history.csv` and the one-screen end summary. The records they are made of are in
//! [`crate::record`].

use crate::case::Case;
use crate::contact::solver::State;
use crate::driver::Simulation;
use crate::error::{CheckFailure, RunError};
use crate::model::Model;
use crate::model::step::ContactFigures;
use crate::record::{FrictionSummary, StepRecord};
use serde::Serialize;
use std::path::Path;

/// What `summary.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub case: String,
    pub title: String,
    pub mesh: String,
    pub nodes: usize,
    pub triangles: usize,
    pub dofs_free: usize,
    pub dofs_retained: usize,
    pub contact_nodes: usize,
    pub candidate_gap: Option<f64>,
    pub stiffness_nonzeros_upper: usize,
    pub threads: usize,
    pub timings_s: crate::model::Timings,
    /// Time in the contact iterations (part of `timings_s.solve`).
    pub contact_solve_s: f64,
    /// Its parts in the structured solve (see [`crate::contact::solver::SolveTimings`]).
    pub contact_phases_s: crate::contact::solver::SolveTimings,
    pub newton_iterations: usize,
    /// Dense factorisations and GMRES iterations of the contact Newton solves.
    pub lu_factorisations: usize,
    pub gmres_iterations: usize,
    /// Contact unknowns from which the structured contact solve takes its shortcuts (null:
    /// switched off by `STICKSLIP_CONTACT_SHORTCUTS=off`, every iteration solved directly).
    pub contact_shortcuts_from: Option<usize>,
    pub peak_memory_mib: Option<f64>,
    /// The numeric factorisation's modelled operations (null where this run did not analyse
    /// a contact model: a model-cache hit, or no contact).
    pub factor_flops: Option<crate::model::FactorFlops>,
    pub friction: Option<FrictionSummary>,
    /// Self-checks of the last converged step (see [`crate::checks`]).
    pub checks: Vec<crate::checks::Check>,
    pub steps: Vec<StepRecord>,
    pub output_dir: String,
    /// `completed`, or why the run stopped early.
    pub status: String,
    /// The energy balance, when the run keeps it (see [`crate::case::Output::energy`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<crate::energy::EnergySummary>,
    /// How the model cache served the run: `hit`, `miss` (built and written), `rebuilt` (an
    /// unusable entry replaced) or `off`, with the entry's path and size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cache: Option<crate::cache::Report>,
    /// Bytes of this run's files in the output directory (`.vtu`, `.pvd`, contact tables,
    /// restart states, `history.csv`, `energy.csv`), counted when `summary.json` is written
    /// (which it does not count).
    pub output_bytes: u64,
    /// The stages integrated in time (dynamic stages and the event after a lost equilibrium).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<crate::driver::EventSummary>,
}

/// The self-checks of the last converged step (none when no step converged).
pub(crate) fn final_checks(
    model: &Model,
    last_u: Option<Vec<f64>>,
    last_state: Option<&State>,
    last_scale: f64,
    records: &[StepRecord],
    friction: Option<&FrictionSummary>,
    equilibrium: Option<crate::checks::Check>,
) -> Vec<crate::checks::Check> {
    let u = match (last_u, last_state) {
        (Some(u), _) => u,
        (None, Some(st)) => model.contact_displacement(last_scale, st),
        (None, None) => return Vec::new(),
    };
    crate::checks::run_checks(&crate::checks::Input {
        model,
        u: &u,
        scale: last_scale,
        state: last_state,
        records,
        friction,
        equilibrium,
    })
}

/// The failure an error-level check makes of a run that otherwise completed.
fn failed_check(checks: &[crate::checks::Check]) -> Option<CheckFailure> {
    checks
        .iter()
        .find(|c| c.level == crate::checks::Level::Error)
        .map(|c| CheckFailure {
            name: c.name.to_string(),
            value: c.value,
            limit: c.limit,
            note: c.note.to_string(),
        })
}

/// The one-screen summary printed at the end of a run.
pub fn end_summary(case_path: &Path, s: &Summary, out_dir: &Path, stem: &str) -> String {
    let mut o = String::new();
    let t = &s.timings_s;
    o += &format!(
        "stickslip: {} — {} ({} steps)\n",
        case_path.display(),
        s.status,
        s.steps.len()
    );
    o += &format!(
        "  mesh      {}: {} triangles, {} nodes, {} DOFs ({} retained)\n",
        s.mesh, s.triangles, s.nodes, s.dofs_free, s.dofs_retained
    );
    if let Some(c) = s.steps.last().and_then(|r| r.contact) {
        o += &format!(
            "  contact   a = {:.5}, c = {:.5}, b = {:.5}; {} nodes in contact ({} stick, {} slip); force ({:.5}, {:.5})\n",
            c.a, c.c, c.b, c.n_contact, c.n_stick, c.n_slip, c.fx, c.fy
        );
    }
    if let Some(f) = &s.friction {
        let opt = |v: Option<f64>| v.map_or("–".to_string(), |x| format!("{x:.4}"));
        o += &format!(
            "  friction  f_s = {}, f_d = {}, Δ = {}: Λ = {}, χ = {}, Ψ = {}, s0/a = {}{}\n",
            f.f_s,
            opt(f.f_d),
            f.delta.map_or("–".into(), |d| format!("{d:.3e}")),
            opt(f.lambda),
            opt(f.chi),
            opt(f.psi),
            opt(f.s0_over_a),
            match f.resolved {
                Some(true) => " (resolved)",
                Some(false) => " (NOT resolved by the mesh)",
                None => "",
            }
        );
        let peaked = s.status.starts_with("equilibrium lost")
            || s.steps
                .last()
                .and_then(|r| r.pilot)
                .is_some_and(|p| p.fx.abs() < f.q_max - 1e-9 * f.q_max.max(1.0));
        let theory = match &f.not_hertzian {
            Some(why) if f.apparent_friction_jkr.is_none() => format!("no closed form: {why}"),
            _ => format!(
                "JKR {}, double C–M {}",
                opt(f.apparent_friction_jkr),
                opt(f.apparent_friction_dcm)
            ),
        };
        o += &format!(
            "  Q_max/P   {} ({theory}){}\n",
            format_args!("{:.5}", f.apparent_friction),
            if peaked {
                ": the peak was reached"
            } else {
                ": largest load applied; the peak was not reached"
            }
        );
    }
    if s.newton_iterations > 0 {
        o += &format!(
            "  Newton    {} iterations, {} factorisations, {} GMRES iterations, {:.3} s\n",
            s.newton_iterations, s.lu_factorisations, s.gmres_iterations, s.contact_solve_s
        );
    }
    o += &format!(
        "  time      read {:.3}, pair {:.3}, assemble {:.3}, analyse {:.3}, factorise {:.3}, condense {:.3}, solve {:.3}, write {:.3} (waited for {:.3}) s; peak memory {}\n",
        t.read,
        t.pair,
        t.assemble,
        t.analyse,
        t.factorise,
        t.condense,
        t.solve,
        t.write,
        t.write_wait,
        s.peak_memory_mib
            .map_or("unknown".into(), |m| format!("{m:.0} MiB"))
    );
    if let Some(f) = &s.factor_flops {
        // What the factorisation had to do, whatever the machine: where a finer mesh's time
        // goes (the constraint rows' part grows fastest along a ladder that refines the contact).
        o += &format!(
            "  factor    {:.2e} modelled operations ({:.0} % K̂, {:.0} % the constraint rows' coupling, {:.0} % their dense block){}\n",
            f.total(),
            100.0 * f.k / f.total(),
            100.0 * f.coupling / f.total(),
            100.0 * f.constraint_block / f.total(),
            if t.factorise > 0.0 {
                format!(", {:.1} Gflop/s", f.total() / t.factorise / 1e9)
            } else {
                String::new()
            }
        );
    }
    o += &format!(
        "  output    {} ({stem}.pvd, history.csv, summary.json): {}\n",
        out_dir.display(),
        human_bytes(s.output_bytes)
    );
    if let Some(c) = &s.cache
        && let (Some(path), Some(bytes)) = (&c.path, c.bytes)
    {
        o += &format!(
            "  cache     {} entry {path}: {} (clear with `rm -r` of its directory)\n",
            serde_json::to_value(c.status)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default(),
            human_bytes(bytes)
        );
    }
    o
}

/// `bytes` for a person: B, KiB, MiB or GiB.
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    match bytes {
        0..1024 => format!("{bytes} B"),
        1024..1_048_576 => format!("{:.1} KiB", b / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.1} MiB", b / 1_048_576.0),
        _ => format!("{:.2} GiB", b / 1_073_741_824.0),
    }
}

/// Bytes of the files of a run of case `stem` in `dir` (see [`Summary::output_bytes`]).
pub fn output_bytes(dir: &Path, stem: &str) -> u64 {
    let ours = |n: &str| {
        n == crate::output::JOURNAL
            || n.starts_with(&format!("{stem}_")) && n.ends_with(".vtu")
            || n == format!("{stem}.pvd")
            || n == format!("{stem}_time.pvd")
            || n.starts_with("contact_") && n.ends_with(".csv")
            || n.starts_with("state_") && n.ends_with(".json")
            || n == "history.csv"
            || n == "energy.csv"
    };
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| ours(&e.file_name().to_string_lossy()))
        .filter_map(|e| e.metadata().ok())
        .map(|m| m.len())
        .sum()
}

/// The friction summary of a run: the law's Δ and W/p and the paper's scales Λ, χ, Ψ, s0 for
/// the load the run reached.
pub fn friction_summary(
    model: &Model,
    law: Option<&crate::friction::FrictionLaw>,
    last: Option<ContactFigures>,
    q_max: f64,
) -> Option<FrictionSummary> {
    let law = law?.clone();
    let cm = model.contact.as_ref()?;
    let fig = last?;
    let n0 = cm.pair.common_normal.unwrap_or([0.0, 1.0]);
    let load = (fig.fx * n0[0] + fig.fy * n0[1]).abs();
    // Effective radius from the initial gaps of the zone nodes: g0 ≈ t²/(2R), t along the face.
    let (radius, x0, tau, rms) = crate::checks::fit_radius(model, None)?;
    let not_hertzian = crate::checks::not_hertzian(radius, rms);
    let a_hertz = not_hertzian
        .is_none()
        .then(|| crate::checks::hertz_a(load, radius, cm.e_star));
    let fs = law.f_static();
    let fd = law.f_dynamic().ok();
    let weakening = fd.filter(|fd| fs > *fd);
    let delta = weakening.and_then(|_| law.delta().ok());
    let w_over_p = weakening.and_then(|_| law.w_over_p().ok());
    let lambda = match (weakening, delta, a_hertz) {
        (Some(fd), Some(d), Some(a)) if a > 0.0 => Some(radius * d / ((fs - fd) * a * a)),
        _ => None,
    };
    let ratio = weakening.map(|fd| fs / fd - 1.0);
    let chi = lambda.zip(ratio).map(|(l, r)| r * l);
    let psi = lambda.zip(ratio).map(|(l, r)| r * r * l);
    let s0_over_a = lambda.map(|l| 2.0 * l / std::f64::consts::PI);
    // The contact's half-width: Hertz's where it applies, else the one computed.
    let half_width = a_hertz.unwrap_or(fig.a);
    let h_contact = cm
        .pair
        .zone_edges
        .iter()
        .filter(|e| {
            let x = model.mesh.nodes[e[2]];
            ((x[0] - x0[0]) * tau[0] + (x[1] - x0[1]) * tau[1]).abs() <= half_width
        })
        .map(|e| {
            let (p, q) = (model.mesh.nodes[e[0]], model.mesh.nodes[e[1]]);
            (p[0] - q[0]).hypot(p[1] - q[1])
        })
        .fold(0.0, f64::max);
    let resolved = s0_over_a
        .zip(a_hertz)
        .map(|(s, a)| h_contact <= 0.5 * s * a);
    // Closed-form apparent friction Q_max/P (eqs. QJKR and Qx at their maxima, Fig. 6).
    let closed = match (weakening, chi) {
        (Some(fd), Some(chi)) => crate::analytic::apparent::apparent(chi, fs / fd, true)
            .ok()
            .map(|p| (p.q_max_jkr * fd, p.q_max_dcm.map(|q| q * fd))),
        _ => None,
    };
    // Constant friction: Q_max = f P whatever the profile.
    let constant = if weakening.is_none() { fd } else { None };
    let apparent_friction_jkr = closed.map(|c| c.0).or(constant);
    let apparent_friction_dcm = closed.and_then(|c| c.1).or(constant);
    Some(FrictionSummary {
        law,
        f_s: fs,
        f_d: fd,
        delta,
        w_over_p,
        load,
        radius,
        profile_rms: rms,
        hertzian: not_hertzian.is_none(),
        not_hertzian,
        a_hertz,
        lambda,
        chi,
        psi,
        s0_over_a,
        h_contact,
        resolved,
        q_max,
        apparent_friction: if load > 0.0 { q_max / load } else { 0.0 },
        apparent_friction_jkr,
        apparent_friction_dcm,
    })
}

/// `history.csv`: one row per converged step (integer columns printed as integers; a value
/// that does not apply, such as K_II without a front, as `NaN`). `t` is the physical time
/// (advanced by the steps integrated in time only) and `kinetic` the kinetic energy (zero in
/// quasi-static steps). The fronts of weakening, their energy release rates and fracture
/// energies (`front_*`, `g_*`, `gamma_*`, [`crate::record::FrontFigures`]) are given in the
/// steps integrated in time.
pub fn history_csv(records: &[StepRecord]) -> String {
    let na = |v: Option<f64>| v.unwrap_or(f64::NAN);
    // Quasi-static steps take no physical time and are at rest.
    let mut t = 0.0;
    let rows: Vec<Vec<f64>> = records
        .iter()
        .map(|r| {
            t = r.physical_time.unwrap_or(t);
            let p = r.pilot.unwrap_or_default();
            let c = r.contact.unwrap_or_default();
            let f = r.fronts.unwrap_or_default();
            vec![
                r.step as f64,
                r.stage as f64,
                r.time,
                r.traction_scale,
                p.ux,
                p.uy,
                p.fx,
                p.fy,
                r.iterations as f64,
                r.cutbacks as f64,
                c.n_contact as f64,
                c.n_stick as f64,
                c.n_slip as f64,
                c.a,
                c.x_centre,
                c.c,
                c.b,
                c.fx,
                c.fy,
                r.wall_s,
                c.mean_slip,
                r.cycle.unwrap_or(0) as f64,
                t,
                r.kinetic.unwrap_or(0.0),
                na(c.c_left),
                na(c.c_right),
                na(c.b_left),
                na(c.b_right),
                na(c.k2_left),
                na(c.k2_right),
                na(c.k2_paper),
                na(f.front[0]),
                na(f.front[1]),
                na(f.g[0]),
                na(f.g[1]),
                na(f.gamma[0]),
                na(f.gamma[1]),
            ]
        })
        .collect();
    crate::output::csv(
        &[
            "step",
            "stage",
            "time",
            "traction_scale",
            "pilot_ux",
            "pilot_uy",
            "pilot_fx",
            "pilot_fy",
            "iterations",
            "cutbacks",
            "n_contact",
            "n_stick",
            "n_slip",
            "a",
            "x_centre",
            "c",
            "b",
            "contact_fx",
            "contact_fy",
            "wall_s",
            "mean_slip",
            "cycle",
            "t",
            "kinetic",
            "c_left",
            "c_right",
            "b_left",
            "b_right",
            "k2_left",
            "k2_right",
            "k2_paper",
            "front_left",
            "front_right",
            "g_left",
            "g_right",
            "gamma_left",
            "gamma_right",
        ],
        &rows,
        &[
            "step",
            "stage",
            "iterations",
            "cutbacks",
            "n_contact",
            "n_stick",
            "n_slip",
            "cycle",
        ],
    )
}

/// The summary of a finished (or stopped) run, with why it stopped: the failure (a solver
/// failure, or an error-level check of the last step) and the bracket of a lost equilibrium.
/// `equilibrium` is the equilibrium check of the last step when the caller computed it already
/// (a run computes it while its last steps are written).
pub fn summarise(
    model: &Model,
    case: &Case,
    case_path: &Path,
    out_dir: &Path,
    sim: Simulation,
    equilibrium: Option<crate::checks::Check>,
) -> (Summary, Option<RunError>, Option<(f64, f64)>) {
    let Simulation {
        records,
        failure,
        lost_equilibrium,
        newton_iterations,
        lu_factorisations,
        gmres_iterations,
        contact_solve_s,
        contact_phases_s,
        last_u,
        last_state,
        last_scale,
        events,
        ..
    } = sim;
    // The quasi-static peak: the pilot force of a step integrated in time also moves the
    // bodies' mass.
    let q_max = records
        .iter()
        .filter(|r| r.kinetic.is_none())
        .filter_map(|r| r.pilot)
        .map(|p| p.fx.abs())
        .fold(0.0, f64::max);
    let friction = friction_summary(
        model,
        model.friction.as_ref(),
        records.last().and_then(|r| r.contact),
        q_max,
    );
    let checks = final_checks(
        model,
        last_u,
        last_state.as_ref(),
        last_scale,
        &records,
        friction.as_ref(),
        equilibrium,
    );
    let (failure, status) = judge(failure, lost_equilibrium, friction.as_ref(), &checks);
    let status = match (&failure, lost_equilibrium) {
        (Some(_), None) => format!("{status}; the output holds the steps before it"),
        _ => status,
    };
    let status = match events.iter().rfind(|e| e.after_lost_equilibrium) {
        Some(e) if lost_equilibrium.is_some() => format!(
            "{status}; the jump under that load was integrated in time and {}",
            e.describe()
        ),
        _ => status,
    };
    let summary = Summary {
        case: case_path.display().to_string(),
        title: case.title.clone(),
        mesh: model.mesh.source.display().to_string(),
        nodes: model.active.iter().filter(|a| **a).count(),
        triangles: model.elems.len(),
        dofs_free: model.dofs.n_free(),
        dofs_retained: model.dofs.n_retained,
        contact_nodes: model.contact.as_ref().map_or(0, |c| c.system.ns),
        candidate_gap: model.contact.as_ref().map(|c| c.pair.candidate_gap),
        stiffness_nonzeros_upper: model.stiffness_nonzeros,
        threads: rayon::current_num_threads(),
        timings_s: model.timings.clone(),
        contact_solve_s,
        contact_phases_s,
        newton_iterations,
        lu_factorisations,
        gmres_iterations,
        contact_shortcuts_from: crate::contact::solver::shortcuts_from(),
        peak_memory_mib: crate::output::peak_memory_bytes().map(|b| b as f64 / (1024.0 * 1024.0)),
        factor_flops: model.factor_flops,
        friction,
        checks,
        steps: records,
        output_dir: out_dir.display().to_string(),
        status,
        energy: None,
        events,
        cache: model.cache_report(),
        output_bytes: 0,
    };
    (summary, failure, lost_equilibrium)
}

/// How a run (or a sweep row) ended: the error that stopped it, if any (a failed step, else an
/// error-level check of the last step), and its status line: `completed`, `equilibrium lost …`
/// with Q_max and the load that found no equilibrium, or `failed at …`.
pub fn judge(
    failure: Option<crate::error::StepFailure>,
    lost_equilibrium: Option<(f64, f64)>,
    friction: Option<&FrictionSummary>,
    checks: &[crate::checks::Check],
) -> (Option<RunError>, String) {
    let failure: Option<RunError> = match failure {
        Some(f) => Some(f.into()),
        None => failed_check(checks).map(Into::into),
    };
    let status = match (&failure, lost_equilibrium) {
        (None, _) => "completed".into(),
        (Some(_), Some((q, qf))) => {
            // Below f_d P the contact can carry the load: a local peak, not gross sliding.
            match friction.and_then(|f| f.local_peak(q)) {
                None => format!("equilibrium lost: Q_max = {q:.6} (no equilibrium at {qf:.6})"),
                Some(fdp) => format!(
                    "equilibrium lost at a local peak (not gross sliding: Q_max < f_d P = {fdp:.6}): Q_max = {q:.6} (no equilibrium at {qf:.6})"
                ),
            }
        }
        (Some(m), None) => format!("failed at {m}"),
    };
    (failure, status)
}

/// Prints the warnings of a summary (`show`: the log level lets warnings through): an
/// unresolved slip-weakening transition, and every warning-level check.
pub fn print_warnings(summary: &Summary, show: bool) {
    if !show {
        return;
    }
    if let Some(fr) = &summary.friction
        && fr.resolved == Some(false)
    {
        eprintln!(
            "warning: the contact elements (h = {:.3e}) are larger than s0/2 = {:.3e}: the slip-weakening transition zone is not resolved; use a finer mesh along the faces",
            fr.h_contact,
            fr.s0_over_a.unwrap_or(0.0) * fr.a_hertz.unwrap_or(0.0) / 2.0
        );
    }
    for c in &summary.checks {
        if c.level == crate::checks::Level::NotApplied {
            eprintln!("note: check `{}` {}", c.name, c.note);
        }
        // The s0 warning is printed above in its own words.
        if c.level == crate::checks::Level::Warning && c.name != "s0_resolution" {
            eprintln!(
                "warning: check `{}`: {:.4e} against {} {:.4e}: {}",
                c.name,
                c.value,
                if c.at_least { "at least" } else { "at most" },
                c.limit,
                c.note
            );
        }
    }
}
