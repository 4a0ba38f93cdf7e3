//! Stages integrated in time ([`crate::dynamics`]): a case's dynamic stages, and the event
//! that follows a lost equilibrium when the case asks for it (`on_lost_equilibrium`).
//!
//! A dynamic stage starts from the state the run is in: the motion of a dynamic stage just
//! before it, else the last converged quasi-static state at rest. Its loads go linearly from
//! where the stage starts to its targets at `ramp` and are held to its end. It ends at its
//! duration, or with `until: "rest"` once the loads are at their targets and either
//! * the kinetic energy has stayed below `rest_ratio` times its peak in the stage over the
//!   last `rest_window` steps (the event is over: the bodies are at rest, re-stuck), or
//! * every contact node has slid at μ = f_d over the last `rest_window` steps (gross sliding).
//!
//! A time step whose contact Newton does not converge is taken again as two steps of half
//! the size, down to `Δt / 2^MAX_DT_HALVINGS` (each size's `K + c M` factorised once, when
//! first needed); past that the run stops with the last converged state. Dynamic stages take
//! no checkpoints: a resumed run goes on from the last quasi-static one.
//!
//! Under a force above f_d P gross sliding has no end: the body slides at μ = f_d and
//! accelerates at `(Q − f_d P) / m`; `rest` then ends the stage once the whole contact has slid
//! at f_d for the window.

use super::checkpoint::StageStart;
use super::outcome::StepEvent;
use super::stage::Driver;
use super::timestep::{
    EndWatch, Ladder, MAX_DT_HALVINGS, RATE_CHANGE, Sizer, rate_change, state_changes,
};
use crate::case::{Control, DynamicSpec};
use crate::contact::solver::{State, Status};
use crate::dynamics::{Integrator, Scheme, TimeState};
use crate::error::{RunError, StepError};
use crate::record::{EventEnd, EventSummary, StepRecord};
use std::time::Instant;

/// The load of a dynamic stage at time `tau` from its start: traction scale and pilot drive.
type LoadAt<'a> = &'a dyn Fn(f64) -> (f64, [Control; 2]);

/// A time step taken (beside the motion it reached): its contact state, load, Newton
/// iterations, its size in doublings of the stage's Δt (negative: halvings) and whether it
/// was calm.
struct Sub {
    contact: Option<State>,
    iterations: usize,
    scale: f64,
    control: [Control; 2],
    doublings: isize,
    /// No contact node changed its state and the slip rate changed by at most half of
    /// [`RATE_CHANGE`]: a step of twice the size would be kept.
    calm: bool,
    dt: f64,
    wall: f64,
}

/// Why a time step gave no state: the step itself, or building a halved step's matrix.
enum Failure {
    Step(StepError),
    Run(RunError),
}

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
        let end = self.integrate(si, spec, (false, 0.0), &load, last_stage, on_step)?;
        Ok(end != EventEnd::Failed)
    }

    /// Weakens what the growing patches of stage `si` have reached at time `tau` into the stage
    /// (only a dynamic stage has growing patches; an event after a lost equilibrium runs in a
    /// quasi-static stage, which has none).
    fn grow_patches(&mut self, si: usize, tau: f64) {
        let growing = self.case.stages[si]
            .weaken
            .iter()
            .filter(|p| p.speed.is_some());
        if let Some(st) = self.cstate.as_mut() {
            // A patch that holds no node yet (it starts from its centre) weakens nothing.
            let _ = self
                .model
                .weaken(growing.map(|p| (p.extent(tau), p.slip)), &mut st.slip_mu);
        }
    }

    /// The event after a lost equilibrium in stage `si`: the load `held` (the first without
    /// equilibrium, at the fraction `alpha` of the stage) integrated in time from the last
    /// converged state. Returns how it ended.
    pub(super) fn run_event(
        &mut self,
        si: usize,
        alpha: f64,
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
        self.integrate(si, &spec, (true, alpha), &load, false, on_step)
    }

    /// After a lost equilibrium at the fraction `alpha` of stage `si` under the load `held`:
    /// with `on_lost_equilibrium`, the event integrated in time ([`Driver::run_event`]). The
    /// run's stop stays the lost equilibrium's unless the event came to rest: then `true`,
    /// and the stage goes on from the load held.
    pub(super) fn event_after_lost(
        &mut self,
        si: usize,
        alpha: f64,
        held: (f64, [Control; 2]),
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<bool, RunError> {
        if self.lost_equilibrium.is_none() || self.case.on_lost_equilibrium.is_none() {
            return Ok(false);
        }
        let lost = self.failure.take();
        let end = self.run_event(si, alpha, held, on_step)?;
        match end {
            EventEnd::Rest => {
                self.lost_equilibrium = None;
                Ok(true)
            }
            // A failed time step is the run's stop.
            EventEnd::Failed => Ok(false),
            _ => {
                self.failure = lost;
                Ok(false)
            }
        }
    }

    /// Steps `spec` in time with the loads `load(τ)`. `after_lost`: the event after a lost
    /// equilibrium at the fraction `alpha0` of stage `si`, whose steps' pseudo-time runs from
    /// there towards the stage's end over the event's duration (a dynamic stage's from its
    /// start, `alpha0` = 0).
    fn integrate(
        &mut self,
        si: usize,
        spec: &DynamicSpec,
        (after_lost, alpha0): (bool, f64),
        load: LoadAt,
        last_stage: bool,
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<EventEnd, RunError> {
        let t_stage = Instant::now();
        let (n_steps, dt) = spec.steps_and_dt();
        let scheme = Scheme::new(spec.rho_inf);
        let mut sizer = Sizer::new(spec);
        let factorise_s = self.integrator_for(scheme, dt, sizer.up_max)?;
        let mut now = match self.motion.take() {
            Some(m) => m,
            None => self.at_rest(),
        };
        let mut summary = EventSummary {
            stage: si,
            after_lost_equilibrium: after_lost,
            rho_inf: spec.rho_inf,
            dt,
            dt_largest: 0.0,
            t_start: now.time,
            t_end: now.time,
            steps: 0,
            newton_iterations: 0,
            peak_kinetic: 0.0,
            end: EventEnd::Duration,
            factorise_s,
            wall_s: 0.0,
        };
        let mut watch = EndWatch::new(spec, dt, after_lost);
        let f_d = self.law.as_ref().and_then(|l| l.f_dynamic().ok());
        // The nominal steps of `dt` reached; a step of `2^u` of them starts on a multiple of
        // `2^u`. Within a step split by halvings, positions count in `dt / 2^MAX_DT_HALVINGS`.
        let mut k = 0;
        let fine = 1usize << MAX_DT_HALVINGS;
        // The nominal index of a step of the event after a lost equilibrium counts from the
        // event's start (the stage's nominal loads are the quasi-static ones).
        let offset = if after_lost {
            0
        } else {
            self.nominal_before(si)
        };
        while k < n_steps {
            let u = sizer.next(k, n_steps);
            let span = 1usize << u;
            let tau = (k + span) as f64 * dt;
            self.grow_patches(si, tau);
            let st = self.cstate.clone();
            let subs = match self.advance(u as isize, &now, st.as_ref(), k as f64 * dt, load) {
                Ok(s) => s,
                Err(Failure::Run(e)) => return Err(e),
                Err(Failure::Step(e)) => {
                    if !self.quiet {
                        eprintln!(
                            "stage {si}: the time step to t = {:.6e} failed even at Δt/{}: {e}; the run stops at t = {:.6e}, its last converged state",
                            now.time + span as f64 * dt,
                            1 << MAX_DT_HALVINGS,
                            now.time
                        );
                    }
                    summary.end = EventEnd::Failed;
                    self.events.push(summary);
                    self.motion = Some(now);
                    self.stop(self.records.len() + 1, e, None);
                    return Ok(EventEnd::Failed);
                }
            };
            let least = subs.iter().map(|s| s.1.doublings).min().unwrap_or(0);
            let calm = subs.iter().all(|s| s.1.calm);
            sizer.taken(u, least.max(0) as usize, calm);
            let mut pos = k * fine;
            for (time, sub) in subs {
                now = self.take_sub(time, &sub);
                summary.steps += 1;
                summary.newton_iterations += sub.iterations;
                summary.peak_kinetic = summary.peak_kinetic.max(now.kinetic);
                summary.dt_largest = summary.dt_largest.max(sub.dt);
                summary.t_end = now.time;
                pos += 1 << (MAX_DT_HALVINGS as isize + sub.doublings);
                // The end criteria and the nominal index, where a step lands on a nominal one.
                let landed = pos.is_multiple_of(fine).then(|| {
                    let k1 = pos / fine;
                    let k0 = std::mem::replace(&mut k, k1);
                    (k0, k1)
                });
                let end = landed.and_then(|(k0, k1)| {
                    let sliding = self.all_sliding(f_d);
                    watch
                        .observe((k0, k1), now.kinetic, summary.peak_kinetic, sliding)
                        .or((k1 == n_steps).then_some(EventEnd::Duration))
                });
                let nominal = landed.map(|(k0, k1)| (offset + k1, k1 - k0));
                let pseudo = si as f64
                    + alpha0
                    + (1.0 - alpha0) * (now.time - summary.t_start) / (n_steps as f64 * dt);
                let last = last_stage && end.is_some() && !after_lost;
                self.record_sub(si, &sub, &now, (pseudo, nominal, last), on_step)?;
                if let Some(e) = end {
                    summary.end = e;
                    break;
                }
            }
            if summary.end != EventEnd::Duration {
                break;
            }
        }
        summary.wall_s = t_stage.elapsed().as_secs_f64();
        let end = summary.end;
        if !self.quiet {
            eprintln!(
                "stage {si}: integrated in time to t = {:.6e} in {} steps of {} ({} Newton iterations, peak kinetic energy {:.4e}): {}",
                summary.t_end,
                summary.steps,
                if summary.dt_largest > dt * (1.0 + 1e-9) {
                    format!("{dt:.3e} to {:.3e}", summary.dt_largest)
                } else {
                    format!("{dt:.3e}")
                },
                summary.newton_iterations,
                summary.peak_kinetic,
                match end {
                    EventEnd::Duration => "duration reached",
                    EventEnd::Rest => "at rest",
                    EventEnd::Sliding => "gross sliding at f_d",
                    EventEnd::Failed => "failed",
                }
            );
        }
        self.events.push(summary);
        self.motion = Some(now);
        Ok(end)
    }

    /// The state at rest the motion starts from after a quasi-static stage: its last
    /// converged field, zero velocity and acceleration.
    fn at_rest(&self) -> TimeState {
        let model = self.model;
        let u = match (&self.cstate, &self.last_u) {
            (Some(st), _) if !self.records.is_empty() => model.contact_displacement(self.scale, st),
            (None, Some(u)) => u.clone(),
            _ => vec![0.0; model.dofs.n_free()],
        };
        let pilot = model.dofs.pilot.map(|_| self.pilot);
        Integrator::at_rest(
            model,
            self.physical_time,
            self.scale,
            u,
            self.cstate.as_ref(),
            pilot,
        )
    }

    /// Takes the time step `sub` as the driver's state; returns its motion.
    fn take_sub(&mut self, time: TimeState, sub: &Sub) -> TimeState {
        self.physical_time = time.time;
        self.scale = sub.scale;
        self.control = sub.control;
        if let Some(p) = time.pilot {
            self.pilot = p;
        }
        if sub.contact.is_some() {
            self.cstate = sub.contact.clone();
        }
        // A contact state's field is recovered from it, as after a quasi-static step.
        if self.cstate.is_none() {
            self.last_u = Some(time.u.clone());
        }
        self.newton_total += sub.iterations;
        self.t_solve += sub.wall;
        time
    }

    /// Records the time step `sub` of stage `si` (reaching `now`) and hands it to `on_step`
    /// with its pseudo-time, nominal index and whether it is the run's last.
    fn record_sub(
        &mut self,
        si: usize,
        sub: &Sub,
        now: &TimeState,
        (pseudo, nominal, last): (f64, Option<(usize, usize)>, bool),
        on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    ) -> Result<(), RunError> {
        let model = self.model;
        let step = self.records.len() + 1;
        let figures = self
            .cstate
            .as_ref()
            .map(|st| model.contact_figures(st, self.law.as_ref()));
        let density = self.densities();
        let fronts = match (&self.cstate, &self.law) {
            (Some(st), Some(law)) => {
                let near = self
                    .near_face
                    .get_or_init(|| crate::dynamics::flux::near_face(model));
                Some(crate::dynamics::flux::front_figures(
                    model,
                    (&density, near),
                    now,
                    st,
                    law,
                ))
            }
            _ => None,
        };
        self.records.push(StepRecord {
            step,
            stage: si,
            time: pseudo,
            traction_scale: sub.scale,
            pilot: model.dofs.pilot.is_some().then_some(self.pilot),
            iterations: sub.iterations,
            cutbacks: (-sub.doublings).max(0) as usize,
            contact: figures,
            wall_s: sub.wall,
            cycle: self.case.stages[si].cycle,
            physical_time: Some(now.time),
            kinetic: Some(now.kinetic),
            fronts,
        });
        on_step(&StepEvent {
            step,
            time: pseudo,
            scale: sub.scale,
            last,
            nominal: nominal.map(|n| n.0),
            spans: nominal.map_or(1, |n| n.1),
            u: Some(&now.u),
            contact: self.cstate.as_ref(),
            record: self.records.last().expect("pushed above"),
            checkpoint: None,
            dt: Some(sub.dt),
        })
    }

    /// The integrators of `scheme` for the time step `dt`, its `up_max` doublings and its
    /// halvings, kept unless the ones in hand are those; builds the one of `dt` and returns
    /// the seconds it took (`K + c M` factorised).
    fn integrator_for(&mut self, scheme: Scheme, dt: f64, up_max: usize) -> Result<f64, RunError> {
        if self
            .integrators
            .as_ref()
            .is_some_and(|l| l.scheme == scheme && l.dt == dt && l.up_max == up_max)
        {
            return Ok(0.0);
        }
        let t = Instant::now();
        let mut ladder = Ladder::new(scheme, dt, up_max);
        let integ = self.build_integrator(scheme, dt)?;
        self.warn_of_coarse_step(&integ);
        *ladder.size(0) = Some(integ);
        self.integrators = Some(ladder);
        Ok(t.elapsed().as_secs_f64())
    }

    fn build_integrator(&self, scheme: Scheme, dt: f64) -> Result<Integrator, RunError> {
        Integrator::new(self.case, self.model, &self.densities(), scheme, dt)
            .map_err(RunError::Model)
    }

    /// The density of each body of the case (every body has one where the case integrates in
    /// time: checked with the case).
    fn densities(&self) -> Vec<f64> {
        let bodies = &self.case.bodies;
        bodies
            .iter()
            .map(|b| b.density.expect("checked with the case"))
            .collect()
    }

    /// One time step of `dt · 2^u` from `now` (contact state `st`) at `τ0` from the stage's
    /// start. Where its contact Newton does not converge, or the step is larger than `dt` and
    /// changes a contact node's state or the slip rate too much ([`Sizer::refuses`]), two
    /// steps of half the size, down to [`MAX_DT_HALVINGS`] halvings of `dt`. Returns the
    /// steps taken.
    fn advance(
        &mut self,
        u: isize,
        now: &TimeState,
        st: Option<&State>,
        tau0: f64,
        load: LoadAt,
    ) -> Result<Vec<(TimeState, Sub)>, Failure> {
        let t = Instant::now();
        let ladder = self.integrators.as_mut().expect("built with the stage");
        let (scheme, h) = (ladder.scheme, ladder.dt_of(u));
        if ladder.size(u).is_none() {
            let integ = self.build_integrator(scheme, h).map_err(Failure::Run)?;
            *self.integrators.as_mut().expect("built").size(u) = Some(integ);
        }
        // A node on the friction limit may flip its set at round-off level from one iteration
        // to the next; a time step cannot cut its load back, so it settles there.
        let copt = self.copt.map(|mut o| {
            o.settle_round_off = true;
            o
        });
        let law = self.law.clone();
        let ladder = self.integrators.as_mut().expect("built");
        let integ = ladder.size(u).as_mut().expect("built above");
        let (scale, control) = load(tau0 + h);
        let tried = integ.step(now, st, scale, control, law.as_ref(), copt.as_ref());
        let error = match tried {
            Ok(s) if s.time.u.iter().all(|v| v.is_finite()) => {
                let changes = state_changes(st, s.contact.as_ref());
                let eta = rate_change((st, now.dt), (s.contact.as_ref(), h));
                if !Sizer::refuses(u.max(0) as usize, changes, eta) {
                    integ.lu.end_step();
                    return Ok(vec![(
                        s.time,
                        Sub {
                            contact: s.contact,
                            iterations: s.iterations,
                            scale,
                            control,
                            doublings: u,
                            calm: changes == 0 && eta <= 0.5 * RATE_CHANGE,
                            dt: h,
                            wall: t.elapsed().as_secs_f64(),
                        },
                    )]);
                }
                integ.lu.end_step();
                None
            }
            Ok(_) => Some(StepError::NotFinite),
            Err(e) => Some(e),
        };
        if let Some(error) = &error {
            if u <= -(MAX_DT_HALVINGS as isize) {
                return Err(Failure::Step(error.clone()));
            }
            if !self.quiet {
                eprintln!(
                    "the time step to t = {:.6e} (Δt = {h:.3e}): {error}; two steps of Δt/2",
                    now.time + h
                );
            }
        }
        let mut first = self.advance(u - 1, now, st, tau0, load)?;
        let mid = first.last().expect("at least one step");
        let (mid_time, mid_contact) = (mid.0.clone(), mid.1.contact.clone());
        let second = self.advance(u - 1, &mid_time, mid_contact.as_ref(), tau0 + 0.5 * h, load)?;
        first.extend(second);
        Ok(first)
    }

    /// Whether every contact node slides at μ = f_d.
    fn all_sliding(&self, f_d: Option<f64>) -> bool {
        match (&self.cstate, &self.law, f_d) {
            (Some(st), Some(law), Some(fd)) => {
                let mut on = (0..st.status.len())
                    .filter(|&j| st.status[j] != Status::Open)
                    .peekable();
                on.peek().is_some()
                    && on.all(|j| {
                        st.status[j] == Status::Slip
                            && law.mu(st.slip_mu[j]) <= fd + 1e-9 * fd.abs().max(1e-300)
                    })
            }
            _ => false,
        }
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
