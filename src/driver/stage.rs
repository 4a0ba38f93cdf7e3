//! The stepping of a stage: the load fraction advanced towards the next nominal load, each
//! step attempted from the last converged state with a predictor from the two before it, a
//! failed attempt cut back (halved) down to a floor, a probe past a stall, the bracketing of
//! a lost equilibrium, and every converged step recorded and handed to the caller.

use super::checkpoint::{Checkpoint, StagePosition, StageStart};
use super::outcome::{Simulation, StepEvent};
use super::refuse::{unheld_after, unheld_before};
use crate::case::{Case, Control, Stage};
use crate::contact::solver::{self, ContactError, State, Status};
use crate::error::{RunError, StepError, StepFailure};
use crate::friction::FrictionLaw;
use crate::model::Model;
use crate::model::step::PilotState;
use crate::model::step::StepLoad;
use crate::record::StepRecord;
use std::time::Instant;

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
pub(super) struct Driver<'a> {
    pub(super) model: &'a Model,
    pub(super) case: &'a Case,
    pub(super) law: Option<FrictionLaw>,
    pub(super) quiet: bool,
    pub(super) copt: Option<solver::Options>,
    pub(super) cstate: Option<State>,
    pub(super) lu_cache: solver::LuCache,
    pub(super) control: [Control; 2],
    pub(super) pilot: PilotState,
    pub(super) scale: f64,
    pub(super) records: Vec<StepRecord>,
    pub(super) t_solve: f64,
    pub(super) t_contact: f64,
    pub(super) newton_total: usize,
    pub(super) failure: Option<StepFailure>,
    /// The last converged tangential force and the first that failed, while cutbacks bisect.
    pub(super) bracket: Option<(f64, f64)>,
    pub(super) lost_equilibrium: Option<(f64, f64)>,
    pub(super) bracket_attempts: usize,
    pub(super) last_u: Option<Vec<f64>>,
    pub(super) checkpoint_every: Option<usize>,
    /// The time integrators of the last dynamic stage (`K + c M` factorised for its Δt, then
    /// for each other size a step needed).
    pub(super) integrators: Option<super::timestep::Ladder>,
    /// The motion a dynamic stage leaves to the next (none after a quasi-static stage).
    pub(super) motion: Option<crate::dynamics::TimeState>,
    /// Physical time reached by the dynamic stages so far.
    pub(super) physical_time: f64,
    /// The stage about to begin follows a dynamic stage (it is no hold: see
    /// [`Driver::begin_stage`]).
    pub(super) after_motion: bool,
    pub(super) events: Vec<crate::record::EventSummary>,
    /// The elements a front's J-integral can reach ([`crate::dynamics::flux::near_face`]).
    pub(super) near_face: std::sync::OnceLock<Vec<usize>>,
}
/// A stage being stepped: its fixed figures, where its load stands, and the counters of its
/// cutbacks and probes.
struct StageRun {
    si: usize,
    /// The stage's nominal steps, its nominal fraction `1/steps` and the floor of the
    /// increment `Δα_min` (the nominal one over `2^MAX_CUTBACKS`).
    steps: usize,
    nominal: f64,
    d_min: f64,
    start: StageStart,
    target: [Option<Control>; 2],
    traction_scale: Option<f64>,
    /// The load fraction reached and the next increment.
    alpha: f64,
    dalpha: f64,
    /// The state before the last converged one, with its load fraction (none across stages).
    older: Option<(f64, State)>,
    /// The next nominal fraction to reach: `k_next / steps`.
    k_next: usize,
    /// Failed attempts since the last nominal fraction reached.
    attempts: usize,
    /// The load of a probe past a stalled one, to attempt next, and whether one was tried
    /// since the last nominal load reached.
    probe: Option<f64>,
    probed: bool,
    /// Cutbacks of the step under way.
    cutbacks: usize,
    /// The stage's step budget, the run's steps before this call and the stage's steps taken
    /// before it (a resumed stage).
    budget: usize,
    first_step: usize,
    taken_before: usize,
    /// A stage that changes no load (a hold): every step of it keeps the converged state.
    hold: bool,
}

impl StageRun {
    /// Goes on from the load fraction `a` reached otherwise (an event that came to rest):
    /// a nominal increment, no predictor, no failed attempts.
    fn resume_at(&mut self, a: f64) {
        self.alpha = a;
        self.dalpha = self.nominal;
        self.k_next = next_nominal(a, self.steps);
        self.older = None;
        (self.attempts, self.probed, self.cutbacks) = (0, false, 0);
    }

    /// The load fraction of the next attempt: `α + Δα`, the next nominal fraction when that
    /// is within `Δα_min / 2` of it, or a probe's load.
    fn next_alpha(&mut self) -> f64 {
        let goal = self.k_next as f64 / self.steps as f64;
        let mut a_new = self.alpha + self.dalpha;
        if goal - a_new < 0.5 * self.d_min {
            a_new = goal;
        }
        if let Some(p) = self.probe.take() {
            a_new = p;
        }
        a_new
    }

    /// The load at the fraction `a` of the stage: the traction scale and the pilot's drive.
    fn aim(&self, a: f64) -> Aim {
        let scale = match self.traction_scale {
            Some(v) => self.start.scale + a * (v - self.start.scale),
            None => self.start.scale,
        };
        Aim {
            alpha: a,
            scale,
            control: self.start.control_at(self.target, a),
        }
    }
}

/// The load a step attempts: its fraction of the stage, traction scale and pilot drive.
struct Aim {
    alpha: f64,
    scale: f64,
    control: [Control; 2],
}

/// A converged attempt: the free solution (runs without contact), the pilot's state and the
/// Newton iterations.
type Solved = (Option<Vec<f64>>, Option<PilotState>, usize);

impl<'a> Driver<'a> {
    /// A driver at the unloaded state of `model`, with friction law `law`, the contact solver's
    /// options `copt`, and a checkpoint every `checkpoint_every` nominal steps.
    pub(super) fn new(
        model: &'a Model,
        case: &'a Case,
        law: Option<&FrictionLaw>,
        quiet: bool,
        copt: Option<solver::Options>,
        checkpoint_every: Option<usize>,
    ) -> Self {
        Driver {
            model,
            case,
            law: law.cloned(),
            quiet,
            copt,
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
            checkpoint_every,
            integrators: None,
            motion: None,
            physical_time: 0.0,
            after_motion: false,
            events: Vec::new(),
            near_face: std::sync::OnceLock::new(),
        }
    }

    /// What the run gives its caller once the stages are stepped.
    pub(super) fn finish(self) -> Simulation {
        Simulation {
            failure: self.failure,
            lost_equilibrium: self.lost_equilibrium,
            bracket_attempts: self.bracket_attempts,
            newton_iterations: self.newton_total,
            lu_factorisations: self.lu_cache.factorisations,
            gmres_iterations: self.lu_cache.gmres_iterations,
            solve_s: self.t_solve,
            contact_solve_s: self.t_contact,
            contact_phases_s: self.lu_cache.timings,
            last_u: self.last_u,
            last_state: if self.records.is_empty() {
                None
            } else {
                self.cstate
            },
            last_scale: self.scale,
            records: self.records,
            events: self.events,
        }
    }
}

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
    ///   else a failed step) ([`Driver::cut_back`]);
    /// * every accepted step advances `α` by at least `Δα_min / 2`;
    /// * a stage accepts at most [`step_budget`] steps.
    pub(super) fn run_stage(
        &mut self,
        si: usize,
        stage: &Stage,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
        resume: Option<StagePosition>,
    ) -> Result<bool, RunError> {
        let mut s = self.begin_stage(si, stage, resume);
        while s.k_next <= s.steps {
            let a_new = s.next_alpha();
            let step = self.records.len() + 1;
            if s.taken_before + (step - 1 - s.first_step) >= s.budget {
                let why = StepError::StepBudget {
                    stage: si,
                    budget: s.budget,
                    steps: s.steps,
                    reached: s.alpha,
                };
                return Ok(self.stop(step, why, None));
            }
            let t = Instant::now();
            let aim = s.aim(a_new);
            if let Some(why) = unheld_before(self.model, self.case, &aim.control) {
                return Ok(self.stop(step, why, None));
            }
            let solved = match self.attempt(&mut s, &aim) {
                Ok(c) => c,
                Err(Attempt::Fatal(e)) => return Err(e),
                Err(Attempt::Stop(why)) => return Ok(self.stop(step, why, None)),
                Err(Attempt::Retry(e)) => {
                    // Failed attempts count in the solve time too (they can dominate a run
                    // that brackets Q_max).
                    self.t_solve += t.elapsed().as_secs_f64();
                    if self.cut_back(&mut s, step, e, &aim) {
                        continue;
                    }
                    let before = self.records.len();
                    if self.event_after_lost(si, aim.alpha, (aim.scale, aim.control), on_step)? {
                        // Re-stuck: the stage goes on from the load held; its time steps do
                        // not count in the stage's step budget.
                        s.first_step += self.records.len() - before;
                        s.resume_at(aim.alpha);
                        continue;
                    }
                    return Ok(false);
                }
            };
            if !self.finite(solved.0.as_ref()) {
                return Ok(self.stop(step, StepError::NotFinite, None));
            }
            self.accept(&mut s, step, t, aim, solved, on_step)?;
        }
        Ok(true)
    }

    /// Stage `si` at its start, or where `resume` says it stands.
    fn begin_stage(&self, si: usize, stage: &Stage, resume: Option<StagePosition>) -> StageRun {
        let nominal = 1.0 / stage.steps as f64;
        let (start, alpha, dalpha, older) = resume.unwrap_or((
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
        StageRun {
            si,
            steps: stage.steps,
            nominal,
            d_min: nominal / (1u64 << MAX_CUTBACKS) as f64,
            start,
            target,
            traction_scale: stage.traction_scale,
            alpha,
            dalpha,
            older,
            k_next: next_nominal(alpha, stage.steps),
            attempts: 0,
            probe: None,
            probed: false,
            cutbacks: 0,
            budget: step_budget(stage.steps),
            first_step: self.records.len(),
            taken_before: self.records.iter().filter(|r| r.stage == si).count(),
            hold: start.is_hold(target, stage.traction_scale) && !self.after_motion,
        }
    }

    /// One attempt at the load `aim`: a contact solve from the committed contact state (which
    /// becomes the predictor's older state when it converges), or the solve of a run without
    /// contact.
    fn attempt(&mut self, s: &mut StageRun, aim: &Aim) -> Result<Solved, Attempt> {
        match self.cstate.take() {
            Some(prev) => {
                let res = self.contact_attempt(
                    &prev,
                    aim.scale,
                    aim.control,
                    (s.alpha, aim.alpha),
                    &s.older,
                    s.hold,
                );
                match res {
                    Ok((state, p, it)) => {
                        s.older = Some((s.alpha, prev));
                        self.cstate = Some(state);
                        Ok((None, p, it))
                    }
                    Err(e) => {
                        self.cstate = Some(prev);
                        Err(e)
                    }
                }
            }
            None => match self.model.solve_step(aim.scale, aim.control) {
                Ok((u, p)) => Ok((Some(u), p, 0)),
                Err(m) => Err(Attempt::Stop(m)),
            },
        }
    }

    /// After the failed attempt at `aim` of step `step` (cause `e`): halves the increment, or
    /// once it is at its floor probes past the load once per nominal step; `true` to attempt
    /// again, `false` when the stage ends here (the failure, and a lost equilibrium's
    /// bracket, recorded).
    fn cut_back(&mut self, s: &mut StageRun, step: usize, e: StepError, aim: &Aim) -> bool {
        let si = s.si;
        // A singular contact system is cut back too: an active-set guess in which every node
        // slips is singular along the pilot's force-controlled axis, and a smaller step starts
        // from another guess. (A direction that nothing holds at all was refused before the
        // first step: `free_direction`.)
        s.attempts += 1;
        let bracketing = self.note_failed_load(aim.control, s.target[0]);
        s.cutbacks += 1;
        s.dalpha = 0.5 * (aim.alpha - s.alpha);
        if s.dalpha >= s.d_min {
            if !self.quiet {
                eprintln!(
                    "step {step} of stage {si}: {e}; cutting the load increment back to {:.3e} of the stage",
                    s.dalpha
                );
            }
            return true;
        }
        // The increment reached its floor. Before the load is called the end of the path,
        // once per nominal step, a probe past it: the nominal load at least half a nominal
        // step further, and if that fails, the cutbacks again from there, which try loads
        // other than the first sequence did. Newton can stall on a load where the active set
        // chatters while an equilibrium exists past it; past a lost equilibrium every attempt
        // fails and the floor is reached a second time. (Not for a singular system: no load
        // past it cures that.)
        let stalled = matches!(e, StepError::Contact(ContactError::NoConvergence { .. }));
        if !s.probed && stalled {
            s.probed = true;
            let k = ((s.alpha + 0.5 * s.nominal) * s.steps as f64).ceil() as usize;
            let p = (k.min(s.steps) as f64) / s.steps as f64;
            if p > aim.alpha {
                s.probe = Some(p);
                if !self.quiet {
                    eprintln!(
                        "step {step} of stage {si}: {e}; the increment is at its floor ({:.3e} of the stage): probing the load at {p:.6} of the stage",
                        s.d_min
                    );
                }
                return true;
            }
        }
        if bracketing {
            self.lost_equilibrium = self.bracket;
            self.bracket_attempts = s.attempts;
        }
        self.stop(step, e, Some(s.attempts))
    }

    /// Commits the converged attempt at `aim` as step `step` (begun at `t`): the load reached,
    /// the step's record, the next increment (doubled, up to the nominal one), and the event
    /// handed to `on_step`, with a checkpoint on the nominal steps that take one.
    fn accept(
        &mut self,
        s: &mut StageRun,
        step: usize,
        t: Instant,
        aim: Aim,
        (u, p, iterations): Solved,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<(), RunError> {
        let si = s.si;
        s.alpha = aim.alpha;
        // A nominal load reached: the aimed one, or one a probe reached.
        let landed = (s.alpha * s.steps as f64).round() as usize;
        let landed = (landed as f64 / s.steps as f64 == s.alpha).then_some(landed);
        if let Some(k) = landed {
            s.k_next = k + 1;
            s.attempts = 0;
            s.probed = false;
        }
        self.control = aim.control;
        self.scale = aim.scale;
        if let Some(p) = p {
            self.pilot = p;
        }
        let wall = t.elapsed().as_secs_f64();
        self.t_solve += wall;
        let last = si + 1 == self.case.stages.len() && s.k_next > s.steps;
        self.record(si, s.alpha, iterations, s.cutbacks, wall);
        // The cutback count is per step: the next step starts afresh.
        s.cutbacks = 0;
        if s.dalpha < s.nominal {
            s.dalpha = (2.0 * s.dalpha).min(s.nominal);
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
            (Some(n), Some(k)) if k.is_multiple_of(n) || last => Some(self.checkpoint(s)),
            _ => None,
        };
        on_step(&StepEvent {
            step,
            time: si as f64 + s.alpha,
            scale: aim.scale,
            last,
            nominal: nominal_index,
            spans: 1,
            u: if has_u { self.last_u.as_ref() } else { None },
            contact: self.cstate.as_ref(),
            record: self.records.last().expect("pushed above"),
            checkpoint: checkpoint.as_ref(),
            dt: None,
        })
    }

    /// The driver's state after the step just accepted in stage `s`, to go on from.
    fn checkpoint(&self, s: &StageRun) -> Checkpoint {
        Checkpoint {
            contact_block: self.lu_cache.checkpoint(),
            stage: s.si,
            start: s.start,
            alpha: s.alpha,
            dalpha: s.dalpha,
            older: s.older.clone(),
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
            physical_time: self.physical_time,
            events: self.events.clone(),
        }
    }

    /// Nominal steps of the stages before `si`.
    pub(super) fn nominal_before(&self, si: usize) -> usize {
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
            let guess = t.map(|(old, t)| solver::predicted_state(prev, old, t));
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
    pub(super) fn restore(&mut self, c: Checkpoint) -> (usize, StagePosition) {
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
        self.physical_time = c.physical_time;
        self.events = c.events;
        (c.stage, (c.start, c.alpha, c.dalpha, c.older))
    }

    /// Records why the run stops at `step`; returns `false` (the stage loop's "stop").
    pub(super) fn stop(&mut self, step: usize, cause: StepError, cutbacks: Option<usize>) -> bool {
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
            physical_time: None,
            kinetic: None,
            fronts: None,
        });
    }
}
