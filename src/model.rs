//! A model ready to solve: the checked mesh, the DOF numbering, the assembled and factorised
//! stiffness, the condensed system on the retained DOFs and the load vectors.

use crate::assembly::{self, UpperCsc};
use crate::case::{Case, TractionKind};
use crate::condense::Condensed;
use crate::dofs::{DofMap, SupportSpec};
use crate::elasticity::{self, Material};
use crate::linsolve::PartialSymbolic;
use crate::loads::{EdgeOrientation, Traction};
use crate::mesh::{GroupDim, Mesh, check};
use std::time::Instant;

/// Anything that stops a model from being built or solved.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error(transparent)]
    MeshRead(#[from] crate::mesh::gmsh::MeshReadError),
    #[error(transparent)]
    MeshCheck(#[from] crate::mesh::check::MeshCheckError),
    #[error("{path}: {source}")]
    Dof {
        path: String,
        source: crate::dofs::DofError,
    },
    #[error("{path}: {source}")]
    Edge {
        path: String,
        source: crate::loads::DanglingEdge,
    },
    #[error(transparent)]
    Factor(#[from] crate::linsolve::FactorError),
    #[error("{0}")]
    Unsupported(String),
}

/// Wall time of each phase, seconds.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Timings {
    pub read: f64,
    pub assemble: f64,
    /// Symbolic analysis (fill-reducing ordering, elimination tree), done once per pattern.
    pub analyse: f64,
    /// Numeric Cholesky factorisation.
    pub factorise: f64,
    pub condense: f64,
    pub solve: f64,
    pub write: f64,
}

/// The assembled model.
pub struct Model {
    pub mesh: Mesh,
    /// Active triangles with their materials.
    pub elems: Vec<(usize, Material)>,
    /// Body index (into the case's `bodies`) of each active triangle.
    pub elem_body: Vec<usize>,
    pub dofs: DofMap,
    pub k: UpperCsc,
    /// Symbolic analysis of the stiffness (ordering with the retained DOFs last).
    pub symbolic: PartialSymbolic,
    /// Factorised stiffness and condensed system on the retained DOFs.
    pub condensed: Condensed,
    /// Nodal forces of the tractions at scale 1 (free DOFs).
    pub f_traction: Vec<f64>,
    /// Forces due to prescribed displacements (free DOFs).
    pub f_prescribed: Vec<f64>,
    /// Active nodes (used by some active triangle).
    pub active: Vec<bool>,
    pub timings: Timings,
}

impl Model {
    /// Reads the mesh of a case and builds the model. `case_path` resolves the mesh path.
    pub fn build(case: &Case, case_path: &std::path::Path) -> Result<Model, ModelError> {
        let t0 = Instant::now();
        let mesh = crate::mesh::gmsh::read(&case.mesh_path(case_path))?;
        let mut timings = Timings {
            read: t0.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Self::from_mesh(case, mesh, &mut timings)
    }

    /// Builds the model on an already read mesh.
    pub fn from_mesh(case: &Case, mesh: Mesh, timings: &mut Timings) -> Result<Model, ModelError> {
        let path = mesh.source.display().to_string();
        let bodies: Vec<&str> = case.bodies.iter().map(|b| b.group.as_str()).collect();
        let mut curves: Vec<&str> = case.supports.iter().map(|s| s.group.as_str()).collect();
        curves.extend(case.tractions.iter().map(|t| t.group.as_str()));
        if let Some(p) = &case.pilot {
            curves.push(&p.group);
        }
        check::check(&mesh, &bodies, &curves)?;

        let mut elems = Vec::new();
        let mut elem_body = Vec::new();
        for (bi, b) in case.bodies.iter().enumerate() {
            let mat = Material { e: b.e, nu: b.nu };
            for &e in &mesh.group(&b.group).expect("checked").elements {
                elems.push((e, mat));
                elem_body.push(bi);
            }
        }
        let mut active = vec![false; mesh.nodes.len()];
        for (e, _) in &elems {
            for &n in &mesh.triangles[*e].nodes {
                active[n] = true;
            }
        }
        let tris: Vec<usize> = elems.iter().map(|(e, _)| *e).collect();
        let orient = EdgeOrientation::new(&mesh, &tris);
        // Every boundary group must lie on the active bodies.
        for name in &curves {
            let g = mesh.group(name).expect("checked");
            for &l in &g.elements {
                orient
                    .oriented_coords(&mesh, l, name)
                    .map_err(|source| ModelError::Edge {
                        path: path.clone(),
                        source,
                    })?;
            }
        }

        let support_nodes: Vec<Vec<usize>> = case
            .supports
            .iter()
            .map(|s| mesh.group_nodes(mesh.group(&s.group).expect("checked")))
            .collect();
        let supports: Vec<SupportSpec> = case
            .supports
            .iter()
            .zip(&support_nodes)
            .map(|(s, nodes)| SupportSpec {
                group: &s.group,
                nodes,
                value: [s.ux, s.uy],
            })
            .collect();
        let pilot_nodes = case
            .pilot
            .as_ref()
            .map(|p| mesh.group_nodes(mesh.group(&p.group).expect("checked")));
        let dofs = DofMap::build(
            &mesh.node_tags,
            &active,
            &supports,
            case.pilot
                .as_ref()
                .map(|p| p.group.as_str())
                .zip(pilot_nodes.as_deref()),
            &[],
        )
        .map_err(|source| ModelError::Dof {
            path: path.clone(),
            source,
        })?;

        let t = Instant::now();
        let mut k = UpperCsc::pattern(&mesh, &elems, &dofs);
        let f_prescribed = assembly::assemble_stiffness(&mesh, &elems, &dofs, &mut k);
        let mut f_traction = vec![0.0; dofs.n_free()];
        for spec in &case.tractions {
            let load = match spec.kind {
                TractionKind::Uniform => Traction::Uniform {
                    tx: spec.tx.unwrap_or(0.0),
                    ty: spec.ty.unwrap_or(0.0),
                },
                TractionKind::Pressure => Traction::Pressure {
                    p: spec.p.expect("validated"),
                },
                TractionKind::Hertz => Traction::Hertz {
                    p0: spec.p0.expect("validated"),
                    a: spec.a.expect("validated"),
                    x0: spec.x0.unwrap_or(0.0),
                },
            };
            let g = mesh.group(&spec.group).expect("checked");
            for &l in &g.elements {
                let nodes = orient.oriented_nodes(&mesh, l).expect("checked above");
                let xe = nodes.map(|n| mesh.nodes[n]);
                let fe = crate::loads::edge_forces(&xe, &load);
                for a in 0..3 {
                    for c in 0..2 {
                        if let crate::dofs::Dof::Free(i) = dofs.node[nodes[a]][c] {
                            f_traction[i] += fe[a][c];
                        }
                    }
                }
            }
        }
        timings.assemble = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let symbolic =
            PartialSymbolic::analyse(dofs.n_free(), dofs.n_retained, &k.col_ptr, &k.row_idx)?;
        timings.analyse = t.elapsed().as_secs_f64();
        let t = Instant::now();
        // The pilot's DOFs are grounded: the body it drives may be held by nothing else.
        let grounded: Vec<usize> = dofs
            .pilot
            .map(|p| p.iter().map(|d| d - dofs.n_interior).collect())
            .unwrap_or_default();
        let condensed = Condensed::build(&k, dofs.n_interior, &grounded, &symbolic)?;
        timings.factorise = t.elapsed().as_secs_f64();
        let _ = GroupDim::Curve;
        Ok(Model {
            mesh,
            elems,
            elem_body,
            dofs,
            k,
            symbolic,
            condensed,
            f_traction,
            f_prescribed,
            active,
            timings: timings.clone(),
        })
    }

    /// Nodal stresses (σxx, σyy, σxy, σzz), averaged over the elements around each node.
    pub fn nodal_stresses(&self, u: &[f64]) -> Vec<[f64; 4]> {
        use rayon::prelude::*;
        let per_elem: Vec<[[f64; 3]; 6]> = self
            .elems
            .par_iter()
            .map(|(e, mat)| {
                let nodes = &self.mesh.triangles[*e].nodes;
                let ue: [f64; 12] =
                    std::array::from_fn(|i| self.dofs.displacement(nodes[i / 2], u)[i % 2]);
                elasticity::nodal_stress(&self.mesh.tri_coords(*e), &ue, mat)
            })
            .collect();
        let mut acc = vec![[0.0; 4]; self.mesh.nodes.len()];
        let mut count = vec![0u32; self.mesh.nodes.len()];
        for ((e, mat), s) in self.elems.iter().zip(&per_elem) {
            for (a, &n) in self.mesh.triangles[*e].nodes.iter().enumerate() {
                let sz = mat.sigma_zz(s[a]);
                for i in 0..3 {
                    acc[n][i] += s[a][i];
                }
                acc[n][3] += sz;
                count[n] += 1;
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
