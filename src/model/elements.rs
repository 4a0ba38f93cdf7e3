//! Reads of solution fields element by element: each element's twelve displacements (through
//! a table of where each is), fields interleaved for the loops that run across several at
//! once, and the nodal stresses averaged over the elements around each node.

use super::Model;
use crate::elasticity::{self, Material};

impl Model {
    /// The displacements of element `i` (of `self.elems`) from the free solution `u`: the same
    /// numbers as [`crate::dofs::DofMap::element_displacement`], read through a table of where each is
    /// (an index into `u`, or into the prescribed values past `u`'s length, or none) built at
    /// the first call: 48 bytes per element read in order, instead of each node's two DOFs
    /// (32 bytes) looked up in a table the size of the mesh, which was a tenth of the work of
    /// the output writer and the summary on L5.
    pub fn element_u(&self, i: usize, u: &[f64]) -> [f64; 12] {
        let table = self.element_dof_table();
        let n_free = self.dofs.n_free();
        table[i].map(|k| {
            let k = k as usize;
            if k < n_free {
                u[k]
            } else {
                self.dofs.prescribed.get(k - n_free).copied().unwrap_or(0.0)
            }
        })
    }

    /// The fields `us` (of the free DOFs) interleaved for the loops that run across several
    /// fields at once: `[d][j]` is field `j` at the DOF `d` of [`Model::element_dof_table`]
    /// (the free DOFs, then the prescribed values), one cache line per DOF for all of them;
    /// the lanes past `us` are zero.
    pub fn interleave<const R: usize>(&self, us: &[&[f64]]) -> Vec<[f64; R]> {
        let n_free = self.dofs.n_free();
        let mut uu: Vec<[f64; R]> = Vec::with_capacity(n_free + self.dofs.prescribed.len());
        for d in 0..n_free {
            uu.push(std::array::from_fn(|j| us.get(j).map_or(0.0, |u| u[d])));
        }
        uu.extend(self.dofs.prescribed.iter().map(|&p| [p; R]));
        uu
    }

    /// [`Model::element_u`] of interleaved fields ([`Model::interleave`]) for an element's
    /// row `dofs` of [`Model::element_dof_table`] (taken once by the caller's loop: asked for
    /// per element it cost the loop a sixth): `[k][j]` is DOF `k` of field `j`.
    #[inline(always)]
    pub fn element_u_lanes<const R: usize>(dofs: &[u32; 12], uu: &[[f64; R]]) -> [[f64; R]; 12] {
        std::array::from_fn(|k| uu.get(dofs[k] as usize).copied().unwrap_or([0.0; R]))
    }

    /// Where each DOF of each element is (of `self.elems`): its index among the free DOFs
    /// (below [`crate::dofs::DofMap::n_free`]), `n_free` plus its index among the prescribed ones, or
    /// `u32::MAX` for none.
    pub fn element_dof_table(&self) -> &[[u32; 12]] {
        // Built on the calling thread: a rayon task waiting for this initialisation (the
        // writer's and the driver's threads both compute stresses at the end of a run) must
        // not be the one that would have to run part of it.
        self.elem_dofs.get_or_init(|| {
            use crate::dofs::Dof;
            let n_free = self.dofs.n_free();
            assert!(
                n_free + self.dofs.prescribed.len() < u32::MAX as usize,
                "DOF indices fit 32 bits"
            );
            self.elems
                .iter()
                .map(|(e, _)| {
                    let nodes = &self.mesh.triangles[*e].nodes;
                    std::array::from_fn(|k| match self.dofs.node[nodes[k / 2]][k % 2] {
                        Dof::Free(i) => i as u32,
                        Dof::Fixed(q) => (n_free + q) as u32,
                        Dof::Unused => u32::MAX,
                    })
                })
                .collect()
        })
    }

    /// [`Model::nodal_stresses`] of several fields, up to four at a time in one pass over the
    /// elements on the calling thread (each element's gradients mapped once for them): the
    /// same bits as one by one.
    pub fn nodal_stresses_many(&self, us: &[&[f64]]) -> Vec<Vec<[f64; 4]>> {
        let mut out = Vec::with_capacity(us.len());
        for group in us.chunks(4) {
            match group.len() {
                1 => out.push(self.nodal_stresses(group[0], false)),
                2 => out.extend(self.nodal_stresses_lanes::<2>(group)),
                _ => out.extend(self.nodal_stresses_lanes::<4>(group)),
            }
        }
        out
    }

    /// [`Model::nodal_stresses_many`] of at most `R` fields (the lanes past them zero).
    fn nodal_stresses_lanes<const R: usize>(&self, us: &[&[f64]]) -> Vec<Vec<[f64; 4]>> {
        self.nodal_stresses_lanes_body::<R>(us)
    }

    #[inline(always)]
    fn nodal_stresses_lanes_body<const R: usize>(&self, us: &[&[f64]]) -> Vec<Vec<[f64; 4]>> {
        let d3 = elasticity::stress_point_gradients();
        let uu = self.interleave::<R>(us);
        let table = self.element_dof_table();
        let mut acc = vec![[[0.0; R]; 4]; self.mesh.nodes.len()];
        let mut count = vec![0u32; self.mesh.nodes.len()];
        for (i, (e, mat)) in self.elems.iter().enumerate() {
            let ue = Model::element_u_lanes(&table[i], &uu);
            let s = elasticity::nodal_stress_lanes(&self.mesh.tri_coords(*e), &ue, mat, &d3);
            for (a, &n) in self.mesh.triangles[*e].nodes.iter().enumerate() {
                for c in 0..4 {
                    for j in 0..R {
                        acc[n][c][j] += s[a][c][j];
                    }
                }
                count[n] += 1;
            }
        }
        (0..us.len())
            .map(|j| {
                acc.iter()
                    .zip(&count)
                    .map(|(a, &c)| {
                        std::array::from_fn(|i| if c > 0 { a[i][j] / c as f64 } else { a[i][j] })
                    })
                    .collect()
            })
            .collect()
    }

    /// Nodal stresses (σxx, σyy, σxy, σzz), averaged over the elements around each node; the
    /// elements on rayon's threads with `parallel`, else on the calling thread (the same bits).
    pub fn nodal_stresses(&self, u: &[f64], parallel: bool) -> Vec<[f64; 4]> {
        use rayon::prelude::*;
        let d3 = elasticity::stress_point_gradients();
        let one = |(i, (e, mat)): (usize, &(usize, Material))| {
            let ue: [f64; 12] = self.element_u(i, u);
            elasticity::nodal_stress_at(&self.mesh.tri_coords(*e), &ue, mat, &d3)
        };
        let mut acc = vec![[0.0; 4]; self.mesh.nodes.len()];
        let mut count = vec![0u32; self.mesh.nodes.len()];
        // Each element's stresses added to its nodes, in the order of the elements.
        let mut add = |e: usize, s: &[[f64; 4]; 6]| {
            for (a, &n) in self.mesh.triangles[e].nodes.iter().enumerate() {
                for i in 0..4 {
                    acc[n][i] += s[a][i];
                }
                count[n] += 1;
            }
        };
        if parallel {
            let per_elem: Vec<[[f64; 4]; 6]> = self.elems.par_iter().enumerate().map(one).collect();
            for ((e, _), s) in self.elems.iter().zip(&per_elem) {
                add(*e, s);
            }
        } else {
            // No array of the elements' stresses: 8.6 MB of fresh memory per step at L5.
            for (i, em) in self.elems.iter().enumerate() {
                add(em.0, &one((i, em)));
            }
        }
        for (a, c) in acc.iter_mut().zip(&count) {
            if *c > 0 {
                for v in a.iter_mut() {
                    *v /= *c as f64;
                }
            }
        }
        acc
    }
}
