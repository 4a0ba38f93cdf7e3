//! The time step of a dynamic stage: the integrators of each step size, the size control of
//! an adaptive stage (`dt_max`) and the end criteria of `until: "rest"`.
//!
//! Every size is `dt · 2^u` for an integer `u`: the stage's `dt` (`u = 0`), its doublings up
//! to `dt_max` and its halvings down to `dt / 2^MAX_DT_HALVINGS`, each with `K + c M`
//! factorised once, when first needed. A stage's time is counted in *nominal* steps of `dt`:
//! a step of `dt · 2^u` (u ≥ 0) starts on a multiple of `2^u` and covers `2^u` of them.
//!
//! **Size control** (only with `dt_max` > `dt`). A step larger than `dt` is kept only if
//! * it changes no contact node's state (open, stick, slip): contact changes state where
//!   fronts pass, and every change is then taken by a step of `dt` (or finer), located in
//!   time as a run with every step `dt` locates it; and
//! * the slip rate changes little over it: with `ṡ_j = Δs_j / Δt` node `j`'s slip rate over
//!   a step, `max_j |ṡ_j − ṡ_j^prev| ≤ RATE_CHANGE · max_j max(|ṡ_j|, |ṡ_j^prev|)`
//!   ([`rate_change`], [`RATE_CHANGE`]). A slip that grows exponentially at the rate λ
//!   changes by `1 − e^(−λΔt)` per step, so the step stays below about `0.29/λ` wherever
//!   slip accelerates (a creep running away towards the collapse).
//!
//! A step refused is taken again as two of half its size. After [`CALM_STEPS`] steps in a
//! row that changed no node's state and whose slip rate changed by at most half the bound
//! (a step twice as long would be kept), the size doubles, up to `dt_max`; a refused step
//! sets the size to the one that was kept. A stage starts with `dt`. What this leaves to the
//! user: `dt_max` bounds the step where neither criterion acts (every node stuck, or slip at
//! a steady rate), so it is what resolves the bodies' own vibrations there.

use crate::case::DynamicSpec;
use crate::contact::solver::State;
use crate::dynamics::{Integrator, Scheme};
use crate::record::EventEnd;
use std::collections::VecDeque;

/// Halvings of a dynamic stage's time step `dt` before a step is given up.
pub const MAX_DT_HALVINGS: usize = 3;

/// Steps in a row at a size, none changing a contact node's state and each changing the
/// slip rate by at most `RATE_CHANGE / 2`, before the size doubles.
pub const CALM_STEPS: usize = 8;

/// The largest relative change of the slip rate over a step larger than `dt`
/// ([`rate_change`]).
pub const RATE_CHANGE: f64 = 0.25;

/// The relative change of the contact nodes' slip rate from the step before (contact state
/// `before`, a step of `dt0`) to the step after (`after`, a step of `dt1`):
/// `max_j |ṡ_j − ṡ_j^prev| / max_j max(|ṡ_j|, |ṡ_j^prev|)` with `ṡ = Δs / Δt` the signed slip
/// increments over each step's length; 0 where nothing slips (or without contact), 1 after
/// a state at rest (`dt0` = 0).
pub fn rate_change(
    (before, dt0): (Option<&State>, f64),
    (after, dt1): (Option<&State>, f64),
) -> f64 {
    let (Some(b), Some(a)) = (before, after) else {
        return 0.0;
    };
    let (mut change, mut scale) = (0.0f64, 0.0f64);
    for (db, da) in b.dv.iter().zip(&a.dv) {
        let r0 = if dt0 > 0.0 { db / dt0 } else { 0.0 };
        let r1 = da / dt1;
        change = change.max((r1 - r0).abs());
        scale = scale.max(r0.abs()).max(r1.abs());
    }
    if scale > 0.0 { change / scale } else { 0.0 }
}

/// The number of contact nodes whose state differs between `before` and `after`.
pub fn state_changes(before: Option<&State>, after: Option<&State>) -> usize {
    match (before, after) {
        (Some(b), Some(a)) => b
            .status
            .iter()
            .zip(&a.status)
            .filter(|(x, y)| x != y)
            .count(),
        _ => 0,
    }
}

/// The integrators of one scheme and stage step `dt`, one per step size `dt · 2^u` for
/// `−MAX_DT_HALVINGS ≤ u ≤ up_max`, each built when first needed.
pub(super) struct Ladder {
    pub scheme: Scheme,
    pub dt: f64,
    pub up_max: usize,
    sizes: Vec<Option<Integrator>>,
}

impl Ladder {
    /// An empty ladder.
    pub fn new(scheme: Scheme, dt: f64, up_max: usize) -> Ladder {
        Ladder {
            scheme,
            dt,
            up_max,
            sizes: (0..=up_max + MAX_DT_HALVINGS).map(|_| None).collect(),
        }
    }

    /// The step size `dt · 2^u`.
    pub fn dt_of(&self, u: isize) -> f64 {
        self.dt * 2f64.powi(u as i32)
    }

    /// The integrator of the size `dt · 2^u`, if built.
    pub fn size(&mut self, u: isize) -> &mut Option<Integrator> {
        &mut self.sizes[(u + MAX_DT_HALVINGS as isize) as usize]
    }
}

/// The size control of a dynamic stage, in doublings `u` of its `dt` (see the module's
/// documentation). A stage without `dt_max` has `up_max = 0`: every step is `dt`.
pub(super) struct Sizer {
    /// Doublings allowed: `dt · 2^up_max` ≤ `dt_max`.
    pub up_max: usize,
    /// The doublings of the next step.
    up: usize,
    /// Steps in a row at the current size that changed no contact node's state.
    calm: usize,
}

impl Sizer {
    pub fn new(spec: &DynamicSpec) -> Sizer {
        Sizer {
            up_max: spec.doublings(),
            up: 0,
            calm: 0,
        }
    }

    /// The doublings of the step from nominal index `k` of a stage of `n` nominal steps: the
    /// current size, smaller where the step would not start on a multiple of its size or
    /// would pass the stage's end.
    pub fn next(&self, k: usize, n: usize) -> usize {
        let mut u = self.up;
        while u > 0 && (!k.is_multiple_of(1 << u) || k + (1 << u) > n) {
            u -= 1;
        }
        u
    }

    /// Whether a step of `u` doublings that changed the state of `changes` contact nodes and
    /// the slip rate by `rate` ([`rate_change`]) is refused: one larger than `dt` that
    /// changed a state or the slip rate by more than [`RATE_CHANGE`].
    pub fn refuses(u: usize, changes: usize, rate: f64) -> bool {
        u > 0 && (changes > 0 || rate > RATE_CHANGE)
    }

    /// After a step tried at `tried` doublings, taken as steps whose smallest had `least`
    /// doublings (`least < tried` when it was split), `calm` when each changed no node's
    /// state and the slip rate by at most `RATE_CHANGE / 2`.
    pub fn taken(&mut self, tried: usize, least: usize, calm: bool) {
        if least < tried {
            self.up = least;
            self.calm = 0;
        } else if calm {
            self.calm += 1;
            if self.calm >= CALM_STEPS && self.up < self.up_max {
                self.up += 1;
                self.calm = 0;
            }
        } else {
            self.calm = 0;
        }
    }
}

/// The end criteria of `until: "rest"` ([`DynamicSpec`]), observed at the end of each of a
/// stage's time steps, over a window of `rest_window` nominal steps of `dt`.
pub(super) struct EndWatch {
    rest: bool,
    ratio: f64,
    window: usize,
    /// From when the loads are at their targets, in nominal steps.
    ramp: f64,
    /// The kinetic energy at the end of the steps ending within the window.
    recent: VecDeque<(usize, f64)>,
    /// The nominal index from which every contact node has slid at f_d.
    sliding_since: Option<usize>,
}

impl EndWatch {
    /// The criteria of `spec` (time step `dt`); `after_lost`: the loads are at their targets
    /// from the start.
    pub fn new(spec: &DynamicSpec, dt: f64, after_lost: bool) -> EndWatch {
        EndWatch {
            rest: spec.until == crate::case::Until::Rest,
            ratio: spec.rest_ratio,
            window: spec.rest_window,
            ramp: if after_lost {
                0.0
            } else {
                spec.ramp_time() / dt
            },
            recent: Default::default(),
            sliding_since: None,
        }
    }

    /// The end reached by the step from nominal index `k0` to `k` with kinetic energy
    /// `kinetic` at its end (the stage's peak so far `peak`), `sliding` when every contact
    /// node slides at f_d.
    pub fn observe(
        &mut self,
        (k0, k): (usize, usize),
        kinetic: f64,
        peak: f64,
        sliding: bool,
    ) -> Option<EventEnd> {
        self.recent.push_back((k, kinetic));
        while self.recent.len() > 1 && self.recent[0].0 + self.window <= k {
            self.recent.pop_front();
        }
        self.sliding_since = if sliding {
            self.sliding_since.or(Some(k0))
        } else {
            None
        };
        if !self.rest || (k as f64) < self.ramp * (1.0 - 1e-12) || k < self.window {
            return None;
        }
        let top = self.recent.iter().map(|r| r.1).fold(0.0, f64::max);
        if peak > 0.0 && top <= self.ratio * peak {
            Some(EventEnd::Rest)
        } else if self.sliding_since.is_some_and(|s| k - s >= self.window) {
            Some(EventEnd::Sliding)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sizer(up_max: usize) -> Sizer {
        Sizer {
            up_max,
            up: 0,
            calm: 0,
        }
    }

    #[test]
    fn the_size_doubles_after_calm_steps_up_to_its_limit_and_falls_to_a_split() {
        let mut s = sizer(2);
        let mut k = 0;
        let mut sizes = vec![];
        for _ in 0..30 {
            let u = s.next(k, 1000);
            sizes.push(u);
            s.taken(u, u, true);
            k += 1 << u;
        }
        assert!(sizes[..CALM_STEPS].iter().all(|&u| u == 0));
        assert_eq!(sizes[CALM_STEPS], 1);
        assert_eq!(*sizes.last().unwrap(), 2);
        assert!(sizes.iter().all(|&u| u <= 2));
        // A step split down to dt sets the size back to dt; one kept but not calm keeps its
        // size and starts the count again.
        s.taken(2, 0, false);
        assert_eq!(s.next(k, 1000), 0);
        let mut s = sizer(2);
        s.up = 2;
        s.calm = CALM_STEPS - 1;
        s.taken(2, 2, false);
        assert_eq!((s.up, s.calm), (2, 0));
    }

    #[test]
    fn steps_start_on_a_multiple_of_their_size_and_stop_at_the_stage_end() {
        let mut s = sizer(4);
        s.up = 4;
        assert_eq!(s.next(0, 100), 4);
        assert_eq!(s.next(8, 100), 3);
        assert_eq!(s.next(3, 100), 0);
        assert_eq!(s.next(96, 100), 2);
        assert_eq!(s.next(99, 100), 0);
        assert!(!Sizer::refuses(0, 50, 1.0));
        assert!(!Sizer::refuses(3, 0, RATE_CHANGE));
        assert!(Sizer::refuses(1, 1, 0.0));
        assert!(Sizer::refuses(1, 0, 1.01 * RATE_CHANGE));
    }

    fn watch(window: usize) -> EndWatch {
        EndWatch {
            rest: true,
            ratio: 1e-3,
            window,
            ramp: 0.0,
            recent: Default::default(),
            sliding_since: None,
        }
    }

    /// The window is counted in nominal steps: steps of one and of four nominal steps end
    /// the stage at the same nominal index.
    #[test]
    fn the_rest_window_is_a_time_not_a_count_of_steps() {
        for span in [1, 4] {
            let mut w = watch(8);
            let mut k = 0;
            let end = loop {
                let (k0, k1) = (k, k + span);
                k = k1;
                // Kinetic energy 1 up to nominal 12, then 1e-6.
                let ke = if k1 <= 12 { 1.0 } else { 1e-6 };
                if let Some(e) = w.observe((k0, k1), ke, 1.0, false) {
                    break (e, k1);
                }
            };
            assert_eq!(end, (EventEnd::Rest, 20), "span {span}");
            let mut w = watch(8);
            let mut k = 0;
            let end = loop {
                let (k0, k1) = (k, k + span);
                k = k1;
                if let Some(e) = w.observe((k0, k1), 1.0, 1.0, k0 >= 4) {
                    break (e, k1);
                }
            };
            assert_eq!(end, (EventEnd::Sliding, 12), "span {span}");
        }
    }
}
