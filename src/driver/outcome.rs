//! What the driver hands its caller: each converged step as it is taken ([`StepEvent`]) and
//! the outcome of the run ([`Simulation`]).

use super::checkpoint::Checkpoint;
use crate::contact::solver::{self, State};
use crate::error::StepFailure;
use crate::record::StepRecord;

/// One converged step, handed to the caller of [`super::simulate`].
pub struct StepEvent<'a> {
    pub step: usize,
    pub time: f64,
    pub scale: f64,
    /// Whether this is the last step of the last stage.
    pub last: bool,
    /// The case's nominal step (counted over all stages, from 1) this step lands on; `None` for
    /// a sub-step between two nominal loads (after a cutback).
    pub nominal: Option<usize>,
    /// The nominal steps this step covers, ending at `nominal`: one, or `2^u` for a step of
    /// `dt · 2^u` of an adaptive dynamic stage.
    pub spans: usize,
    /// The free solution, where the step computed it (runs without contact).
    pub u: Option<&'a Vec<f64>>,
    /// The contact state (runs with contact; the full field is recovered on demand).
    pub contact: Option<&'a State>,
    /// The record of this step.
    pub record: &'a StepRecord,
    /// The driver's state after this step, when it is a checkpoint ([`super::Restart::every`]).
    pub checkpoint: Option<&'a Checkpoint>,
    /// The time step of a step integrated in time (its physical time is in the record).
    pub dt: Option<f64>,
}

/// What [`super::simulate`] returns.
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
    /// The stages integrated in time.
    pub events: Vec<crate::record::EventSummary>,
}
