//! Shared by the bench targets: run the `stickslip` binary on a case in its own process.
#![allow(dead_code)]

use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// Runs `stickslip SUBCOMMAND INPUTS… --out OUT --quiet --threads T`, timing the process, and
/// returns whether it succeeded, its wall time and the JSON file `OUT/result` (`Value::Null`
/// if none was written).
fn run_timed(
    subcommand: &str,
    inputs: &[&Path],
    out: &Path,
    threads: &str,
    result: &str,
) -> (bool, f64, Value) {
    let mut args = vec![subcommand];
    args.extend(inputs.iter().map(|p| p.to_str().expect("utf-8 path")));
    args.extend([
        "--out",
        out.to_str().expect("utf-8 path"),
        "--quiet",
        "--threads",
        threads,
    ]);
    let t = std::time::Instant::now();
    let st = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // Cold builds, timed: no model cache.
        .env("STICKSLIP_NO_CACHE", "1")
        .args(&args)
        .status()
        .expect("the stickslip binary runs");
    let wall = t.elapsed().as_secs_f64();
    let json = std::fs::read_to_string(out.join(result))
        .ok()
        .and_then(|s| serde_json::from_str(&s).ok())
        .unwrap_or(Value::Null);
    (st.success(), wall, json)
}

/// Writes `case` to `dir/name.json`, runs it into `dir/name/` with `--quiet --threads T`, and
/// returns whether it exited successfully, the wall time of the process and its `summary.json`
/// (`Value::Null` if none was written).
pub fn run_case(case: &Value, name: &str, dir: &Path, threads: &str) -> (bool, f64, Value) {
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string(case).expect("serialisable"))
        .expect("writable temp dir");
    run_timed("run", &[&path], &dir.join(name), threads, "summary.json")
}

/// Writes `case` to `dir/name.json` and `{"friction": laws}` to `dir/name_sweep.json`, runs
/// `stickslip sweep` on them into `dir/name_sweep/` with `--quiet --threads T`, and returns
/// whether it exited successfully, the wall time of the process and its `sweep.json`
/// (`Value::Null` if none was written).
pub fn run_sweep(
    case: &Value,
    laws: &[Value],
    name: &str,
    dir: &Path,
    threads: &str,
) -> (bool, f64, Value) {
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string(case).expect("serialisable"))
        .expect("writable temp dir");
    let sweep = dir.join(format!("{name}_sweep.json"));
    std::fs::write(&sweep, serde_json::json!({ "friction": laws }).to_string())
        .expect("writable temp dir");
    let out = dir.join(format!("{name}_sweep"));
    run_timed("sweep", &[&path, &sweep], &out, threads, "sweep.json")
}

/// `stickslip analytic ARGS…`: its standard output (panics if the command fails).
pub fn analytic(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // Cold builds, timed: no model cache.
        .env("STICKSLIP_NO_CACHE", "1")
        .arg("analytic")
        .args(args)
        .output()
        .expect("the stickslip binary runs");
    assert!(out.status.success(), "stickslip analytic {args:?} failed");
    String::from_utf8(out.stdout).expect("utf-8 output")
}
