//! Stability study: contact method × friction-law shape × load-step count × mesh size relative
//! to the transition length s0, on the paper's Fig. 2 problem (f_s = 0.15, f_d = 0.1, Λ = 0.05,
//! Q ramped to 0.8 f_d P under force control), and a second table through the peak: method ×
//! shape × control (force control past Q_max, slip control down the softening branch).
//!
//! For every combination: whether it converged, Newton iterations per step, cutbacks, and the
//! error of the stick semi-width against the double Cattaneo–Mindlin c (the same for every
//! shape: they share W = (f_s − f_d)Δ).
//!
//! Run: `cargo bench --bench stability` — prints a markdown table and writes
//! `out/bench/stability.csv`; `python3 post/stability_chart.py out/bench/stability.csv OUT.png`
//! draws the chart.

use serde_json::{Value, json};
use std::path::PathBuf;

#[path = "common/mod.rs"]
mod common;

fn main() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tmp =
        std::env::temp_dir().join(format!("stickslip-bench-stability-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let threads = std::env::var("STICKSLIP_THREADS").unwrap_or_else(|_| "2".into());
    // Double C–M c/a for Q = 0.8 f_d P, Λ = 0.05 (stickslip analytic dcm).
    let dcm: Value = serde_json::from_str(&common::analytic(&[
        "dcm",
        "--fs",
        "0.15",
        "--fd",
        "0.1",
        "--lambda",
        "0.05",
        "--q-ratio",
        "0.8",
    ]))
    .unwrap();
    let c_ref = dcm["c"].as_f64().unwrap();
    let a = 0.680_778;
    let s0 = 2.0 * 0.05 * a / std::f64::consts::PI;
    let mut rows = vec![
        "method,shape,steps,level,h_over_s0,converged,iterations_per_step,cutbacks,c_error,status"
            .to_string(),
    ];
    println!(
        "| method | shape | steps | mesh | h/s0 | converged | Newton its/step | cutbacks | c error vs double C–M |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for method in ["newton", "penalty", "augmented_lagrangian"] {
        for shape in ["step", "ramp", "exponential"] {
            for steps in [5, 20, 80] {
                for level in [2, 3, 4] {
                    let h = a / (3.2 * 2f64.powi(level));
                    let mut v = fig2_variant(&repo, level, method, shape);
                    v["stages"][1]["steps"] = json!(steps);
                    let name = format!("{method}_{shape}_{steps}_L{level}");
                    let (ok, _, s) = common::run_case(&v, &name, &tmp, &threads);
                    let steps_done = s["steps"].as_array().map_or(0, |v| v.len());
                    let its = s["newton_iterations"].as_f64().unwrap_or(0.0);
                    let cut: f64 = s["steps"].as_array().map_or(0.0, |v| {
                        v.iter()
                            .map(|r| r["cutbacks"].as_f64().unwrap_or(0.0))
                            .fold(0.0, f64::max)
                    });
                    let c = s["steps"]
                        .as_array()
                        .and_then(|v| v.last())
                        .and_then(|r| r["contact"]["c"].as_f64())
                        .unwrap_or(f64::NAN);
                    let err = if ok { c / c_ref - 1.0 } else { f64::NAN };
                    let status = s["status"]
                        .as_str()
                        .unwrap_or("no summary")
                        .replace(',', ";");
                    println!(
                        "| {method} | {shape} | {steps} | L{level} | {:.2} | {} | {:.1} | {} | {} |",
                        h / s0,
                        if ok { "yes" } else { "**no**" },
                        its / steps_done.max(1) as f64,
                        cut,
                        if ok {
                            format!("{:+.2} %", 100.0 * err)
                        } else {
                            status.clone()
                        }
                    );
                    rows.push(format!("{method},{shape},{steps},{level},{:.4},{ok},{:.3},{cut},{err:.6},\"{status}\"", h / s0, its / steps_done.max(1) as f64));
                }
            }
        }
    }
    let dir = repo.join("out/bench");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("stability.csv"), rows.join("\n") + "\n").unwrap();
    println!(
        "\n(double C–M c/a = {:.4}; s0 = 2Λa/π = {s0:.4} mm; table in out/bench/stability.csv)",
        c_ref / a
    );
    peak_study(&repo, &tmp, &threads);
    let _ = std::fs::remove_dir_all(&tmp);
}

/// `cases/fig2.json` on VM272 level `level` with the contact method and law shape given, without
/// VTK output.
fn fig2_variant(repo: &std::path::Path, level: i32, method: &str, shape: &str) -> Value {
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(repo.join("cases/fig2.json")).unwrap())
            .unwrap();
    v["mesh"] = json!(
        repo.join(format!("meshes/vm272_L{level}.msh"))
            .to_str()
            .unwrap()
    );
    v["output"] = json!({"vtu": false});
    v["contact"]["method"] = json!(method);
    v["contact"]["friction"]["shape"] = json!(shape);
    v
}

/// Through the peak: method × shape × control on Fig. 2's law. Force control ramps Q to
/// 1.2 f_d P (past Q_max: the run must end with exit status 5 and Q_max bracketed); slip
/// control drives the mean slip to 2.72e-3 mm (past the peak, before the stick zone vanishes on
/// L4, see tests/onset.rs). Records the exit status, Q_max against the JKR limit, how far the
/// stick zone shrank past the peak, iterations per step and cutbacks.
fn peak_study(repo: &std::path::Path, tmp: &std::path::Path, threads: &str) {
    let q_jkr = 1.074_709; // stickslip analytic jkr --psi 0.0125
    let a = 0.680_778;
    let mut rows = vec![
        "method,shape,control,level,exit,q_max,q_max_vs_jkr,c_peak_over_a,c_lowest_over_a,steps_past_peak,iterations_per_step,max_cutbacks"
            .to_string(),
    ];
    println!("\n### Through the peak (Fig. 2's law, Ψ = 0.0125, JKR Q_max = {q_jkr} f_d P)\n");
    println!(
        "| method | shape | control | mesh | exit | Q_max/(f_d P) | vs JKR | c/a at peak | lowest c/a past it | steps past it | Newton its/step | max cutbacks |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for method in ["newton", "penalty", "augmented_lagrangian"] {
        for shape in ["step", "ramp", "exponential"] {
            for control in ["force", "slip"] {
                for level in [3, 4] {
                    let mut v = fig2_variant(repo, level, method, shape);
                    v["stages"][1] = if control == "force" {
                        json!({"steps": 40, "pilot_x": {"force": 1.2}})
                    } else {
                        json!({"steps": 109, "pilot_x": {"slip": 0.00272}})
                    };
                    let name = format!("peak_{method}_{shape}_{control}_L{level}");
                    let (_, _, s) = common::run_case(&v, &name, tmp, threads);
                    let status = s["status"].as_str().unwrap_or("no summary");
                    let exit = if status == "completed" {
                        0
                    } else if status.starts_with("equilibrium lost") {
                        5
                    } else {
                        3
                    };
                    let steps: Vec<&Value> = s["steps"]
                        .as_array()
                        .map(|v| v.iter().filter(|r| r["stage"] == 1).collect())
                        .unwrap_or_default();
                    let q: Vec<f64> = steps
                        .iter()
                        .map(|r| r["pilot"]["fx"].as_f64().unwrap_or(0.0))
                        .collect();
                    let c: Vec<f64> = steps
                        .iter()
                        .map(|r| r["contact"]["c"].as_f64().unwrap_or(0.0) / a)
                        .collect();
                    let i = (0..q.len()).fold(0, |m, k| if q[k] > q[m] { k } else { m });
                    let q_max = s["friction"]["q_max"].as_f64().unwrap_or(f64::NAN);
                    let c_peak = c.get(i).copied().unwrap_or(f64::NAN);
                    let c_low = c[i.min(c.len().saturating_sub(1))..]
                        .iter()
                        .cloned()
                        .fold(f64::INFINITY, f64::min);
                    let past = q.len().saturating_sub(i + 1);
                    let its = s["newton_iterations"].as_f64().unwrap_or(0.0)
                        / s["steps"].as_array().map_or(1, |v| v.len().max(1)) as f64;
                    let cut = steps
                        .iter()
                        .map(|r| r["cutbacks"].as_f64().unwrap_or(0.0))
                        .fold(0.0, f64::max);
                    println!(
                        "| {method} | {shape} | {control} | L{level} | {exit} | {q_max:.5} | {:+.2} % | {c_peak:.3} | {} | {past} | {its:.1} | {cut} |",
                        100.0 * (q_max / q_jkr - 1.0),
                        if past > 0 {
                            format!("{c_low:.3}")
                        } else {
                            "—".into()
                        },
                    );
                    rows.push(format!(
                        "{method},{shape},{control},{level},{exit},{q_max:.6},{:.6},{c_peak:.4},{c_low:.4},{past},{its:.3},{cut}",
                        q_max / q_jkr - 1.0
                    ));
                }
            }
        }
    }
    let dir = repo.join("out/bench");
    std::fs::write(dir.join("stability_peak.csv"), rows.join("\n") + "\n").unwrap();
    println!("\n(table in out/bench/stability_peak.csv)");
}
