//! The consistent mass of a model's elements ([`crate::mass::element_mass`]) at the densities
//! of their bodies: products `M x` on the free DOFs and kinetic energies.

use crate::model::Model;
use rayon::prelude::*;

/// The elements' scalar mass blocks, in the order of `model.elems`.
pub struct Masses {
    blocks: Vec<[f64; 36]>,
}

impl Masses {
    /// The masses of `model`'s elements with `density[b]` for body `b` of the case.
    pub fn new(model: &Model, density: &[f64]) -> Masses {
        let blocks = model
            .elems
            .par_iter()
            .zip(&model.elem_body)
            .map(|((e, _), &b)| crate::mass::element_mass(&model.mesh.tri_coords(*e), density[b]))
            .collect();
        Masses { blocks }
    }

    /// The total mass (per unit thickness).
    pub fn total(&self) -> f64 {
        self.blocks.iter().map(|m| m.iter().sum::<f64>()).sum()
    }

    /// `Σ_e M_e x_e` scattered onto the free DOFs, with `x_e` read by `x(i)` for element `i`
    /// (its twelve DOFs in the order of [`Model::element_dof_table`]), in element order on the
    /// calling thread's pool and summed in element order (the same bits on any thread count).
    pub fn apply_with(
        &self,
        model: &Model,
        x: impl Fn(usize) -> [f64; 12] + Sync,
        out: &mut [f64],
    ) {
        let table = model.element_dof_table();
        let n_free = model.dofs.n_free();
        let ye: Vec<[f64; 12]> = self
            .blocks
            .par_iter()
            .enumerate()
            .map(|(i, m)| crate::mass::apply(m, &x(i)))
            .collect();
        for (row, y) in table.iter().zip(&ye) {
            for k in 0..12 {
                let d = row[k] as usize;
                if d < n_free {
                    out[d] += y[k];
                }
            }
        }
    }

    /// The kinetic energy `½ vᵀ M v` of the free velocities `v` (prescribed DOFs at rest).
    pub fn kinetic(&self, model: &Model, v: &[f64]) -> f64 {
        let table = model.element_dof_table();
        let n_free = model.dofs.n_free();
        0.5 * self
            .blocks
            .par_iter()
            .zip(table)
            .map(|(m, row)| {
                let ve: [f64; 12] = row.map(|d| {
                    let d = d as usize;
                    if d < n_free { v[d] } else { 0.0 }
                });
                let mv = crate::mass::apply(m, &ve);
                (0..12).map(|k| ve[k] * mv[k]).sum::<f64>()
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum::<f64>()
    }
}
