//! The contact problem on the contact unknowns alone.
//!
//! The elastic bodies are condensed onto the retained DOFs `R` (contact nodes and pilot):
//! `Ŝ u_R = g + r_R` (see [`crate::condense`]). The contact and pilot forces enter as
//! `r_R = Yᵀ μ` with `Y = [Ĝ; T̂; E_Pᵀ]` and unknowns `μ = (F_n, F_t, z)`: nodal normal forces,
//! nodal tangential forces on the master side, and the pilot's force plus its grounding spring
//! force `z = r_P + k_g u_P`. Then
//! ```text
//!   Y u_R = w0 + W μ,   W = Y Ŝ⁻¹ Yᵀ = Y K̂⁻¹ Yᵀ,   w0 = Y K̂⁻¹ f,
//! ```
//! gives every nodal gap `ĝ = g0 + (Y u_R)_n`, relative tangential displacement
//! `v̂ = (Y u_R)_t` and the pilot displacement from `μ` alone. `W` (the Delassus operator) is
//! dense and small and is built once per model, from the trailing block of the factorised
//! saddle-point matrix `[K̂ Yᵀ; Y 0]` ([`crate::la::SaddleSymbolic`]); each Newton iteration is a dense solve on the
//! active unknowns.
//!
//! Complementarity at each slave node j (forces, gaps and slips are nodal quantities):
//! * normal: `F_n ≥ 0, ĝ ≥ 0, F_n ĝ = 0`, written `F_n − max(0, F_n − c ĝ) = 0`;
//! * friction (Coulomb with `μ_j = f(U_j)` of the accumulated slip `U_j`): stick
//!   (`Δv̂ = 0`) while `|F_t − c Δv̂| < μ_j (F_n − c ĝ)`, else slip with
//!   `F_t = μ_j F_n sign(F_t − c Δv̂)` (the force on the master opposes its slip).
//!
//! `c = E*` (the composite plane-strain modulus) makes the complementarity functions
//! homogeneous in force per length, so iterates do not depend on the units. In 2-D the
//! semi-smooth Newton method on these functions is the primal–dual active-set method: each
//! iteration fixes the sets (inactive / stick / slip) from the current iterate and solves the
//! linear equations they imply; it has converged when the sets no longer change and the
//! update is small. The penalty and augmented-Lagrangian methods solve the same equations with
//! `F_n = ε max(0, −ĝ)` (and an elastic tangential spring), the latter with an outer update of
//! the multiplier estimate until the penetration is below tolerance.

//!
//! The rooms: this module holds the types and the operator; [`enforce`] the active sets and
//! the linearised equations of each method (one source, assembled densely or handed to the
//! structured solve); [`newton`] the iteration of a load step; [`linalg`] the factorisations
//! kept across iterations (Cholesky/Woodbury, LU + GMRES).

mod block;
mod enforce;
mod factors;
mod newton;
mod seeds;
mod system;
#[cfg(test)]
mod tests;

pub use block::{BlockRecord, BlockStore};
pub use enforce::{Equation, NewtonRows, NewtonSystem, SlipLin, SpecialRow, WTerms};
pub use factors::{LuCache, SolveTimings};
pub use system::*;

/// The number of contact unknowns from which the structured solve takes its shortcuts, or
/// `None` where `STICKSLIP_CONTACT_SHORTCUTS=off` switched them off (reported in the summary
/// and part of a restart state's identity: the two paths differ in the last digits).
pub fn shortcuts_from() -> Option<usize> {
    seeds::shortcuts_allowed().then_some(seeds::SHORTCUTS_FROM)
}

/// What a run's identity (a restart state's, a sweep part's) adds for the contact-solve path:
/// nothing by default, a marker with the shortcuts off.
pub fn path_identity() -> Option<&'static [u8]> {
    shortcuts_from()
        .is_none()
        .then_some(b"STICKSLIP_CONTACT_SHORTCUTS=off".as_slice())
}
