//! stickslip — plane-strain finite elements for frictional contact of two half-cylinders
//! with a slip-weakening friction coefficient (Papangelo, Ciavarella & Barber).
//!
//! Pipeline: [`mesh`] (gmsh reader and checks) → [`dofs`] → [`assembly`] of [`elasticity`]
//! on [`shapes::tri6`] → [`la`] (orderings, sparse and dense factorisations) → [`condense`] onto retained DOFs →
//! [`run`] (load stages) → [`output`] (VTK, CSV, JSON). Closed forms live in [`analytic`].

pub mod analytic;
pub mod assembly;
pub mod cache;
pub mod case;
pub mod checks;
pub mod condense;
pub mod contact;
pub mod dofs;
pub mod driver;
pub mod dynamics;
pub mod elasticity;
pub mod energy;
pub mod error;
pub mod friction;
pub mod la;
pub mod loads;
pub mod mass;
pub mod mesh;
pub mod model;
pub mod output;
pub mod probe;
pub mod quadrature;
pub mod record;
pub mod report;
pub mod restart;
pub mod run;
pub mod shapes;
pub mod sweep;
pub mod trace;
