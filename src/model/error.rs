//! Why a model cannot be built or solved.

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
    Factor(#[from] crate::linsolve::FactorError),
    #[error("{path}: {source}")]
    Contact {
        path: String,
        source: crate::contact::PairError,
    },
    #[error("contact.friction: {0}")]
    Friction(#[from] crate::friction::FrictionError),
}
