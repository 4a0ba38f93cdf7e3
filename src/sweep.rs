//! `stickslip sweep`: one case, many friction laws and/or loads, one shared model, one table.

use crate::case::{Case, FrictionSpec, Stage};
use crate::model::Model;
use crate::output;
use crate::report::{FrictionSummary, final_checks, friction_summary, judge};
use crate::run::{LogLevel, simulate};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The sweep file: at least one of the two lists. The sweep runs every law with every load.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Friction laws, each as a case's `contact.friction`; absent or empty: the case's own law.
    #[serde(default)]
    pub friction: Vec<FrictionSpec>,
    /// Loads, each a whole replacement of the case's `stages`; absent or empty: the case's own.
    #[serde(default)]
    pub stages: Vec<Vec<Stage>>,
}

/// Runs a sweep from the command line. Errors carry the exit status.
pub fn run(
    case_path: &Path,
    sweep_path: &Path,
    out: Option<PathBuf>,
    quiet: bool,
) -> Result<(), (u8, String)> {
    let bad = |e: String| (2u8, e);
    let case = Case::load(case_path).map_err(|e| bad(e.to_string()))?;
    if case.contact.is_none() {
        return Err(bad(format!(
            "{}: a sweep needs a case with `contact`",
            case_path.display()
        )));
    }
    let text = std::fs::read_to_string(sweep_path).map_err(|e| {
        bad(format!(
            "{}: cannot read the sweep file: {e}",
            sweep_path.display()
        ))
    })?;
    let file: SweepFile =
        serde_json::from_str(&text).map_err(|e| bad(format!("{}: {e}", sweep_path.display())))?;
    if file.friction.is_empty() && file.stages.is_empty() {
        return Err(bad(format!(
            "{}: neither `friction` (laws) nor `stages` (loads) lists anything to sweep",
            sweep_path.display()
        )));
    }
    // One case per load, each checked like a case file (ranges, pilot, slip control).
    let loads = if file.stages.is_empty() {
        vec![case.clone()]
    } else {
        file.stages
            .iter()
            .enumerate()
            .map(|(i, st)| {
                let mut c = case.clone();
                c.stages = st.clone();
                c.validate(&format!("{}: stages[{i}]", sweep_path.display()))
                    .map(|()| c)
                    .map_err(|e| bad(e.to_string()))
            })
            .collect::<Result<Vec<_>, _>>()?
    };
    let t = std::time::Instant::now();
    let model = Model::build(&case, case_path).map_err(|e| bad(e.to_string()))?;
    let e_star = model.contact.as_ref().map(|c| c.e_star).expect("contact");
    let mut laws = file
        .friction
        .iter()
        .enumerate()
        .map(|(i, f)| {
            f.resolve(e_star)
                .map_err(|e| bad(format!("{}: friction[{i}]: {e}", sweep_path.display())))
        })
        .collect::<Result<Vec<_>, _>>()?;
    if laws.is_empty() {
        laws.push(model.friction.clone().ok_or_else(|| {
            bad(format!(
                "{}: the case has no friction law; list laws under `friction`",
                case_path.display()
            ))
        })?);
    }
    let build_s = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let rows = sweep(&model, &loads, &laws);
    let sweep_s = t.elapsed().as_secs_f64();
    let out_dir = out.unwrap_or_else(|| {
        PathBuf::from("out").join(format!(
            "{}_sweep",
            case_path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default()
        ))
    });
    std::fs::create_dir_all(&out_dir).map_err(|e| (4, format!("{}: {e}", out_dir.display())))?;
    let w = |name: &str, bytes: &[u8]| {
        output::write_atomic(&out_dir.join(name), bytes)
            .map_err(|e| (4u8, format!("{}: {e}", out_dir.join(name).display())))
    };
    w("sweep.csv", table(&rows).as_bytes())?;
    let json = serde_json::json!({"case": case_path.display().to_string(), "build_s": build_s, "sweep_s": sweep_s, "threads": rayon::current_num_threads(), "rows": rows});
    w(
        "sweep.json",
        serde_json::to_string_pretty(&json)
            .expect("serialisable")
            .as_bytes(),
    )?;
    if !quiet {
        eprintln!(
            "{} laws × {} loads on {} ({} triangles): model built in {build_s:.2} s, sweep {sweep_s:.2} s; table in {}",
            laws.len(),
            loads.len(),
            case_path.display(),
            model.elems.len(),
            out_dir.join("sweep.csv").display()
        );
    }
    Ok(())
}

/// The sweep table as CSV.
pub fn table(rows: &[SweepRow]) -> String {
    let mut s = String::from(
        "index,load_index,f_s,f_d,delta,lambda,chi,psi,load,q_max,apparent_friction,apparent_friction_jkr,apparent_friction_dcm,c,b,steps,newton_iterations,wall_s,resolved,status,failed_checks\n",
    );
    let o = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.9e}"));
    for r in rows {
        let f = r.friction.as_ref();
        s += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{:.9e},{:.9e},{},{},{:.4},{},\"{}\",{}\n",
            r.index,
            r.load_index,
            o(f.map(|f| f.f_s)),
            o(f.and_then(|f| f.f_d)),
            o(f.and_then(|f| f.delta)),
            o(f.and_then(|f| f.lambda)),
            o(f.and_then(|f| f.chi)),
            o(f.and_then(|f| f.psi)),
            o(f.map(|f| f.load)),
            o(f.map(|f| f.q_max)),
            o(f.map(|f| f.apparent_friction)),
            o(f.and_then(|f| f.apparent_friction_jkr)),
            o(f.and_then(|f| f.apparent_friction_dcm)),
            r.c,
            r.b,
            r.steps,
            r.newton_iterations,
            r.wall_s,
            f.and_then(|f| f.resolved)
                .map_or(String::new(), |b| b.to_string()),
            r.status.replace('"', "'"),
            r.checks
                .iter()
                .filter(|c| c.level != crate::checks::Level::Ok)
                .map(|c| c.name)
                .collect::<Vec<_>>()
                .join(";")
        );
    }
    s
}

/// One row of a sweep: a friction law run on the shared model.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// Index of the friction law and of the load (stage list) in the sweep file.
    pub index: usize,
    pub load_index: usize,
    pub status: String,
    pub steps: usize,
    pub newton_iterations: usize,
    /// Factorisations of the contact Newton solves (see [`Summary::lu_factorisations`]).
    pub lu_factorisations: usize,
    pub wall_s: f64,
    /// Stick and transition semi-widths at the last converged step.
    pub c: f64,
    pub b: f64,
    pub friction: Option<FrictionSummary>,
    /// The self-checks of the last converged step (an error-level one fails the row).
    pub checks: Vec<crate::checks::Check>,
}

/// Runs each of `loads` (cases that differ from the model's in their stages only) with each
/// friction law on one built model, in parallel, and returns one row per (load, law) pair,
/// loads outermost, in the order given. The model (assembly, factorisation, condensation,
/// Delassus operator) is shared: stages change only the loads, never the matrices.
pub fn sweep(
    model: &Model,
    loads: &[Case],
    laws: &[crate::friction::FrictionLaw],
) -> Vec<SweepRow> {
    use rayon::prelude::*;
    let jobs: Vec<(usize, usize)> = (0..loads.len())
        .flat_map(|l| (0..laws.len()).map(move |i| (l, i)))
        .collect();
    jobs.par_iter()
        .map(|&(load_index, index)| {
            let (case, law) = (&loads[load_index], &laws[index]);
            let t = Instant::now();
            let res = simulate(model, case, Some(law), LogLevel::Error, &mut |_| Ok(()));
            let wall_s = t.elapsed().as_secs_f64();
            match res {
                Ok(mut sim) => {
                    let last = sim.records.last().and_then(|r| r.contact);
                    let q_max = sim
                        .records
                        .iter()
                        .filter_map(|r| r.pilot)
                        .map(|p| p.fx.abs())
                        .fold(0.0, f64::max);
                    let friction = friction_summary(model, Some(law), last, q_max);
                    let checks = final_checks(
                        model,
                        sim.last_u.take(),
                        sim.last_state.as_ref(),
                        sim.last_scale,
                        &sim.records,
                        friction.as_ref(),
                    );
                    let (_, status) =
                        judge(sim.failure, sim.lost_equilibrium, friction.as_ref(), &checks);
                    SweepRow {
                        index,
                        load_index,
                        status,
                        steps: sim.records.len(),
                        newton_iterations: sim.newton_iterations,
                        lu_factorisations: sim.lu_factorisations,
                        wall_s,
                        c: last.map_or(0.0, |f| f.c),
                        b: last.map_or(0.0, |f| f.b),
                        friction,
                        checks,
                    }
                }
                Err(e) => SweepRow {
                    index,
                    load_index,
                    status: format!("error: {e}"),
                    steps: 0,
                    newton_iterations: 0,
                    lu_factorisations: 0,
                    wall_s,
                    c: 0.0,
                    b: 0.0,
                    friction: None,
                    checks: Vec::new(),
                },
            }
        })
        .collect()
}
