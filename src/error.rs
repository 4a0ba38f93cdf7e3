//! Why a run stopped, and the process exit status of each reason (the one place exit codes are
//! mapped).

use crate::contact::solver::ContactError;

/// Anything that stops a model from being built or solved.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error(transparent)]
    MeshRead(#[from] crate::mesh::gmsh::MeshReadError),
    #[error(transparent)]
    MeshCheck(#[from] crate::mesh::check::MeshCheckError),
    #[error("{path}: {source}")]
    Dof {
        path: String,
        source: crate::dofs::DofError,
    },
    #[error("{path}: {source}")]
    Edge {
        path: String,
        source: crate::loads::DanglingEdge,
    },
    #[error(transparent)]
    Factor(#[from] crate::la::FactorError),
    #[error("{path}: {source}")]
    Contact {
        path: String,
        source: crate::contact::PairError,
    },
    #[error("contact.friction: {0}")]
    Friction(#[from] crate::friction::FrictionError),
}

/// Why a load step has no answer.
#[derive(Debug, Clone, thiserror::Error)]
pub enum StepError {
    #[error(transparent)]
    Contact(#[from] ContactError),
    #[error("slip control needs frictional contact")]
    SlipWithoutFriction,
    #[error(
        "the pilot is force-controlled but the body it drives is not held in that direction \
         (no support and no contact): control it by displacement instead"
    )]
    PilotUnheld,
    #[error(
        "the pilot's force pilot_{axis} = {force:e} pulls `{body}` away from the contact, and \
         nothing else holds that body (no support): no equilibrium exists; press the bodies \
         together or control the pilot by displacement"
    )]
    PulledApart {
        axis: &'static str,
        force: f64,
        body: String,
    },
    #[error(
        "the pilot moved {moved:e}, more than {limit} times the model's size {size:e}: a body is \
         not held (check the supports and that the loads press the bodies together)"
    )]
    RanAway { moved: f64, limit: f64, size: f64 },
    #[error(
        "no node is in contact and nothing else holds `{body}` along {axis} (no support, \
         pilot_{axis} force-controlled): the body is free; press the bodies together or control \
         the pilot by displacement"
    )]
    Free { body: String, axis: &'static str },
    #[error("the solution is not finite")]
    NotFinite,
    #[error(
        "stage {stage} took its budget of {budget} steps ({steps} nominal) and reached {:.6} of \
         its load: the increments stayed small (see the cutbacks in history.csv); give the \
         stage more steps or look at why its steps fail",
        reached
    )]
    StepBudget {
        stage: usize,
        budget: usize,
        steps: usize,
        reached: f64,
    },
    #[error(
        "the stage drives pilot_x = {q:e} and pilot_y = {p:e} together from no load: it asks for \
         Q/P = {:.6} at every load, above the largest friction coefficient {mu:.6} of the law, so \
         no load of it has an equilibrium; apply the normal load in a stage of its own first, or \
         lower the tangential force",
        (q / p).abs()
    )]
    BeyondFriction { q: f64, p: f64, mu: f64 },
}

/// A step that failed for good: its number, why, and the cutbacks tried first.
#[derive(Debug, Clone, thiserror::Error)]
#[error("step {step}: {cause}{}", cutbacks.map_or(String::new(), |n| format!(" (after {n} cutbacks)")))]
pub struct StepFailure {
    pub step: usize,
    pub cause: StepError,
    pub cutbacks: Option<usize>,
}

/// An error-level self-check of the last converged step (see [`crate::checks`]).
#[derive(Debug, Clone, thiserror::Error)]
#[error("the last step: check `{name}` failed ({value:.3e} against {limit:.3e}): {note}")]
pub struct CheckFailure {
    pub name: String,
    pub value: f64,
    pub limit: f64,
    pub note: String,
}

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Step(#[from] StepFailure),
    #[error(transparent)]
    Check(#[from] CheckFailure),
    #[error(
        "the contact zone kept growing (candidate gap {gap:e} after {doublings} doublings): check \
         the loads and the candidate gap"
    )]
    ZoneKeptGrowing { gap: f64, doublings: usize },
    #[error("cannot write output `{path}`: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error("--resume {path}: {why}")]
    Resume { path: String, why: String },
    #[error(
        "stage {stage} leaves `{key}` force-controlled, but with frictionless contact nothing \
         holds `{body}` along that axis (no support, and the contact carries no tangential \
         force): give `{key}` a displacement (e.g. \"{key}\": {{\"displacement\": 0.0}}) or \
         friction to the contact"
    )]
    FreeDirection {
        key: &'static str,
        stage: usize,
        body: String,
    },
    #[error(
        "the contact reached the edge of the candidate zone (candidate gap {gap:e}) at step {step}"
    )]
    ZoneClipped { gap: f64, step: usize },
    #[error("{}", event.as_ref().map_or_else(|| lost_message(*q_max, *q_fail, *cutbacks, *local_peak), |e| event_message(*q_max, *q_fail, e)))]
    EquilibriumLost {
        q_max: f64,
        q_fail: f64,
        cutbacks: usize,
        /// f_d P when Q_max is below it (a local peak, not the loss of equilibrium).
        local_peak: Option<f64>,
        /// How the jump integrated in time ended (`on_lost_equilibrium`), if it was.
        event: Option<String>,
    },
}

/// Why a sweep (or the merge of its parts) stopped; nothing is written for input errors.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{path}: cannot read: {source}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Parse {
        path: String,
        source: serde_json::Error,
    },
    #[error("{path}: {}{why}", if key.is_empty() { String::new() } else { format!("`{key}` ") })]
    Input {
        path: String,
        key: String,
        why: String,
    },
    #[error("--shard {spec}: {why}")]
    Shard { spec: String, why: String },
    #[error(
        "{path} belongs to another sweep (sweep id {found}, this one {expected}: the case, its \
         mesh, the sweep file, the program's build or STICKSLIP_CONTACT_SHORTCUTS changed); use another \
         --out, or --fresh to discard it"
    )]
    ForeignPart {
        path: String,
        found: String,
        expected: String,
    },
    #[error("{path}: not a sweep part ({why})")]
    BadPart { path: String, why: String },
    #[error(
        "the parts are of different sweeps: {first} has sweep id {a}, {second} has {b}; merge \
         parts of one case and sweep file only"
    )]
    Mismatch {
        first: String,
        second: String,
        a: String,
        b: String,
    },
    #[error("no sweep parts (part_K_of_N.jsonl) in {dirs}")]
    NoParts { dirs: String },
    #[error(
        "{} of {total} rows are missing (rows {}{}): run the shards that hold them (row r is \
         in shard r mod N) and merge again; nothing was written",
        missing.len(),
        missing.iter().take(10).map(|r| r.to_string()).collect::<Vec<_>>().join(", "),
        if missing.len() > 10 { ", …" } else { "" }
    )]
    Missing { missing: Vec<usize>, total: usize },
    #[error("cannot write output `{path}`: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
}

impl SweepError {
    /// Process exit status, as for a run: 2 bad input, 3 a failure to compute (or rows still
    /// missing), 4 output errors.
    pub fn exit_code(&self) -> i32 {
        match self {
            SweepError::Model(e) => model_exit_code(e),
            SweepError::Missing { .. } => 3,
            SweepError::Write { .. } => 4,
            _ => 2,
        }
    }
}

/// Exit status of a model that could not be built: 2 for bad input, 3 for a factorisation.
fn model_exit_code(e: &ModelError) -> i32 {
    match e {
        ModelError::MeshRead(_)
        | ModelError::MeshCheck(_)
        | ModelError::Dof { .. }
        | ModelError::Edge { .. }
        | ModelError::Contact { .. }
        | ModelError::Friction(_) => 2,
        ModelError::Factor(_) => 3,
    }
}

impl RunError {
    /// Process exit status: 2 for bad input, 3 for a solver failure, 4 for output errors, 5 when
    /// a force-controlled tangential load passes the largest load the contact can carry.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_) | RunError::Resume { .. } | RunError::FreeDirection { .. } => 2,
            RunError::Model(e) => model_exit_code(e),
            // A load path that no equilibrium carries at any load: known before its first step.
            RunError::Step(f) if matches!(f.cause, StepError::BeyondFriction { .. }) => 2,
            RunError::Step(_)
            | RunError::Check(_)
            | RunError::ZoneKeptGrowing { .. }
            | RunError::ZoneClipped { .. } => 3,
            RunError::Write { .. } => 4,
            RunError::EquilibriumLost { .. } => 5,
        }
    }
}

/// The message of [`RunError::EquilibriumLost`] after the jump was integrated in time.
fn event_message(q_max: f64, q_fail: f64, event: &str) -> String {
    format!(
        "equilibrium lost at Q_max = {q_max:.6} (none at {q_fail:.6}): the jump under that load \
         was integrated in time and {event}; the output holds the event"
    )
}

/// The message of [`RunError::EquilibriumLost`]: gross sliding, or a local peak of the load path
/// when Q_max is below f_d P (the least the contact carries once every point has weakened).
fn lost_message(q_max: f64, q_fail: f64, cutbacks: usize, local_peak: Option<f64>) -> String {
    let bracket = format!(
        "Q_max = {q_max:.6} (bracketed to [{q_max:.6}, {q_fail:.6}] in {cutbacks} failed attempts); the \
         output holds the state just before it"
    );
    match local_peak {
        None => {
            format!("equilibrium lost (gross sliding): the tangential load cannot exceed {bracket}")
        }
        Some(fdp) => format!(
            "equilibrium lost at a local peak, not gross sliding: force control cannot pass \
             {bracket}. Q_max is below f_d P = {fdp:.6}, which the contact carries even when \
             every point has weakened: part of the contact lets go in a jump that quasi-static \
             force control cannot follow (typically a mesh that does not resolve s0); slip \
             control traces the path past it"
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_local_peak_below_fd_p_is_not_called_gross_sliding() {
        let local = lost_message(0.5438, 0.5439, 7, Some(1.0));
        assert!(local.contains("local peak, not gross sliding"), "{local}");
        assert!(local.contains("f_d P = 1.000000"), "{local}");
        assert!(local.contains("in 7 failed attempts"), "{local}");
        let gross = lost_message(1.2, 1.21, 20, None);
        assert!(
            gross.starts_with("equilibrium lost (gross sliding)"),
            "{gross}"
        );
    }
}
