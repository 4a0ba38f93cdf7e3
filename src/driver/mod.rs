//! The load-path driver: the stages of a case stepped on a built model, with a predictor
//! from the last two steps, cutbacks of a step that does not converge, and the bracketing of
//! the peak tangential force when a force-controlled load passes it. It reads the model and
//! the case, and hands every converged step to its caller ([`StepEvent`]); it writes nothing.
//!
//! | module | content |
//! |---|---|
//! | this file | how a run is driven: [`simulate`], [`simulate_with`] and their options |
//! | `stage` | the stepping of a stage: attempts, cutbacks, probes, the records of the steps |
//! | `outcome` | what the driver hands its caller: each step ([`StepEvent`]), the run ([`Simulation`]) |
//! | `dynamic` | stages integrated in time, and the event after a lost equilibrium |
//! | `timestep` | a dynamic stage's step sizes: their integrators, the size control, the end criteria |
//! | `checkpoint` | what a run keeps between steps to go on exactly ([`Checkpoint`]) |
//! | `refuse` | loads that no equilibrium can carry, refused before the first step or per step |

mod checkpoint;
mod dynamic;
mod outcome;
mod refuse;
mod stage;
mod timestep;

pub use crate::record::{EventEnd, EventSummary};
pub use checkpoint::Checkpoint;
pub use outcome::{Simulation, StepEvent};
pub use refuse::{DISPLACEMENT_ERROR, beyond_friction_at_start, free_direction, refuse_unloadable};
pub use stage::{MAX_CUTBACKS, STEP_BUDGET, STEP_BUDGET_MIN, step_budget};

use crate::case::Case;
use crate::contact::solver;
use crate::error::RunError;
use crate::friction::FrictionLaw;
use crate::model::Model;
use stage::Driver;

/// How much a run prints to standard error.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, clap::ValueEnum)]
pub enum LogLevel {
    Error,
    Warn,
    #[default]
    Info,
    Debug,
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

/// [`simulate`] with checkpoints and resumption.
pub fn simulate_with(
    model: &Model,
    case: &Case,
    law: Option<&FrictionLaw>,
    log: LogLevel,
    on_step: &mut dyn FnMut(&StepEvent) -> Result<(), RunError>,
    restart: Restart,
) -> Result<Simulation, RunError> {
    let copt = case.contact.as_ref().map(|c| solver::Options {
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
        settle_round_off: false,
    });
    let mut d = Driver::new(model, case, law, log < LogLevel::Warn, copt, restart.every);
    if restart.from.is_none() {
        refuse_unloadable(model, case, law)?;
    }
    let mut resume = restart.from.map(|c| d.restore(c));
    let first = resume.as_ref().map_or(0, |r| r.0);
    for (si, stage) in case.stages.iter().enumerate().skip(first) {
        // A stage's whole patches weaken the contact as it starts (not when resumed within
        // it); growing ones advance with its time steps.
        if (si > first || resume.is_none())
            && let Some(st) = d.cstate.as_mut()
        {
            let whole = stage.weaken.iter().filter(|p| p.speed.is_none());
            model
                .weaken(whole.map(|p| (p.x, p.slip)), &mut st.slip_mu)
                .expect("run refuses a patch without a node");
        }
        let go_on = match &stage.dynamic {
            Some(spec) => d.run_dynamic_stage(si, spec, on_step)?,
            None => {
                // After a dynamic stage the state balances inertia too: the stage's first
                // step solves for equilibrium even where its loads do not change.
                d.after_motion = d.motion.take().is_some();
                d.run_stage(si, stage, on_step, resume.take().map(|r| r.1))?
            }
        };
        if !go_on {
            break;
        }
    }
    Ok(d.finish())
}
