//! The run driver: stages and load steps, the solve of each step on the condensed system,
//! and the output of every step.

use crate::case::{Case, Control};
use crate::model::{Model, ModelError};
use crate::output::{self, PvdEntry, vtu};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{0}")]
    Solve(String),
    #[error("cannot write output `{path}`: {source}")]
    Write {
        path: String,
        source: std::io::Error,
    },
}

impl RunError {
    /// Process exit status: 2 for bad input, 3 for a solver failure, 4 for output errors.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_)
            | RunError::Model(
                ModelError::MeshRead(_)
                | ModelError::MeshCheck(_)
                | ModelError::Dof { .. }
                | ModelError::Edge { .. }
                | ModelError::Unsupported(_),
            ) => 2,
            RunError::Model(ModelError::Factor(_)) | RunError::Solve(_) => 3,
            RunError::Write { .. } => 4,
        }
    }
}

/// Options of a run from the command line.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (overrides the case's).
    pub out: Option<PathBuf>,
    pub quiet: bool,
}

/// The state of the pilot after a step.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct PilotState {
    pub ux: f64,
    pub uy: f64,
    pub fx: f64,
    pub fy: f64,
}

/// One converged load step.
#[derive(Clone, Debug, Serialize)]
pub struct StepRecord {
    pub step: usize,
    pub stage: usize,
    pub time: f64,
    pub traction_scale: f64,
    pub pilot: Option<PilotState>,
}

/// What `summary.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub case: String,
    pub title: String,
    pub mesh: String,
    pub nodes: usize,
    pub triangles: usize,
    pub dofs_free: usize,
    pub dofs_retained: usize,
    pub stiffness_nonzeros_upper: usize,
    pub threads: usize,
    pub timings_s: crate::model::Timings,
    pub peak_memory_mib: Option<f64>,
    pub steps: Vec<StepRecord>,
    pub output_dir: String,
    /// `completed`, or why the run stopped early.
    pub status: String,
}

impl Model {
    /// Solves one load step: tractions at `scale`, the pilot driven by `control`.
    /// Returns the free solution vector and the pilot state (if there is a pilot).
    pub fn solve_step(
        &self,
        scale: f64,
        control: [Control; 2],
    ) -> Result<(Vec<f64>, Option<PilotState>), String> {
        let f: Vec<f64> = self
            .f_traction
            .iter()
            .zip(&self.f_prescribed)
            .map(|(a, b)| scale * a + b)
            .collect();
        let cond = &self.condensed;
        if self.dofs.pilot.is_none() {
            return Ok((cond.recover(&f, &[], &[]), None));
        }
        let g = cond.reduce(&f);
        let (u, r) = solve_pilot(&cond.s_dense(), &g, control, cond.krr_scale)?;
        Ok((
            cond.recover(&f, &r, &u),
            Some(PilotState {
                ux: u[0],
                uy: u[1],
                fx: r[0],
                fy: r[1],
            }),
        ))
    }
}

/// Solves `S u = g + r` on the pilot DOFs with, per component, either the force `r` or the
/// displacement `u` given. Returns (u, r). `scale` is the stiffness scale of the pilot
/// before condensation: a pivot below 1e-10 of it means nothing holds the pilot.
pub fn solve_pilot(
    s: &[f64],
    g: &[f64],
    control: [Control; 2],
    scale: f64,
) -> Result<([f64; 2], [f64; 2]), String> {
    let mut u = [0.0; 2];
    let mut r = [0.0; 2];
    let mut free = Vec::new();
    for c in 0..2 {
        match control[c] {
            Control::Force(f) => {
                r[c] = f;
                free.push(c);
            }
            Control::Displacement(d) => u[c] = d,
        }
    }
    // S_FF u_F = g_F + r_F − S_FD u_D
    let rhs: Vec<f64> = free
        .iter()
        .map(|&i| {
            g[i] + r[i]
                - (0..2)
                    .filter(|j| !free.contains(j))
                    .map(|j| s[i * 2 + j] * u[j])
                    .sum::<f64>()
        })
        .collect();
    match free.len() {
        1 => {
            let i = free[0];
            if s[i * 2 + i].abs() <= 1e-10 * scale {
                return Err(singular());
            }
            u[i] = rhs[0] / s[i * 2 + i];
        }
        2 => {
            let det = s[0] * s[3] - s[1] * s[2];
            if s[0].abs().min(s[3].abs()) <= 1e-10 * scale || det.abs() <= 1e-10 * scale * scale {
                return Err(singular());
            }
            u[0] = (s[3] * rhs[0] - s[1] * rhs[1]) / det;
            u[1] = (s[0] * rhs[1] - s[2] * rhs[0]) / det;
        }
        _ => {}
    }
    for i in 0..2 {
        r[i] = s[i * 2] * u[0] + s[i * 2 + 1] * u[1] - g[i];
    }
    Ok((u, r))
}

fn singular() -> String {
    "the pilot is force-controlled but the body it drives is not held in that direction \
     (no support and no contact): control it by displacement instead"
        .into()
}

/// Runs a case file end to end and writes its output. Returns the summary.
pub fn run(case_path: &Path, opts: &RunOptions) -> Result<Summary, RunError> {
    let case = Case::load(case_path)?;
    let model = Model::build(&case, case_path)?;
    let out_dir = opts
        .out
        .clone()
        .or(case.output.dir.clone())
        .unwrap_or_else(|| {
            PathBuf::from("out").join(
                case_path
                    .file_stem()
                    .map(|s| s.to_string_lossy().to_string())
                    .unwrap_or("case".into()),
            )
        });
    run_model(&case, case_path, model, &out_dir, opts)
}

fn wr(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    output::write_atomic(path, bytes).map_err(|source| RunError::Write {
        path: path.display().to_string(),
        source,
    })
}

/// Steps through the stages of a built model, writing output to `out_dir`.
pub fn run_model(
    case: &Case,
    case_path: &Path,
    mut model: Model,
    out_dir: &Path,
    opts: &RunOptions,
) -> Result<Summary, RunError> {
    std::fs::create_dir_all(out_dir).map_err(|source| RunError::Write {
        path: out_dir.display().to_string(),
        source,
    })?;
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or("case".into());
    let total = case.total_steps();
    let has_pilot = model.dofs.pilot.is_some();
    let mut control = [Control::Force(0.0); 2];
    let mut pilot = PilotState::default();
    let mut scale = 0.0;
    let mut records = Vec::new();
    let mut pvd = Vec::new();
    let mut step = 0;
    let (mut t_solve, mut t_write) = (0.0, 0.0);
    let mut failure: Option<String> = None;
    'stages: for (si, stage) in case.stages.iter().enumerate() {
        let start = (pilot, scale);
        let target = [stage.pilot_x, stage.pilot_y];
        for k in 1..=stage.steps {
            step += 1;
            let alpha = k as f64 / stage.steps as f64;
            let t = Instant::now();
            scale = match stage.traction_scale {
                Some(v) => start.1 + alpha * (v - start.1),
                None => start.1,
            };
            let (u0, r0) = ([start.0.ux, start.0.uy], [start.0.fx, start.0.fy]);
            for c in 0..2 {
                control[c] = match (target[c], control[c]) {
                    (Some(Control::Force(f)), _) => Control::Force(r0[c] + alpha * (f - r0[c])),
                    (Some(Control::Displacement(d)), _) => {
                        Control::Displacement(u0[c] + alpha * (d - u0[c]))
                    }
                    (None, Control::Force(_)) => Control::Force(r0[c]),
                    (None, Control::Displacement(_)) => Control::Displacement(u0[c]),
                };
            }
            let (u, p) = match model.solve_step(scale, control) {
                Ok(v) => v,
                Err(m) => {
                    failure = Some(format!("step {step}: {m}"));
                    break 'stages;
                }
            };
            if let Some(p) = p {
                pilot = p;
            }
            if u.iter().any(|v| !v.is_finite()) {
                failure = Some(format!("step {step}: the solution is not finite"));
                break 'stages;
            }
            t_solve += t.elapsed().as_secs_f64();
            let time = si as f64 + alpha;
            records.push(StepRecord {
                step,
                stage: si,
                time,
                traction_scale: scale,
                pilot: has_pilot.then_some(pilot),
            });
            if case.output.vtu && (step % case.output.every == 0 || step == total) {
                let t = Instant::now();
                let name = format!("{stem}_{step:04}.vtu");
                wr(
                    &out_dir.join(&name),
                    &bodies_vtu(&model, &u, case).map_err(|e| RunError::Write {
                        path: name.clone(),
                        source: std::io::Error::other(e.to_string()),
                    })?,
                )?;
                pvd.push(PvdEntry {
                    time,
                    part: 0,
                    file: name,
                });
                wr(
                    &out_dir.join(format!("{stem}.pvd")),
                    output::pvd(&pvd).as_bytes(),
                )?;
                t_write += t.elapsed().as_secs_f64();
            }
        }
    }
    model.timings.solve = t_solve;
    model.timings.write = t_write;
    let rows: Vec<Vec<f64>> = records
        .iter()
        .map(|r| {
            let p = r.pilot.unwrap_or_default();
            vec![
                r.step as f64,
                r.stage as f64,
                r.time,
                r.traction_scale,
                p.ux,
                p.uy,
                p.fx,
                p.fy,
            ]
        })
        .collect();
    wr(
        &out_dir.join("history.csv"),
        output::csv(
            &[
                "step",
                "stage",
                "time",
                "traction_scale",
                "pilot_ux",
                "pilot_uy",
                "pilot_fx",
                "pilot_fy",
            ],
            &rows,
        )
        .as_bytes(),
    )?;
    let summary = Summary {
        case: case_path.display().to_string(),
        title: case.title.clone(),
        mesh: model.mesh.source.display().to_string(),
        nodes: model.active.iter().filter(|a| **a).count(),
        triangles: model.elems.len(),
        dofs_free: model.dofs.n_free(),
        dofs_retained: model.dofs.n_retained,
        stiffness_nonzeros_upper: model.k.row_idx.len(),
        threads: rayon::current_num_threads(),
        timings_s: model.timings.clone(),
        peak_memory_mib: output::peak_memory_bytes().map(|b| b as f64 / (1024.0 * 1024.0)),
        steps: records,
        output_dir: out_dir.display().to_string(),
        status: match &failure {
            None => "completed".into(),
            Some(m) => format!("failed at {m}; the output holds the steps before it"),
        },
    };
    wr(
        &out_dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .expect("serialisable")
            .as_bytes(),
    )?;
    if let Some(m) = failure {
        return Err(RunError::Solve(m));
    }
    if !opts.quiet {
        eprintln!(
            "{}: {} steps, {} nodes, {} triangles, {} DOFs; assemble {:.3} s, factorise {:.3} s, solve {:.3} s; output in {}",
            case_path.display(),
            total,
            summary.nodes,
            summary.triangles,
            summary.dofs_free,
            summary.timings_s.assemble,
            summary.timings_s.factorise,
            summary.timings_s.solve,
            out_dir.display()
        );
    }
    Ok(summary)
}

/// The bodies dataset of one step: displacement, stresses, von Mises, body id.
pub fn bodies_vtu(model: &Model, u: &[f64], case: &Case) -> Result<Vec<u8>, vtkio::Error> {
    let mut index = vec![usize::MAX; model.mesh.nodes.len()];
    let mut points = Vec::new();
    for (n, &a) in model.active.iter().enumerate() {
        if a {
            index[n] = points.len();
            points.push(model.mesh.nodes[n]);
        }
    }
    let stress = model.nodal_stresses(u);
    let mut disp = Vec::with_capacity(points.len() * 3);
    let (mut sxx, mut syy, mut sxy, mut szz, mut vm) = (vec![], vec![], vec![], vec![], vec![]);
    for (n, &a) in model.active.iter().enumerate() {
        if !a {
            continue;
        }
        let d = model.dofs.displacement(n, u);
        disp.extend([d[0], d[1], 0.0]);
        let s = stress[n];
        sxx.push(s[0]);
        syy.push(s[1]);
        sxy.push(s[2]);
        szz.push(s[3]);
        vm.push(crate::elasticity::von_mises(s[0], s[1], s[2], s[3]));
    }
    let cells: Vec<Vec<usize>> = model
        .elems
        .iter()
        .map(|(e, _)| {
            model.mesh.triangles[*e]
                .nodes
                .iter()
                .map(|&n| index[n])
                .collect()
        })
        .collect();
    let body: Vec<f64> = model.elem_body.iter().map(|&b| b as f64).collect();
    vtu::unstructured(
        &case.title,
        &points,
        &cells,
        vtu::Kind::Tri6,
        vec![
            vtu::Field::vector("displacement", disp),
            vtu::Field::scalar("stress_xx", sxx),
            vtu::Field::scalar("stress_yy", syy),
            vtu::Field::scalar("stress_xy", sxy),
            vtu::Field::scalar("stress_zz", szz),
            vtu::Field::scalar("von_mises", vm),
        ],
        vec![vtu::Field::scalar("body_id", body)],
    )
}
