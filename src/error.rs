//! Why a run stopped, and the process exit status of each reason (the one place exit codes are
//! mapped).

use crate::model::ModelError;

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{0}")]
    Solve(String),
    #[error("cannot write output `{path}`: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
    #[error(
        "the contact reached the edge of the candidate zone (candidate gap {gap:e}) at step {step}"
    )]
    ZoneClipped { gap: f64, step: usize },
    #[error(
        "equilibrium lost (gross sliding): the tangential load cannot exceed Q_max = {q_max:.6} \
         (bracketed to [{q_max:.6}, {q_fail:.6}] by {cutbacks} bisections); the output holds the \
         state just before it"
    )]
    EquilibriumLost {
        q_max: f64,
        q_fail: f64,
        cutbacks: usize,
    },
}

impl RunError {
    /// Process exit status: 2 for bad input, 3 for a solver failure, 4 for output errors, 5 when
    /// a force-controlled tangential load passes the largest load the contact can carry.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_)
            | RunError::Model(
                ModelError::MeshRead(_)
                | ModelError::MeshCheck(_)
                | ModelError::Dof { .. }
                | ModelError::Edge { .. }
                | ModelError::Contact { .. }
                | ModelError::Unsupported(_),
            ) => 2,
            RunError::Model(ModelError::Factor(_))
            | RunError::Solve(_)
            | RunError::ZoneClipped { .. } => 3,
            RunError::Write { .. } => 4,
            RunError::EquilibriumLost { .. } => 5,
        }
    }
}
