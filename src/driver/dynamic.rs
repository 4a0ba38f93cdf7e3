//! Stages integrated in time ([`crate::dynamics`]): a case's dynamic stages, and the event
//! that follows a lost equilibrium when the case asks for it (`on_lost_equilibrium`).
//!
//! A dynamic stage starts from the state the run is in: the motion of a dynamic stage just
//! before it, else the last converged quasi-static state at rest. Its loads go linearly from
//! where the stage starts to its targets at `ramp` and are held to its end. It ends at its
//! duration, or with `until: "rest"` once the loads are at their targets and either
//! * the kinetic energy has stayed below `rest_ratio` times its peak in the stage over the
//!   last `rest_window` steps (the event is over: the bodies are at rest, re-stuck), or
//! * every contact node has slid at μ = f_d over the last `rest_window` steps (steady gross
//!   sliding: no quasi-static state follows under a force above f_d P).
//!
//! A time step whose contact Newton does not converge stops the run with the last converged
//! state (a time step is not cut back: that would refactorise `K + c M`).

use super::checkpoint::StageStart;
use super::outcome::StepEvent;
use super::stage::Driver;
use crate::case::{Control, DynamicSpec};
use crate::contact::solver::Status;
use crate::dynamics::{Integrator, Scheme};
use crate::error::{RunError, StepError};
use crate::record::StepRecord;
use serde::Serialize;
use std::time::Instant;

/// How a dynamic stage ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EventEnd {
    /// At its duration.
    Duration,
    /// The kinetic energy decayed (`until: "rest"`).
    Rest,
    /// Steady gross sliding at f_d (`until: "rest"`).
    Sliding,
    /// A time step failed (the run stops).
    Failed,
}

/// The figures of one dynamic stage, for the summary.
#[derive(Clone, Debug, Serialize)]
pub struct EventSummary {
    pub stage: usize,
    /// Whether it followed a lost equilibrium (`on_lost_equilibrium`).
    pub after_lost_equilibrium: bool,
    pub rho_inf: f64,
    pub dt: f64,
    pub t_start: f64,
    pub t_end: f64,
    pub steps: usize,
    pub newton_iterations: usize,
    pub peak_kinetic: f64,
    pub end: EventEnd,
    /// Seconds to build and factorise `K + c M` (zero when reused) and to step.
    pub factorise_s: f64,
    pub wall_s: f64,
}

/// The load of a dynamic stage at time `tau` from its start: traction scale and pilot drive.
type LoadAt<'a> = &'a dyn Fn(f64) -> (f64, [Control; 2]);

impl Driver<'_> {
    /// The case's dynamic stage `si` (its `dynamic` block `spec`); `false` when the run stops.
    pub(super) fn run_dynamic_stage(
        &mut self,
        si: usize,
        spec: &DynamicSpec,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<bool, RunError> {
        let stage = &self.case.stages[si];
        let start = StageStart {
            pilot: self.pilot,
            scale: self.scale,
            control: self.control,
            mean_slip: self.cstate.as_ref().map_or(0.0, |s| s.mean_slip),
        };
        let target = [stage.pilot_x, stage.pilot_y];
        let (s0, s1) = (self.scale, stage.traction_scale);
        let (ramp, shape) = (spec.ramp_time(), spec.ramp_shape);
        let load = move |tau: f64| {
            let a = if ramp > 0.0 {
                shape.fraction(tau / ramp)
            } else {
                1.0
            };
            let scale = s1.map_or(s0, |v| s0 + a * (v - s0));
            (scale, start.control_at(target, a))
        };
        let last_stage = si + 1 == self.case.stages.len();
        let end = self.integrate(si, spec, false, &load, last_stage, on_step)?;
        Ok(end != EventEnd::Failed)
    }

    /// The event after a lost equilibrium in stage `si`: the load `held` (the first without
    /// equilibrium) integrated in time from the last converged state. Returns how it ended.
    pub(super) fn run_event(
        &mut self,
        si: usize,
        held: (f64, [Control; 2]),
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<EventEnd, RunError> {
        let spec = self
            .case
            .on_lost_equilibrium
            .as_ref()
            .expect("asked for")
            .dynamic
            .clone();
        self.motion = None;
        let load = move |_: f64| held;
        self.integrate(si, &spec, true, &load, false, on_step)
    }

    /// Steps `spec` in time with the loads `load(τ)`.
    fn integrate(
        &mut self,
        si: usize,
        spec: &DynamicSpec,
        after_lost: bool,
        load: LoadAt,
        last_stage: bool,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<EventEnd, RunError> {
        let t_stage = Instant::now();
        let (n_steps, dt) = spec.steps_and_dt();
        let scheme = Scheme::new(spec.rho_inf);
        let factorise_s = self.integrator_for(scheme, dt)?;
        let model = self.model;
        let now = match self.motion.take() {
            Some(m) => m,
            None => {
                let u = match (&self.cstate, &self.last_u) {
                    (Some(st), _) if !self.records.is_empty() => {
                        model.contact_displacement(self.scale, st)
                    }
                    (None, Some(u)) => u.clone(),
                    _ => vec![0.0; model.dofs.n_free()],
                };
                let pilot = model.dofs.pilot.map(|_| self.pilot);
                let integ = self.integrator.as_ref().expect("built above");
                integ.at_rest(
                    model,
                    self.physical_time,
                    self.scale,
                    u,
                    self.cstate.as_ref(),
                    pilot,
                )
            }
        };
        let mut now = now;
        let mut summary = EventSummary {
            stage: si,
            after_lost_equilibrium: after_lost,
            rho_inf: spec.rho_inf,
            dt,
            t_start: now.time,
            t_end: now.time,
            steps: 0,
            newton_iterations: 0,
            peak_kinetic: 0.0,
            end: EventEnd::Duration,
            factorise_s,
            wall_s: 0.0,
        };
        let window = spec.rest_window;
        let mut recent_ke: std::collections::VecDeque<f64> = Default::default();
        let mut sliding_run = 0usize;
        let ramp = if after_lost { 0.0 } else { spec.ramp_time() };
        let f_d = self.law.as_ref().and_then(|l| l.f_dynamic().ok());
        for k in 1..=n_steps {
            let t = Instant::now();
            let tau = k as f64 * dt;
            let (scale, control) = load(tau);
            let integ = self.integrator.as_mut().expect("built above");
            let step = self.records.len() + 1;
            let stepped = match integ.step(
                &now,
                self.cstate.as_ref(),
                scale,
                control,
                self.law.as_ref(),
                self.copt.as_ref(),
            ) {
                Ok(s) => s,
                Err(e) => {
                    summary.end = EventEnd::Failed;
                    self.events.push(summary);
                    self.motion = Some(now);
                    self.stop(step, e, None);
                    return Ok(EventEnd::Failed);
                }
            };
            integ.lu.end_step();
            let finite = stepped.time.u.iter().all(|v| v.is_finite());
            if !finite {
                summary.end = EventEnd::Failed;
                self.events.push(summary);
                self.motion = Some(now);
                self.stop(step, StepError::NotFinite, None);
                return Ok(EventEnd::Failed);
            }
            now = stepped.time;
            self.physical_time = now.time;
            self.scale = scale;
            self.control = control;
            if let Some(p) = now.pilot {
                self.pilot = p;
            }
            if stepped.contact.is_some() {
                self.cstate = stepped.contact;
            }
            self.last_u = Some(now.u.clone());
            self.newton_total += stepped.iterations;
            summary.newton_iterations += stepped.iterations;
            summary.peak_kinetic = summary.peak_kinetic.max(now.kinetic);
            summary.steps = k;
            summary.t_end = now.time;
            // The end criteria, once the loads are at their targets.
            recent_ke.push_back(now.kinetic);
            if recent_ke.len() > window {
                recent_ke.pop_front();
            }
            let all_sliding = match (&self.cstate, &self.law, f_d) {
                (Some(st), Some(law), Some(fd)) => {
                    let on: Vec<usize> = (0..st.status.len())
                        .filter(|&j| st.status[j] != Status::Open)
                        .collect();
                    !on.is_empty()
                        && on.iter().all(|&j| {
                            st.status[j] == Status::Slip
                                && law.mu(st.slip_mu[j]) <= fd + 1e-9 * fd.abs().max(1e-300)
                        })
                }
                _ => false,
            };
            sliding_run = if all_sliding { sliding_run + 1 } else { 0 };
            let loaded = tau >= ramp;
            let mut end = None;
            if spec.until == crate::case::Until::Rest && loaded && recent_ke.len() == window {
                let top = recent_ke.iter().cloned().fold(0.0, f64::max);
                if summary.peak_kinetic > 0.0 && top <= spec.rest_ratio * summary.peak_kinetic {
                    end = Some(EventEnd::Rest);
                } else if sliding_run >= window {
                    end = Some(EventEnd::Sliding);
                }
            }
            if k == n_steps && end.is_none() {
                end = Some(EventEnd::Duration);
            }
            let wall = t.elapsed().as_secs_f64();
            self.t_solve += wall;
            let figures = self
                .cstate
                .as_ref()
                .map(|st| model.contact_figures(st, self.law.as_ref()));
            let pseudo = si as f64 + tau / (n_steps as f64 * dt);
            self.records.push(StepRecord {
                step,
                stage: si,
                time: pseudo,
                traction_scale: scale,
                pilot: model.dofs.pilot.is_some().then_some(self.pilot),
                iterations: stepped.iterations,
                cutbacks: 0,
                contact: figures,
                wall_s: wall,
                cycle: self.case.stages[si].cycle,
                physical_time: Some(now.time),
                kinetic: Some(now.kinetic),
            });
            let last = last_stage && end.is_some() && !after_lost;
            on_step(&StepEvent {
                step,
                time: pseudo,
                scale,
                last,
                nominal: Some(self.nominal_before(si) + k.min(self.case.stages[si].steps)),
                u: Some(&now.u),
                contact: self.cstate.as_ref(),
                record: self.records.last().expect("pushed above"),
                checkpoint: None,
            })?;
            if let Some(e) = end {
                summary.end = e;
                break;
            }
        }
        summary.wall_s = t_stage.elapsed().as_secs_f64();
        let end = summary.end;
        if !self.quiet {
            eprintln!(
                "stage {si}: integrated in time to t = {:.6e} in {} steps of {dt:.3e} ({} Newton iterations, peak kinetic energy {:.4e}): {}",
                summary.t_end,
                summary.steps,
                summary.newton_iterations,
                summary.peak_kinetic,
                match end {
                    EventEnd::Duration => "duration reached",
                    EventEnd::Rest => "at rest",
                    EventEnd::Sliding => "steady gross sliding",
                    EventEnd::Failed => "failed",
                }
            );
        }
        self.events.push(summary);
        self.motion = Some(now);
        Ok(end)
    }

    /// The integrator of time step `dt` and `scheme`, built (and `K + c M` factorised) unless
    /// the one in hand has both; returns the seconds spent building it.
    fn integrator_for(&mut self, scheme: Scheme, dt: f64) -> Result<f64, RunError> {
        if self
            .integrator
            .as_ref()
            .is_some_and(|i| i.scheme == scheme && i.dt == dt)
        {
            return Ok(0.0);
        }
        let t = Instant::now();
        self.integrator = None;
        let density: Vec<f64> = self
            .case
            .bodies
            .iter()
            .map(|b| b.density.expect("checked with the case"))
            .collect();
        let integ = Integrator::new(self.case, self.model, &density, scheme, dt)
            .map_err(RunError::Model)?;
        self.warn_of_coarse_step(&integ);
        self.integrator = Some(integ);
        Ok(t.elapsed().as_secs_f64())
    }

    /// Warns when a shear wave crosses more than one contact element per step: fronts, which
    /// run at most at the shear wave speed below supershear, are then not resolved in time.
    fn warn_of_coarse_step(&self, integ: &Integrator) {
        let Some(cm) = &self.model.contact else {
            return;
        };
        let h = cm
            .pair
            .mortar
            .h
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min);
        let c_s = self
            .case
            .bodies
            .iter()
            .filter_map(|b| {
                let mu = b.e / (2.0 * (1.0 + b.nu));
                b.density.map(|r| (mu / r).sqrt())
            })
            .fold(0.0, f64::max);
        let courant = c_s * integ.dt / h;
        if courant > 1.0 && !self.quiet {
            eprintln!(
                "warning: c_s Δt / h = {courant:.2} (c_s = {c_s:.4e}, Δt = {:.3e}, h = {h:.3e} along the contact): a front at the shear wave speed crosses {courant:.1} contact elements per step; a Δt below {:.3e} resolves it",
                integ.dt,
                h / c_s
            );
        }
    }
}
