//! Loads that no equilibrium can carry. Before the first step: a pilot axis that nothing holds,
//! a first stage beyond friction at every load ([`refuse_unloadable`]). At each step: a pilot
//! that pulls a body nothing else holds, or an answer in which that body floats free or ran
//! away.

use crate::case::{Case, Control};
use crate::contact::solver::{State, Status};
use crate::error::{RunError, StepError, StepFailure};
use crate::friction::FrictionLaw;
use crate::model::Model;

/// Displacement over model size above which a body ran away: no linear-elastic answer of a
/// held body moves ten times its own size, while an unheld one, kept only by round-off, moves
/// 1e9 times. A converged step of a pilot that moved farther is a failed step
/// (`unheld_after`); the self-check `max_displacement` of a finished run calls a field that
/// did an error.
pub const DISPLACEMENT_ERROR: f64 = 10.0;

/// The pilot's drive along the direction that separates its (otherwise unheld) body from the
/// contact: the dominant component of that direction, and its force if force-controlled. A
/// force at the round-off of zero (below 1e-12 of the largest modulus times the model's
/// diameter: e.g. a stage that holds the force a zero load converged to) counts as zero, whose
/// sign means nothing.
fn separating_force(model: &Model, ctl: &[Control; 2]) -> Option<(usize, usize, Option<f64>)> {
    let (body, sep) = model.pilot_separation?;
    let k = if sep[0].abs() > sep[1].abs() { 0 } else { 1 };
    let (size, e_max) = model.scales();
    let round_off = 1e-12 * e_max * size;
    let f = match ctl[k] {
        Control::Force(f) if f.abs() <= round_off => Some(0.0),
        Control::Force(f) => Some(f * sep[k].signum()),
        Control::Displacement(_) | Control::Slip(_) => None,
    };
    Some((body, k, f))
}

/// A step that cannot have an equilibrium: the pilot pulls a body that nothing else holds away
/// from the contact (a force along the separating direction).
pub(super) fn unheld_before(model: &Model, case: &Case, ctl: &[Control; 2]) -> Option<StepError> {
    let (body, k, f) = separating_force(model, ctl)?;
    let f = f.filter(|f| *f > 0.0)?;
    Some(StepError::PulledApart {
        axis: ["x", "y"][k],
        force: f * model.pilot_separation.expect("checked").1[k].signum(),
        body: case.bodies[body].group.clone(),
    })
}

/// A converged step whose answer means nothing: a force-controlled pilot body with no node in
/// contact and no support (held only by the solver's grounding spring), or a pilot that ran
/// away ([`DISPLACEMENT_ERROR`]).
pub(super) fn unheld_after(
    model: &Model,
    case: &Case,
    ctl: &[Control; 2],
    st: &State,
) -> Option<StepError> {
    let size = model.scales().0;
    let u = st.pilot_u[0].hypot(st.pilot_u[1]);
    let limit = DISPLACEMENT_ERROR;
    if model.dofs.pilot.is_some() && (u.is_nan() || u > limit * size) {
        return Some(StepError::RanAway {
            moved: u,
            limit,
            size,
        });
    }
    let (body, k, f) = separating_force(model, ctl)?;
    f?;
    if st.status.iter().all(|s| *s == Status::Open) {
        return Some(StepError::Free {
            body: case.bodies[body].group.clone(),
            axis: ["x", "y"][k],
        });
    }
    None
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
