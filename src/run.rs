//! The run driver: stages and load steps (with cutback), the solve of each step on the
//! condensed system, and the output of every step.

use crate::case::{Case, Control};
use crate::contact::solver::{self, ContactError, PilotDrive, State, Status};
use crate::model::{Model, ModelError};
use crate::output::{self, PvdEntry, vtu};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{0}")]
    Solve(String),
    #[error("cannot write output `{path}`: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error(
        "the contact reached the edge of the candidate zone (candidate gap {gap:e}) at step {step}"
    )]
    ZoneClipped { gap: f64, step: usize },
    #[error(
        "equilibrium lost (gross sliding): the tangential load cannot exceed Q_max = {q_max:.6} \
         (bracketed to [{q_max:.6}, {q_fail:.6}] by {cutbacks} bisections); the output holds the \
         state just before it"
    )]
    EquilibriumLost {
        q_max: f64,
        q_fail: f64,
        cutbacks: usize,
    },
}

impl RunError {
    /// Process exit status: 2 for bad input, 3 for a solver failure, 4 for output errors, 5 when
    /// a force-controlled tangential load passes the largest load the contact can carry.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_)
            | RunError::Model(
                ModelError::MeshRead(_)
                | ModelError::MeshCheck(_)
                | ModelError::Dof { .. }
                | ModelError::Edge { .. }
                | ModelError::Contact { .. }
                | ModelError::Unsupported(_),
            ) => 2,
            RunError::Model(ModelError::Factor(_))
            | RunError::Solve(_)
            | RunError::ZoneClipped { .. } => 3,
            RunError::Write { .. } => 4,
            RunError::EquilibriumLost { .. } => 5,
        }
    }
}

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

/// The state of the pilot after a step.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PilotState {
    pub ux: f64,
    pub uy: f64,
    pub fx: f64,
    pub fy: f64,
}

/// Figures of the contact after a step.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ContactFigures {
    /// Nodes in contact, in stick, in slip.
    pub n_contact: usize,
    pub n_stick: usize,
    pub n_slip: usize,
    /// Contact semi-width (edges extrapolated with p² linear in x between the two outermost
    /// contact nodes on each side).
    pub a: f64,
    /// Centre of the contact.
    pub x_centre: f64,
    /// Stick semi-width (each edge midway between the outermost stick node and the next node).
    pub c: f64,
    /// Semi-width of the zone where μ has not yet reached its dynamic value (midway rule).
    pub b: f64,
    /// Total contact force on the master side.
    pub fx: f64,
    pub fy: f64,
    /// Mean slip over the contact (the quantity of slip control; see `State::mean_slip`).
    pub mean_slip: f64,
}

/// One converged load step.
#[derive(Clone, Debug, Serialize)]
pub struct StepRecord {
    pub step: usize,
    pub stage: usize,
    pub time: f64,
    pub traction_scale: f64,
    pub pilot: Option<PilotState>,
    pub iterations: usize,
    pub cutbacks: usize,
    pub contact: Option<ContactFigures>,
    pub wall_s: f64,
}

/// The friction law and the paper's scales of the run (eqs. Maugis, Maugis10, Lambda, s0).
#[derive(Clone, Debug, Serialize)]
pub struct FrictionSummary {
    pub law: crate::friction::FrictionLaw,
    pub f_s: f64,
    pub f_d: Option<f64>,
    /// Slip length Δ and fracture energy per unit pressure W/p (slip-weakening laws).
    pub delta: Option<f64>,
    pub w_over_p: Option<f64>,
    /// Normal load P (contact force along the common normal at the last step), effective
    /// radius R (fitted to the initial gap, g0 ≈ t²/2R) and Hertz semi-width a.
    pub load: f64,
    pub radius: f64,
    pub a_hertz: f64,
    pub lambda: Option<f64>,
    pub chi: Option<f64>,
    pub psi: Option<f64>,
    /// Small-scale transition length at the centre, s0 = 2Λa/π, over a.
    pub s0_over_a: Option<f64>,
    /// Largest slave element in the contact, and whether it resolves s0 (h ≤ s0/2).
    pub h_contact: f64,
    pub resolved: Option<bool>,
    /// The largest tangential load reached (|pilot force| along the tangent), and the apparent
    /// static friction coefficient Q_max/P it implies.
    pub q_max: f64,
    pub apparent_friction: f64,
    /// Closed-form predictions of Q_max/P: the JKR limit (eq. QJKR at its maximum, with Ψ) and
    /// the double Cattaneo–Mindlin maximum (with Λ).
    pub apparent_friction_jkr: Option<f64>,
    pub apparent_friction_dcm: Option<f64>,
}

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
    pub newton_iterations: usize,
    /// Dense factorisations and GMRES iterations of the contact Newton solves.
    pub lu_factorisations: usize,
    pub gmres_iterations: usize,
    pub peak_memory_mib: Option<f64>,
    pub friction: Option<FrictionSummary>,
    /// Self-checks of the last converged step (see [`crate::checks`]).
    pub checks: Vec<crate::checks::Check>,
    pub steps: Vec<StepRecord>,
    pub output_dir: String,
    /// `completed`, or why the run stopped early.
    pub status: String,
}

/// The load of one step: the traction scale and the pilot's two controls.
#[derive(Clone, Copy, Debug)]
pub struct StepLoad {
    pub scale: f64,
    pub control: [Control; 2],
}

impl Model {
    /// Solves one load step without contact: tractions at `scale`, the pilot driven by
    /// `control`. Returns the free solution vector and the pilot state (if there is a pilot).
    pub fn solve_step(
        &self,
        scale: f64,
        control: [Control; 2],
    ) -> Result<(Vec<f64>, Option<PilotState>), String> {
        let f = self.load(scale);
        let cond = &self.condensed;
        if self.dofs.pilot.is_none() {
            return Ok((cond.recover(&f, &[], &[]), None));
        }
        let g = cond.reduce(&f);
        let (u, r) = solve_pilot(&cond.s_dense(), &g, control, cond.krr_scale)?;
        Ok((
            cond.recover(&f, &r, &u),
            Some(PilotState {
                ux: u[0],
                uy: u[1],
                fx: r[0],
                fy: r[1],
            }),
        ))
    }

    /// The free load vector at traction scale `scale`.
    pub fn load(&self, scale: f64) -> Vec<f64> {
        self.f_traction
            .iter()
            .zip(&self.f_prescribed)
            .map(|(a, b)| scale * a + b)
            .collect()
    }

    /// Solves one load step with contact from the committed state `prev` (the contact unknowns
    /// only; [`Model::contact_displacement`] recovers the full field when it is wanted).
    pub fn solve_contact_step(
        &self,
        load: StepLoad,
        prev: &State,
        guess: Option<&State>,
        opt: &solver::Options,
        law: Option<&crate::friction::FrictionLaw>,
        cache: Option<&mut solver::LuCache>,
    ) -> Result<solver::StepOutcome, ContactError> {
        let StepLoad { scale, control } = load;
        let cm = self.contact.as_ref().expect("contact model");
        let w0: Vec<f64> = self.contact_w0[0]
            .iter()
            .zip(&self.contact_w0[1])
            .map(|(a, b)| scale * a + b)
            .collect();
        let drive = control.map(|c| match c {
            Control::Force(f) => PilotDrive::Force(f),
            Control::Displacement(d) => PilotDrive::Displacement(d),
            Control::Slip(s) => PilotDrive::Slip(s),
        });
        cm.system
            .solve_step(&w0, drive, law, prev, guess, opt, cache)
    }

    /// The displacement of all free DOFs for a contact state at traction scale `scale`: one
    /// solve with the factorised stiffness.
    pub fn contact_displacement(&self, scale: f64, st: &State) -> Vec<f64> {
        let cm = self.contact.as_ref().expect("contact model");
        let r = cm.retained_forces(st, self.dofs.n_retained);
        self.condensed.recover_total(&self.load(scale), &r)
    }

    /// Contact figures of a state.
    pub fn contact_figures(
        &self,
        st: &State,
        law: Option<&crate::friction::FrictionLaw>,
    ) -> ContactFigures {
        let cm = self.contact.as_ref().expect("contact model");
        let m = &cm.pair.mortar;
        let xs: Vec<f64> = m
            .slave_nodes
            .iter()
            .map(|&n| self.mesh.nodes[n][0])
            .collect();
        let p: Vec<f64> = (0..xs.len()).map(|j| st.f_n[j] / m.weight[j]).collect();
        let on: Vec<usize> = (0..xs.len())
            .filter(|&j| st.status[j] != Status::Open)
            .collect();
        let mut fig = ContactFigures {
            n_contact: on.len(),
            n_stick: st.status.iter().filter(|s| **s == Status::Stick).count(),
            n_slip: st.status.iter().filter(|s| **s == Status::Slip).count(),
            ..Default::default()
        };
        let r = cm.retained_forces(st, self.dofs.n_retained);
        let (mut fx, mut fy) = (0.0, 0.0);
        for &node in &m.master_nodes {
            for c in 0..2 {
                if let crate::dofs::Dof::Free(i) = self.dofs.node[node][c] {
                    let k = i - self.dofs.n_interior;
                    if c == 0 { fx += r[k] } else { fy += r[k] }
                }
            }
        }
        fig.fx = fx;
        fig.fy = fy;
        fig.mean_slip = st.mean_slip;
        if on.is_empty() {
            return fig;
        }
        let (lo, hi) = (on[0], *on.last().expect("non-empty"));
        let edge = |j1: usize, j2: usize| -> f64 {
            // p² linear in x through the two outermost nodes, extrapolated to zero.
            let (a, b) = (p[j1].max(0.0).powi(2), p[j2].max(0.0).powi(2));
            let dx = xs[j1] - xs[j2];
            if b > a && dx != 0.0 {
                {
                    // at most one node spacing beyond the last contact node
                    let ext = a / (b - a) * dx;
                    xs[j1] + if dx > 0.0 { ext.min(dx) } else { ext.max(dx) }
                }
            } else {
                xs[j1]
            }
        };
        let left = if lo < hi { edge(lo, lo + 1) } else { xs[lo] };
        let right = if hi > lo { edge(hi, hi - 1) } else { xs[hi] };
        // The face may run in −x (a slave on the upper body): widths are absolute.
        fig.a = 0.5 * (right - left).abs();
        fig.x_centre = 0.5 * (right + left);
        let half_width = |pred: &dyn Fn(usize) -> bool| -> f64 {
            let idx: Vec<usize> = (0..xs.len()).filter(|&j| pred(j)).collect();
            if idx.is_empty() {
                return 0.0;
            }
            let (a, b) = (idx[0], *idx.last().expect("non-empty"));
            let l = if a > 0 {
                0.5 * (xs[a] + xs[a - 1])
            } else {
                xs[a]
            };
            let r = if b + 1 < xs.len() {
                0.5 * (xs[b] + xs[b + 1])
            } else {
                xs[b]
            };
            0.5 * (r - l).abs()
        };
        fig.c = half_width(&|j| st.status[j] == Status::Stick);
        if let Some(law) = law
            && let Ok(fd) = law.f_dynamic()
        {
            let fs = law.f_static();
            if fs > fd {
                let tol = 1e-9 * (fs - fd);
                fig.b =
                    half_width(&|j| st.status[j] != Status::Open && law.mu(st.slip[j]) > fd + tol);
            }
        }
        fig
    }
}

/// Solves `S u = g + r` on the pilot DOFs with, per component, either the force `r` or the
/// displacement `u` given. Returns (u, r). `scale` is the stiffness scale of the pilot
/// before condensation: a pivot below 1e-10 of it means nothing holds the pilot.
pub fn solve_pilot(
    s: &[f64],
    g: &[f64],
    control: [Control; 2],
    scale: f64,
) -> Result<([f64; 2], [f64; 2]), String> {
    let mut u = [0.0; 2];
    let mut r = [0.0; 2];
    let mut free = Vec::new();
    for c in 0..2 {
        match control[c] {
            Control::Force(f) => {
                r[c] = f;
                free.push(c);
            }
            Control::Displacement(d) => u[c] = d,
            Control::Slip(_) => {
                return Err("slip control needs frictional contact".into());
            }
        }
    }
    // S_FF u_F = g_F + r_F − S_FD u_D
    let rhs: Vec<f64> = free
        .iter()
        .map(|&i| {
            g[i] + r[i]
                - (0..2)
                    .filter(|j| !free.contains(j))
                    .map(|j| s[i * 2 + j] * u[j])
                    .sum::<f64>()
        })
        .collect();
    match free.len() {
        1 => {
            let i = free[0];
            if s[i * 2 + i].abs() <= 1e-10 * scale {
                return Err(singular());
            }
            u[i] = rhs[0] / s[i * 2 + i];
        }
        2 => {
            let det = s[0] * s[3] - s[1] * s[2];
            if s[0].abs().min(s[3].abs()) <= 1e-10 * scale || det.abs() <= 1e-10 * scale * scale {
                return Err(singular());
            }
            u[0] = (s[3] * rhs[0] - s[1] * rhs[1]) / det;
            u[1] = (s[0] * rhs[1] - s[2] * rhs[0]) / det;
        }
        _ => {}
    }
    for i in 0..2 {
        r[i] = s[i * 2] * u[0] + s[i * 2 + 1] * u[1] - g[i];
    }
    Ok((u, r))
}

fn singular() -> String {
    "the pilot is force-controlled but the body it drives is not held in that direction \
     (no support and no contact): control it by displacement instead"
        .into()
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

/// The self-checks of the last converged step (none when no step converged).
fn final_checks(
    model: &Model,
    last_u: Option<Vec<f64>>,
    last_state: Option<&State>,
    last_scale: f64,
    records: &[StepRecord],
    friction: Option<&FrictionSummary>,
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
    })
}

/// The failure an error-level check makes of a run that otherwise completed.
fn failed_check(checks: &[crate::checks::Check]) -> Option<String> {
    checks
        .iter()
        .find(|c| c.level == crate::checks::Level::Error)
        .map(|c| {
            format!(
                "the last step: check `{}` failed ({:.3e} against {:.3e}): {}",
                c.name, c.value, c.limit, c.note
            )
        })
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
                let res = model.solve_contact_step(
                    StepLoad {
                        scale: sc,
                        control: ctl,
                    },
                    prev,
                    guess.as_ref(),
                    opt,
                    law.as_ref(),
                    Some(&mut lu_cache),
                );
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
                        let lost = matches!(ctl[0], Control::Force(_))
                            && matches!(target[0], Some(Control::Force(_)))
                            && law.is_some();
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
                format!("equilibrium lost: Q_max = {q:.6} (no equilibrium at {qf:.6})")
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
        return Err(RunError::EquilibriumLost {
            q_max,
            q_fail,
            cutbacks: MAX_CUTBACKS,
        });
    }
    if let Some(m) = failure {
        return Err(RunError::Solve(m));
    }
    Ok(summary)
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
        o += &format!(
            "  Q_max/P   {} (JKR {}, double C–M {}){}\n",
            format_args!("{:.5}", f.apparent_friction),
            opt(f.apparent_friction_jkr),
            opt(f.apparent_friction_dcm),
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
        "  time      read {:.3}, assemble {:.3}, analyse {:.3}, factorise {:.3}, condense {:.3}, solve {:.3}, write {:.3} s; peak memory {}\n",
        t.read,
        t.assemble,
        t.analyse,
        t.factorise,
        t.condense,
        t.solve,
        t.write,
        s.peak_memory_mib
            .map_or("unknown".into(), |m| format!("{m:.0} MiB"))
    );
    o += &format!(
        "  output    {} ({stem}.pvd, history.csv, summary.json)\n",
        out_dir.display()
    );
    o
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
    let (radius, x0, tau, _) = crate::checks::fit_radius(model, None)?;
    let a_hertz = crate::checks::hertz_a(load, radius, cm.e_star);
    let fs = law.f_static();
    let fd = law.f_dynamic().ok();
    let weakening = fd.filter(|fd| fs > *fd);
    let delta = weakening.and_then(|_| law.delta().ok());
    let w_over_p = weakening.and_then(|_| law.w_over_p().ok());
    let lambda = match (weakening, delta) {
        (Some(fd), Some(d)) if a_hertz > 0.0 => Some(radius * d / ((fs - fd) * a_hertz * a_hertz)),
        _ => None,
    };
    let ratio = weakening.map(|fd| fs / fd - 1.0);
    let chi = lambda.zip(ratio).map(|(l, r)| r * l);
    let psi = lambda.zip(ratio).map(|(l, r)| r * r * l);
    let s0_over_a = lambda.map(|l| 2.0 * l / std::f64::consts::PI);
    let h_contact = cm
        .pair
        .zone_edges
        .iter()
        .filter(|e| {
            let x = model.mesh.nodes[e[2]];
            ((x[0] - x0[0]) * tau[0] + (x[1] - x0[1]) * tau[1]).abs() <= a_hertz
        })
        .map(|e| {
            let (p, q) = (model.mesh.nodes[e[0]], model.mesh.nodes[e[1]]);
            (p[0] - q[0]).hypot(p[1] - q[1])
        })
        .fold(0.0, f64::max);
    let resolved = s0_over_a.map(|s| h_contact <= 0.5 * s * a_hertz);
    // Closed-form apparent friction Q_max/P (eqs. QJKR and Qx at their maxima, Fig. 6).
    let closed = match (weakening, chi) {
        (Some(fd), Some(chi)) => crate::analytic::apparent::apparent(chi, fs / fd, true)
            .ok()
            .map(|p| (p.q_max_jkr * fd, p.q_max_dcm.map(|q| q * fd))),
        _ => None,
    };
    let apparent_friction_jkr = closed
        .map(|c| c.0)
        .or(if weakening.is_none() { fd } else { None });
    let apparent_friction_dcm =
        closed
            .and_then(|c| c.1)
            .or(if weakening.is_none() { fd } else { None });
    Some(FrictionSummary {
        law,
        f_s: fs,
        f_d: fd,
        delta,
        w_over_p,
        load,
        radius,
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

/// Per slave node: (p, q, gap, slip, slip increment, status, μ, q/p).
fn contact_fields(model: &Model, st: &State) -> Vec<[f64; 8]> {
    let m = &model.contact.as_ref().expect("contact").pair.mortar;
    (0..m.slave_nodes.len())
        .map(|j| {
            let p = st.f_n[j] / m.weight[j];
            // Shear traction on the slave body along its tangent (the master force is −F_t τ on the slave).
            let q = -st.f_t[j] / m.weight[j];
            let ratio = if p > 0.0 { q / p } else { 0.0 };
            [
                p,
                q,
                st.gap[j],
                st.slip[j],
                st.dv[j],
                st.status[j].code(),
                st.mu[j],
                ratio,
            ]
        })
        .collect()
}

const CONTACT_FIELDS: [&str; 8] = [
    "pressure",
    "shear",
    "gap",
    "slip",
    "slip_increment",
    "status",
    "mu",
    "q_over_p",
];

/// The contact dataset: the slave edges of the candidate zone with the nodal contact fields.
pub fn contact_vtu(model: &Model, st: &State) -> Result<Vec<u8>, vtkio::Error> {
    let cm = model.contact.as_ref().expect("contact");
    let m = &cm.pair.mortar;
    let mut index = std::collections::HashMap::new();
    let mut points = Vec::new();
    let mut node_ids = Vec::new();
    for e in &cm.pair.zone_edges {
        for &n in e {
            index.entry(n).or_insert_with(|| {
                points.push(model.mesh.nodes[n]);
                node_ids.push(n);
                points.len() - 1
            });
        }
    }
    let cells: Vec<Vec<usize>> = cm
        .pair
        .zone_edges
        .iter()
        .map(|e| e.iter().map(|n| index[n]).collect())
        .collect();
    let fields = contact_fields(model, st);
    let slot: std::collections::HashMap<usize, usize> = m
        .slave_nodes
        .iter()
        .enumerate()
        .map(|(j, &n)| (n, j))
        .collect();
    let mut data: Vec<vtu::Field> = CONTACT_FIELDS
        .iter()
        .enumerate()
        .map(|(k, name)| {
            vtu::Field::scalar(
                name,
                node_ids
                    .iter()
                    .map(|n| slot.get(n).map_or(0.0, |&j| fields[j][k]))
                    .collect(),
            )
        })
        .collect();
    let mut traction = Vec::new();
    let mut normal = Vec::new();
    for n in &node_ids {
        match slot.get(n) {
            Some(&j) => {
                let (p, q) = (fields[j][0], fields[j][1]);
                let (nv, tv) = (m.normal[j], m.tangent[j]);
                // Traction on the slave body: pressure pushes against its outward normal.
                traction.extend([-p * nv[0] + q * tv[0], -p * nv[1] + q * tv[1], 0.0]);
                normal.extend([nv[0], nv[1], 0.0]);
            }
            None => {
                traction.extend([0.0; 3]);
                normal.extend([0.0; 3]);
            }
        }
    }
    data.push(vtu::Field::vector("traction", traction));
    data.push(vtu::Field::vector("normal", normal));
    vtu::unstructured("contact", &points, &cells, vtu::Kind::Line3, data, vec![])
}

/// The per-step CSV along the slave face.
pub fn contact_csv(model: &Model, st: &State) -> String {
    let m = &model.contact.as_ref().expect("contact").pair.mortar;
    let fields = contact_fields(model, st);
    let rows: Vec<Vec<f64>> = m
        .slave_nodes
        .iter()
        .zip(&fields)
        .map(|(&n, f)| {
            let x = model.mesh.nodes[n];
            let mut r = vec![x[0], x[1]];
            r.extend_from_slice(f);
            r
        })
        .collect();
    let mut header = vec!["x", "y"];
    header.extend(CONTACT_FIELDS);
    output::csv(&header, &rows, &["status"])
}

/// The bodies dataset of one step: displacement, stresses, von Mises, body id.
pub fn bodies_vtu(model: &Model, u: &[f64], case: &Case) -> Result<Vec<u8>, vtkio::Error> {
    let mut index = vec![usize::MAX; model.mesh.nodes.len()];
    let mut points = Vec::new();
    for (n, &a) in model.active.iter().enumerate() {
        if a {
            index[n] = points.len();
            points.push(model.mesh.nodes[n]);
        }
    }
    let stress = model.nodal_stresses(u);
    let mut disp = Vec::with_capacity(points.len() * 3);
    let (mut sxx, mut syy, mut sxy, mut szz, mut vm) = (vec![], vec![], vec![], vec![], vec![]);
    for (n, &a) in model.active.iter().enumerate() {
        if !a {
            continue;
        }
        let d = model.dofs.displacement(n, u);
        disp.extend([d[0], d[1], 0.0]);
        let s = stress[n];
        sxx.push(s[0]);
        syy.push(s[1]);
        sxy.push(s[2]);
        szz.push(s[3]);
        vm.push(crate::elasticity::von_mises(s[0], s[1], s[2], s[3]));
    }
    let cells: Vec<Vec<usize>> = model
        .elems
        .iter()
        .map(|(e, _)| {
            model.mesh.triangles[*e]
                .nodes
                .iter()
                .map(|&n| index[n])
                .collect()
        })
        .collect();
    let body: Vec<f64> = model.elem_body.iter().map(|&b| b as f64).collect();
    vtu::unstructured(
        &case.title,
        &points,
        &cells,
        vtu::Kind::Tri6,
        vec![
            vtu::Field::vector("displacement", disp),
            vtu::Field::scalar("stress_xx", sxx),
            vtu::Field::scalar("stress_yy", syy),
            vtu::Field::scalar("stress_xy", sxy),
            vtu::Field::scalar("stress_zz", szz),
            vtu::Field::scalar("von_mises", vm),
        ],
        vec![vtu::Field::scalar("body_id", body)],
    )
}

/// One row of a sweep: a friction law run on the shared model.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// Index of the friction law and of the load (stage list) in the sweep file.
    pub index: usize,
    pub load_index: usize,
    pub status: String,
    pub steps: usize,
    pub newton_iterations: usize,
    /// Factorisations of the contact Newton solves (see [`Summary::lu_factorisations`]).
    pub lu_factorisations: usize,
    pub wall_s: f64,
    /// Stick and transition semi-widths at the last converged step.
    pub c: f64,
    pub b: f64,
    pub friction: Option<FrictionSummary>,
    /// The self-checks of the last converged step (an error-level one fails the row).
    pub checks: Vec<crate::checks::Check>,
}

/// Runs each of `loads` (cases that differ from the model's in their stages only) with each
/// friction law on one built model, in parallel, and returns one row per (load, law) pair,
/// loads outermost, in the order given. The model (assembly, factorisation, condensation,
/// Delassus operator) is shared: stages change only the loads, never the matrices.
pub fn sweep(
    model: &Model,
    loads: &[Case],
    laws: &[crate::friction::FrictionLaw],
) -> Vec<SweepRow> {
    use rayon::prelude::*;
    let jobs: Vec<(usize, usize)> = (0..loads.len())
        .flat_map(|l| (0..laws.len()).map(move |i| (l, i)))
        .collect();
    jobs.par_iter()
        .map(|&(load_index, index)| {
            let (case, law) = (&loads[load_index], &laws[index]);
            let t = Instant::now();
            let res = simulate(model, case, Some(law), LogLevel::Error, &mut |_| Ok(()));
            let wall_s = t.elapsed().as_secs_f64();
            match res {
                Ok(mut sim) => {
                    let last = sim.records.last().and_then(|r| r.contact);
                    let q_max = sim
                        .records
                        .iter()
                        .filter_map(|r| r.pilot)
                        .map(|p| p.fx.abs())
                        .fold(0.0, f64::max);
                    let friction = friction_summary(model, Some(law), last, q_max);
                    let checks = final_checks(
                        model,
                        sim.last_u.take(),
                        sim.last_state.as_ref(),
                        sim.last_scale,
                        &sim.records,
                        friction.as_ref(),
                    );
                    if sim.failure.is_none() {
                        sim.failure = failed_check(&checks);
                    }
                    let status = match (&sim.failure, sim.lost_equilibrium) {
                        (None, _) => "completed".to_string(),
                        (Some(_), Some((q, qf))) => {
                            format!("equilibrium lost: Q_max = {q:.6} (none at {qf:.6})")
                        }
                        (Some(m), None) => format!("failed: {m}"),
                    };
                    SweepRow {
                        index,
                        load_index,
                        status,
                        steps: sim.records.len(),
                        newton_iterations: sim.newton_iterations,
                        lu_factorisations: sim.lu_factorisations,
                        wall_s,
                        c: last.map_or(0.0, |f| f.c),
                        b: last.map_or(0.0, |f| f.b),
                        friction,
                        checks,
                    }
                }
                Err(e) => SweepRow {
                    index,
                    load_index,
                    status: format!("error: {e}"),
                    steps: 0,
                    newton_iterations: 0,
                    lu_factorisations: 0,
                    wall_s,
                    c: 0.0,
                    b: 0.0,
                    friction: None,
                    checks: Vec::new(),
                },
            }
        })
        .collect()
}
