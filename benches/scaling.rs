//! Scaling benchmark (the "speed at scale" issue): the phases of the paper's Fig. 2 run against
//! the number of DOFs over the VM272 ladder, with fitted exponents and the ratios.
//!
//! The case is `cases/fig2.json` as shipped (normal load, 40 tangential steps, VTU every 10th
//! step) with its mesh replaced by `meshes/vm272_L{k}.msh`. L6 and L7 are not committed: they
//! are built on demand by `python3 meshes/generate.py vm272_L6 vm272_L7` (needs
//! `pip install gmsh`); a missing level is skipped with that hint.
//!
//! Each level runs in its own `stickslip` process, timed as a process (wall time). With a
//! model cache (`--cache`), each level runs twice against a fresh cache directory: cold (a
//! miss, the cache written) and warm (a hit); the phases reported are the cold run's. This is
//! repeated `SCALING_REPEAT` times (default 3): the cold run of median wall time gives the
//! row, the warm wall is the median of the warm runs (a shared machine's noise is tens of
//! per cent from one run to the next).
//!
//! Printed (and written to `out/bench/scaling.md`, the table to `out/bench/scaling.csv`):
//! * per level: DOFs, constraint rows, the phases of `summary.json` (`read`, `assemble`,
//!   `analyse`, `factorise` with its `constraint block` part (the dense Delassus operator
//!   `W` and its `L D Lᵀ`, timed apart inside the factorisation), `condense` (`W` handed to
//!   the contact model), `solve` with its
//!   `contact Newton` part, `write` and `write_wait`), the process wall time, peak memory
//!   and peak memory per DOF, the warm run's wall time;
//! * the modelled operations of the numeric factorisation (`factor_flops` of the summary, from
//!   the symbolic analysis: `K̂` itself, the coupling the constraint rows add, the constraint
//!   block), which do not depend on the machine, and the measured `factorise` per operation;
//! * the least-squares exponent of each phase (and of each part of the modelled operations)
//!   against DOFs over `SCALING_FIT` (default L3–L7);
//! * the contact Newton's parts per level (`contact_phases_s` of `summary.json`: Cholesky
//!   factorisations of the Delassus block, the columns `K⁻¹ e_q` of slip rows, direct solves,
//!   the capacitance systems and products with `W`), with its iterations and factorisations;
//! * the ratios: wall / floor of the shipped case on L5 (floor = assemble + analyse +
//!   factorise as they ran: `build_span` of the summary, since the assembly runs alongside
//!   the analysis; the ratio to the three phases summed is printed too), warm / cold wall on
//!   L5, wall / floor on L7, factorise L7 / L5 (and the modelled operations' L7 / L5, the
//!   time ratio the same speed per operation would give); for L5 and L7 also the ratio of every cold
//!   run against its own floor (the row's ratio is the median-wall run's, and the floor
//!   itself moves by a tenth between runs on a shared machine).
//!
//! * a PASS or FAIL line per target of the issue, for this run.
//!
//! Run: `cargo bench --bench scaling`. Environment: `STICKSLIP_THREADS` (default 2),
//! `SCALING_LEVELS` (default `0-7`, or a list `4,5,7`), `SCALING_FIT` (default `3-7`),
//! `SCALING_REPEAT` (default 3).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn levels(var: &str, default: &str) -> Vec<usize> {
    let s = std::env::var(var).unwrap_or_else(|_| default.into());
    if let Some((a, b)) = s.split_once('-') {
        let (a, b): (usize, usize) = (a.trim().parse().unwrap(), b.trim().parse().unwrap());
        (a..=b).collect()
    } else {
        s.split(',').map(|x| x.trim().parse().unwrap()).collect()
    }
}

/// Runs `stickslip run CASE --out OUT --quiet --threads T [extra…]`; returns success, the
/// process wall time and `summary.json`.
fn run(case: &Path, out: &Path, threads: &str, extra: &[&str]) -> (bool, f64, Value) {
    let t = std::time::Instant::now();
    let st = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .arg("run")
        .arg(case)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--threads",
            threads,
        ])
        .args(extra)
        .status()
        .expect("the stickslip binary runs");
    let wall = t.elapsed().as_secs_f64();
    let json = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok())
        .unwrap_or(Value::Null);
    (st.success(), wall, json)
}

/// Whether the binary has a model cache (`--cache DIR`).
fn has_cache() -> bool {
    let out = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args(["run", "--help"])
        .output()
        .expect("the stickslip binary runs");
    String::from_utf8_lossy(&out.stdout).contains("--cache")
}

/// Least-squares slope of log y against log x.
fn slope(pts: &[(f64, f64)]) -> Option<f64> {
    let p: Vec<(f64, f64)> = pts
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if p.len() < 2 {
        return None;
    }
    let n = p.len() as f64;
    let (mx, my) = (
        p.iter().map(|q| q.0).sum::<f64>() / n,
        p.iter().map(|q| q.1).sum::<f64>() / n,
    );
    let sxy: f64 = p.iter().map(|q| (q.0 - mx) * (q.1 - my)).sum();
    let sxx: f64 = p.iter().map(|q| (q.0 - mx).powi(2)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

const PHASES: [&str; 8] = [
    "read",
    "assemble",
    "analyse",
    "factorise",
    "condense",
    "solve",
    "write",
    "write_wait",
];

struct Row {
    level: usize,
    dofs: f64,
    constraints: f64,
    phases: Vec<f64>,
    /// `build_span` of the summary: the wall time from the start of the assembly to the end
    /// of the factorisation (the assembly runs alongside the analysis), 0 if not reported.
    span: f64,
    contact: f64,
    wall: f64,
    warm: Option<f64>,
    peak: f64,
    status: String,
    /// The contact Newton's parts (see [`CONTACT_PARTS`]), iterations and factorisations.
    contact_parts: Vec<f64>,
    iterations: f64,
    factorisations: f64,
    /// Wall / floor of every cold run of the level (each against its own floor), in the order
    /// they ran: the spread the row's single ratio comes from.
    ratios: Vec<f64>,
    /// `timings_s.constraint_block`: the part of `factorise` spent on the dense block of the
    /// contact constraint rows (the Delassus operator `W` and its `L D Lᵀ`).
    block: f64,
    /// `factorise` and `constraint_block` of every cold run, in the order they ran.
    factorise_runs: Vec<(f64, f64)>,
    /// `factor_flops` of the summary: the modelled operations of the numeric factorisation
    /// (`K̂`, the coupling the constraint rows add, the constraint block), zeros if none.
    flops: [f64; 3],
}

const CONTACT_PARTS: [&str; 5] = ["factorise", "columns", "direct", "woodbury", "products"];

/// The median of `v` (the upper one of an even count).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Writes dirty pages out (`sync`), so that one run's files are not flushed during the next.
fn flush() {
    let _ = std::process::Command::new("sync").status();
}

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let threads = std::env::var("STICKSLIP_THREADS").unwrap_or_else(|_| "2".into());
    let work = root.join("out/bench/scaling");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let shipped: Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("cases/fig2.json")).unwrap())
            .unwrap();
    let cache = has_cache();
    let mut rows = Vec::new();
    for l in levels("SCALING_LEVELS", "0-7") {
        let mesh = root.join(format!("meshes/vm272_L{l}.msh"));
        if !mesh.exists() {
            println!(
                "L{l}: {} missing, skipped (build it: python3 meshes/generate.py vm272_L{l})",
                mesh.display()
            );
            continue;
        }
        let mut case = shipped.clone();
        case["mesh"] = Value::String(mesh.to_str().unwrap().into());
        let path = work.join(format!("fig2_L{l}.json"));
        std::fs::write(&path, serde_json::to_string_pretty(&case).unwrap()).unwrap();
        let cache_dir = work.join(format!("cache_L{l}"));
        let cache_args: Vec<&str> = if cache {
            vec!["--cache", cache_dir.to_str().unwrap()]
        } else {
            vec![]
        };
        let repeat: usize = std::env::var("SCALING_REPEAT")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(3)
            .max(1);
        let mut colds = Vec::new();
        let mut warms = Vec::new();
        for k in 0..repeat {
            let _ = std::fs::remove_dir_all(&cache_dir);
            let out = work.join(format!("L{l}_{k}"));
            colds.push(run(&path, &out, &threads, &cache_args));
            // The cold run leaves its cache entry (≈ 0.6 GB at L7) and output in the page
            // cache; flush them outside the timed runs so that the kernel's writeback does not
            // run during the next run's factorisation.
            flush();
            if cache {
                let warm_out = work.join(format!("L{l}_{k}_warm"));
                warms.push(run(&path, &warm_out, &threads, &cache_args).1);
                flush();
            }
        }
        let ratios: Vec<f64> = colds
            .iter()
            .filter_map(|(_, wall, s)| {
                let span = s["timings_s"]["build_span"].as_f64()?;
                (span > 0.0).then(|| wall / span)
            })
            .collect();
        let factorise_runs: Vec<(f64, f64)> = colds
            .iter()
            .map(|(_, _, s)| {
                let t = &s["timings_s"];
                (
                    t["factorise"].as_f64().unwrap_or(0.0),
                    t["constraint_block"].as_f64().unwrap_or(0.0),
                )
            })
            .collect();
        colds.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (ok, wall, s) = colds.swap_remove(colds.len() / 2);
        let warm = cache.then(|| median(&mut warms));
        let t = &s["timings_s"];
        let row = Row {
            level: l,
            dofs: s["dofs_free"].as_f64().unwrap_or(0.0),
            constraints: s["contact_nodes"].as_f64().unwrap_or(0.0) * 2.0,
            phases: PHASES
                .iter()
                .map(|p| t[*p].as_f64().unwrap_or(0.0))
                .collect(),
            span: t["build_span"].as_f64().unwrap_or(0.0),
            contact: s["contact_solve_s"].as_f64().unwrap_or(0.0),
            wall,
            warm,
            peak: s["peak_memory_mib"].as_f64().unwrap_or(0.0),
            contact_parts: CONTACT_PARTS
                .iter()
                .map(|p| s["contact_phases_s"][*p].as_f64().unwrap_or(0.0))
                .collect(),
            iterations: s["newton_iterations"].as_f64().unwrap_or(0.0),
            factorisations: s["lu_factorisations"].as_f64().unwrap_or(0.0),
            ratios,
            block: t["constraint_block"].as_f64().unwrap_or(0.0),
            factorise_runs,
            flops: ["k", "coupling", "constraint_block"]
                .map(|k| s["factor_flops"][k].as_f64().unwrap_or(0.0)),
            // A run that stops early (e.g. exit 5 at a local peak) still has its summary.
            status: match s["status"].as_str() {
                Some(st) => st.chars().take(40).collect::<String>().replace(',', ";"),
                None if ok => "?".into(),
                None => "failed".into(),
            },
        };
        eprintln!("L{l}: {:.2} s, {}", row.wall, row.status);
        rows.push(row);
    }
    let mut md = String::new();
    md += &format!(
        "Fig. 2 (`cases/fig2.json` as shipped, VTU every 10th step), {threads} threads. Times in s.\n\n"
    );
    md += "| L | DOFs | constraint rows | read | assemble | analyse | factorise | of it: constraint block | condense | solve | contact Newton | write | write wait | wall | floor | floor phases summed | wall / floor | warm wall | warm / cold | peak MiB | KiB per DOF | status |\n";
    md += &format!("|{}\n", "---|".repeat(23));
    let mut csv = String::from(
        "level,dofs,constraints,read,assemble,analyse,factorise,condense,solve,write,write_wait,contact_newton,wall,warm_wall,peak_mib,status,build_span,constraint_block,flops_k,flops_coupling,flops_block\n",
    );
    // The floor: the wall time the assembly, analysis and factorisation took together. The
    // assembly overlaps the analysis, so the sum of the three phases counts the overlap
    // twice; the floor is their span as the run reports it (the sum where it does not).
    let sum = |r: &Row| r.phases[1] + r.phases[2] + r.phases[3];
    let floor = |r: &Row| if r.span > 0.0 { r.span } else { sum(r) };
    for r in &rows {
        let p = &r.phases;
        let warm = r.warm.map_or("—".into(), |w| format!("{w:.2}"));
        let ratio = r.warm.map_or("—".into(), |w| format!("{:.2}", w / r.wall));
        md += &format!(
            "| {} | {:.0} | {:.0} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} | {:.0} | {:.2} | {} |\n",
            r.level,
            r.dofs,
            r.constraints,
            p[0],
            p[1],
            p[2],
            p[3],
            r.block,
            p[4],
            p[5],
            r.contact,
            p[6],
            p[7],
            r.wall,
            floor(r),
            sum(r),
            r.wall / floor(r),
            warm,
            ratio,
            r.peak,
            r.peak * 1024.0 / r.dofs,
            r.status
        );
        csv += &format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.level,
            r.dofs,
            r.constraints,
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            p[5],
            p[6],
            p[7],
            r.contact,
            r.wall,
            r.warm.map_or(String::new(), |w| w.to_string()),
            r.peak,
            r.status,
            r.span,
            r.block,
            r.flops[0],
            r.flops[1],
            r.flops[2]
        );
    }
    // The modelled operations: what each level's factorisation has to do, whatever the
    // machine's speed on the day.
    md += "\nModelled operations of the numeric factorisation (`factor_flops` of the summary, from the symbolic analysis: `K̂` itself, the coupling the constraint rows add to its elimination (their rows below every separator they reach and the updates they carry up), the constraint block's own `L D Lᵀ`), and the measured `factorise` per modelled operation.\n\n| L | DOFs | constraint rows | K̂ | coupling | constraint block | total | factorise s | Gflop/s |\n|---|---|---|---|---|---|---|---|---|\n";
    for r in rows.iter().filter(|r| r.flops.iter().sum::<f64>() > 0.0) {
        let total: f64 = r.flops.iter().sum();
        md += &format!(
            "| {} | {:.0} | {:.0} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.3} | {:.1} |\n",
            r.level,
            r.dofs,
            r.constraints,
            r.flops[0],
            r.flops[1],
            r.flops[2],
            total,
            r.phases[3],
            total / r.phases[3] / 1e9
        );
    }
    md += "\nThe contact Newton's parts (s): Cholesky factorisations of the Delassus block `K`, the columns `K⁻¹ e_q` of the rows that differ from `K`, direct solves with the factor, the capacitance systems (Woodbury) and products with `W` for rows outside the system; `other` is the rest (the sets, the equations, the driver's work in the contact solve).\n\n| L | contact rows | Newton iterations | factorisations | contact Newton | factorise | columns | direct | woodbury | products | other |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in &rows {
        let c = &r.contact_parts;
        md += &format!(
            "| {} | {:.0} | {:.0} | {:.0} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
            r.level,
            r.constraints,
            r.iterations,
            r.factorisations,
            r.contact,
            c[0],
            c[1],
            c[2],
            c[3],
            c[4],
            r.contact - c.iter().sum::<f64>()
        );
    }
    let fit = levels("SCALING_FIT", "3-7");
    let fitted: Vec<&Row> = rows.iter().filter(|r| fit.contains(&r.level)).collect();
    md += &format!(
        "\nFitted exponents (least-squares slope of log time against log DOFs over L{}–L{}):\n\n| phase | exponent |\n|---|---|\n",
        fit.first().unwrap(),
        fit.last().unwrap()
    );
    let mut series: Vec<(&str, Vec<(f64, f64)>)> = PHASES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            (
                *name,
                fitted.iter().map(|r| (r.dofs, r.phases[i])).collect(),
            )
        })
        .collect();
    series.push((
        "of factorise: constraint block",
        fitted.iter().map(|r| (r.dofs, r.block)).collect(),
    ));
    series.push((
        "of factorise: the rest",
        fitted
            .iter()
            .map(|r| (r.dofs, r.phases[3] - r.block))
            .collect(),
    ));
    for (k, name) in [
        "modelled operations: K̂",
        "modelled operations: coupling",
        "modelled operations: constraint block",
    ]
    .into_iter()
    .enumerate()
    {
        series.push((name, fitted.iter().map(|r| (r.dofs, r.flops[k])).collect()));
    }
    series.push((
        "contact Newton",
        fitted.iter().map(|r| (r.dofs, r.contact)).collect(),
    ));
    series.push(("floor", fitted.iter().map(|r| (r.dofs, floor(r))).collect()));
    series.push(("wall", fitted.iter().map(|r| (r.dofs, r.wall)).collect()));
    series.push((
        "peak memory",
        fitted.iter().map(|r| (r.dofs, r.peak)).collect(),
    ));
    for (name, pts) in &series {
        let e = slope(pts).map_or("—".into(), |e| format!("{e:.2}"));
        md += &format!("| {name} | {e} |\n");
    }
    let at = |l: usize| rows.iter().find(|r| r.level == l);
    // The ratio of every cold run of a level, and their median and largest.
    let spread = |r: &Row| {
        let mut v = r.ratios.clone();
        if v.len() < 2 {
            return String::new();
        }
        let list: Vec<String> = v.iter().map(|x| format!("{x:.2}")).collect();
        let largest = v.iter().copied().fold(0.0, f64::max);
        format!(
            "; each of the {} cold runs against its own floor: {} (median {:.2}, largest {:.2})",
            v.len(),
            list.join(", "),
            median(&mut v),
            largest
        )
    };
    md += "\nThe issue's ratios (same run):\n\n";
    if let Some(r5) = at(5) {
        md += &format!(
            "* Fig. 2 on L5: process wall / floor (assemble + analyse + factorise, as they ran: the assembly alongside the analysis) = {:.2} / {:.2} = **{:.2}** (target ≤ 1.3); against the three phases summed ({:.2}): {:.2}{}\n",
            r5.wall,
            floor(r5),
            r5.wall / floor(r5),
            sum(r5),
            r5.wall / sum(r5),
            spread(r5)
        );
        if let Some(w) = r5.warm {
            md += &format!(
                "* Fig. 2 on L5, second run (model cache hit) / first: {:.2} / {:.2} = **{:.2}** (target ≤ 0.35)\n",
                w,
                r5.wall,
                w / r5.wall
            );
        }
    }
    if let Some(r7) = at(7) {
        md += &format!(
            "* Fig. 2 on L7: process wall / floor = {:.2} / {:.2} = **{:.2}** (target ≤ 1.5); against the three phases summed ({:.2}): {:.2}{}\n",
            r7.wall,
            floor(r7),
            r7.wall / floor(r7),
            sum(r7),
            r7.wall / sum(r7),
            spread(r7)
        );
        if let Some(r5) = at(5) {
            md += &format!(
                "* factorise L7 / L5 = {:.2} / {:.2} = **{:.1}** (target ≤ 6)\n",
                r7.phases[3],
                r5.phases[3],
                r7.phases[3] / r5.phases[3]
            );
            // Every cold run's factorisation: the row's single ratio pairs two runs whose
            // factorisations each move by a fifth on a shared machine.
            let runs = |r: &Row| {
                let mut f: Vec<f64> = r.factorise_runs.iter().map(|x| x.0).collect();
                let list: Vec<String> = f.iter().map(|x| format!("{x:.3}")).collect();
                (median(&mut f), list.join(", "))
            };
            let ((m7, l7), (m5, l5)) = (runs(r7), runs(r5));
            md += &format!(
                "  * every cold run's factorise: L7 {l7}; L5 {l5}; medians {m7:.3} / {m5:.3} = **{:.1}**\n",
                m7 / m5
            );
            md += &format!(
                "  * of it the constraint block (the dense Delassus operator `W`: its updates, the top separator's columns eliminated from it, its `L D Lᵀ`): L7 {:.3} s, L5 {:.3} s; the rest (the sparse factor of `K̂`, `Y`'s columns carried along) L7 / L5 = {:.2} / {:.2} = {:.1}\n",
                r7.block,
                r5.block,
                r7.phases[3] - r7.block,
                r5.phases[3] - r5.block,
                (r7.phases[3] - r7.block) / (r5.phases[3] - r5.block)
            );
            let (f7, f5) = (r7.flops, r5.flops);
            let (t7, t5): (f64, f64) = (f7.iter().sum(), f5.iter().sum());
            if t7 > 0.0 && t5 > 0.0 {
                md += &format!(
                    "  * modelled operations L7 / L5 (independent of the machine): **{:.1}** in all — `K̂` {:.1}, the coupling {:.1}, the constraint block {:.0}; the coupling and the block alone at L7 are {:.1} × L5's whole factorisation, so at the same speed per operation the time ratio would be {:.1}; L7 ran {:.2} × as many operations per second as L5\n",
                    t7 / t5,
                    f7[0] / f5[0],
                    f7[1] / f5[1],
                    f7[2] / f5[2],
                    (f7[1] + f7[2]) / t5,
                    t7 / t5,
                    (t7 / r7.phases[3]) / (t5 / r5.phases[3])
                );
            }
        }
    }
    // The contact block against the rest of the factorisation, level by level.
    let over: Vec<String> = rows
        .iter()
        .filter(|r| r.block > 0.0 && r.block >= r.phases[3] - r.block)
        .map(|r| format!("L{}", r.level))
        .collect();
    let shares: Vec<String> = rows
        .iter()
        .filter(|r| r.phases[3] > 0.0)
        .map(|r| format!("L{} {:.0} %", r.level, 100.0 * r.block / r.phases[3]))
        .collect();
    md += &format!(
        "* the contact block below the rest of the factorisation at every level: **{}** (its share of `factorise`: {})\n",
        if over.is_empty() {
            "yes".to_string()
        } else {
            format!("no, at {}", over.join(", "))
        },
        shares.join(", ")
    );
    if !cache {
        md += "\n(This binary has no model cache: no warm runs.)\n";
    }
    // One line per target of the issue, as in the sweep bench: what this run shows.
    let mut verdicts = Vec::new();
    let mut verdict = |name: &str, value: f64, limit: f64| {
        let pass = value <= limit;
        verdicts.push(format!(
            "{}: {name} {value:.2} (target ≤ {limit})",
            if pass { "PASS" } else { "FAIL" }
        ));
    };
    if let Some(r5) = at(5) {
        verdict("Fig. 2 on L5, wall / floor", r5.wall / floor(r5), 1.3);
        if let Some(w) = r5.warm {
            verdict("Fig. 2 on L5, second run / first", w / r5.wall, 0.35);
        }
    }
    if let Some(r7) = at(7) {
        verdict("Fig. 2 on L7, wall / floor", r7.wall / floor(r7), 1.5);
        if let Some(r5) = at(5) {
            verdict("factorise L7 / L5", r7.phases[3] / r5.phases[3], 6.0);
        }
    }
    if !verdicts.is_empty() {
        md += &format!("\n{}\n", verdicts.join("\n"));
        md += &format!(
            "{}: the contact block below the rest of the factorisation at every level\n",
            if over.is_empty() { "PASS" } else { "FAIL" }
        );
    }
    println!("{md}");
    std::fs::write(root.join("out/bench/scaling.md"), &md).unwrap();
    std::fs::write(root.join("out/bench/scaling.csv"), &csv).unwrap();
}
