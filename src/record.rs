//! What a run records: the record of each converged step ([`StepRecord`], made by the
//! [`crate::driver`]), the figures of each stage integrated in time ([`EventSummary`]) and the
//! friction summary of the run ([`FrictionSummary`], made by [`crate::report`] and judged by
//! [`crate::checks`]). Plain data, below every module that reads it.

use crate::model::step::{ContactFigures, PilotState};
use serde::Serialize;

/// One converged load step.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
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
    /// The cycle (from 1) of a stage of a cycle group.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cycle: Option<usize>,
    /// Physical time at the end of a step integrated in time (steps of dynamic stages).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physical_time: Option<f64>,
    /// Kinetic energy `½ vᵀ M v` at the end of a step integrated in time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinetic: Option<f64>,
    /// The fronts of weakening of a step integrated in time and their energy release rates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fronts: Option<FrontFigures>,
}

/// The leftmost and rightmost fronts of weakening of a step integrated in time
/// ([`crate::model::fronts::weakening_fronts`]): position, the energy release rate `G` measured
/// by the dynamic J-integral ([`crate::dynamics::flux`]) and the fracture energy `Γ` of its
/// process zone; `None` where there is no front or no value.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct FrontFigures {
    pub front: [Option<f64>; 2],
    pub g: [Option<f64>; 2],
    pub gamma: [Option<f64>; 2],
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
    /// The relative RMS residual of that fit (see [`crate::checks::fit_radius`]) and whether
    /// the profile counts as Hertzian (`profile_rms ≤` [`crate::checks::HERTZ_PROFILE_LIMIT`]
    /// with a finite positive R). Where it does not, no closed form of the paper applies: `a_hertz`,
    /// Λ, χ, Ψ, s0 and the predicted Q_max/P are absent and `not_hertzian` says why.
    pub profile_rms: f64,
    pub hertzian: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub not_hertzian: Option<String>,
    pub a_hertz: Option<f64>,
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

impl FrictionSummary {
    /// f_d P when `q_max` is below it by more than 0.1 %: the least the contact carries once
    /// every point has weakened, so a force-controlled run that stopped there met a local
    /// peak of the load path, not gross sliding. (The margin is above the bracket's width,
    /// 2^-11 of a nominal step, and the change of P over it where P moves with Q.)
    pub fn local_peak(&self, q_max: f64) -> Option<f64> {
        self.f_d
            .map(|fd| fd * self.load)
            .filter(|fdp| q_max < (1.0 - 1e-3) * fdp)
    }
}

/// How a dynamic stage ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
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
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct EventSummary {
    pub stage: usize,
    /// Whether it followed a lost equilibrium (`on_lost_equilibrium`).
    pub after_lost_equilibrium: bool,
    pub rho_inf: f64,
    /// The stage's time step `dt`, and the largest step it took (above `dt` only where the
    /// stage adapts its step, `dt_max`).
    pub dt: f64,
    #[serde(default)]
    pub dt_largest: f64,
    pub t_start: f64,
    pub t_end: f64,
    /// The time steps taken, at every size.
    pub steps: usize,
    pub newton_iterations: usize,
    pub peak_kinetic: f64,
    pub end: EventEnd,
    /// Seconds to build and factorise `K + c M` (zero when reused) and to step.
    pub factorise_s: f64,
    pub wall_s: f64,
}

impl EventSummary {
    /// How the stage ended, in words.
    pub fn describe(&self) -> String {
        let t = self.t_end;
        match self.end {
            EventEnd::Duration => format!("reached the end of its duration at t = {t:.6e}"),
            EventEnd::Rest => format!("came to rest at t = {t:.6e}"),
            EventEnd::Sliding => format!(
                "ended in gross sliding at f_d at t = {t:.6e} (every contact node sliding at μ = f_d: under a force above f_d P the body accelerates)"
            ),
            EventEnd::Failed => format!("stopped at t = {t:.6e}: a time step failed"),
        }
    }
}
