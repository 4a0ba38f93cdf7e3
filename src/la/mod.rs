//! The sparse and dense linear algebra of the program, one layer that depends on nothing of
//! the project above it (only on [`crate::trace`] for its timeline marks):
//!
//! * [`ordering`]: fill-reducing orderings (faer's AMD, and nested dissection);
//! * [`saddle`]: the `L D Lᵀ` factorisation of the contact saddle-point matrix `[K̂ Yᵀ; Y 0]`
//!   and its Delassus operator `W = Y K̂⁻¹ Yᵀ`, and the partial Cholesky without contact;
//! * [`supernodal`]: the numeric factorisation of a supernodal structure on the elimination
//!   tree's schedule;
//! * [`dense`]: dense kernels and solves of the contact Newton systems;
//! * [`par`]: arrays filled on rayon's threads, and the factorisations' parallelism;
//! * [`values`]: where a factor's values live (a vector, or memory a caller provides, such
//!   as a mapped model-cache file).
//!
//! The contact solver, the model and the model cache use this layer; it uses none of them.

mod base;
pub mod dense;
pub mod ordering;
pub mod par;
mod partial;
pub mod saddle;
pub mod supernodal;
pub mod values;

pub use base::FactorError;
pub use partial::{PartialCholesky, PartialSymbolic};
pub use saddle::{SaddleFactor, SaddleSymbolic, Supernodes};
pub use values::{DenseColumns, FactorValues, SharedValues, StoredValues, ValuesDestination};
