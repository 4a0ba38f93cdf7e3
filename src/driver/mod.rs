//! The load-path driver: the stages of a case stepped on a built model, with a predictor
//! from the last two steps, cutbacks of a step that does not converge, and the bracketing of
//! the peak tangential force when a force-controlled load passes it. It reads the model and
//! the case, and hands every converged step to its caller ([`StepEvent`]); it writes nothing.

mod unheld;

use crate::case::{Case, Control, Stage};
use crate::contact::solver::{self, ContactError, State, Status};
use crate::error::{RunError, StepError, StepFailure};
use crate::friction::FrictionLaw;
use crate::model::Model;
use crate::model::StepLoad;
use crate::model::step::PilotState;
use crate::record::StepRecord;
use std::time::Instant;
pub use unheld::DISPLACEMENT_ERROR;
use unheld::{unheld_after, unheld_before};

/// Halvings of a stage's nominal increment before a step is given up: no increment is smaller
/// than the nominal one over `2^MAX_CUTBACKS`, so a lost equilibrium is bracketed to within
/// `2^(1 − MAX_CUTBACKS)` of a nominal step (5e-4 of it; see [`Driver::run_stage`]).
pub const MAX_CUTBACKS: usize = 12;

/// A stage accepts at most `STEP_BUDGET` times its nominal steps, and at least
/// `STEP_BUDGET_MIN` steps (room for the bracketing of a peak in a stage of one step), after
/// which the run stops with [`StepError::StepBudget`] and keeps its last converged state.
pub const STEP_BUDGET: usize = 10;
pub const STEP_BUDGET_MIN: usize = 50;

/// The step budget of a stage of `steps` nominal steps.
pub fn step_budget(steps: usize) -> usize {
    (STEP_BUDGET * steps).max(STEP_BUDGET_MIN)
}

/// The index `k` of the first nominal fraction `k / steps` above `alpha` (a fraction reached
/// exactly counts as passed).
fn next_nominal(alpha: f64, steps: usize) -> usize {
    let k = (alpha * steps as f64).floor() as usize;
    if (k as f64 / steps as f64) <= alpha {
        k + 1
    } else {
        k
    }
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

/// One converged step, handed to the caller of [`simulate`].
pub struct StepEvent<'a> {
    pub step: usize,
    pub time: f64,
    pub scale: f64,
    /// Whether this is the last step of the last stage.
    pub last: bool,
    /// The case's nominal step (counted over all stages, from 1) this step lands on; `None` for
    /// a sub-step between two nominal loads (after a cutback).
    pub nominal: Option<usize>,
    /// The free solution, where the step computed it (runs without contact).
    pub u: Option<&'a Vec<f64>>,
    /// The contact state (runs with contact; the full field is recovered on demand).
    pub contact: Option<&'a State>,
    /// The record of this step.
    pub record: &'a StepRecord,
    /// The driver's state after this step, when it is a checkpoint ([`Restart::every`]).
    pub checkpoint: Option<&'a Checkpoint>,
}

/// What [`simulate`] returns.
pub struct Simulation {
    pub records: Vec<StepRecord>,
    /// Why the run stopped early, if it did.
    pub failure: Option<StepFailure>,
    /// (Q_max, the load at which no equilibrium was found) when a force-controlled tangential
    /// load passed the peak.
    pub lost_equilibrium: Option<(f64, f64)>,
    /// The failed attempts that bracketed the lost equilibrium.
    pub bracket_attempts: usize,
    pub newton_iterations: usize,
    /// Dense factorisations and GMRES iterations of the contact Newton solves.
    pub lu_factorisations: usize,
    pub gmres_iterations: usize,
    pub solve_s: f64,
    pub contact_solve_s: f64,
    /// Seconds in the parts of the structured contact solve (this process's share).
    pub contact_phases_s: solver::SolveTimings,
    /// The last converged step: its free solution (runs without contact), contact state and
    /// traction scale.
    pub last_u: Option<Vec<f64>>,
    pub last_state: Option<State>,
    pub last_scale: f64,
}

/// Steps through the stages of a case on a built model with friction law `law` (overriding
/// the model's), calling `on_step` after every converged step. Steps that do not converge are
/// cut back (halved) from the last converged state, down to the floor of [`MAX_CUTBACKS`]
/// halvings of a nominal step (see [`Driver::run_stage`]).
pub fn simulate(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
    log: LogLevel,
    on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
) -> Result<Simulation, RunError> {
    simulate_with(model, case, law, log, on_step, Restart::default())
}

/// Checkpoints of a run and where it resumes.
#[derive(Default)]
pub struct Restart {
    /// Hand a [`Checkpoint`] to the caller with every `n`-th step (and the last). The contact
    /// solver keeps from its cache only what the checkpoint records and a resumed run rebuilds
    /// (see [`solver::BlockRecord`]), so that a run resumed from it computes bit for bit what the
    /// uninterrupted run computes.
    pub every: Option<usize>,
    /// Resume from this checkpoint instead of the unloaded state.
    pub from: Option<Checkpoint>,
}

/// Everything the driver needs to go on from a converged step exactly as it would have.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Checkpoint {
    pub stage: usize,
    start: StageStart,
    pub alpha: f64,
    dalpha: f64,
    older: Option<(f64, State)>,
    pub cstate: Option<State>,
    control: [Control; 2],
    pilot: PilotState,
    pub scale: f64,
    /// The records of the steps so far: in the journal, not in the state file (see
    /// [`crate::restart`]).
    #[serde(skip)]
    pub records: Vec<StepRecord>,
    newton_total: usize,
    factorisations: usize,
    gmres_iterations: usize,
    /// The contact solver's factorised Delassus block, for the resumed run to rebuild.
    #[serde(default)]
    contact_block: Option<solver::BlockRecord>,
    bracket: Option<(f64, f64)>,
    pub last_u: Option<Vec<f64>>,
    t_solve: f64,
    t_contact: f64,
}

/// [`simulate`] with checkpoints and resumption.
pub fn simulate_with(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
    log: LogLevel,
    on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    restart: Restart,
) -> Result<Simulation, RunError> {
    let mut d = Driver {
        model,
        case,
        law: law.cloned(),
        quiet: log < LogLevel::Warn,
        copt: case.contact.as_ref().map(|c| solver::Options {
            method: c.method,
            kappa: c.penalty.unwrap_or(100.0),
            max_iterations: c.max_iterations.unwrap_or(60),
            tolerance: c.tolerance.unwrap_or(1e-8),
            verbose: log >= LogLevel::Debug,
            history: c
                .friction
                .as_ref()
                .map_or_else(Default::default, |f| f.history),
            normal_first: true,
            hertz_start: true,
        }),
        cstate: model.contact.as_ref().map(|c| c.system.initial_state()),
        lu_cache: solver::LuCache::sharing(model.contact_blocks()),
        control: [Control::Force(0.0); 2],
        pilot: PilotState::default(),
        scale: 0.0,
        records: Vec::new(),
        t_solve: 0.0,
        t_contact: 0.0,
        newton_total: 0,
        failure: None,
        bracket: None,
        lost_equilibrium: None,
        bracket_attempts: 0,
        last_u: None,
        checkpoint_every: restart.every,
    };
    if restart.from.is_none() {
        refuse_unloadable(model, case, d.law.as_ref())?;
    }
    let mut resume = restart.from.map(|c| d.restore(c));
    let first = resume.as_ref().map_or(0, |r| r.0);
    for (si, stage) in case.stages.iter().enumerate().skip(first) {
        if !d.run_stage(si, stage, on_step, resume.take().map(|r| r.1))? {
            break;
        }
    }
    Ok(Simulation {
        failure: d.failure,
        lost_equilibrium: d.lost_equilibrium,
        bracket_attempts: d.bracket_attempts,
        newton_iterations: d.newton_total,
        lu_factorisations: d.lu_cache.factorisations,
        gmres_iterations: d.lu_cache.gmres_iterations,
        solve_s: d.t_solve,
        contact_solve_s: d.t_contact,
        contact_phases_s: d.lu_cache.timings,
        last_u: d.last_u,
        last_state: if d.records.is_empty() { None } else { d.cstate },
        last_scale: d.scale,
        records: d.records,
    })
}

/// Refuses, before the first step, the load paths that no step can carry: a free pilot axis
/// ([`free_direction`]) and a first stage above the friction coefficient at every load
/// ([`beyond_friction_at_start`]).
pub fn refuse_unloadable(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
) -> Result<(), RunError> {
    free_direction(model, case, law)?;
    beyond_friction_at_start(model, case, law)
}

/// A first stage that drives both pilot forces in proportion from no load and asks for a
/// tangential force above the largest friction coefficient times the normal force, `|Q| >
/// max_u f(u) |P|`, at every load of the stage: Coulomb's law gives no equilibrium anywhere on
/// it (the pilot is the only load of its body: the case has no traction loads, so the
/// contact's resultant is the pilot's force).
pub fn beyond_friction_at_start(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
) -> Result<(), RunError> {
    let (Some(law), Some(stage), Some(_)) = (law, case.stages.first(), model.dofs.pilot) else {
        return Ok(());
    };
    let (Some(Control::Force(q)), Some(Control::Force(p))) = (stage.pilot_x, stage.pilot_y) else {
        return Ok(());
    };
    let mu = law.mu_max();
    if stage.traction_scale.is_some_and(|v| v != 0.0) || q.abs() <= mu * p.abs() {
        return Ok(());
    }
    Err(RunError::Step(StepFailure {
        step: 1,
        cause: StepError::BeyondFriction { q, p, mu },
        cutbacks: None,
    }))
}

/// Refuses, before the first step, a pilot axis that nothing holds: the pilot drives a body
/// that no support holds, the contact is frictionless, and a stage leaves the pilot's
/// tangential axis (across the direction that separates the bodies) force-controlled. A
/// frictionless contact carries no force along it, so the Newton system of every step is
/// singular in that direction. (A pilot axis keeps its control from stage to stage; before the
/// first stage that sets it, it is force-controlled at zero.)
pub fn free_direction(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
) -> Result<(), RunError> {
    let (Some((body, sep)), None, Some(_)) = (model.pilot_separation, law, &model.contact) else {
        return Ok(());
    };
    // The tangential axis: the one the separating direction has the least of.
    let k = if sep[0].abs() > sep[1].abs() { 1 } else { 0 };
    let mut force = true;
    for (si, st) in case.stages.iter().enumerate() {
        if let Some(c) = [st.pilot_x, st.pilot_y][k] {
            force = matches!(c, Control::Force(_));
        }
        if force {
            return Err(RunError::FreeDirection {
                key: ["pilot_x", "pilot_y"][k],
                stage: si,
                body: case.bodies[body].group.clone(),
            });
        }
    }
    Ok(())
}

/// The committed loads at the start of a stage, from which its steps interpolate.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct StageStart {
    pilot: PilotState,
    scale: f64,
    control: [Control; 2],
    mean_slip: f64,
}

impl StageStart {
    /// The pilot's drive at the fraction `a` of the stage towards `target`.
    fn control_at(&self, target: [Option<Control>; 2], a: f64) -> [Control; 2] {
        let (u0, r0, m0) = (
            [self.pilot.ux, self.pilot.uy],
            [self.pilot.fx, self.pilot.fy],
            self.mean_slip,
        );
        std::array::from_fn(|c| match (target[c], self.control[c]) {
            (Some(Control::Force(f)), _) => Control::Force(r0[c] + a * (f - r0[c])),
            (Some(Control::Displacement(d)), _) => Control::Displacement(u0[c] + a * (d - u0[c])),
            (None, Control::Force(_)) => Control::Force(r0[c]),
            (None, Control::Displacement(_)) => Control::Displacement(u0[c]),
            (Some(Control::Slip(s)), _) => Control::Slip(m0 + a * (s - m0)),
            (None, Control::Slip(_)) => Control::Slip(m0),
        })
    }

    /// Whether a stage towards `target` (and traction scale `scale`) changes no load: a hold.
    fn is_hold(&self, target: [Option<Control>; 2], scale: Option<f64>) -> bool {
        scale.is_none_or(|v| v == self.scale)
            && (0..2).all(|c| match (target[c], self.control[c]) {
                (None, _) => true,
                (Some(Control::Force(f)), Control::Force(f0)) => f == f0,
                (Some(Control::Displacement(d)), _) => d == [self.pilot.ux, self.pilot.uy][c],
                (Some(Control::Slip(s)), _) => s == self.mean_slip,
                (Some(Control::Force(_)), _) => false,
            })
    }
}

/// Why a step attempt gave no converged state.
enum Attempt {
    /// The solve failed or its answer means nothing: cut the increment back.
    Retry(StepError),
    /// Nothing to retry (a run without contact whose solve failed).
    Stop(StepError),
    /// The run cannot go on as set up (the contact reached the rim of its candidate zone).
    Fatal(RunError),
}

/// The state of a run between steps.
struct Driver<'a> {
    model: &'a Model,
    case: &'a Case,
    law: Option<FrictionLaw>,
    quiet: bool,
    copt: Option<solver::Options>,
    cstate: Option<State>,
    lu_cache: solver::LuCache,
    control: [Control; 2],
    pilot: PilotState,
    scale: f64,
    records: Vec<StepRecord>,
    t_solve: f64,
    t_contact: f64,
    newton_total: usize,
    failure: Option<StepFailure>,
    /// The last converged tangential force and the first that failed, while cutbacks bisect.
    bracket: Option<(f64, f64)>,
    lost_equilibrium: Option<(f64, f64)>,
    bracket_attempts: usize,
    last_u: Option<Vec<f64>>,
    checkpoint_every: Option<usize>,
}

/// Where a stage resumes: its start, the load fraction reached, the next increment and the
/// predictor's older state.
type StagePosition = (StageStart, f64, f64, Option<(f64, State)>);

impl Driver<'_> {
    /// Runs the steps of stage `si`; `false` when the run stops (a failure is recorded).
    ///
    /// The stage's load fraction `α` runs from 0 to 1. A step aims at `α + Δα`, and at the
    /// next nominal fraction `k / steps` when that is nearer, so the nominal loads are reached
    /// exactly whatever the cutbacks on the way. A failed attempt halves `Δα`; a converged
    /// step doubles it, up to the nominal `1/steps`. Invariants that bound the loop:
    /// * `Δα` is never below `Δα_min = (1/steps) / 2^MAX_CUTBACKS`. The first time in a
    ///   nominal step that a failure would need a smaller increment, the step probes the
    ///   nominal load at least half a nominal step further and cuts back from there; the
    ///   second time ends the stage (a lost equilibrium under force control, bracketed
    ///   between the last converged load and one at most `2 Δα_min` of the stage above it;
    ///   else a failed step);
    /// * every accepted step advances `α` by at least `Δα_min / 2`;
    /// * a stage accepts at most [`step_budget`] steps.
    fn run_stage(
        &mut self,
        si: usize,
        stage: &Stage,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
        resume: Option<StagePosition>,
    ) -> Result<bool, RunError> {
        let nominal = 1.0 / stage.steps as f64;
        let d_min = nominal / (1u64 << MAX_CUTBACKS) as f64;
        // The state before the last converged one, with its load fraction (none across stages).
        let (start, mut alpha, mut dalpha, mut older) = resume.unwrap_or((
            StageStart {
                pilot: self.pilot,
                scale: self.scale,
                control: self.control,
                mean_slip: self.cstate.as_ref().map_or(0.0, |s| s.mean_slip),
            },
            0.0,
            nominal,
            None,
        ));
        let target = [stage.pilot_x, stage.pilot_y];
        // The next nominal fraction to reach: `k_next / steps`.
        let mut k_next = next_nominal(alpha, stage.steps);
        // Failed attempts since the last nominal fraction reached.
        let mut attempts = 0usize;
        // The load of a probe past a stalled one, to attempt next, and whether one was tried
        // since the last nominal load reached.
        let mut probe: Option<f64> = None;
        let mut probed = false;
        let mut cutbacks = 0;
        let budget = step_budget(stage.steps);
        let first_step = self.records.len();
        let taken_before = self.records.iter().filter(|r| r.stage == si).count();
        // A stage that changes no load (a hold): every step of it keeps the converged state.
        let hold = start.is_hold(target, stage.traction_scale);
        while k_next <= stage.steps {
            let goal = k_next as f64 / stage.steps as f64;
            let mut a_new = alpha + dalpha;
            if goal - a_new < 0.5 * d_min {
                a_new = goal;
            }
            if let Some(p) = probe.take() {
                a_new = p;
            }
            let step = self.records.len() + 1;
            if taken_before + (step - 1 - first_step) >= budget {
                let why = StepError::StepBudget {
                    stage: si,
                    budget,
                    steps: stage.steps,
                    reached: alpha,
                };
                return Ok(self.stop(step, why, None));
            }
            let t = Instant::now();
            let sc = match stage.traction_scale {
                Some(v) => start.scale + a_new * (v - start.scale),
                None => start.scale,
            };
            let ctl = start.control_at(target, a_new);
            if let Some(why) = unheld_before(self.model, self.case, &ctl) {
                return Ok(self.stop(step, why, None));
            }
            let attempt = match self.cstate.take() {
                Some(prev) => {
                    let res = self.contact_attempt(&prev, sc, ctl, (alpha, a_new), &older, hold);
                    match res {
                        Ok((state, p, it)) => {
                            older = Some((alpha, prev));
                            self.cstate = Some(state);
                            Ok((None, p, it))
                        }
                        Err(e) => {
                            self.cstate = Some(prev);
                            Err(e)
                        }
                    }
                }
                None => match self.model.solve_step(sc, ctl) {
                    Ok((u, p)) => Ok((Some(u), p, 0)),
                    Err(m) => Err(Attempt::Stop(m)),
                },
            };
            let (u, p, iterations) = match attempt {
                Ok(c) => c,
                Err(Attempt::Fatal(e)) => return Err(e),
                Err(Attempt::Stop(why)) => return Ok(self.stop(step, why, None)),
                Err(Attempt::Retry(e)) => {
                    // Failed attempts count in the solve time too (they can dominate a run
                    // that brackets Q_max).
                    self.t_solve += t.elapsed().as_secs_f64();
                    // A singular contact system is cut back too: an active-set guess in which
                    // every node slips is singular along the pilot's force-controlled axis, and
                    // a smaller step starts from another guess. (A direction that nothing
                    // holds at all was refused before the first step: `free_direction`.)
                    attempts += 1;
                    let bracketing = self.note_failed_load(ctl, target[0]);
                    cutbacks += 1;
                    dalpha = 0.5 * (a_new - alpha);
                    if dalpha >= d_min {
                        if !self.quiet {
                            eprintln!(
                                "step {step} of stage {si}: {e}; cutting the load increment back to {dalpha:.3e} of the stage"
                            );
                        }
                        continue;
                    }
                    // The increment reached its floor. Before the load is called the end of
                    // the path, once per nominal step, a probe past it: the nominal load at
                    // least half a nominal step further, and if that fails, the cutbacks
                    // again from there, which try loads other than the first sequence did.
                    // Newton can stall on a load where the active set chatters while an
                    // equilibrium exists past it; past a lost equilibrium every attempt
                    // fails and the floor is reached a second time.
                    // (Not for a singular system: no load past it cures that.)
                    let stalled =
                        matches!(e, StepError::Contact(ContactError::NoConvergence { .. }));
                    if !probed && stalled {
                        probed = true;
                        let k = ((alpha + 0.5 * nominal) * stage.steps as f64).ceil() as usize;
                        let p = (k.min(stage.steps) as f64) / stage.steps as f64;
                        if p > a_new {
                            probe = Some(p);
                            if !self.quiet {
                                eprintln!(
                                    "step {step} of stage {si}: {e}; the increment is at its floor ({d_min:.3e} of the stage): probing the load at {p:.6} of the stage"
                                );
                            }
                            continue;
                        }
                    }
                    if bracketing {
                        self.lost_equilibrium = self.bracket;
                        self.bracket_attempts = attempts;
                    }
                    return Ok(self.stop(step, e, Some(attempts)));
                }
            };
            if !self.finite(u.as_ref()) {
                return Ok(self.stop(step, StepError::NotFinite, None));
            }
            alpha = a_new;
            // A nominal load reached: the aimed one, or one a probe reached.
            let landed = (alpha * stage.steps as f64).round() as usize;
            let landed = (landed as f64 / stage.steps as f64 == alpha).then_some(landed);
            if let Some(k) = landed {
                k_next = k + 1;
                attempts = 0;
                probed = false;
            }
            self.control = ctl;
            self.scale = sc;
            if let Some(p) = p {
                self.pilot = p;
            }
            let wall = t.elapsed().as_secs_f64();
            self.t_solve += wall;
            let last = si + 1 == self.case.stages.len() && k_next > stage.steps;
            self.record(si, alpha, iterations, cutbacks, wall);
            // The cutback count is per step: the next step starts afresh.
            cutbacks = 0;
            if dalpha < nominal {
                dalpha = (2.0 * dalpha).min(nominal);
            }
            let has_u = u.is_some();
            if has_u {
                self.last_u = u;
            }
            // The contact solver carries to the next step only what a checkpoint records, at
            // every step, so the answers do not depend on which steps are written.
            self.lu_cache.end_step();
            // The case's nominal step this step completes, if it lands on one: only those are
            // checkpoints (and written, unless the case asks for every sub-step).
            let nominal_index = landed.map(|k| k + self.nominal_before(si));
            let checkpoint = match (self.checkpoint_every, nominal_index) {
                (Some(n), Some(k)) if k.is_multiple_of(n) || last => Some(Checkpoint {
                    contact_block: self.lu_cache.checkpoint(),
                    stage: si,
                    start,
                    alpha,
                    dalpha,
                    older: older.clone(),
                    cstate: self.cstate.clone(),
                    control: self.control,
                    pilot: self.pilot,
                    scale: self.scale,
                    records: self.records.clone(),
                    newton_total: self.newton_total,
                    factorisations: self.lu_cache.factorisations,
                    gmres_iterations: self.lu_cache.gmres_iterations,
                    bracket: self.bracket,
                    last_u: self.last_u.clone(),
                    t_solve: self.t_solve,
                    t_contact: self.t_contact,
                }),
                _ => None,
            };
            on_step(&StepEvent {
                step,
                time: si as f64 + alpha,
                scale: sc,
                last,
                nominal: nominal_index,
                u: if has_u { self.last_u.as_ref() } else { None },
                contact: self.cstate.as_ref(),
                record: self.records.last().expect("pushed above"),
                checkpoint: checkpoint.as_ref(),
            })?;
        }
        Ok(true)
    }

    /// Nominal steps of the stages before `si`.
    fn nominal_before(&self, si: usize) -> usize {
        self.case.stages[..si].iter().map(|s| s.steps).sum()
    }

    /// One contact solve from the committed state `prev` to the fraction `a.1` of the stage
    /// (from `a.0`), with a predictor from the state `older` before it.
    fn contact_attempt(
        &mut self,
        prev: &State,
        scale: f64,
        ctl: [Control; 2],
        (alpha, a_new): (f64, f64),
        older: &Option<(f64, State)>,
        hold: bool,
    ) -> Result<(State, Option<PilotState>, usize), Attempt> {
        let opt = self
            .copt
            .as_ref()
            .expect("a contact state comes with contact options");
        let tc = Instant::now();
        let res = if !self.records.is_empty() && hold {
            // A step that changes no load (a hold) from a converged state: that state is its
            // answer, with no slip in the step (rate-independent friction). A Newton solve
            // could cycle at the tolerance between nodes on the Coulomb limit and be mistaken
            // for a lost equilibrium.
            let mut state = prev.clone();
            state.dv.iter_mut().for_each(|v| *v = 0.0);
            Ok(solver::StepOutcome {
                state,
                iterations: 0,
                last_update: 0.0,
            })
        } else {
            let t = older
                .as_ref()
                .filter(|(a0, _)| *a0 >= 0.0)
                .map(|(a_old, old)| (old, (a_new - alpha) / (alpha - a_old).max(1e-300)));
            let guess = t.map(|(old, t)| predict(prev, old, t));
            self.lu_cache.predict_with(t.map(|(_, t)| t));
            self.model.solve_contact_step(
                StepLoad {
                    scale,
                    control: ctl,
                },
                prev,
                guess.as_ref(),
                opt,
                self.law.as_ref(),
                Some(&mut self.lu_cache),
            )
        };
        self.t_contact += tc.elapsed().as_secs_f64();
        let out = res.map_err(|e| Attempt::Retry(e.into()))?;
        // Clipping: contact on the rim of the candidate zone.
        let cm = self.model.contact.as_ref().expect("contact");
        let rim = cm
            .pair
            .mortar
            .slave_nodes
            .iter()
            .zip(&out.state.status)
            .any(|(n, s)| *s != Status::Open && cm.pair.rim_nodes.binary_search(n).is_ok());
        if rim {
            return Err(Attempt::Fatal(RunError::ZoneClipped {
                gap: cm.pair.candidate_gap,
                step: self.records.len() + 1,
            }));
        }
        // A converged answer of an unheld body is a failed step: under force control the
        // cutbacks then bracket the load that lost equilibrium.
        if let Some(why) = unheld_after(self.model, self.case, &ctl, &out.state) {
            return Err(Attempt::Retry(why));
        }
        let p = PilotState {
            ux: out.state.pilot_u[0],
            uy: out.state.pilot_u[1],
            fx: out.state.pilot_f[0],
            fy: out.state.pilot_f[1],
        };
        self.newton_total += out.iterations;
        let pilot = self.model.dofs.pilot.is_some().then_some(p);
        Ok((out.state, pilot, out.iterations))
    }

    /// A force-controlled tangential load that no equilibrium carries: the cutbacks bisect
    /// between the last converged load and this one; a failure that survives all of them is
    /// reported as the loss of equilibrium. (Only when the step raised that load: a step that
    /// failed at the load of the last converged one is a solver failure, not a peak.)
    /// Returns whether the failure is such a load.
    fn note_failed_load(&mut self, ctl: [Control; 2], target_x: Option<Control>) -> bool {
        if let (Control::Force(f), Some(Control::Force(_)), true) =
            (ctl[0], target_x, self.law.is_some())
            && ctl[0] != self.control[0]
        {
            self.bracket = Some((self.pilot.fx, f));
            return true;
        }
        false
    }

    /// Takes over the state of checkpoint `c`; returns the stage it resumes in and where.
    fn restore(&mut self, c: Checkpoint) -> (usize, StagePosition) {
        self.cstate = c.cstate;
        self.control = c.control;
        self.pilot = c.pilot;
        self.scale = c.scale;
        self.records = c.records;
        self.newton_total = c.newton_total;
        self.lu_cache.factorisations = c.factorisations;
        self.lu_cache.gmres_iterations = c.gmres_iterations;
        if let (Some(rec), Some(cm)) = (&c.contact_block, &self.model.contact) {
            // A block that does not factorise leaves the cache empty: the solves still
            // converge, though not bit for bit as the uninterrupted run.
            self.lu_cache
                .replay(&cm.system.w, cm.system.prefix.as_ref(), rec);
        }
        self.bracket = c.bracket;
        self.last_u = c.last_u;
        self.t_solve = c.t_solve;
        self.t_contact = c.t_contact;
        (c.stage, (c.start, c.alpha, c.dalpha, c.older))
    }

    /// Records why the run stops at `step`; returns `false` (the stage loop's "stop").
    fn stop(&mut self, step: usize, cause: StepError, cutbacks: Option<usize>) -> bool {
        self.failure = Some(StepFailure {
            step,
            cause,
            cutbacks,
        });
        false
    }

    fn finite(&self, u: Option<&Vec<f64>>) -> bool {
        match (u, &self.cstate) {
            (Some(u), _) => u.iter().all(|v| v.is_finite()),
            (None, Some(st)) => st
                .f_n
                .iter()
                .chain(&st.f_t)
                .chain(&st.z)
                .all(|v| v.is_finite()),
            (None, None) => true,
        }
    }

    fn record(&mut self, si: usize, alpha: f64, iterations: usize, cutbacks: usize, wall: f64) {
        let figures = self
            .cstate
            .as_ref()
            .map(|st| self.model.contact_figures(st, self.law.as_ref()));
        self.records.push(StepRecord {
            step: self.records.len() + 1,
            stage: si,
            time: si as f64 + alpha,
            traction_scale: self.scale,
            pilot: self.model.dofs.pilot.is_some().then_some(self.pilot),
            iterations,
            cutbacks,
            contact: figures,
            wall_s: wall,
            cycle: self.case.stages[si].cycle,
        });
    }
}

/// The predicted forces of the next step: the last two states extrapolated by `t` (the ratio
/// of the next increment to the last), normal forces kept non-negative.
fn predict(prev: &State, old: &State, t: f64) -> State {
    let mut g = prev.clone();
    g.status = solver::predict_slip(prev, old, t);
    [g.f_n, g.f_t, g.z] = solver::predicted_forces(
        [&prev.f_n, &prev.f_t, &prev.z],
        [&old.f_n, &old.f_t, &old.z],
        t,
    );
    g
}
