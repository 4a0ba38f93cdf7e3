//! Loads that no equilibrium can carry: a pilot that pulls a body nothing else holds, or an
//! answer in which that body floats free or ran away.

use crate::case::{Case, Control};
use crate::contact::solver::{State, Status};
use crate::error::StepError;
use crate::model::Model;

/// Displacement over model size above which a body ran away: no linear-elastic answer of a
/// held body moves ten times its own size, while an unheld one, kept only by round-off, moves
/// 1e9 times. A converged step of a pilot that moved farther is a failed step
/// ([`unheld_after`]); the self-check `max_displacement` of a finished run calls a field that
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
