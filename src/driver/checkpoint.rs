//! What a run keeps between steps to go on exactly as it would have: the loads a stage
//! starts from ([`StageStart`]) and the driver's state after a converged step
//! ([`Checkpoint`]), which a restart state carries.

use crate::case::Control;
use crate::contact::solver::{self, State};
use crate::model::step::PilotState;
use crate::record::StepRecord;

/// Everything the driver needs to go on from a converged step exactly as it would have.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Checkpoint {
    pub stage: usize,
    pub(super) start: StageStart,
    pub alpha: f64,
    pub(super) dalpha: f64,
    pub(super) older: Option<(f64, State)>,
    pub cstate: Option<State>,
    pub(super) control: [Control; 2],
    pub(super) pilot: PilotState,
    pub scale: f64,
    /// The records of the steps so far: in the journal, not in the state file (see
    /// [`crate::restart`]).
    #[serde(skip)]
    pub records: Vec<StepRecord>,
    pub(super) newton_total: usize,
    pub(super) factorisations: usize,
    pub(super) gmres_iterations: usize,
    /// The contact solver's factorised Delassus block, for the resumed run to rebuild.
    #[serde(default)]
    pub(super) contact_block: Option<solver::BlockRecord>,
    pub(super) bracket: Option<(f64, f64)>,
    pub last_u: Option<Vec<f64>>,
    pub(super) t_solve: f64,
    pub(super) t_contact: f64,
    /// Physical time reached by the dynamic stages before this checkpoint.
    #[serde(default)]
    pub(super) physical_time: f64,
    /// The stages integrated in time before this checkpoint.
    #[serde(default)]
    pub(super) events: Vec<crate::record::EventSummary>,
}

/// The committed loads at the start of a stage, from which its steps interpolate.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct StageStart {
    pub(super) pilot: PilotState,
    pub(super) scale: f64,
    pub(super) control: [Control; 2],
    pub(super) mean_slip: f64,
}

impl StageStart {
    /// The pilot's drive at the fraction `a` of the stage towards `target`.
    pub(super) fn control_at(&self, target: [Option<Control>; 2], a: f64) -> [Control; 2] {
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
    pub(super) fn is_hold(&self, target: [Option<Control>; 2], scale: Option<f64>) -> bool {
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

/// Where a stage resumes: its start, the load fraction reached, the next increment and the
/// predictor's older state.
pub(super) type StagePosition = (StageStart, f64, f64, Option<(f64, State)>);
