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
    /// The sparsity pattern of the free DOFs of the given elements: the entries of each
    /// column counted, written into one array and then sorted and deduplicated column by
    /// column in parallel (no per-column allocations).
    pub fn pattern(mesh: &Mesh, elems: &[(usize, Material)], dofs: &DofMap) -> UpperCsc {
        let n = dofs.n_free();
        // The free DOFs of each element.
        let free = |e: usize| -> ([usize; 12], usize) {
            let mut f = [0usize; 12];
            let mut k = 0;
            for d in dofs.element_dofs(&mesh.triangles[e].nodes) {
                if let Dof::Free(c) = d {
                    f[k] = c;
                    k += 1;
                }
            }
            (f, k)
        };
        // Entries per column, repeats included.
        let mut start = vec![0usize; n + 1];
        for (e, _) in elems {
            let (f, k) = free(*e);
            for &c in &f[..k] {
                start[c + 1] += f[..k].iter().filter(|&&r| r <= c).count();
            }
        }
        for c in 0..n {
            start[c + 1] += start[c];
        }
        let mut rows = vec![0usize; start[n]];
        let mut next = start[..n].to_vec();
        for (e, _) in elems {
            let (f, k) = free(*e);
            for &c in &f[..k] {
                for &r in &f[..k] {
                    if r <= c {
                        rows[next[c]] = r;
                        next[c] += 1;
                    }
                }
            }
        }
        // Each column sorted and deduplicated in place: its distinct rows first.
        let mut cols: Vec<&mut [usize]> = Vec::with_capacity(n);
        let mut rest = rows.as_mut_slice();
        for c in 0..n {
            let (head, tail) = rest.split_at_mut(start[c + 1] - start[c]);
            cols.push(head);
            rest = tail;
        }
        let distinct: Vec<usize> = cols
            .par_iter_mut()
            .with_min_len(1024)
            .map(|col| {
                col.sort_unstable();
                let mut m = 0;
                for i in 0..col.len() {
                    if m == 0 || col[i] != col[m - 1] {
                        col[m] = col[i];
                        m += 1;
                    }
                }
                m
            })
            .collect();
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::with_capacity(distinct.iter().sum());
        for c in 0..n {
            row_idx.extend_from_slice(&rows[start[c]..start[c] + distinct[c]]);
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
        position_in(&self.col_ptr, &self.row_idx, r, c)
    }
}

/// Position of entry (r, c), r ≤ c, in the values of the upper CSC pattern `col_ptr`, `row_idx`.
#[inline]
fn position_in(col_ptr: &[usize], row_idx: &[usize], r: usize, c: usize) -> usize {
    let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
    col_ptr[c] + rows.binary_search(&r).expect("entry in pattern")
}

/// Fills `k.values` with the stiffness of the given elements and returns the forces on the free
/// DOFs due to the prescribed displacements, `−K_fp u_p`.
pub fn assemble_stiffness(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    dofs: &DofMap,
    k: &mut UpperCsc,
) -> Vec<f64> {
    let mut values = std::mem::take(&mut k.values);
    let f = assemble_values(mesh, elems, dofs, (&k.col_ptr, &k.row_idx), &mut values);
    k.values = values;
    f
}

/// [`assemble_stiffness`] into the `values` of the pattern `(col_ptr, row_idx)` (of
/// [`UpperCsc::pattern`]), which another thread may read meanwhile (the analysis).
pub fn assemble_values(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    dofs: &DofMap,
    pattern: (&[usize], &[usize]),
    values: &mut [f64],
) -> Vec<f64> {
    assemble_shifted(mesh, elems, None, dofs, pattern, values)
}

/// [`assemble_values`] of `K + M_s`, where element `i` adds its consistent mass
/// ([`crate::mass::element_mass`]) at density `shift[i]`: the effective stiffness
/// `K + c M` of an implicit time step with `shift[i] = c ρ_i` (the same pattern as `K`).
/// The forces of the prescribed values are those of `K + M_s`.
pub fn assemble_shifted(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    shift: Option<&[f64]>,
    dofs: &DofMap,
    (col_ptr, row_idx): (&[usize], &[usize]),
    values: &mut [f64],
) -> Vec<f64> {
    let kes: Vec<[f64; 144]> = elems
        .par_iter()
        .enumerate()
        .map(|(i, (e, mat))| {
            let xe = mesh.tri_coords(*e);
            let mut ke = elasticity::element_stiffness(&xe, mat);
            if let Some(s) = shift {
                let m = crate::mass::expand(&crate::mass::element_mass(&xe, s[i]));
                ke.iter_mut().zip(m).for_each(|(k, m)| *k += m);
            }
            ke
        })
        .collect();
    values.iter_mut().for_each(|v| *v = 0.0);
    let n = dofs.n_free();
    let mut f = vec![0.0; n];
    // The scatter in parallel: each thread owns a range of columns of K (about equal numbers of
    // nonzeros) and the same range of rows of f, and goes through all elements in order adding
    // only to what it owns, so every entry receives its terms in element order, as a serial
    // scatter adds them, whatever the number of threads.
    let nnz = col_ptr[n];
    let parts = rayon::current_num_threads().clamp(1, n.max(1));
    // Non-decreasing, from 0 to n (every column and row in one range).
    let bounds: Vec<usize> = (0..=parts)
        .map(|t| match t {
            t if t == parts => n,
            t => col_ptr[..=n]
                .partition_point(|&p| p < t * nnz / parts)
                .min(n),
        })
        .collect();
    let mut owned: Vec<&mut [f64]> = Vec::with_capacity(parts);
    let mut forces: Vec<&mut [f64]> = Vec::with_capacity(parts);
    let (mut v_rest, mut f_rest) = (&mut values[..], &mut f[..]);
    for t in 0..parts {
        let (lo, hi) = (bounds[t], bounds[t + 1]);
        let (v, vr) = v_rest.split_at_mut(col_ptr[hi] - col_ptr[lo]);
        let (fp, fr) = f_rest.split_at_mut(hi - lo);
        owned.push(v);
        forces.push(fp);
        (v_rest, f_rest) = (vr, fr);
    }
    owned
        .into_par_iter()
        .zip(forces)
        .enumerate()
        .for_each(|(t, (vals, fs))| {
            let (lo, hi) = (bounds[t], bounds[t + 1]);
            let base = col_ptr[lo];
            for ((e, _), ke) in elems.iter().zip(&kes) {
                let d = dofs.element_dofs(&mesh.triangles[*e].nodes);
                for i in 0..12 {
                    let Dof::Free(r) = d[i] else { continue };
                    for j in 0..12 {
                        match d[j] {
                            Dof::Free(c) if r <= c && (lo..hi).contains(&c) => {
                                vals[position_in(col_ptr, row_idx, r, c) - base] += ke[i * 12 + j];
                            }
                            Dof::Fixed(q) if (lo..hi).contains(&r) => {
                                fs[r - lo] -= ke[i * 12 + j] * dofs.prescribed[q];
                            }
                            _ => {}
                        }
                    }
                }
            }
        });
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
