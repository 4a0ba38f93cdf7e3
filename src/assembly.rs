//! Assembly of the global stiffness: the sparsity pattern once (symbolic), then the values
//! (numeric), element kernels evaluated in parallel with rayon.
//!
//! The matrix is stored as the **upper triangle** in compressed sparse columns over the free
//! DOFs, interior columns first. Its leading `n_interior` columns are therefore themselves a
//! valid upper-triangular CSC matrix: the interior block `K_II` that is factorised.

use crate::dofs::{Dof, DofMap};
use crate::elasticity::{self, Material};
use crate::mesh::Mesh;
use rayon::prelude::*;

/// An upper-triangular CSC matrix (rows sorted within each column).
#[derive(Clone, Debug, Default)]
pub struct UpperCsc {
    pub n: usize,
    pub col_ptr: Vec<usize>,
    pub row_idx: Vec<usize>,
    pub values: Vec<f64>,
}

impl UpperCsc {
    /// The sparsity pattern of the free DOFs of the given elements.
    pub fn pattern(mesh: &Mesh, elems: &[(usize, Material)], dofs: &DofMap) -> UpperCsc {
        let n = dofs.n_free();
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (e, _) in elems {
            let d = dofs.element_dofs(&mesh.triangles[*e].nodes);
            for a in d {
                let Dof::Free(c) = a else { continue };
                for b in d {
                    if let Dof::Free(r) = b
                        && r <= c
                    {
                        cols[c].push(r);
                    }
                }
            }
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for c in cols.iter_mut() {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        UpperCsc {
            n,
            col_ptr,
            row_idx,
            values: vec![0.0; nnz],
        }
    }

    /// Position of entry (r, c), r ≤ c, in `values`.
    #[inline]
    pub fn position(&self, r: usize, c: usize) -> usize {
        let rows = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
        self.col_ptr[c] + rows.binary_search(&r).expect("entry in pattern")
    }
}

/// Fills `k.values` with the stiffness of the given elements and returns the forces on the free
/// DOFs due to the prescribed displacements, `−K_fp u_p`.
pub fn assemble_stiffness(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    dofs: &DofMap,
    k: &mut UpperCsc,
) -> Vec<f64> {
    let kes: Vec<[f64; 144]> = elems
        .par_iter()
        .map(|(e, mat)| elasticity::element_stiffness(&mesh.tri_coords(*e), mat))
        .collect();
    k.values.iter_mut().for_each(|v| *v = 0.0);
    let mut f = vec![0.0; dofs.n_free()];
    for ((e, _), ke) in elems.iter().zip(&kes) {
        let d = dofs.element_dofs(&mesh.triangles[*e].nodes);
        for i in 0..12 {
            let Dof::Free(r) = d[i] else { continue };
            for j in 0..12 {
                match d[j] {
                    Dof::Free(c) if r <= c => {
                        let p = k.position(r, c);
                        k.values[p] += ke[i * 12 + j];
                    }
                    Dof::Fixed(q) => f[r] -= ke[i * 12 + j] * dofs.prescribed[q],
                    _ => {}
                }
            }
        }
    }
    f
}

/// Adds element forces `fe` (12 entries) to the free vector `f`.
pub fn add_element_vector(dofs: &DofMap, nodes: &[usize; 6], fe: &[f64; 12], f: &mut [f64]) {
    for (i, d) in dofs.element_dofs(nodes).iter().enumerate() {
        if let Dof::Free(r) = d {
            f[*r] += fe[i];
        }
    }
}
