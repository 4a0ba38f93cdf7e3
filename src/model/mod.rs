//! A model ready to solve: the checked mesh, the DOF numbering, the assembled and factorised
//! stiffness, the condensed system on the retained DOFs and the load vectors.

mod cached;
pub mod step;
pub use step::StepLoad;

use crate::assembly::{self, UpperCsc};
use crate::case::{Case, TractionKind};
use crate::condense::Condensed;
use crate::dofs::{DofMap, SupportSpec};
use crate::elasticity::{self, Material};
use crate::la::{PartialSymbolic, SaddleSymbolic};
use crate::loads::{EdgeOrientation, Traction};
use crate::mesh::{Mesh, check};
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
    Factor(#[from] crate::la::FactorError),
    #[error("{path}: {source}")]
    Contact {
        path: String,
        source: crate::contact::PairError,
    },
    #[error("contact.friction: {0}")]
    Friction(#[from] crate::friction::FrictionError),
}

/// Wall time of each phase, seconds.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Timings {
    pub read: f64,
    /// The contact pair: candidate zone, mortar operator and its coverage checks.
    pub pair: f64,
    pub assemble: f64,
    /// Symbolic analysis (fill-reducing ordering, elimination tree), done once per pattern.
    pub analyse: f64,
    /// Numeric Cholesky factorisation.
    pub factorise: f64,
    /// Part of `factorise`: the dense block of the contact constraint rows, the Delassus
    /// operator `W = Y K̂⁻¹ Yᵀ` (the updates of its columns, the elimination of the top
    /// separator's columns from it, and its `L D Lᵀ`); the rest of `factorise` is the sparse
    /// factor of `K̂`, with `Y`'s columns carried along. Zero where it is not timed apart.
    pub constraint_block: f64,
    /// Wall time from the start of the assembly to the end of the numeric factorisation
    /// (zero on a model-cache hit): the values are assembled alongside the analysis, so this
    /// is less than `assemble + analyse + factorise`.
    pub build_span: f64,
    pub condense: f64,
    pub solve: f64,
    /// The output writer's busy time: it writes on a thread of its own, while the next steps
    /// are solved.
    pub write: f64,
    /// Time the run spent waiting for the output writer (a step still queued, and the last
    /// steps at the end): the part of `write` that adds to the wall time.
    pub write_wait: f64,
    /// The model cache: the key (a hash of the mesh file and the case's parts it depends on),
    /// and on a hit reading and checking the entry (apart from the analysis that overlaps it).
    pub cache: f64,
}

/// The modelled floating-point operations of a contact model's numeric factorisation, from its
/// symbolic analysis ([`crate::la::SaddleSymbolic::flops`]): a count that does not depend
/// on the machine, beside the measured `factorise` time.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct FactorFlops {
    /// The elimination of `K̂` itself: each supernode's own block, its solve and its updates
    /// of the rows of `K̂`.
    pub k: f64,
    /// What the constraint rows add to the elimination of `K̂`: the rows of `Y` that fill in
    /// below every separator they reach (`L_MK`) and the updates they carry up to the
    /// constraint block.
    pub coupling: f64,
    /// The constraint block's own `L D Lᵀ`: the dense Delassus operator's columns.
    pub constraint_block: f64,
}

impl FactorFlops {
    /// All three.
    pub fn total(&self) -> f64 {
        self.k + self.coupling + self.constraint_block
    }
}

/// The assembled model.
pub struct Model {
    pub mesh: Mesh,
    /// Active triangles with their materials.
    pub elems: Vec<(usize, Material)>,
    /// Body index (into the case's `bodies`) of each active triangle.
    pub elem_body: Vec<usize>,
    pub dofs: DofMap,
    /// Nonzeros of the upper triangle of the assembled stiffness (`K` itself is not kept: it
    /// is factorised, and a model from the cache is not assembled at all).
    pub stiffness_nonzeros: usize,
    /// The factorisation's modelled operations ([`FactorFlops`]): a contact model analysed in
    /// this run (`None` on a model-cache hit, which skips the analysis, and without contact).
    pub factor_flops: Option<FactorFlops>,
    /// Factorised stiffness and condensed system on the retained DOFs.
    pub condensed: Condensed,
    /// Nodal forces of the tractions at scale 1 (free DOFs).
    pub f_traction: Vec<f64>,
    /// Forces due to prescribed displacements (free DOFs).
    pub f_prescribed: Vec<f64>,
    /// Active nodes (used by some active triangle).
    pub active: Vec<bool>,
    /// The friction law of the contact pair (resolved from the case), if any.
    pub friction: Option<crate::friction::FrictionLaw>,
    /// The contact pair on the condensed system, if the case has one.
    pub contact: Option<crate::contact::ContactModel>,
    /// Condensed contact loads `w0` of the tractions at scale 1 and of the prescribed
    /// displacements.
    pub contact_w0: [Vec<f64>; 2],
    /// When the pilot drives a body that no support holds (only the contact can): the
    /// direction of pilot motion that opens the contact. A force along it has no equilibrium.
    /// (body index, direction).
    pub pilot_separation: Option<(usize, [f64; 2])>,
    pub timings: Timings,
    /// How the model cache served this model (`None`: built without one, as by [`Model::build`]).
    pub cache: Option<crate::cache::Report>,
    /// The cache entry being written in the background, until [`Model::cache_report`] waits
    /// for it (else its `Drop` waits for the write when the model is dropped), and the reason
    /// the write failed, once known.
    cache_job: std::sync::Mutex<(Option<crate::cache::Job>, Option<String>)>,
    /// The factorised Delassus blocks shared by the simulations of this model once
    /// [`Model::share_contact_blocks`] has been called (a sweep does).
    contact_blocks: std::sync::OnceLock<std::sync::Arc<crate::contact::solver::BlockStore>>,
    /// The mesh's diameter and the largest Young's modulus of the bodies in use (see
    /// [`Model::scales`]).
    scales: std::sync::OnceLock<(f64, f64)>,
    /// Where each element's twelve displacements are (see [`Model::element_u`]).
    elem_dofs: std::sync::OnceLock<Vec<[u32; 12]>>,
    /// Per element, what its internal forces read of its geometry, once
    /// [`Model::keep_force_geometry`] has been called (for timing: `examples/stress_timing`).
    force_geometry: std::sync::OnceLock<Vec<crate::elasticity::ForceGeometry>>,
}

impl Model {
    /// How the model cache served this model, for a summary: a new entry's write waited for
    /// first, so that an entry that could not be written (no room, say) is reported as such
    /// (`path` cleared, the reason in `note`) rather than named.
    pub fn cache_report(&self) -> Option<crate::cache::Report> {
        let mut report = self.cache.clone()?;
        let mut job = self.cache_job.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(j) = job.0.take() {
            job.1 = j.settle();
        }
        if let Some(e) = &job.1 {
            report.not_written(e);
        }
        Some(report)
    }

    /// Reads the mesh of a case and builds the model. `case_path` resolves the mesh path.
    pub fn build(case: &Case, case_path: &std::path::Path) -> Result<Model, ModelError> {
        Self::build_with_gap(case, case_path, None)
    }

    /// As [`Model::build`], overriding the contact candidate gap.
    pub fn build_with_gap(
        case: &Case,
        case_path: &std::path::Path,
        gap: Option<f64>,
    ) -> Result<Model, ModelError> {
        Self::build_cached(case, case_path, gap, None)
    }

    /// As [`Model::build_with_gap`], with the model cache `store` (see [`crate::cache`]): its
    /// linear algebra (ordering, factor, Delassus operator, condensed loads of the prescribed
    /// displacements) is loaded when an entry of the same key is there, else built and written
    /// to it in the background. The result is the same, bit for bit.
    pub fn build_cached(
        case: &Case,
        case_path: &std::path::Path,
        gap: Option<f64>,
        store: Option<&crate::cache::Store>,
    ) -> Result<Model, ModelError> {
        let t0 = Instant::now();
        let path = case.mesh_path(case_path);
        let bytes = std::fs::read(&path).map_err(|source| {
            ModelError::MeshRead(crate::mesh::gmsh::MeshReadError::Io {
                path: path.display().to_string(),
                source,
            })
        })?;
        let mesh = crate::mesh::gmsh::parse(&bytes, &path)?;
        crate::trace::mark("mesh read");
        let mut timings = Timings {
            read: t0.elapsed().as_secs_f64(),
            ..Default::default()
        };
        Self::build_on(
            case,
            mesh,
            store.map(|s| (s, &bytes[..])),
            &mut timings,
            gap,
        )
    }

    /// Builds the model on an already read mesh (`gap` overrides the contact candidate gap).
    pub fn from_mesh(
        case: &Case,
        mesh: Mesh,
        timings: &mut Timings,
        gap: Option<f64>,
    ) -> Result<Model, ModelError> {
        Self::build_on(case, mesh, None, timings, gap)
    }

    /// [`Model::from_mesh`] with the model cache and the bytes of the mesh file, if any.
    fn build_on(
        case: &Case,
        mesh: Mesh,
        cache: Option<(&crate::cache::Store, &[u8])>,
        timings: &mut Timings,
        gap: Option<f64>,
    ) -> Result<Model, ModelError> {
        // faer's dense kernels (the contact Newton's block factorisations, solves and products)
        // run sequentially: in parallel, some split their sums by the number of threads, and a
        // run's results then depended on `--threads` (at 1e-10 on Fig. 2 at L5). The sparse
        // factorisation and the Delassus product take the threads explicitly
        // (`la::factor_parallelism`); with them the results do not depend on the thread
        // count (`tests/determinism.rs`).
        faer::set_global_parallelism(faer::Par::Seq);
        let path = mesh.source.display().to_string();
        // Each group with the case key that names it, for the messages.
        let (named_bodies, named_curves) = case.named_groups();
        check::check_named(&mesh, &named_bodies, &named_curves)?;
        let curves = boundary_groups(case);
        crate::trace::mark("mesh checked");

        let (elems, elem_body) = body_elements(case, &mesh);
        let active = active_nodes(&mesh, &elems);
        let tris: Vec<usize> = elems.iter().map(|(e, _)| *e).collect();
        let orient = EdgeOrientation::for_groups(&mesh, &tris, &curves);
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

        // Contact: candidate zone and mortar operator, whose nodes are retained.
        crate::trace::mark("orientation");
        let t = Instant::now();
        let pair = contact_pair(case, &mesh, &orient, gap, &path)?;
        timings.pair = t.elapsed().as_secs_f64();
        crate::trace::mark("contact pair");
        let retained = retained_nodes(pair.as_ref());
        let e_star = pair
            .as_ref()
            .map(|p| pair_e_star(case, &mesh, &orient, &elems, &elem_body, p));

        let (dofs, pilot_nodes) = number_dofs(case, &mesh, &active, &retained, &path)?;
        let pilot_separation = pilot_nodes
            .as_ref()
            .zip(pair.as_ref())
            .and_then(|(pn, p)| pilot_separation(&mesh, &elems, &elem_body, pn, p, &dofs));
        // The pilot's DOFs are grounded: the body it drives may be held by nothing else.
        let mut grounded: Vec<usize> = dofs
            .pilot
            .map(|p| p.iter().map(|d| d - dofs.n_interior).collect())
            .unwrap_or_default();
        if !retained.is_empty() {
            grounded.extend(anchors_of_floating_bodies(
                &mesh,
                &elems,
                &elem_body,
                case.bodies.len(),
                &dofs,
                &retained,
            ));
        }
        let y = pair
            .as_ref()
            .map(|p| crate::contact::ConstraintRows::new(p, &dofs, &grounded));
        // The order of the constraint rows in the saddle-point factorisation (large contact
        // zones: the one whose trailing block is also a Cholesky factor of leading sets).
        let row_order = y
            .as_ref()
            .filter(|y| y.rows.len() >= crate::contact::solver::PREFIX_FROM)
            .map(|y| crate::contact::solver::prefix_order(&y.gap0, y.rows.len()));
        crate::trace::mark("pair, dofs");
        let t = Instant::now();
        let f_traction = traction_forces(case, &mesh, &orient, &dofs);
        let t_traction = t.elapsed().as_secs_f64();

        // The model cache: the linear algebra of an earlier build of the same model, if any.
        let sizes = cached::Sizes {
            contact: pair.is_some(),
            n_free: dofs.n_free(),
            n_interior: dofs.n_interior,
            n_retained: dofs.n_retained,
            m: y.as_ref().map_or(0, |y| y.rows.len()),
            row_order: row_order.clone(),
        };
        let t = Instant::now();
        let mut lookup = cached::Lookup::None;
        if let Some((store, bytes)) = cache {
            lookup = cached::lookup(
                store,
                case,
                bytes,
                pair.as_ref().map(|p| p.candidate_gap),
                &sizes,
                &grounded,
            );
        }
        let analyse_s = match &lookup {
            cached::Lookup::Hit(r) => r.analyse_s,
            _ => 0.0,
        };
        timings.cache = t.elapsed().as_secs_f64() - analyse_s;
        let mut cache_report = lookup.report();

        let mut factor_flops = None;
        let (condensed, contact, f_prescribed, stiffness_nonzeros, w0_cached, pending) =
            match lookup {
                cached::Lookup::Hit(r) => {
                    let r = *r;
                    timings.assemble = t_traction;
                    timings.analyse = r.analyse_s;
                    let t = Instant::now();
                    let (w, prefix) = (r.w, r.prefix);
                    let contact = pair.zip(y).map(|(p, y)| {
                        crate::contact::ContactModel::with_w(
                            p,
                            y,
                            dofs.pilot.is_some(),
                            &r.condensed,
                            e_star.expect("with pair"),
                            w.expect("a contact model's entry holds W"),
                            prefix,
                        )
                    });
                    timings.condense = t.elapsed().as_secs_f64();
                    (
                        r.condensed,
                        contact,
                        r.f_prescribed,
                        r.stiffness_nonzeros,
                        r.w0,
                        None,
                    )
                }
                other => {
                    let t0 = Instant::now();
                    let mut k = UpperCsc::pattern(&mesh, &elems, &dofs);
                    let t_pattern = t0.elapsed().as_secs_f64();
                    crate::trace::mark("pattern");
                    // The analysis needs the pattern only: the values are assembled alongside
                    // it, on the cores that its sequential parts (the top separators of the
                    // ordering, faer's symbolic factorisation) leave idle.
                    let mut values = std::mem::take(&mut k.values);
                    let t_join = Instant::now();
                    let (analysed, (f_prescribed, t_values)) = rayon::join(
                        || {
                            let t = Instant::now();
                            let s = analyse(&k, &dofs, y.as_ref(), row_order.as_deref());
                            (s, t.elapsed().as_secs_f64())
                        },
                        || {
                            let t = Instant::now();
                            let f = assembly::assemble_values(
                                &mesh,
                                &elems,
                                &dofs,
                                (&k.col_ptr, &k.row_idx),
                                &mut values,
                            );
                            crate::trace::mark("assembled");
                            (f, t.elapsed().as_secs_f64())
                        },
                    );
                    k.values = values;
                    let t_joined = t_join.elapsed().as_secs_f64();
                    let (symbolic, t_analyse) = analysed;
                    if let Ok(Analysis::Saddle(s, _)) = &symbolic {
                        let (k, coupling, constraint_block) = s.flops();
                        factor_flops = Some(FactorFlops {
                            k,
                            coupling,
                            constraint_block,
                        });
                    }
                    timings.assemble = t_pattern + t_values + t_traction;
                    timings.analyse = t_analyse;
                    let nnz = k.row_idx.len();
                    // A miss: the entry's file takes the factor's values as they are computed.
                    let entry_to = match (&other, cache) {
                        (cached::Lookup::Miss(p), Some((store, _))) => Some((store, p.key)),
                        _ => None,
                    };
                    let (condensed, contact, ordering, draft) = factorise(
                        &mut k,
                        &dofs,
                        &grounded,
                        pair.zip(y),
                        e_star,
                        (symbolic?, row_order),
                        entry_to,
                        timings,
                    )?;
                    // The pattern, the assembly and analysis together, the factorisation.
                    timings.build_span = t_pattern + t_joined + timings.factorise + t_traction;
                    let pending = match other {
                        cached::Lookup::Miss(p) => Some((p, ordering, k, draft)),
                        _ => None,
                    };
                    (condensed, contact, f_prescribed, nnz, None, pending)
                }
            };
        crate::trace::mark("factorised");
        let contact = contact.map(|mut c| {
            c.system.floating_pilot = pilot_separation.is_some();
            c
        });
        let t = Instant::now();
        let friction = match (&case.contact, e_star) {
            (Some(cs), Some(es)) => cs
                .friction
                .as_ref()
                .map(|f| f.resolve(es))
                .transpose()
                .map_err(ModelError::Friction)?,
            _ => None,
        };
        let contact_w0 = match &contact {
            Some(c) => {
                let (traction, prescribed) = match w0_cached {
                    Some((ft, w0t, w0p)) => (
                        cached::same_bits(&ft, &f_traction).then_some(w0t),
                        Some(w0p),
                    ),
                    None => (None, None),
                };
                [
                    traction.unwrap_or_else(|| c.w0(&condensed, &f_traction)),
                    prescribed.unwrap_or_else(|| c.w0(&condensed, &f_prescribed)),
                ]
            }
            None => [Vec::new(), Vec::new()],
        };
        timings.condense += t.elapsed().as_secs_f64();

        // A miss: write the entry while the run goes on.
        let cache_job = match (cache, pending) {
            (Some((store, _)), Some((p, ordering, k, draft))) => {
                let t = Instant::now();
                let entry = cached::entry(cached::Built {
                    sizes: &sizes,
                    ordering,
                    k,
                    nnz: stiffness_nonzeros,
                    grounded: &grounded,
                    condensed: &condensed,
                    w: contact.as_ref().map(|c| &c.system.w),
                    prefix: contact.as_ref().and_then(|c| c.system.prefix.as_ref()),
                    f_prescribed: &f_prescribed,
                    f_traction: &f_traction,
                    contact_w0: &contact_w0,
                    draft,
                });
                let (report, job) = store.write_in_background(p.key, entry, p.status, p.note);
                timings.cache += t.elapsed().as_secs_f64();
                cache_report = Some(report);
                job
            }
            _ => None,
        };
        Ok(Model {
            mesh,
            elems,
            elem_body,
            dofs,
            stiffness_nonzeros,
            factor_flops,
            condensed,
            f_traction,
            f_prescribed,
            active,
            friction,
            contact,
            contact_w0,
            pilot_separation,
            timings: timings.clone(),
            cache: cache_report,
            cache_job: std::sync::Mutex::new((cache_job, None)),
            contact_blocks: std::sync::OnceLock::new(),
            force_geometry: std::sync::OnceLock::new(),
            scales: std::sync::OnceLock::new(),
            elem_dofs: std::sync::OnceLock::new(),
        })
    }

    /// The mesh's diameter and the largest Young's modulus of the bodies in use: the scales
    /// of the round-off limits that the per-step checks of the driver use (computed once; the
    /// diameter scans every node, which per step and per sweep row added up).
    pub fn scales(&self) -> (f64, f64) {
        *self.scales.get_or_init(|| {
            let e_max = self
                .elems
                .iter()
                .map(|(_, m)| m.e.abs())
                .fold(0.0, f64::max);
            (self.mesh.diameter(), e_max)
        })
    }

    /// The displacements of element `i` (of `self.elems`) from the free solution `u`: the same
    /// numbers as [`DofMap::element_displacement`], read through a table of where each is
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
    /// (below [`DofMap::n_free`]), `n_free` plus its index among the prescribed ones, or
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
        #[cfg(target_arch = "x86_64")]
        if crate::la::simd::avx2() {
            // SAFETY: the processor has AVX2 (checked at run time).
            return unsafe { self.nodal_stresses_lanes_avx2::<R>(us) };
        }
        self.nodal_stresses_lanes_body::<R>(us)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn nodal_stresses_lanes_avx2<const R: usize>(
        &self,
        us: &[&[f64]],
    ) -> Vec<Vec<[f64; 4]>> {
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

/// The symbolic analysis of a model's matrix: of `K̂` with the retained DOFs last (no contact),
/// or of the saddle-point matrix with the contact constraint rows (kept with it, by free DOF).
enum Analysis {
    Partial(PartialSymbolic),
    Saddle(SaddleSymbolic, Vec<Vec<(usize, f64)>>),
}

/// Analyses the pattern of the stiffness `k` (its values are not read): with the constraint
/// rows `y` of a contact pair, the saddle-point matrix; without, `K̂` with the retained (pilot)
/// DOFs last.
fn analyse(
    k: &UpperCsc,
    dofs: &DofMap,
    y: Option<&crate::contact::ConstraintRows>,
    row_order: Option<&[usize]>,
) -> Result<Analysis, ModelError> {
    Ok(match y {
        None => Analysis::Partial(PartialSymbolic::analyse(
            dofs.n_free(),
            dofs.n_retained,
            &k.col_ptr,
            &k.row_idx,
        )?),
        Some(y) => {
            let mut y_free = y.free(dofs.n_interior);
            if let Some(order) = row_order {
                y_free = order
                    .iter()
                    .map(|&i| std::mem::take(&mut y_free[i]))
                    .collect();
            }
            let symbolic = SaddleSymbolic::analyse(dofs.n_free(), &k.col_ptr, &k.row_idx, &y_free)?;
            Analysis::Saddle(symbolic, y_free)
        }
    })
}

/// What [`factorise`] gives: the condensed system, the contact model, the ordering of the free
/// DOFs and the model-cache entry's draft file when the factor's values are in it.
type Factorised = (
    Condensed,
    Option<crate::contact::ContactModel>,
    Vec<usize>,
    Option<crate::cache::DraftFile>,
);

/// Factorises the stiffness `k` analysed by [`analyse`] with springs on the `grounded`
/// retained DOFs, and builds the contact model of `pair` on it: without contact, a partial
/// factorisation with the retained (pilot) DOFs last; with contact, the saddle-point matrix
/// with the contact constraint rows, whose trailing block gives the Delassus operator (its
/// values computed in the file of the model-cache entry `entry_to`, on a miss, where that can
/// be done safely: [`crate::cache::Draft`]). Records the `factorise` and `condense` (the
/// Delassus operator) timings. Also returns the ordering of the analysis (for the model cache).
#[allow(clippy::too_many_arguments)]
fn factorise(
    k: &mut UpperCsc,
    dofs: &DofMap,
    grounded: &[usize],
    pair: Option<(crate::contact::Pair, crate::contact::ConstraintRows)>,
    e_star: Option<f64>,
    (analysis, row_order): (Analysis, Option<Vec<usize>>),
    entry_to: Option<(&crate::cache::Store, crate::cache::Key)>,
    timings: &mut Timings,
) -> Result<Factorised, ModelError> {
    let n_i = dofs.n_interior;
    let t = Instant::now();
    match (pair, analysis) {
        (None, Analysis::Partial(symbolic)) => {
            let condensed = Condensed::build(k, n_i, grounded, &symbolic)?;
            // The values are in the factor now; the pattern stays for the model cache.
            k.values = Vec::new();
            timings.factorise = t.elapsed().as_secs_f64();
            Ok((condensed, None, symbolic.ordering(), None))
        }
        (Some((pair, y)), Analysis::Saddle(symbolic, y_free)) => {
            // A new cache entry's file, whose pages the factorisation writes its values in
            // (none where that cannot be done safely: the values go to memory, and the entry's
            // writer copies them as for a model without contact).
            let draft = entry_to.and_then(|(store, key)| store.draft(key, symbolic.len_val()));
            let (draft, dest) = match draft {
                Some(d) => (
                    Some(d.file),
                    Some(Box::new(d.values) as Box<dyn crate::la::ValuesDestination>),
                ),
                None => (None, None),
            };
            let condensed = Condensed::build_saddle(k, n_i, grounded, &y_free, &symbolic, dest)?;
            timings.factorise = t.elapsed().as_secs_f64();
            timings.constraint_block = condensed.constraint_block_s();
            // The stiffness is in the factor now, and a contact model's cache entry does not
            // keep its pattern: freed before the Delassus operator's three dense m × m arrays
            // are allocated, which is when a run's memory peaks (L7: K's 0.11 GB of 1.5 GB).
            *k = UpperCsc::default();
            crate::trace::mark("numeric factor");
            let t = Instant::now();
            let contact = crate::contact::ContactModel::new(
                pair,
                y,
                dofs.pilot.is_some(),
                &condensed,
                e_star.expect("with pair"),
                row_order,
            );
            timings.condense = t.elapsed().as_secs_f64();
            Ok((condensed, Some(contact), symbolic.ordering(), draft))
        }
        _ => unreachable!("analysed with the same constraint rows"),
    }
}

/// The curve groups the case names: supports, tractions, the pilot, then the contact pair
/// (slave, master).
fn boundary_groups(case: &Case) -> Vec<&str> {
    let mut curves: Vec<&str> = case.supports.iter().map(|s| s.group.as_str()).collect();
    curves.extend(case.tractions.iter().map(|t| t.group.as_str()));
    if let Some(p) = &case.pilot {
        curves.push(&p.group);
    }
    if let Some(c) = &case.contact {
        curves.push(&c.slave);
        curves.push(&c.master);
    }
    curves
}

/// The active triangles with their materials, body by body, and the body index of each.
fn body_elements(case: &Case, mesh: &Mesh) -> (Vec<(usize, Material)>, Vec<usize>) {
    let mut elems = Vec::new();
    let mut elem_body = Vec::new();
    for (bi, b) in case.bodies.iter().enumerate() {
        let mat = Material { e: b.e, nu: b.nu };
        for &e in &mesh.group(&b.group).expect("checked").elements {
            elems.push((e, mat));
            elem_body.push(bi);
        }
    }
    (elems, elem_body)
}

/// Flags per mesh node: used by some active triangle.
fn active_nodes(mesh: &Mesh, elems: &[(usize, Material)]) -> Vec<bool> {
    let mut active = vec![false; mesh.nodes.len()];
    for (e, _) in elems {
        for &n in &mesh.triangles[*e].nodes {
            active[n] = true;
        }
    }
    active
}

/// The contact pair of the case (candidate zone and mortar operator), if it has a `contact`.
fn contact_pair(
    case: &Case,
    mesh: &Mesh,
    orient: &EdgeOrientation,
    gap: Option<f64>,
    path: &str,
) -> Result<Option<crate::contact::Pair>, ModelError> {
    let Some(cs) = &case.contact else {
        return Ok(None);
    };
    let perr = |source| ModelError::Contact {
        path: path.to_string(),
        source,
    };
    let slave = crate::contact::oriented_edges(mesh, orient, &cs.slave).map_err(perr)?;
    let master = crate::contact::oriented_edges(mesh, orient, &cs.master).map_err(perr)?;
    let g = gap
        .or(cs.candidate_gap)
        .unwrap_or_else(|| crate::contact::default_candidate_gap(mesh, &slave));
    Ok(Some(
        crate::contact::build_pair(
            mesh,
            &cs.slave,
            &cs.master,
            &slave,
            &master,
            g,
            cs.normal == crate::case::NormalKind::Common,
        )
        .map_err(perr)?,
    ))
}

/// The nodes kept in the condensed system: those of the candidate zone and of the mortar rows,
/// each once, in order of first appearance.
fn retained_nodes(pair: Option<&crate::contact::Pair>) -> Vec<usize> {
    let mut retained: Vec<usize> = Vec::new();
    if let Some(p) = pair {
        let m = &p.mortar;
        retained.extend(p.zone_edges.iter().flatten());
        retained.extend(m.g_rows.iter().chain(&m.t_rows).flatten().map(|(n, _)| *n));
        let mut seen = std::collections::HashSet::new();
        retained.retain(|n| seen.insert(*n));
    }
    retained
}

/// The composite modulus E* of the pair, from the slave body (of the first zone edge) and the
/// master body (adjacent to the first master edge; the slave body if there is none).
fn pair_e_star(
    case: &Case,
    mesh: &Mesh,
    orient: &EdgeOrientation,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    p: &crate::contact::Pair,
) -> f64 {
    let mut tri_body = vec![usize::MAX; mesh.triangles.len()];
    for ((e, _), &b) in elems.iter().zip(elem_body) {
        tri_body[*e] = b;
    }
    let body_of = |e: &[usize; 3]| {
        orient
            .edge_triangle(e[0], e[1])
            .map(|t| tri_body[t])
            .expect("oriented edge")
    };
    let mb = p.mortar.master_nodes.first().and_then(|_| {
        // The master body: the triangle adjacent to any master edge of the case group.
        let cs = case.contact.as_ref().expect("pair implies contact");
        crate::contact::oriented_edges(mesh, orient, &cs.master)
            .ok()
            .and_then(|v| v.first().map(body_of))
    });
    let sb = body_of(&p.zone_edges[0]);
    let inv = |b: usize| (1.0 - case.bodies[b].nu.powi(2)) / case.bodies[b].e;
    1.0 / (inv(sb) + inv(mb.unwrap_or(sb)))
}

/// Numbers the DOFs (supports, pilot, retained nodes); also returns the pilot's nodes.
fn number_dofs(
    case: &Case,
    mesh: &Mesh,
    active: &[bool],
    retained: &[usize],
    path: &str,
) -> Result<(DofMap, Option<Vec<usize>>), ModelError> {
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
        active,
        &supports,
        case.pilot
            .as_ref()
            .map(|p| p.group.as_str())
            .zip(pilot_nodes.as_deref()),
        retained,
    )
    .map_err(|source| ModelError::Dof {
        path: path.to_string(),
        source,
    })?;
    Ok((dofs, pilot_nodes))
}

/// [`Model::pilot_separation`]: when the pilot (on nodes `pn`) drives the slave or master body
/// and no support holds that body, the body and the direction of pilot motion that opens the
/// contact (the slave's outward normal at the first touch, reversed for the slave body).
fn pilot_separation(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    pn: &[usize],
    p: &crate::contact::Pair,
    dofs: &DofMap,
) -> Option<(usize, [f64; 2])> {
    let node_body = node_bodies(mesh, elems, elem_body);
    let bp = node_body[*pn.first()?];
    let sb = node_body[p.zone_edges[0][0]];
    let mb = node_body[*p.mortar.master_nodes.first()?];
    let n = p.first_touch;
    match held_by_supports(mesh, &node_body, bp, dofs).0 {
        true => None,
        false if bp == mb => Some((bp, n)),
        false if bp == sb => Some((bp, [-n[0], -n[1]])),
        false => None,
    }
}

/// Nodal forces (free DOFs) of the case's tractions at scale 1, edge by edge.
fn traction_forces(case: &Case, mesh: &Mesh, orient: &EdgeOrientation, dofs: &DofMap) -> Vec<f64> {
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
            let nodes = orient.oriented_nodes(mesh, l).expect("checked above");
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
    f_traction
}

/// The body of each node (`usize::MAX` for nodes of no active triangle).
fn node_bodies(mesh: &Mesh, elems: &[(usize, Material)], elem_body: &[usize]) -> Vec<usize> {
    let mut node_body = vec![usize::MAX; mesh.nodes.len()];
    for ((e, _), &b) in elems.iter().zip(elem_body) {
        for &n in &mesh.triangles[*e].nodes {
            node_body[n] = b;
        }
    }
    node_body
}

/// Whether the supports of body `b` hold its three rigid modes (1,0), (0,1), (−y, x) (their
/// restriction to the body's fixed DOFs has rank 3), and whether the pilot drives the body.
fn held_by_supports(mesh: &Mesh, node_body: &[usize], b: usize, dofs: &DofMap) -> (bool, bool) {
    use crate::dofs::Dof;
    let pilot_dof = |d: Dof| matches!((d, dofs.pilot), (Dof::Free(i), Some(p)) if p.contains(&i));
    let mut g = [[0.0f64; 3]; 3];
    let mut piloted = false;
    let mut scale: f64 = 0.0;
    for (n, &nb) in node_body.iter().enumerate() {
        if nb != b {
            continue;
        }
        let x = mesh.nodes[n];
        scale = scale.max(x[0].abs()).max(x[1].abs());
        for c in 0..2 {
            let d = dofs.node[n][c];
            if pilot_dof(d) {
                piloted = true;
            }
            if let Dof::Fixed(_) = d {
                let row = if c == 0 {
                    [1.0, 0.0, -x[1]]
                } else {
                    [0.0, 1.0, x[0]]
                };
                for i in 0..3 {
                    for j in 0..3 {
                        g[i][j] += row[i] * row[j];
                    }
                }
            }
        }
    }
    // Normalise the rotation column so the determinant test is scale-free.
    let s = scale.max(f64::MIN_POSITIVE);
    for i in 0..3 {
        g[i][2] /= s;
        g[2][i] /= s;
    }
    let det = g[0][0] * (g[1][1] * g[2][2] - g[1][2] * g[2][1])
        - g[0][1] * (g[1][0] * g[2][2] - g[1][2] * g[2][0])
        + g[0][2] * (g[1][0] * g[2][1] - g[1][1] * g[2][0]);
    let tr = g[0][0] + g[1][1] + g[2][2];
    (det > 1e-8 * tr.powi(3), piloted)
}

/// Retained DOFs (as retained indices) to ground in bodies that no support or pilot holds, so
/// that a body held by contact alone still has a factorisable stiffness. Each such body gets
/// three anchors on its contact nodes (both components of one node, one component of the node
/// farthest from it), which the contact solver drives at zero force.
fn anchors_of_floating_bodies(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    nbodies: usize,
    dofs: &DofMap,
    retained: &[usize],
) -> Vec<usize> {
    use crate::dofs::Dof;
    let node_body = node_bodies(mesh, elems, elem_body);
    let mut out = Vec::new();
    for b in 0..nbodies {
        let (held, piloted) = held_by_supports(mesh, &node_body, b, dofs);
        if piloted || held {
            continue;
        }
        let nodes: Vec<usize> = retained
            .iter()
            .copied()
            .filter(|&n| node_body[n] == b)
            .collect();
        let free = |n: usize, c: usize| match dofs.node[n][c] {
            Dof::Free(i) if i >= dofs.n_interior => Some(i - dofs.n_interior),
            _ => None,
        };
        let Some(&a) = nodes
            .iter()
            .find(|&&n| free(n, 0).is_some() && free(n, 1).is_some())
        else {
            continue;
        };
        let xa = mesh.nodes[a];
        let far = nodes.iter().copied().max_by(|&p, &q| {
            let d = |n: usize| (mesh.nodes[n][0] - xa[0]).hypot(mesh.nodes[n][1] - xa[1]);
            d(p).partial_cmp(&d(q)).expect("finite")
        });
        out.extend(free(a, 0));
        out.extend(free(a, 1));
        if let Some(f) = far.filter(|&f| f != a) {
            let xf = mesh.nodes[f];
            let c = if (xf[0] - xa[0]).abs() >= (xf[1] - xa[1]).abs() {
                1
            } else {
                0
            };
            out.extend(free(f, c));
        }
    }
    out
}
