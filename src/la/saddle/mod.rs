//! The `L D Lᵀ` factorisation of the contact saddle-point matrix `[K̂ Yᵀ; Y 0]`: its
//! symbolic analysis ([`SaddleSymbolic`]), its numeric factor with the solves and the
//! Delassus operator ([`SaddleFactor`]), and the supernodal layout both read ([`Supernodes`]).

mod factor;
mod layout;
mod symbolic;
#[cfg(test)]
mod tests;

pub use factor::SaddleFactor;
pub use layout::Supernodes;
pub use symbolic::{SaddleSymbolic, tree_scheduled};
