//! Shape functions of the two element shapes the project uses.
//!
//! * [`tri6`]: the 6-node quadratic triangle of the bodies.
//! * [`lin3`]: the 3-node quadratic line of the boundaries (tractions, contact faces).
//!
//! Both follow gmsh's node numbering, so connectivity read from a `.msh` file is used as is.

pub mod lin3;
pub mod tri6;
