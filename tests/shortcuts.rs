//! The structured contact solve's shortcuts (each iteration started from the step's last direct
//! solve, the slip rows linearised at the solve's `W μ`), on from 768 contact unknowns (L5 up),
//! against the same runs with every iteration solved directly
//! (`STICKSLIP_CONTACT_SHORTCUTS=off`), on L5:
//!
//! * the shipped Fig. 2: every column of `history.csv` within 2e-9 of its largest value (the
//!   contact centre, which is zero by symmetry up to 3e-5 mm, within 2e-9 of the contact
//!   semi-width), the same contact sets in every step; 179 Newton iterations with the
//!   shortcuts and 183–191 without (189 measured: the count moves with the factor's last
//!   bits);
//! * Fig. 2 with f_s = 0.2, Λ = 0.025 loaded past its peak under force control: both runs
//!   bracket Q_max (exit 5) and agree on it within 5e-4 of it (2.9e-4 measured): near the
//!   peak, where the tangent is nearly singular, the digit the shortcuts lose decides at which
//!   load a step still converges, and L5 does not resolve this law's s0, so the cutbacks that
//!   follow try other loads;
//! * a restart state written with the shortcuts is refused by a run without them (its id says
//!   which), and resumes with them; a sweep shard's part likewise.

mod common;

use common::{Table, shipped_case_on, stickslip_env, tempdir};
use serde_json::{Value, json};
use std::path::PathBuf;

/// The environment of a run with the shortcuts allowed or not.
fn setting(shortcuts: bool) -> &'static [(&'static str, &'static str)] {
    if shortcuts {
        &[]
    } else {
        &[("STICKSLIP_CONTACT_SHORTCUTS", "off")]
    }
}

/// Runs `case` with the shortcuts allowed or not; returns (exit status, output directory).
fn run(name: &str, case: &Value, shortcuts: bool) -> (i32, PathBuf) {
    let dir = tempdir(&format!("shortcuts-{name}-{shortcuts}"));
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string(case).unwrap()).unwrap();
    let out = dir.join("out");
    let (code, _, stderr) = stickslip_env(
        &[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
        setting(shortcuts),
    );
    assert!(code == 0 || code == 5, "{name}: exit {code}: {stderr}");
    (code, out)
}

fn summary(out: &std::path::Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn fig2_l5() -> Value {
    let mut v = shipped_case_on("fig2.json", "vm272_L5.msh");
    v["output"] = json!({"vtu": false});
    v
}

#[test]
fn the_shortcuts_give_fig2_on_l5_within_round_off_of_direct_solves() {
    let case = fig2_l5();
    let (_, with) = run("fig2", &case, true);
    let (_, without) = run("fig2", &case, false);
    let (a, b) = (
        Table::read(&with.join("history.csv")),
        Table::read(&without.join("history.csv")),
    );
    assert_eq!(a.header, b.header);
    assert_eq!(a.rows.len(), 41);
    assert_eq!(b.rows.len(), 41);
    let col = |name: &str| a.header.iter().position(|h| h == name).unwrap();
    let semi_width = a.rows.iter().map(|r| r[col("a")]).fold(0.0, f64::max);
    for (k, name) in a.header.iter().enumerate() {
        if name == "wall_s" || name == "iterations" {
            continue;
        }
        let size = a
            .rows
            .iter()
            .chain(&b.rows)
            .map(|r| r[k].abs())
            .fold(0.0, f64::max);
        let scale = if name == "x_centre" { semi_width } else { size };
        let worst = a
            .rows
            .iter()
            .zip(&b.rows)
            .map(|(x, y)| (x[k] - y[k]).abs())
            .fold(0.0, f64::max);
        // K_II is a least-squares fit to the tractions over the stick zone, whose conditioning
        // amplifies their round-off (measured 4.1e-9 of the largest K_II).
        let tol = if name.starts_with("k2_") { 1e-8 } else { 2e-9 };
        assert!(
            worst <= tol * scale,
            "{name}: differs by {worst:e} against {scale:e}"
        );
        if ["n_contact", "n_stick", "n_slip", "c", "b"].contains(&name.as_str()) {
            assert_eq!(worst, 0.0, "{name}: the contact sets differ");
        }
    }
    let (sa, sb) = (summary(&with), summary(&without));
    assert_eq!(sa["newton_iterations"], json!(179));
    // Without the shortcuts the count moves with the last bits of the factor, which round-off
    // sets (the order of the sums in the dense kernels): 189 with the tree-scheduled factor
    // (AVX-512), 187 with faer's own loop (`STICKSLIP_FACTOR=faer`).
    let direct = sb["newton_iterations"].as_u64().unwrap();
    assert!((183..=191).contains(&direct), "{direct} iterations without");
    // The summary says which path the run took.
    assert_eq!(sa["contact_shortcuts_from"], json!(768));
    assert_eq!(sb["contact_shortcuts_from"], Value::Null);
}

#[test]
fn the_shortcuts_bracket_a_force_controlled_peak_on_l5_where_direct_solves_do() {
    let mut case = fig2_l5();
    case["contact"]["friction"]["fs"] = json!(0.2);
    case["contact"]["friction"]["lambda"] = json!(0.025);
    case["stages"][1]["pilot_x"] = json!({"force": 1.2});
    case["stages"][1]["steps"] = json!(60);
    let (ca, with) = run("peak", &case, true);
    let (cb, without) = run("peak", &case, false);
    assert_eq!((ca, cb), (5, 5), "both runs lose equilibrium past the peak");
    let q = |out: &std::path::Path| summary(out)["friction"]["q_max"].as_f64().unwrap();
    let (qa, qb) = (q(&with), q(&without));
    // Past f_d P = 1 N/mm (the law weakens to f_d), below f_s P = 2.
    assert!(qa > 1.0 && qa < 2.0, "Q_max {qa}");
    assert!(
        ((qa - qb) / qb).abs() <= 5e-4,
        "Q_max {qa} with the shortcuts, {qb} without"
    );
}

#[test]
fn a_state_resumes_only_with_the_shortcut_setting_that_wrote_it() {
    // Fig. 2 on L3 with a state at every 10th step.
    let mut case = shipped_case_on("fig2.json", "vm272_L3.msh");
    case["output"] = json!({"vtu": true, "every": 10});
    let (_, out) = run("resume", &case, true);
    let dir = out.parent().unwrap().to_path_buf();
    let state = out.join("state_0020.json");
    assert!(state.exists(), "no state at step 20 in {}", out.display());
    let resume = |shortcuts: bool, name: &str| {
        let o = dir.join(name);
        let (code, _, stderr) = stickslip_env(
            &[
                "run",
                dir.join("case.json").to_str().unwrap(),
                "--out",
                o.to_str().unwrap(),
                "--resume",
                state.to_str().unwrap(),
                "--quiet",
            ],
            setting(shortcuts),
        );
        (code, stderr, o)
    };
    let (code, stderr, o) = resume(false, "off");
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("STICKSLIP_CONTACT_SHORTCUTS") && stderr.contains("state_0020.json"),
        "{stderr}"
    );
    assert!(!o.exists(), "a refused resume wrote {}", o.display());
    let (code, stderr, o) = resume(true, "on");
    assert_eq!(code, 0, "{stderr}");
    // The resumed run writes the whole history, as the uninterrupted one did (the files
    // themselves are compared by tests/restart.rs).
    let rows = |d: &std::path::Path| Table::read(&d.join("history.csv")).rows.len();
    assert_eq!((rows(&o), rows(&out)), (41, 41));
}

#[test]
fn a_sweep_part_goes_on_only_with_the_shortcut_setting_that_wrote_it() {
    // Two laws of Fig. 2 on L1, shard 0 of 2 (one row).
    let mut case = shipped_case_on("fig2.json", "vm272_L1.msh");
    case["output"] = json!({"vtu": false});
    let dir = tempdir("shortcuts-shard");
    let (case_path, sweep_path, out) = (
        dir.join("case.json"),
        dir.join("sweep.json"),
        dir.join("out"),
    );
    std::fs::write(&case_path, serde_json::to_string(&case).unwrap()).unwrap();
    let laws = json!({"friction": [
        {"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0},
        {"shape": "ramp", "fs": 0.2, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0}
    ]});
    std::fs::write(&sweep_path, laws.to_string()).unwrap();
    let shard = |envs: &[(&str, &str)]| {
        stickslip_env(
            &[
                "sweep",
                case_path.to_str().unwrap(),
                sweep_path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--shard",
                "0/2",
                "--quiet",
            ],
            envs,
        )
    };
    let (code, _, stderr) = shard(setting(true));
    assert_eq!(code, 0, "{stderr}");
    let part = out.join("part_0_of_2.jsonl");
    // The part's header and rows (each invocation also appends a record of its run).
    let rows_of = |p: &std::path::Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("{\"run\""))
            .map(String::from)
            .collect()
    };
    let before = std::fs::read(&part).unwrap();
    let rows_before = rows_of(&part);
    assert_eq!(rows_before.len(), 2, "a header and one row");
    let (code, _, stderr) = shard(setting(false));
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("another sweep") && stderr.contains("STICKSLIP_CONTACT_SHORTCUTS"),
        "{stderr}"
    );
    assert!(
        std::fs::read(&part).unwrap() == before,
        "the refused shard touched the part"
    );
    // With the setting that wrote it, the shard finds its row done and does not solve it again
    // (so the refusal above was the setting's).
    let (code, _, stderr) = shard(setting(true));
    assert_eq!(code, 0, "{stderr}");
    assert!(
        rows_of(&part) == rows_before,
        "the shard solved its row again"
    );
}
