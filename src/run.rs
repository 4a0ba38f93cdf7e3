//! The run driver: stages and load steps (with cutbacks and the bracketing of Q_max), one
//! solve per step on the condensed model ([`crate::model::step`]), the output of every step
//! ([`crate::output::fields`]) and the report at the end ([`crate::report`]).

use crate::case::{Case, Control};
use crate::contact::solver::{self, State, Status};
pub use crate::error::RunError;
use crate::model::Model;
use crate::model::StepLoad;
use crate::model::step::PilotState;
use crate::output::fields::{bodies_vtu, contact_csv, contact_vtu};
use crate::output::{self, PvdEntry};
use crate::report::{
    StepRecord, Summary, end_summary, failed_check, final_checks, friction_summary,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of a run from the command line.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (overrides the case's).
    pub out: Option<PathBuf>,
    /// Print nothing but errors (same as `log = Error`).
    pub quiet: bool,
    /// How much to print: errors; warnings; progress and the end summary (default); every
    /// Newton iteration.
    pub log: LogLevel,
}

/// How much a run prints to standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, clap::ValueEnum)]
pub enum LogLevel {
    Error,
    Warn,
    #[default]
    Info,
    Debug,
}

impl RunOptions {
    fn level(&self) -> LogLevel {
        if self.quiet {
            LogLevel::Error
        } else {
            self.log
        }
    }
}

/// Runs a case file end to end and writes its output. Returns the summary.
/// If the contact grows to the edge of its candidate zone, the zone is doubled and the run
/// starts again.
pub fn run(case_path: &Path, opts: &RunOptions) -> Result<Summary, RunError> {
    let case = Case::load(case_path)?;
    let out_dir = opts
        .out
        .clone()
        .or(case.output.dir.clone())
        .unwrap_or_else(|| {
            PathBuf::from("out").join(
                case_path
                    .file_stem()
                    .map(|s| s.to_string_lossy().to_string())
                    .unwrap_or("case".into()),
            )
        });
    let mut gap = None;
    for _ in 0..8 {
        let model = Model::build_with_gap(&case, case_path, gap)?;
        match run_model(&case, case_path, model, &out_dir, opts) {
            Err(RunError::ZoneClipped { gap: g, step }) => {
                if !opts.quiet {
                    eprintln!(
                        "note: the contact reached the edge of the candidate zone at step {step} (candidate gap {g:.3e}); doubling the zone and starting again"
                    );
                }
                gap = Some(2.0 * g);
            }
            other => return other,
        }
    }
    Err(RunError::Solve(
        "the contact zone kept growing: check the loads and the candidate gap".into(),
    ))
}

fn wr(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    output::write_atomic(path, bytes).map_err(|source| RunError::Write {
        path: path.display().to_string(),
        source,
    })
}

/// One converged step, handed to the caller of [`simulate`].
pub struct StepEvent<'a> {
    pub step: usize,
    pub time: f64,
    pub scale: f64,
    /// Whether this is the last step of the last stage.
    pub last: bool,
    /// The free solution, where the step computed it (runs without contact).
    pub u: Option<&'a Vec<f64>>,
    /// The contact state (runs with contact; the full field is recovered on demand).
    pub contact: Option<&'a State>,
    /// The record of this step.
    pub record: &'a StepRecord,
}

/// What [`simulate`] returns.
pub struct Simulation {
    pub records: Vec<StepRecord>,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// (Q_max, the load at which no equilibrium was found) when a force-controlled tangential
    /// load passed the peak.
    pub lost_equilibrium: Option<(f64, f64)>,
    pub newton_iterations: usize,
    /// Dense factorisations and GMRES iterations of the contact Newton solves.
    pub lu_factorisations: usize,
    pub gmres_iterations: usize,
    pub solve_s: f64,
    pub contact_solve_s: f64,
    /// The last converged step: its free solution (runs without contact), contact state and
    /// traction scale.
    pub last_u: Option<Vec<f64>>,
    pub last_state: Option<State>,
    pub last_scale: f64,
}

/// Steps through the stages of a case on a built model with friction law `law` (overriding
/// the model's), calling `on_step` after every converged step. Steps that do not converge are
/// cut back (halved) up to 12 times from the last converged state.
pub fn simulate(
    model: &Model,
    case: &Case,
    law: Option<&crate::friction::FrictionLaw>,
    log: LogLevel,
    on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    let quiet = log < LogLevel::Warn;
    let has_pilot = model.dofs.pilot.is_some();
    let law = law.cloned();
    let copt = case.contact.as_ref().map(|c| solver::Options {
        method: c.method,
        kappa: c.penalty.unwrap_or(100.0),
        max_iterations: c.max_iterations.unwrap_or(60),
        tolerance: c.tolerance.unwrap_or(1e-8),
        verbose: log >= LogLevel::Debug,
    });
    let mut cstate = model.contact.as_ref().map(|c| c.system.initial_state());
    let mut lu_cache = solver::LuCache::default();
    let mut control = [Control::Force(0.0); 2];
    let mut pilot = PilotState::default();
    let mut scale = 0.0;
    let mut records = Vec::new();
    let mut step = 0;
    let (mut t_solve, mut t_contact) = (0.0, 0.0);
    let mut newton_total = 0;
    let mut failure: Option<String> = None;
    let mut bracket: Option<(f64, f64)> = None;
    let mut lost_equilibrium: Option<(f64, f64)> = None;
    let mut last_u: Option<Vec<f64>> = None;
    const MAX_CUTBACKS: usize = 12;
    'stages: for (si, stage) in case.stages.iter().enumerate() {
        let start = (
            pilot,
            scale,
            control,
            cstate.as_ref().map_or(0.0, |s| s.mean_slip),
        );
        let target = [stage.pilot_x, stage.pilot_y];
        let nominal = 1.0 / stage.steps as f64;
        let mut alpha = 0.0;
        let mut dalpha = nominal;
        // The state before the last converged one, with its load fraction (none across stages).
        let mut older: Option<(f64, State)> = None;
        let mut cutbacks = 0;
        // A stage that changes no load (a hold): every step of it keeps the converged state.
        let hold = stage.traction_scale.is_none_or(|v| v == start.1)
            && (0..2).all(|c| match (target[c], start.2[c]) {
                (None, _) => true,
                (Some(Control::Force(f)), Control::Force(f0)) => f == f0,
                (Some(Control::Displacement(d)), _) => d == [start.0.ux, start.0.uy][c],
                (Some(Control::Slip(s)), _) => s == start.3,
                (Some(Control::Force(_)), _) => false,
            });
        while alpha < 1.0 - 1e-12 {
            let a_new = (alpha + dalpha).min(1.0);
            let t = Instant::now();
            let sc = match stage.traction_scale {
                Some(v) => start.1 + a_new * (v - start.1),
                None => start.1,
            };
            let (u0, r0) = ([start.0.ux, start.0.uy], [start.0.fx, start.0.fy]);
            let m0 = start.3;
            let mut ctl = control;
            for c in 0..2 {
                ctl[c] = match (target[c], start.2[c]) {
                    (Some(Control::Force(f)), _) => Control::Force(r0[c] + a_new * (f - r0[c])),
                    (Some(Control::Displacement(d)), _) => {
                        Control::Displacement(u0[c] + a_new * (d - u0[c]))
                    }
                    (None, Control::Force(_)) => Control::Force(r0[c]),
                    (None, Control::Displacement(_)) => Control::Displacement(u0[c]),
                    (Some(Control::Slip(s)), _) => Control::Slip(m0 + a_new * (s - m0)),
                    (None, Control::Slip(_)) => Control::Slip(m0),
                };
            }
            if let Some(why) = unheld_before(model, case, &ctl) {
                failure = Some(format!("step {}: {why}", step + 1));
                break 'stages;
            }
            let (u, p, iterations) = if let (Some(prev), Some(opt)) = (&cstate, &copt) {
                let tc = Instant::now();
                // Predictor: extrapolate the forces of the last two steps of this stage.
                let guess = older
                    .as_ref()
                    .filter(|(a0, _)| *a0 >= 0.0)
                    .map(|(a_old, old)| {
                        let t = (a_new - alpha) / (alpha - a_old).max(1e-300);
                        let ext = |c: &[f64], o: &[f64]| {
                            c.iter()
                                .zip(o)
                                .map(|(c, o)| c + t * (c - o))
                                .collect::<Vec<f64>>()
                        };
                        let mut g = prev.clone();
                        g.f_n = ext(&prev.f_n, &old.f_n)
                            .into_iter()
                            .map(|v| v.max(0.0))
                            .collect();
                        g.f_t = ext(&prev.f_t, &old.f_t);
                        g.z = ext(&prev.z, &old.z);
                        g
                    });
                let res = if !records.is_empty() && hold {
                    // A step that changes no load (a hold) from a converged state: that state
                    // is its answer, with no slip in the step (rate-independent friction). A
                    // Newton solve could cycle at the tolerance between nodes on the Coulomb
                    // limit and be mistaken for a lost equilibrium.
                    let mut state = prev.clone();
                    state.dv.iter_mut().for_each(|v| *v = 0.0);
                    Ok(solver::StepOutcome {
                        state,
                        iterations: 0,
                        last_update: 0.0,
                    })
                } else {
                    model.solve_contact_step(
                        StepLoad {
                            scale: sc,
                            control: ctl,
                        },
                        prev,
                        guess.as_ref(),
                        opt,
                        law.as_ref(),
                        Some(&mut lu_cache),
                    )
                };
                t_contact += tc.elapsed().as_secs_f64();
                // A converged answer of an unheld body is a failed step: under force control
                // the cutbacks then bracket the load that lost equilibrium.
                let res = match res {
                    Ok(out) => {
                        // Clipping: contact on the rim of the candidate zone.
                        let cm = model.contact.as_ref().expect("contact");
                        let rim = cm
                            .pair
                            .mortar
                            .slave_nodes
                            .iter()
                            .zip(&out.state.status)
                            .any(|(n, s)| {
                                *s != Status::Open && cm.pair.rim_nodes.binary_search(n).is_ok()
                            });
                        if rim {
                            return Err(RunError::ZoneClipped {
                                gap: cm.pair.candidate_gap,
                                step: step + 1,
                            });
                        }
                        match unheld_after(model, case, &ctl, &out.state) {
                            Some(why) => Err(why),
                            None => Ok(out),
                        }
                    }
                    Err(e) => Err(e.to_string()),
                };
                match res {
                    Ok(out) => {
                        let p = PilotState {
                            ux: out.state.pilot_u[0],
                            uy: out.state.pilot_u[1],
                            fx: out.state.pilot_f[0],
                            fy: out.state.pilot_f[1],
                        };
                        let it = out.iterations;
                        newton_total += it;
                        older = cstate.take().map(|c| (alpha, c));
                        cstate = Some(out.state);
                        (None, has_pilot.then_some(p), it)
                    }
                    Err(e) => {
                        // Failed attempts count in the solve time too (they can dominate a run
                        // that brackets Q_max).
                        t_solve += t.elapsed().as_secs_f64();
                        // A force-controlled tangential load that no equilibrium carries: the
                        // cutbacks bisect between the last converged load and this one; a failure
                        // that survives all of them is reported as the loss of equilibrium.
                        // (Only when the step raised that load: a step that failed at the
                        // load of the last converged one is a solver failure, not a peak.)
                        let lost = matches!(ctl[0], Control::Force(_))
                            && matches!(target[0], Some(Control::Force(_)))
                            && law.is_some()
                            && ctl[0] != control[0];
                        if lost {
                            bracket = Some((
                                pilot.fx,
                                match ctl[0] {
                                    Control::Force(f) => f,
                                    Control::Displacement(_) | Control::Slip(_) => f64::NAN,
                                },
                            ));
                        }
                        if cutbacks < MAX_CUTBACKS {
                            cutbacks += 1;
                            dalpha *= 0.5;
                            if !quiet {
                                eprintln!(
                                    "step {} of stage {si}: {e}; cutting the load increment back to {dalpha:.3e} of the stage",
                                    step + 1
                                );
                            }
                            continue;
                        }
                        failure = Some(format!(
                            "step {}: {e} (after {MAX_CUTBACKS} cutbacks)",
                            step + 1
                        ));
                        lost_equilibrium = bracket;
                        break 'stages;
                    }
                }
            } else {
                match model.solve_step(sc, ctl) {
                    Ok((u, p)) => (Some(u), p, 0),
                    Err(m) => {
                        failure = Some(format!("step {}: {m}", step + 1));
                        break 'stages;
                    }
                }
            };
            let finite = match (&u, &cstate) {
                (Some(u), _) => u.iter().all(|v| v.is_finite()),
                (None, Some(st)) => st
                    .f_n
                    .iter()
                    .chain(&st.f_t)
                    .chain(&st.z)
                    .all(|v| v.is_finite()),
                (None, None) => true,
            };
            if !finite {
                failure = Some(format!("step {}: the solution is not finite", step + 1));
                break 'stages;
            }
            alpha = a_new;
            control = ctl;
            scale = sc;
            if let Some(p) = p {
                pilot = p;
            }
            step += 1;
            let wall = t.elapsed().as_secs_f64();
            t_solve += wall;
            let figures = cstate
                .as_ref()
                .map(|st| model.contact_figures(st, law.as_ref()));
            let time = si as f64 + alpha;
            records.push(StepRecord {
                step,
                stage: si,
                time,
                traction_scale: scale,
                pilot: has_pilot.then_some(pilot),
                iterations,
                cutbacks,
                contact: figures,
                wall_s: wall,
            });
            let last = si + 1 == case.stages.len() && alpha >= 1.0 - 1e-12;
            on_step(&StepEvent {
                step,
                time,
                scale,
                last,
                u: u.as_ref(),
                contact: cstate.as_ref(),
                record: records.last().expect("pushed above"),
            })?;
            if u.is_some() {
                last_u = u;
            }
            // The cutback count is per step: the next step starts afresh.
            cutbacks = 0;
            if dalpha < nominal {
                dalpha = (2.0 * dalpha).min(nominal);
            }
        }
    }
    Ok(Simulation {
        failure,
        lost_equilibrium,
        newton_iterations: newton_total,
        lu_factorisations: lu_cache.factorisations,
        gmres_iterations: lu_cache.gmres_iterations,
        solve_s: t_solve,
        contact_solve_s: t_contact,
        last_u,
        last_state: if records.is_empty() { None } else { cstate },
        last_scale: scale,
        records,
    })
}

/// The pilot's drive along the direction that separates its (otherwise unheld) body from the
/// contact: the dominant component of that direction, and its force if force-controlled.
fn separating_force(model: &Model, ctl: &[Control; 2]) -> Option<(usize, usize, Option<f64>)> {
    let (body, sep) = model.pilot_separation?;
    let k = if sep[0].abs() > sep[1].abs() { 0 } else { 1 };
    let f = match ctl[k] {
        Control::Force(f) => Some(f * sep[k].signum()),
        Control::Displacement(_) | Control::Slip(_) => None,
    };
    Some((body, k, f))
}

/// A step that cannot have an equilibrium: the pilot pulls a body that nothing else holds away
/// from the contact (a force along the separating direction).
fn unheld_before(model: &Model, case: &Case, ctl: &[Control; 2]) -> Option<String> {
    let (body, k, f) = separating_force(model, ctl)?;
    let f = f.filter(|f| *f > 0.0)?;
    Some(format!(
        "the pilot's force pilot_{} = {:e} pulls `{}` away from the contact, and nothing else \
         holds that body (no support): no equilibrium exists; press the bodies together or \
         control the pilot by displacement",
        ["x", "y"][k],
        f * model.pilot_separation.expect("checked").1[k].signum(),
        case.bodies[body].group
    ))
}

/// A converged step whose answer means nothing: a force-controlled pilot body with no node in
/// contact and no support (held only by the solver's grounding spring), or a pilot that ran
/// away (see [`crate::checks::DISPLACEMENT_ERROR`]).
fn unheld_after(model: &Model, case: &Case, ctl: &[Control; 2], st: &State) -> Option<String> {
    let size = model.mesh.diameter();
    let u = st.pilot_u[0].hypot(st.pilot_u[1]);
    let limit = crate::checks::DISPLACEMENT_ERROR;
    if model.dofs.pilot.is_some() && (u.is_nan() || u > limit * size) {
        return Some(format!(
            "the pilot moved {u:e}, more than {limit} times the model's size {size:e}: a body is \
             not held (check the supports and that the loads press the bodies together)"
        ));
    }
    let (body, k, f) = separating_force(model, ctl)?;
    f?;
    if st.status.iter().all(|s| *s == Status::Open) {
        return Some(format!(
            "no node is in contact and nothing else holds `{}` along {} (no support, pilot_{} \
             force-controlled): the body is free; press the bodies together or control the pilot \
             by displacement",
            case.bodies[body].group,
            ["x", "y"][k],
            ["x", "y"][k]
        ));
    }
    None
}

/// How many of the case's nominal load steps the load path has covered at `time` (stage index
/// plus the fraction of that stage).
fn nominal_steps_done(case: &Case, time: f64) -> f64 {
    let mut done = 0.0;
    for (i, st) in case.stages.iter().enumerate() {
        let frac = (time - i as f64).clamp(0.0, 1.0);
        done += frac * st.steps as f64;
    }
    done
}

/// Steps through the stages of a built model, writing output to `out_dir`.
pub fn run_model(
    case: &Case,
    case_path: &Path,
    mut model: Model,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<Summary, RunError> {
    std::fs::create_dir_all(out_dir).map_err(|source| RunError::Write {
        path: out_dir.display().to_string(),
        source,
    })?;
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or("case".into());
    let mut pvd = Vec::new();
    let mut t_write = 0.0;
    let law = model.friction.clone();
    let level = opts.level();
    let total = case.total_steps();
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bar = (level >= LogLevel::Info && tty).then(|| {
        let b = indicatif::ProgressBar::new(total as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} steps {elapsed} {msg}")
                .expect("valid template"),
        );
        b
    });
    // Writes the VTK files of one converged step (and rewrites the .pvd series).
    let mut write_step = |step: usize,
                          time: f64,
                          scale: f64,
                          u: Option<&Vec<f64>>,
                          contact: Option<&State>|
     -> Result<(), RunError> {
        let t = Instant::now();
        let name = format!("{stem}_{step:04}.vtu");
        let u = match (u, contact) {
            (Some(u), _) => u.clone(),
            (None, Some(st)) => model.contact_displacement(scale, st),
            (None, None) => unreachable!("a step has a solution or a contact state"),
        };
        let bytes = bodies_vtu(&model, &u, case).map_err(|e| RunError::Write {
            path: name.clone(),
            source: std::io::Error::other(e.to_string()),
        })?;
        wr(&out_dir.join(&name), &bytes)?;
        pvd.push(PvdEntry {
            time,
            part: 0,
            file: name,
        });
        if let Some(st) = contact {
            let cname = format!("{stem}_contact_{step:04}.vtu");
            let bytes = contact_vtu(&model, st).map_err(|e| RunError::Write {
                path: cname.clone(),
                source: std::io::Error::other(e.to_string()),
            })?;
            wr(&out_dir.join(&cname), &bytes)?;
            pvd.push(PvdEntry {
                time,
                part: 1,
                file: cname,
            });
            wr(
                &out_dir.join(format!("contact_{step:04}.csv")),
                contact_csv(&model, st).as_bytes(),
            )?;
        }
        wr(
            &out_dir.join(format!("{stem}.pvd")),
            output::pvd(&pvd).as_bytes(),
        )?;
        t_write += t.elapsed().as_secs_f64();
        Ok(())
    };
    // The last converged step not yet written (`output.every` > 1).
    #[allow(clippy::type_complexity)]
    let mut unwritten: Option<(usize, f64, f64, Option<Vec<f64>>, Option<State>)> = None;
    let sim = simulate(&model, case, law.as_ref(), level, &mut |ev: &StepEvent| {
        let step = ev.step;
        let r = ev.record;
        let msg = match (r.pilot, r.contact) {
            (Some(p), Some(c)) => format!(
                "Q = {:.5}, P = {:.5}, a = {:.5}, c = {:.5}, {} its",
                p.fx, -p.fy, c.a, c.c, r.iterations
            ),
            (Some(p), None) => format!(
                "pilot u = ({:.4e}, {:.4e}), F = ({:.5}, {:.5})",
                p.ux, p.uy, p.fx, p.fy
            ),
            _ => format!("traction scale {:.4}", r.traction_scale),
        };
        // Progress in nominal steps: cutbacks add steps, so the count is not the position.
        let done = nominal_steps_done(case, ev.time);
        match &bar {
            Some(b) => {
                b.set_position(done.round() as u64);
                b.set_message(msg);
            }
            None if level >= LogLevel::Info => {
                eprintln!(
                    "step {step} (stage {}, {:.0} % of the load path): {msg}",
                    r.stage,
                    100.0 * done / total as f64
                )
            }
            None => {}
        }
        if !case.output.vtu {
            return Ok(());
        }
        if ev.step.is_multiple_of(case.output.every) || ev.last {
            unwritten = None;
            write_step(ev.step, ev.time, ev.scale, ev.u, ev.contact)
        } else {
            // Kept so that a run that stops early still writes its last converged state.
            unwritten = Some((
                ev.step,
                ev.time,
                ev.scale,
                ev.u.cloned(),
                ev.contact.cloned(),
            ));
            Ok(())
        }
    })?;
    if let Some((step, time, scale, u, st)) = unwritten.take()
        && sim.failure.is_some()
    {
        write_step(step, time, scale, u.as_ref(), st.as_ref())?;
    }
    let Simulation {
        records,
        mut failure,
        lost_equilibrium,
        newton_iterations: newton_total,
        lu_factorisations,
        gmres_iterations,
        solve_s: t_solve,
        contact_solve_s: t_contact,
        last_u,
        last_state,
        last_scale,
    } = sim;
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    const MAX_CUTBACKS: usize = 12;
    model.timings.solve = t_solve;
    model.timings.write = t_write;
    let rows: Vec<Vec<f64>> = records
        .iter()
        .map(|r| {
            let p = r.pilot.unwrap_or_default();
            let c = r.contact.unwrap_or_default();
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
            ]
        })
        .collect();
    wr(
        &out_dir.join("history.csv"),
        output::csv(
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
            ],
        )
        .as_bytes(),
    )?;
    let friction = friction_summary(
        &model,
        model.friction.as_ref(),
        records.last().and_then(|r| r.contact),
        records
            .iter()
            .filter_map(|r| r.pilot)
            .map(|p| p.fx.abs())
            .fold(0.0, f64::max),
    );
    let checks = final_checks(
        &model,
        last_u,
        last_state.as_ref(),
        last_scale,
        &records,
        friction.as_ref(),
    );
    if failure.is_none() {
        failure = failed_check(&checks);
    }
    let local_peak =
        lost_equilibrium.and_then(|(q, _)| friction.as_ref().and_then(|f| f.local_peak(q)));
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
        stiffness_nonzeros_upper: model.k.row_idx.len(),
        threads: rayon::current_num_threads(),
        timings_s: model.timings.clone(),
        contact_solve_s: t_contact,
        newton_iterations: newton_total,
        lu_factorisations,
        gmres_iterations,
        peak_memory_mib: output::peak_memory_bytes().map(|b| b as f64 / (1024.0 * 1024.0)),
        friction,
        checks,
        steps: records,
        output_dir: out_dir.display().to_string(),
        status: match (&failure, lost_equilibrium) {
            (None, _) => "completed".into(),
            (Some(_), Some((q, qf))) => {
                // Below f_d P the contact can carry the load: a local peak, not gross sliding.
                match local_peak {
                    None => format!("equilibrium lost: Q_max = {q:.6} (no equilibrium at {qf:.6})"),
                    Some(fdp) => format!(
                        "equilibrium lost at a local peak (not gross sliding: Q_max < f_d P = {fdp:.6}): Q_max = {q:.6} (no equilibrium at {qf:.6})"
                    ),
                }
            }
            (Some(m), None) => format!("failed at {m}; the output holds the steps before it"),
        },
    };
    wr(
        &out_dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .expect("serialisable")
            .as_bytes(),
    )?;
    if let Some(fr) = &summary.friction
        && fr.resolved == Some(false)
        && level >= LogLevel::Warn
    {
        eprintln!(
            "warning: the contact elements (h = {:.3e}) are larger than s0/2 = {:.3e}: the slip-weakening transition zone is not resolved; use a finer mesh along the faces",
            fr.h_contact,
            fr.s0_over_a.unwrap_or(0.0) * fr.a_hertz / 2.0
        );
    }
    if level >= LogLevel::Warn {
        for c in &summary.checks {
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
    if level >= LogLevel::Info {
        eprint!("{}", end_summary(case_path, &summary, out_dir, &stem));
    }
    if let Some((q_max, q_fail)) = lost_equilibrium {
        let local_peak = summary.friction.as_ref().and_then(|f| f.local_peak(q_max));
        return Err(RunError::EquilibriumLost {
            q_max,
            q_fail,
            cutbacks: MAX_CUTBACKS,
            local_peak,
        });
    }
    if let Some(m) = failure {
        return Err(RunError::Solve(m));
    }
    Ok(summary)
}
