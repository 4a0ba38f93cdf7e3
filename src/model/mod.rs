//! A model ready to solve: the checked mesh, the DOF numbering, the assembled and factorised
//! stiffness, the condensed system on the retained DOFs and the load vectors.
//!
//! | module | content |
//! |---|---|
//! | this file | [`Model`] and its build: the parts, the linear algebra (built, or restored from the model cache), the contact loads |
//! | `bodies` | what a case gives on its mesh before any matrix: elements, boundaries, contact pair, DOFs, grounding, tractions |
//! | `cached` | the model's linear algebra in the model cache |
//! | [`step`] | one load step on the condensed model |
//! | [`fronts`] | the stick and weakening zones at each end, and K_II at the stick fronts |
//! | [`profile`] | the initial gap profile: its fitted radius, and whether it is Hertzian |
//! | `elements` | solution fields read element by element: displacements, nodal stresses |

mod bodies;
mod cached;
mod elements;
pub mod fronts;
pub mod profile;
pub mod step;

use crate::assembly::{self, UpperCsc};
use crate::case::Case;
use crate::condense::Condensed;
use crate::dofs::DofMap;
use crate::elasticity::Material;
use crate::error::ModelError;
use crate::la::{PartialSymbolic, SaddleSymbolic};
use crate::mesh::Mesh;
use bodies::Prepared;
use std::time::Instant;

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
            None,
        )
    }

    /// Builds the model on an already read mesh (`gap` overrides the contact candidate gap).
    pub fn from_mesh(
        case: &Case,
        mesh: Mesh,
        timings: &mut Timings,
        gap: Option<f64>,
    ) -> Result<Model, ModelError> {
        Self::build_on(case, mesh, None, timings, gap, None)
    }

    /// The model of an implicit time step on an already read mesh: its factorised matrix is
    /// `K + c M` ([`crate::assembly::assemble_shifted`]), with `shift[b] = c ρ_b` for each
    /// body `b` of the case, and its prescribed-value forces those of `K + c M`; its grounding
    /// springs are `springs` (those of the quasi-static model, [`Condensed::grounding`], so
    /// that a contact state means the same in both). Everything else (DOFs, contact pair,
    /// loads) is that of [`Model::from_mesh`]. Built without the model cache.
    pub fn shifted(
        case: &Case,
        mesh: Mesh,
        shift: &[f64],
        springs: &[f64],
        timings: &mut Timings,
    ) -> Result<Model, ModelError> {
        Self::build_on(case, mesh, None, timings, None, Some((shift, springs)))
    }

    /// [`Model::from_mesh`] with the model cache and the bytes of the mesh file, if any: the
    /// parts of the model on its mesh ([`bodies::prepare`]), its linear algebra (restored from
    /// the cache on a hit, else assembled, analysed and factorised, and on a miss written to
    /// the cache while the run goes on), its friction law and condensed contact loads.
    fn build_on(
        case: &Case,
        mesh: Mesh,
        cache: Option<(&crate::cache::Store, &[u8])>,
        timings: &mut Timings,
        gap: Option<f64>,
        shift: Option<(&[f64], &[f64])>,
    ) -> Result<Model, ModelError> {
        // faer's dense kernels (the contact Newton's block factorisations, solves and products)
        // run sequentially: in parallel, some split their sums by the number of threads, and a
        // run's results then depended on `--threads` (at 1e-10 on Fig. 2 at L5). The sparse
        // factorisation and the Delassus product take the threads explicitly
        // (`la::factor_parallelism`); with them the results do not depend on the thread
        // count (`tests/determinism.rs`).
        faer::set_global_parallelism(faer::Par::Seq);
        let mut parts = bodies::prepare(case, &mesh, gap)?;
        timings.pair = parts.t_pair;
        let springs = shift.map(|s| s.1);
        let shift: Option<Vec<f64>> =
            shift.map(|s| parts.elem_body.iter().map(|&b| s.0[b]).collect());

        // The model cache: the linear algebra of an earlier build of the same model, if any.
        let (sizes, lookup) = look_up(case, cache, &parts, timings);
        let mut cache_report = lookup.report();
        let la = match lookup {
            cached::Lookup::Hit(r) => restored(*r, &mut parts, timings),
            other => {
                let miss = match (other, cache) {
                    (cached::Lookup::Miss(p), Some((store, _))) => Some((store, p)),
                    _ => None,
                };
                assembled(
                    &mesh,
                    &mut parts,
                    (shift.as_deref(), springs),
                    miss,
                    timings,
                )?
            }
        };
        crate::trace::mark("factorised");
        let Prepared {
            elems,
            elem_body,
            active,
            dofs,
            grounded,
            e_star,
            pilot_separation,
            f_traction,
            ..
        } = parts;
        let LinearAlgebra {
            condensed,
            contact,
            f_prescribed,
            stiffness_nonzeros,
            factor_flops,
            w0_cached,
            pending,
        } = la;
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
            (Some((store, _)), Some(m)) => {
                let t = Instant::now();
                let entry = cached::entry(cached::Built {
                    sizes: &sizes,
                    ordering: m.ordering,
                    k: m.k,
                    nnz: stiffness_nonzeros,
                    grounded: &grounded,
                    condensed: &condensed,
                    w: contact.as_ref().map(|c| &c.system.w),
                    prefix: contact.as_ref().and_then(|c| c.system.prefix.as_ref()),
                    f_prescribed: &f_prescribed,
                    f_traction: &f_traction,
                    contact_w0: &contact_w0,
                    draft: m.draft,
                });
                let p = m.pending;
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
}

/// A model's linear algebra: restored from the model cache ([`restored`]) or built
/// ([`assembled`]).
struct LinearAlgebra {
    condensed: Condensed,
    contact: Option<crate::contact::ContactModel>,
    f_prescribed: Vec<f64>,
    stiffness_nonzeros: usize,
    factor_flops: Option<FactorFlops>,
    /// A hit's condensed contact loads: (traction forces, their `w0`, `w0` of the prescribed
    /// displacements).
    w0_cached: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    /// A miss: what its cache entry is written from.
    pending: Option<Missed>,
}

/// What a miss's cache entry is written from, besides the model: the entry's key and status,
/// the ordering of the analysis, the stiffness's pattern and the entry's draft file.
struct Missed {
    pending: cached::Pending,
    ordering: Vec<usize>,
    k: UpperCsc,
    draft: Option<crate::cache::DraftFile>,
}

/// The sizes of the model and what the cache has for it (`cached::Lookup::None` without a
/// cache). Records the `cache` timing (less the analysis a hit redoes).
fn look_up(
    case: &Case,
    cache: Option<(&crate::cache::Store, &[u8])>,
    parts: &Prepared,
    timings: &mut Timings,
) -> (cached::Sizes, cached::Lookup) {
    let (dofs, y) = (&parts.dofs, &parts.y);
    let sizes = cached::Sizes {
        contact: parts.pair.is_some(),
        n_free: dofs.n_free(),
        n_interior: dofs.n_interior,
        n_retained: dofs.n_retained,
        m: y.as_ref().map_or(0, |y| y.rows.len()),
        row_order: parts.row_order.clone(),
    };
    let t = Instant::now();
    let mut lookup = cached::Lookup::None;
    if let Some((store, bytes)) = cache {
        lookup = cached::lookup(
            store,
            case,
            bytes,
            parts.pair.as_ref().map(|p| p.candidate_gap),
            &sizes,
            &parts.grounded,
        );
    }
    let analyse_s = match &lookup {
        cached::Lookup::Hit(r) => r.analyse_s,
        _ => 0.0,
    };
    timings.cache = t.elapsed().as_secs_f64() - analyse_s;
    (sizes, lookup)
}

/// The linear algebra of a cache hit `r`, with the contact model of the pair of `parts` built
/// on its Delassus operator.
fn restored(r: cached::Restored, parts: &mut Prepared, timings: &mut Timings) -> LinearAlgebra {
    timings.assemble = parts.t_traction;
    timings.analyse = r.analyse_s;
    let t = Instant::now();
    let (w, prefix) = (r.w, r.prefix);
    let contact = parts.pair.take().zip(parts.y.take()).map(|(p, y)| {
        crate::contact::ContactModel::with_w(
            p,
            y,
            parts.dofs.pilot.is_some(),
            &r.condensed,
            parts.e_star.expect("with pair"),
            w.expect("a contact model's entry holds W"),
            prefix,
        )
    });
    timings.condense = t.elapsed().as_secs_f64();
    LinearAlgebra {
        condensed: r.condensed,
        contact,
        f_prescribed: r.f_prescribed,
        stiffness_nonzeros: r.stiffness_nonzeros,
        factor_flops: None,
        w0_cached: r.w0,
        pending: None,
    }
}

/// The linear algebra built: the stiffness's pattern, its values assembled alongside the
/// symbolic analysis, the factorisation and the contact model of the pair of `parts`
/// ([`factorise`]). On a cache miss (`miss`: the store and the entry to write), the factor's
/// values are computed in the entry's file where that can be done safely.
fn assembled(
    mesh: &Mesh,
    parts: &mut Prepared,
    (shift, springs): (Option<&[f64]>, Option<&[f64]>),
    miss: Option<(&crate::cache::Store, cached::Pending)>,
    timings: &mut Timings,
) -> Result<LinearAlgebra, ModelError> {
    let (elems, dofs) = (&parts.elems, &parts.dofs);
    let t0 = Instant::now();
    let mut k = UpperCsc::pattern(mesh, elems, dofs);
    let t_pattern = t0.elapsed().as_secs_f64();
    crate::trace::mark("pattern");
    // The analysis needs the pattern only: the values are assembled alongside it, on the cores
    // that its sequential parts (the top separators of the ordering, faer's symbolic
    // factorisation) leave idle.
    let mut values = std::mem::take(&mut k.values);
    let t_join = Instant::now();
    let (analysed, (f_prescribed, t_values)) = rayon::join(
        || {
            let t = Instant::now();
            let s = analyse(&k, dofs, parts.y.as_ref(), parts.row_order.as_deref());
            (s, t.elapsed().as_secs_f64())
        },
        || {
            let t = Instant::now();
            let f = assembly::assemble_shifted(
                mesh,
                elems,
                shift,
                dofs,
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
    let factor_flops = match &symbolic {
        Ok(Analysis::Saddle(s, _)) => {
            let (k, coupling, constraint_block) = s.flops();
            Some(FactorFlops {
                k,
                coupling,
                constraint_block,
            })
        }
        _ => None,
    };
    timings.assemble = t_pattern + t_values + parts.t_traction;
    timings.analyse = t_analyse;
    let nnz = k.row_idx.len();
    // A miss: the entry's file takes the factor's values as they are computed.
    let entry_to = miss.as_ref().map(|(store, p)| (*store, p.key));
    let pair = parts.pair.take().zip(parts.y.take());
    let row_order = parts.row_order.take();
    let (condensed, contact, ordering, draft) = factorise(
        &mut k,
        &parts.dofs,
        (&parts.grounded, springs),
        pair,
        parts.e_star,
        (symbolic?, row_order),
        entry_to,
        timings,
    )?;
    // The pattern, the assembly and analysis together, the factorisation.
    timings.build_span = t_pattern + t_joined + timings.factorise + parts.t_traction;
    Ok(LinearAlgebra {
        condensed,
        contact,
        f_prescribed,
        stiffness_nonzeros: nnz,
        factor_flops,
        w0_cached: None,
        pending: miss.map(|(_, pending)| Missed {
            pending,
            ordering,
            k,
            draft,
        }),
    })
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
    (grounded, springs): (&[usize], Option<&[f64]>),
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
            let condensed = Condensed::build_with_springs(k, n_i, grounded, springs, &symbolic)?;
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
            let condensed =
                Condensed::build_saddle(k, n_i, (grounded, springs), &y_free, &symbolic, dest)?;
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
