//! The keys of time integration: a stage's `dynamic` block, the case's
//! `on_lost_equilibrium`, and their checks (densities of the bodies, time step, duration).

use super::{Case, CaseError, invalid};
use serde::{Deserialize, Serialize};

/// Most time steps of one dynamic stage.
pub const MAX_TIME_STEPS: usize = 1_000_000;

/// Most doublings of an adaptive stage's time step (`dt_max` ≤ `dt · 2^MAX_DOUBLINGS`).
pub const MAX_DOUBLINGS: usize = 10;

/// A stage integrated in time (generalised-α, [`crate::dynamics::Scheme`]): the pilot's
/// targets and the traction scale are reached linearly at `ramp` and held to the end.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DynamicSpec {
    /// Time step Δt (> 0). The stage takes `⌈duration/dt⌉` equal steps of
    /// `duration / ⌈duration/dt⌉`.
    pub dt: f64,
    /// The largest time step of an adaptive stage (≥ `dt`). The step is `dt` times a power
    /// of two: it doubles after steps that changed no contact node's state and the slip rate
    /// little, up to the largest `dt · 2^u` ≤ `dt_max`; a step larger than `dt` that changes
    /// a contact node's state, or the slip rate by more than 25 %, is taken again as two of
    /// half its size, so each change of state is taken at `dt` (the rules:
    /// `docs/dynamics.md`, `driver::timestep`). Absent: every step is `dt`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// Physical duration of the stage (≥ dt).
    pub duration: f64,
    /// The scheme's spectral radius at infinite frequency ρ∞ ∈ [0, 1]: 1 dissipates nothing
    /// (energy conserved for a linear elastic body), lower values damp the frequencies near
    /// the mesh's highest. Default 0.9.
    #[serde(default = "default_rho_inf")]
    pub rho_inf: f64,
    /// Time at which the loads reach their targets, from the stage's start (0 ≤ ramp ≤
    /// duration): 0 applies them at the first step. Default: the duration.
    #[serde(default)]
    pub ramp: Option<f64>,
    /// How the loads go to their targets over the ramp: `linear` (default), or `smooth`
    /// (`½ (1 − cos(π τ/ramp))`: no jump in the loading rate at either end, so the ramp
    /// excites the bodies' vibrations far less).
    #[serde(default)]
    pub ramp_shape: RampShape,
    /// When the stage ends: at its `duration`, or earlier once the event is over (`rest`,
    /// [`DynamicSpec::rest_ratio`]).
    #[serde(default)]
    pub until: Until,
    /// With `until: "rest"`: the stage ends once the loads are at their targets and the kinetic
    /// energy has stayed below `rest_ratio` times its peak in the stage for a window of
    /// `rest_window` steps, or once every contact node has slid at μ = f_d for that window
    /// (steady gross sliding). Default 1e-3.
    #[serde(default = "default_rest_ratio")]
    pub rest_ratio: f64,
    /// The window of the `rest` criterion, in steps (≥ 1). Default 50.
    #[serde(default = "default_rest_window")]
    pub rest_window: usize,
}

/// When a dynamic stage ends.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Until {
    /// At the stage's duration.
    #[default]
    Duration,
    /// When the kinetic energy has decayed or gross sliding is steady (or at the duration).
    Rest,
}

/// The shape of a dynamic stage's ramp.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum RampShape {
    #[default]
    Linear,
    Smooth,
}

impl RampShape {
    /// The load fraction at the fraction `x` ∈ [0, 1] of the ramp.
    pub fn fraction(self, x: f64) -> f64 {
        let x = x.clamp(0.0, 1.0);
        match self {
            RampShape::Linear => x,
            RampShape::Smooth => 0.5 * (1.0 - (std::f64::consts::PI * x).cos()),
        }
    }
}

fn default_rho_inf() -> f64 {
    0.9
}
fn default_rest_ratio() -> f64 {
    1e-3
}
fn default_rest_window() -> usize {
    50
}

impl DynamicSpec {
    /// The number of steps and the time step: `⌈duration/dt⌉` steps of `duration / steps`.
    pub fn steps_and_dt(&self) -> (usize, f64) {
        let n = (self.duration / self.dt * (1.0 - 1e-12)).ceil().max(1.0) as usize;
        (n, self.duration / n as f64)
    }

    /// The doublings of the time step an adaptive stage may take: the largest `u` with
    /// `dt · 2^u ≤ dt_max` (0 without `dt_max`).
    pub fn doublings(&self) -> usize {
        let (_, dt) = self.steps_and_dt();
        let Some(max) = self.dt_max else {
            return 0;
        };
        let mut u = 0;
        while u < MAX_DOUBLINGS && dt * (1u64 << (u + 1)) as f64 <= max * (1.0 + 1e-9) {
            u += 1;
        }
        u
    }

    /// The ramp time (the duration when absent).
    pub fn ramp_time(&self) -> f64 {
        self.ramp.unwrap_or(self.duration)
    }
}

/// What a run does when a force-controlled load passes the peak tangential force (no
/// equilibrium exists): stop there (exit 5, the default when the key is absent), or integrate
/// the event in time from the last converged state under the first load with no equilibrium.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OnLostEquilibrium {
    /// The dynamic stage run from the lost equilibrium (its `ramp` is ignored: the load is
    /// held at the first load without equilibrium).
    pub dynamic: DynamicSpec,
}

/// Checks a dynamic block at `key`.
pub(super) fn validate_spec(path: &str, key: &str, d: &DynamicSpec) -> Result<(), CaseError> {
    let bad = |k: &str, v: String, why: &str| invalid(path, format!("{key}.{k}"), v, why);
    if !(d.dt > 0.0 && d.dt.is_finite()) {
        return Err(bad("dt", format!("{}", d.dt), "must be > 0 and finite"));
    }
    if !(d.duration.is_finite() && d.duration >= d.dt) {
        return Err(bad(
            "duration",
            format!("{}", d.duration),
            &format!("must be finite and at least `dt` = {}", d.dt),
        ));
    }
    if let Some(m) = d.dt_max
        && !(m.is_finite() && m >= d.dt && m <= d.dt * (1u64 << MAX_DOUBLINGS) as f64)
    {
        return Err(bad(
            "dt_max",
            format!("{m}"),
            &format!(
                "must be finite and between `dt` = {} and {} (`dt` · 2^{MAX_DOUBLINGS})",
                d.dt,
                d.dt * (1u64 << MAX_DOUBLINGS) as f64
            ),
        ));
    }
    let (n, _) = d.steps_and_dt();
    if n > MAX_TIME_STEPS {
        return Err(bad(
            "duration",
            format!("{}", d.duration),
            &format!(
                "duration/dt = {n} time steps, more than {MAX_TIME_STEPS}: a larger `dt` or a shorter stage"
            ),
        ));
    }
    if !(0.0..=1.0).contains(&d.rho_inf) {
        return Err(bad(
            "rho_inf",
            format!("{}", d.rho_inf),
            "must be in [0, 1]",
        ));
    }
    if let Some(r) = d.ramp
        && !(r >= 0.0 && r <= d.duration)
    {
        return Err(bad("ramp", format!("{r}"), "must be in [0, duration]"));
    }
    if !(d.rest_ratio > 0.0 && d.rest_ratio < 1.0) {
        return Err(bad(
            "rest_ratio",
            format!("{}", d.rest_ratio),
            "must be in (0, 1)",
        ));
    }
    if d.rest_window == 0 {
        return Err(bad("rest_window", "0".into(), "must be ≥ 1"));
    }
    Ok(())
}

impl Case {
    /// Whether any part of the run may integrate in time (a dynamic stage, or the switch on a
    /// lost equilibrium).
    pub fn uses_dynamics(&self) -> bool {
        self.on_lost_equilibrium.is_some() || self.stages.iter().any(|s| s.dynamic.is_some())
    }

    /// The dynamic blocks are valid, and where dynamics is used every body has a density
    /// (> 0, finite); the error names the body and what needs it.
    pub(super) fn validate_dynamics(&self, path: &str) -> Result<(), CaseError> {
        for (i, s) in self.stages.iter().enumerate() {
            if let Some(d) = &s.dynamic {
                validate_spec(path, &format!("stages[{i}].dynamic"), d)?;
            }
        }
        if let Some(o) = &self.on_lost_equilibrium {
            validate_spec(path, "on_lost_equilibrium.dynamic", &o.dynamic)?;
            if self.contact.as_ref().is_none_or(|c| c.friction.is_none()) {
                return Err(invalid(
                    path,
                    "on_lost_equilibrium".into(),
                    "dynamic".into(),
                    "needs a `contact` with `friction` (only a tangential load can pass the peak)",
                ));
            }
        }
        let user = self
            .stages
            .iter()
            .position(|s| s.dynamic.is_some())
            .map(|i| format!("stages[{i}] integrates in time"))
            .or_else(|| {
                self.on_lost_equilibrium
                    .as_ref()
                    .map(|_| "`on_lost_equilibrium` integrates in time".to_string())
            });
        let Some(user) = user else {
            return Ok(());
        };
        for (i, b) in self.bodies.iter().enumerate() {
            match b.density {
                None => {
                    return Err(invalid(
                        path,
                        format!("bodies[{i}].density"),
                        "missing".into(),
                        &format!("{user} and needs the density of body `{}`", b.group),
                    ));
                }
                Some(r) if !(r > 0.0 && r.is_finite()) => {
                    return Err(invalid(
                        path,
                        format!("bodies[{i}].density"),
                        format!("{r}"),
                        "must be > 0 and finite",
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }
}
