//! Sweeps that outgrow one machine: a grid sweep split into three shards run as separate
//! processes, one of them killed part-way and another cut in the middle of a row, both
//! resumed, then merged, gives the table of the unsharded sweep byte for byte apart from the
//! timings; mismatched parts, missing rows, bad shard numbers and empty grids are refused
//! with a clear message and nothing written.

mod common;
use common::{shipped_case_on, stickslip, tempdir, validation_row};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The grid: 2 loads × (2 shapes × 2 f_s × 1 f_d × 2 Λ) laws = 16 rows.
fn grid() -> Value {
    json!({"grid": {
        "shape": ["ramp", "exponential"],
        "f_s": [0.15, 0.2],
        "f_d": [0.1],
        "lambda": [0.025, 0.1],
        "radius": 4.0,
        "load": 10.0,
        "pilot_x": [{"force": 1.0}, {"force": 1.2}]
    }})
}

const ROWS: usize = 16;

struct Setup {
    dir: PathBuf,
    case: PathBuf,
    sweep: PathBuf,
}

fn setup(name: &str) -> Setup {
    let dir = tempdir(name);
    let v = shipped_case_on("fig2.json", "vm272_L3.msh");
    let case = dir.join("case.json");
    std::fs::write(&case, serde_json::to_string(&v).unwrap()).unwrap();
    let sweep = dir.join("grid.json");
    std::fs::write(&sweep, grid().to_string()).unwrap();
    Setup { dir, case, sweep }
}

fn sweep(s: &Setup, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "sweep",
        s.case.to_str().unwrap(),
        s.sweep.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
    ];
    args.extend_from_slice(extra);
    stickslip(&args)
}

/// The table without its timings: the rows of `sweep.json` without `wall_s`, and `sweep.csv`
/// without its `wall_s` column.
fn without_timings(out: &Path) -> (Vec<Value>, Vec<String>) {
    let table: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let rows = table["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let mut r = r.clone();
            r.as_object_mut().unwrap().remove("wall_s");
            r
        })
        .collect();
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == "wall_s").unwrap();
    let lines = csv
        .lines()
        .map(|l| {
            let mut cols: Vec<&str> = l.split(',').collect();
            cols.remove(k);
            cols.join(",")
        })
        .collect();
    (rows, lines)
}

fn part_lines(path: &Path) -> usize {
    std::fs::read_to_string(path)
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

#[test]
fn three_shards_killed_resumed_and_merged_equal_the_unsharded_sweep() {
    let s = setup("shards");
    let full = s.dir.join("full");
    let (code, _, err) = sweep(&s, &full, &["--quiet"]);
    assert_eq!(code, 0, "{err}");
    let (full_rows, full_csv) = without_timings(&full);
    assert_eq!(full_rows.len(), ROWS);
    // The documented order: loads outermost, then shape, f_s, f_d, Λ fastest.
    for (r, row) in full_rows.iter().enumerate() {
        assert_eq!(row["row"], r);
        assert_eq!(row["load_index"], r / 8);
        assert_eq!(row["index"], r % 8);
        let f = &row["friction"];
        let (fs, lam) = (f["f_s"].as_f64().unwrap(), f["lambda"].as_f64().unwrap());
        assert_eq!(fs, [0.15, 0.2][(r / 2) % 2], "row {r}");
        assert!(
            (lam / [0.025, 0.1][r % 2] - 1.0).abs() < 1e-9,
            "row {r}: Λ {lam}"
        );
        let shape = serde_json::to_string(&f["law"]).unwrap();
        assert!(
            shape.contains(["ramp", "exponential"][(r / 4) % 2]),
            "row {r}: {shape}"
        );
        // Q = 1.0 is below every law's peak; Q = 1.2 passes the peak of the weaker laws
        // (f_s = 0.15, Q_max ≈ 1.05): force control then reports the lost equilibrium.
        let status = row["status"].as_str().unwrap();
        assert!(
            status == "completed" || (r >= 8 && status.starts_with("equilibrium lost")),
            "row {r}: {status}"
        );
    }
    assert!(!full.join("part_0_of_1.jsonl").exists());

    let sh = s.dir.join("sharded");
    // Shard 0 runs whole, numbered by Slurm's array task id.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // No model cache: tests leave the user's cache directory alone.
        .env("STICKSLIP_NO_CACHE", "1")
        .args(["sweep", s.case.to_str().unwrap(), s.sweep.to_str().unwrap()])
        .args([
            "--out",
            sh.to_str().unwrap(),
            "--shard",
            "slurm/3",
            "--quiet",
        ])
        .env("SLURM_ARRAY_TASK_ID", "0")
        .output()
        .unwrap();
    let (code, err) = (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        !sh.join("sweep.csv").exists(),
        "a shard writes its part only"
    );
    // Shard 1 is killed once its part holds a row or two, then started again.
    let part1 = sh.join("part_1_of_3.jsonl");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // No model cache: tests leave the user's cache directory alone.
        .env("STICKSLIP_NO_CACHE", "1")
        .args([
            "sweep",
            s.case.to_str().unwrap(),
            s.sweep.to_str().unwrap(),
            "--out",
            sh.to_str().unwrap(),
            "--threads",
            "1",
            "--shard",
            "1/3",
            "--quiet",
        ])
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while part_lines(&part1) < 2 && t0.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = part_lines(&part1) - 1;
    println!("shard 1 killed with {kept} of 5 rows written");
    let (code, _, err) = sweep(&s, &sh, &["--shard", "1/3"]);
    assert_eq!(code, 0, "{err}");
    if kept < 5 {
        assert!(err.contains("resuming"), "{err}");
    }
    // Shard 2 runs whole, then loses the end of its part in the middle of a row (a kill
    // during a write): the resumed shard drops the half row and runs it again.
    let part2 = sh.join("part_2_of_3.jsonl");
    let (code, _, err) = sweep(&s, &sh, &["--shard", "2/3", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&part2).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let cut = lines[0].len() + 1 + lines[1].len() + 1 + lines[2].len() / 2;
    std::fs::write(&part2, &text.as_bytes()[..cut]).unwrap();
    let (code, _, err) = sweep(&s, &sh, &["--shard", "2/3"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("1 rows already written") && err.contains("cut short dropped"),
        "{err}"
    );
    assert!(err.contains("4 to run"), "{err}");
    // Merge: the same table as the unsharded sweep, apart from the timings.
    let (code, _, err) = stickslip(&["sweep-merge", sh.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (rows, csv) = without_timings(&sh);
    assert_eq!(rows, full_rows);
    assert_eq!(csv, full_csv);
    validation_row(
        "315-sweep-shards",
        "a 16-row grid sweep (2 loads × 2 shapes × 2 f_s × 2 Λ, Fig. 2 on L3) as three shard processes, one killed part-way, one cut in the middle of a row, both resumed, then merged",
        "the unsharded sweep",
        &format!(
            "merged `sweep.json` rows and `sweep.csv` equal to the unsharded sweep's byte for byte apart from the wall times ({ROWS} rows; shard 1 killed with {kept} rows written)"
        ),
        "sweep_shards",
    );
}

#[test]
fn bad_shards_and_merges_are_refused_and_write_nothing() {
    let s = setup("shards-bad");
    // K ≥ N, N = 0, not numbers, Slurm without its variable.
    for (spec, needle) in [
        ("3/3", "must be below N = 3"),
        ("0/0", "N must be at least 1"),
        ("a/2", "not a whole number"),
        ("2", "expected K/N"),
        ("slurm/3", "SLURM_ARRAY_TASK_ID"),
    ] {
        let out = s.dir.join(format!("o-{}", spec.replace('/', "_")));
        let (code, _, err) = if spec.starts_with("slurm") {
            // Outside a job array the variable is absent.
            let o = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
                // No model cache: tests leave the user's cache directory alone.
                .env("STICKSLIP_NO_CACHE", "1")
                .args(["sweep", s.case.to_str().unwrap(), s.sweep.to_str().unwrap()])
                .args(["--out", out.to_str().unwrap(), "--shard", spec])
                .env_remove("SLURM_ARRAY_TASK_ID")
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr).to_string();
            (o.status.code().unwrap_or(-1), String::new(), err)
        } else {
            sweep(&s, &out, &["--shard", spec])
        };
        assert_eq!(code, 2, "--shard {spec}: {err}");
        assert!(
            err.contains(needle) && err.contains(spec),
            "--shard {spec}: {err}"
        );
        assert!(!out.exists(), "--shard {spec} wrote {}", out.display());
    }
    // Empty grid lists, and laws given two ways.
    for (name, v, needle) in [
        (
            "empty-fs",
            json!({"grid": {"f_s": [], "f_d": [0.1], "delta": [1e-3]}}),
            "grid.f_s",
        ),
        (
            "empty-load",
            json!({"grid": {"f_s": [0.2], "f_d": [0.1], "delta": [1e-3], "pilot_x": []}}),
            "grid.pilot_x",
        ),
        (
            "both",
            json!({"friction": [{"shape": "constant", "mu": 0.2}], "grid": {"f_s": [0.2], "f_d": [0.1], "delta": [1e-3]}}),
            "not both",
        ),
        (
            "weakening",
            json!({"grid": {"f_s": [0.1], "f_d": [0.2], "delta": [1e-3]}}),
            "exceeds",
        ),
    ] {
        let file = s.dir.join(format!("{name}.json"));
        std::fs::write(&file, v.to_string()).unwrap();
        let out = s.dir.join(format!("o-{name}"));
        let (code, _, err) = stickslip(&[
            "sweep",
            s.case.to_str().unwrap(),
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(needle) && err.contains(&format!("{name}.json")),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name} wrote output");
    }
    // Two of three shards: the merge reports the missing rows and writes nothing.
    let sh = s.dir.join("sharded");
    for k in ["0/3", "2/3"] {
        let (code, _, err) = sweep(&s, &sh, &["--shard", k, "--quiet"]);
        assert_eq!(code, 0, "{err}");
    }
    let (code, _, err) = stickslip(&["sweep-merge", sh.to_str().unwrap()]);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("5 of 16 rows are missing") && err.contains("rows 1, 4, 7"),
        "{err}"
    );
    assert!(!sh.join("sweep.csv").exists() && !sh.join("sweep.json").exists());
    // A part of another sweep: refused by the merge, and by a shard asked to resume it.
    let mut other = grid();
    other["grid"]["f_d"] = json!([0.12]);
    std::fs::write(&s.sweep, other.to_string()).unwrap();
    let (code, _, err) = sweep(&s, &sh, &["--shard", "0/3"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("another sweep") && err.contains("--fresh"),
        "{err}"
    );
    let elsewhere = s.dir.join("other");
    let (code, _, err) = sweep(&s, &elsewhere, &["--shard", "1/3", "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = stickslip(&[
        "sweep-merge",
        sh.to_str().unwrap(),
        elsewhere.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("different sweeps"), "{err}");
    assert!(!sh.join("sweep.csv").exists());
    // No parts at all.
    let (code, _, err) = stickslip(&["sweep-merge", s.dir.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no sweep parts"), "{err}");
}
