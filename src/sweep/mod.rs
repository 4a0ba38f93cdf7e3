//! `stickslip sweep`: one case, many friction laws and/or loads, one shared model, one table.
//!
//! The rows ([`grid`]) are the product of the loads (outermost) and the laws; a sweep may be
//! split into shards (`--shard K/N`: rows `r` with `r mod N = K`), each appending its rows to
//! its own part file as they finish ([`parts`]), so that a shard killed and started again
//! does only the rows it has not written; the parts merge into `sweep.csv` and `sweep.json`.
//! An unsharded sweep is the one shard `0/1`, merged at the end.

pub mod grid;
pub mod parts;

use crate::case::Case;
use crate::error::SweepError;
use crate::model::Model;
use crate::record::FrictionSummary;
use crate::report::{final_checks, friction_summary, judge};
use crate::run::{LogLevel, simulate};
use serde::Serialize;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

pub use grid::SweepFile;

/// Options of `stickslip sweep`.
#[derive(Clone, Debug, Default)]
pub struct SweepOptions {
    /// Output directory (default `out/<case name>_sweep`).
    pub out: Option<PathBuf>,
    pub quiet: bool,
    /// `(K, N)`: run shard K of N (rows with `row mod N = K`) and write its part only.
    pub shard: Option<(usize, usize)>,
    /// Discard this shard's part if it exists instead of resuming it.
    pub fresh: bool,
    /// The model cache (`--cache DIR`, `--no-cache`; see [`crate::cache`]).
    pub cache: crate::cache::Choice,
}

/// Parses `K/N` (or `slurm/N`: K from `SLURM_ARRAY_TASK_ID`) into a shard, `0 ≤ K < N`.
pub fn parse_shard(spec: &str) -> Result<(usize, usize), SweepError> {
    let bad = |why: String| SweepError::Shard {
        spec: spec.to_string(),
        why,
    };
    let (k, n) = spec
        .split_once('/')
        .ok_or_else(|| bad("expected K/N (e.g. 0/4) or slurm/N".into()))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| bad(format!("N = `{n}` is not a whole number")))?;
    let k: usize = if k.trim().eq_ignore_ascii_case("slurm") {
        let v = std::env::var("SLURM_ARRAY_TASK_ID")
            .map_err(|_| bad("SLURM_ARRAY_TASK_ID is not set (not in a Slurm job array)".into()))?;
        v.trim()
            .parse()
            .map_err(|_| bad(format!("SLURM_ARRAY_TASK_ID = `{v}` is not a whole number")))?
    } else {
        k.trim()
            .parse()
            .map_err(|_| bad(format!("K = `{k}` is not a whole number")))?
    };
    if n == 0 {
        return Err(bad("N must be at least 1".into()));
    }
    if k >= n {
        return Err(bad(format!(
            "K = {k} must be below N = {n} (shards are numbered 0 to N − 1; with Slurm use --array=0-{})",
            n - 1
        )));
    }
    Ok((k, n))
}

/// Runs a sweep (or one shard of it) from the command line.
pub fn run(case_path: &Path, sweep_path: &Path, opts: &SweepOptions) -> Result<(), SweepError> {
    let case = Case::load(case_path)?;
    let input = |key: &str, why: &str| SweepError::Input {
        path: case_path.display().to_string(),
        key: key.into(),
        why: why.into(),
    };
    if case.contact.is_none() {
        return Err(input("", "a sweep needs a case with `contact`"));
    }
    let read = |p: &Path| {
        std::fs::read(p).map_err(|source| SweepError::Read {
            path: p.display().to_string(),
            source,
        })
    };
    let sweep_bytes = read(sweep_path)?;
    let file: SweepFile =
        serde_json::from_slice(&sweep_bytes).map_err(|source| SweepError::Parse {
            path: sweep_path.display().to_string(),
            source,
        })?;
    let rows = grid::expand(&case, &file, sweep_path)?;
    if rows.laws.is_empty() && case.contact.as_ref().is_some_and(|c| c.friction.is_none()) {
        return Err(input(
            "contact.friction",
            "the case has no friction law; list laws under `friction` or `grid` in the sweep file",
        ));
    }
    let (k, n) = opts.shard.unwrap_or((0, 1));
    let total = rows.len();
    // With the program's build and contact path, as a restart state's: rows of another build
    // or path can differ in the last digits, and the merged table must be the one an unsharded
    // sweep writes.
    let (case_bytes, mesh_bytes) = (read(case_path)?, read(&case.mesh_path(case_path))?);
    let id = crate::restart::program_identity(&[&case_bytes, &mesh_bytes, &sweep_bytes]);
    let out_dir = opts.out.clone().unwrap_or_else(|| {
        PathBuf::from("out").join(format!(
            "{}_sweep",
            case_path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default()
        ))
    });
    let header = json!({
        "sweep_id": id,
        "case": case_path.display().to_string(),
        "sweep": sweep_path.display().to_string(),
        "rows": total,
        "shard": k,
        "shards": n,
        "contact_shortcuts_from": crate::contact::solver::shortcuts_from(),
    });
    let part_path = out_dir.join(parts::part_name(k, n));
    // A part of another sweep is refused before the model is built.
    let existing = parts::PartWriter::existing(&part_path, &header, opts.fresh)?;
    let t = Instant::now();
    let store = crate::cache::Store::resolve(&opts.cache, !opts.quiet);
    let model = Model::build_cached(&case, case_path, None, store.as_ref().ok())?;
    // Each load's weakened patches hold a node of the slave face (named as the grid names
    // its loads).
    for (i, c) in rows.loads.iter().enumerate() {
        let at = if file.stages.is_empty() {
            case_path.display().to_string()
        } else {
            format!("{}: load {i}", sweep_path.display())
        };
        model.refuse_empty_patches(c, &at)?;
    }
    let e_star = model.contact.as_ref().map(|c| c.e_star).expect("contact");
    let mut laws = rows
        .laws
        .iter()
        .map(|f| f.resolve(e_star).map(|l| (l, f.history)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(crate::error::ModelError::Friction)?;
    if laws.is_empty() {
        let history = case.contact.as_ref().and_then(|c| c.friction.as_ref());
        laws.push((
            model.friction.clone().expect("checked above"),
            history.map_or_else(Default::default, |f| f.history),
        ));
    }
    let build_s = t.elapsed().as_secs_f64();
    std::fs::create_dir_all(&out_dir).map_err(|source| SweepError::Write {
        path: out_dir.display().to_string(),
        source,
    })?;
    let (writer, done, dropped) = parts::PartWriter::open(&part_path, &header, existing)?;
    let todo: Vec<usize> = (0..total)
        .filter(|r| r % n == k && !done.contains_key(r))
        .collect();
    if !opts.quiet && (!done.is_empty() || dropped > 0) {
        eprintln!(
            "resuming {}: {} rows already written{}, {} to run",
            part_path.display(),
            done.len(),
            if dropped > 0 {
                format!(" ({dropped} bytes of a row cut short dropped)")
            } else {
                String::new()
            },
            todo.len()
        );
    }
    let t = Instant::now();
    let writer = Mutex::new(writer);
    sweep(&model, &rows.loads, &laws, &todo, &|row: SweepRow| {
        let v = serde_json::to_value(&row).expect("serialisable");
        writer.lock().expect("not poisoned").append(&v)
    })?;
    let sweep_s = t.elapsed().as_secs_f64();
    let mut writer = writer.into_inner().expect("not poisoned");
    writer.append(&json!({"run": {
        "shard": k, "shards": n, "rows_run": todo.len(), "build_s": build_s,
        "sweep_s": sweep_s, "threads": rayon::current_num_threads(),
    }}))?;
    drop(writer);
    if !opts.quiet {
        eprintln!(
            "{} laws × {} loads on {} ({} triangles), shard {k}/{n}: {} rows run; model built in {build_s:.2} s, rows {sweep_s:.2} s",
            laws.len(),
            rows.loads.len(),
            case_path.display(),
            model.elems.len(),
            todo.len(),
        );
    }
    if opts.shard.is_none() {
        // The whole sweep in one part: merge it now, then drop the part so that a rerun
        // starts afresh (a run killed before this point resumes instead).
        parts::merge(std::slice::from_ref(&part_path), Some(&out_dir))?;
        let _ = std::fs::remove_file(&part_path);
        if !opts.quiet {
            eprintln!("table in {}", out_dir.join("sweep.csv").display());
        }
    } else if !opts.quiet {
        eprintln!(
            "part in {}; when every shard is done: stickslip sweep-merge {}",
            part_path.display(),
            out_dir.display()
        );
    }
    Ok(())
}

/// The sweep table as CSV, from the rows as JSON (`sweep.json`'s `rows`).
pub fn table(rows: &[Value]) -> String {
    let mut s = String::from(
        "row,index,load_index,f_s,f_d,delta,lambda,chi,psi,load,q_max,apparent_friction,apparent_friction_jkr,apparent_friction_dcm,c,b,steps,newton_iterations,wall_s,resolved,status,failed_checks\n",
    );
    let num = |v: &Value| v.as_f64().map_or(String::new(), |x| format!("{x:.9e}"));
    let int = |v: &Value| v.as_u64().map_or(String::new(), |x| x.to_string());
    for r in rows {
        let f = &r["friction"];
        let fcols: Vec<String> = [
            "f_s",
            "f_d",
            "delta",
            "lambda",
            "chi",
            "psi",
            "load",
            "q_max",
            "apparent_friction",
            "apparent_friction_jkr",
            "apparent_friction_dcm",
        ]
        .iter()
        .map(|k| num(&f[*k]))
        .collect();
        let failed: Vec<&str> = r["checks"]
            .as_array()
            .map(|cs| {
                cs.iter()
                    .filter(|c| c["level"] != "ok")
                    .filter_map(|c| c["name"].as_str())
                    .collect()
            })
            .unwrap_or_default();
        s += &format!(
            "{},{},{},{},{},{},{},{},{:.4},{},\"{}\",{}\n",
            int(&r["row"]),
            int(&r["index"]),
            int(&r["load_index"]),
            fcols.join(","),
            num(&r["c"]),
            num(&r["b"]),
            int(&r["steps"]),
            int(&r["newton_iterations"]),
            r["wall_s"].as_f64().unwrap_or(0.0),
            f["resolved"]
                .as_bool()
                .map_or(String::new(), |b| b.to_string()),
            r["status"].as_str().unwrap_or("").replace('"', "'"),
            failed.join(";")
        );
    }
    s
}

/// One row of a sweep: a friction law run on the shared model.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// The row number: `load_index × laws + index`.
    pub row: usize,
    /// Index of the friction law and of the load (stage list) in the sweep.
    pub index: usize,
    pub load_index: usize,
    pub status: String,
    pub steps: usize,
    pub newton_iterations: usize,
    /// Factorisations of the contact Newton solves (see [`crate::report::Summary::lu_factorisations`]).
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
    laws: &[(crate::friction::FrictionLaw, crate::friction::History)],
    rows: &[usize],
    on_row: &(dyn Fn(SweepRow) -> Result<(), SweepError> + Sync),
) -> Result<(), SweepError> {
    use rayon::prelude::*;
    // The rows factorise the same Delassus blocks: once for all of them.
    // The element geometry is not kept for the rows' equilibrium checks: eight rows checked
    // in one pass map each element once for all of them, as fast as reading it kept (29 MB
    // on L5; the sweep's peak 392–405 MB with it, 363–373 MB without, the same wall time).
    if rows.len() > 1 {
        model.share_contact_blocks();
    }
    // The rows run in chunks of eight per thread; the fields the checks need are recovered for
    // a whole chunk in one block solve, which reads the factor (≈ 200 MB on L5) once instead of
    // once per row.
    let chunk = 8 * rayon::current_num_threads().max(1);
    for part in rows.chunks(chunk) {
        let mut runs: Vec<_> = part
            .par_iter()
            .map(|&row| {
                let (load_index, index) = (row / laws.len(), row % laws.len());
                let (law, history) = &laws[index];
                // The row's case: the load's, with the row's law (and its history) as its
                // friction.
                let mut case = loads[load_index].clone();
                if let Some(c) = case.contact.as_mut() {
                    c.friction = Some(crate::case::FrictionSpec {
                        kind: crate::case::FrictionKind::Law(law.clone()),
                        history: *history,
                    });
                }
                let t = Instant::now();
                let res = simulate(model, &case, Some(law), LogLevel::Error, &mut |_| Ok(()));
                (row, t.elapsed().as_secs_f64(), res)
            })
            .collect();
        crate::trace::mark("sweep: rows solved");
        if model.contact.is_some() {
            // The runs whose checks need a field: (index in `runs`, traction scale, state).
            let need: Vec<(usize, f64, &crate::contact::solver::State)> = runs
                .iter()
                .enumerate()
                .filter_map(|(k, (_, _, res))| match res {
                    Ok(sim) if sim.last_u.is_none() => {
                        sim.last_state.as_ref().map(|st| (k, sim.last_scale, st))
                    }
                    _ => None,
                })
                .collect();
            // One block solve, its columns split over the threads (a group of up to eight
            // interleaved columns per thread, each group one read of the factor).
            let states: Vec<_> = need.iter().map(|&(_, scale, st)| (scale, st)).collect();
            let fields: Vec<(usize, Vec<f64>)> = need
                .iter()
                .map(|&(k, _, _)| k)
                .zip(model.contact_displacements(&states, true))
                .collect();
            for (k, u) in fields {
                if let Ok(sim) = &mut runs[k].2 {
                    sim.last_u = Some(u);
                }
            }
            crate::trace::mark("sweep: fields recovered");
        }
        // The rows' equilibrium checks: eight fields per pass over the elements, a group of
        // rows per thread (the same numbers as each row's own).
        let (ks, inputs): (Vec<usize>, Vec<crate::checks::Input>) = runs
            .iter()
            .enumerate()
            .filter_map(|(k, (_, _, res))| match res {
                Ok(sim) => sim.last_u.as_ref().map(|u| {
                    let inp = crate::checks::Input {
                        model,
                        u,
                        scale: sim.last_scale,
                        state: sim.last_state.as_ref(),
                        records: &sim.records,
                        friction: None,
                        equilibrium: None,
                    };
                    (k, inp)
                }),
                _ => None,
            })
            .unzip();
        let per = inputs
            .len()
            .div_ceil(rayon::current_num_threads().max(1))
            .clamp(1, 8);
        let checked: Vec<crate::checks::Check> = inputs
            .par_chunks(per)
            .flat_map_iter(crate::checks::equilibrium_many)
            .collect();
        drop(inputs);
        // Each run's equilibrium check, by its index in `runs`.
        let mut equilibria: Vec<Option<crate::checks::Check>> = vec![None; runs.len()];
        for (k, check) in ks.into_iter().zip(checked) {
            equilibria[k] = Some(check);
        }
        crate::trace::mark("sweep: rows' equilibrium");
        runs.into_par_iter()
            .zip(equilibria)
            .map(|((row, wall_s, res), equilibrium)| {
                row_of(model, laws, row, wall_s, res, equilibrium)
            })
            .try_for_each(on_row)?;
        crate::trace::mark("sweep: rows checked");
    }
    Ok(())
}

/// The sweep row of one run: its friction figures, self-checks and status (`equilibrium`: the
/// equilibrium check of its last step, computed already).
fn row_of(
    model: &Model,
    laws: &[(crate::friction::FrictionLaw, crate::friction::History)],
    row: usize,
    wall_s: f64,
    res: Result<crate::driver::Simulation, crate::error::RunError>,
    equilibrium: Option<crate::checks::Check>,
) -> SweepRow {
    let (load_index, index) = (row / laws.len(), row % laws.len());
    let law = &laws[index].0;
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
                equilibrium,
            );
            let (_, status) = judge(
                sim.failure,
                sim.lost_equilibrium,
                friction.as_ref(),
                &checks,
            );
            SweepRow {
                row,
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
            row,
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
}
