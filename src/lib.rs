//! stickslip — plane-strain finite elements for frictional contact of two half-cylinders
//! with a slip-weakening friction coefficient (Papangelo, Ciavarella & Barber).

pub mod analytic;
pub mod friction;
