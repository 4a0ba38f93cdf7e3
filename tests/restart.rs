//! Exact restart: a fretting run (two cycles, L3, a state with every 10th nominal step) killed
//! part-way and resumed with `--resume DIR`, and one whose files after its fourth state were
//! deleted and resumed from that state, write what the uninterrupted run writes, file for file
//! and byte for byte apart from the timings; a state from another case or another build of the
//! program, a directory without a state and a corrupt state are refused with nothing written.
//! States do not grow with the steps (their records are in the journal `steps.jsonl`).

mod common;
use common::{mesh_path, shipped_case, stickslip, tempdir, validation_row};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

const TIMING_KEYS: [&str; 12] = [
    // Counts the journal, whose wall times vary in their digits.
    "output_bytes",
    "factor_flops",
    "cache",
    "timings_s",
    "contact_solve_s",
    "contact_phases_s",
    "peak_memory_mib",
    "wall_s",
    "output_dir",
    "t_solve",
    "t_contact",
    "factorise_s",
];

fn strip(v: &mut Value) {
    match v {
        Value::Object(m) => {
            for k in TIMING_KEYS {
                m.remove(k);
            }
            m.values_mut().for_each(strip);
        }
        Value::Array(a) => a.iter_mut().for_each(strip),
        _ => {}
    }
}

/// Files of `a` and `b` that differ (JSON without timings, CSV without `wall_s`, the rest byte
/// for byte), and the files compared.
fn differences(a: &Path, b: &Path) -> (Vec<String>, usize) {
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        v.sort();
        v
    };
    let (na, nb) = (names(a), names(b));
    assert_eq!(na, nb, "the two runs wrote different files");
    let mut diff = Vec::new();
    for n in &na {
        let (pa, pb) = (a.join(n), b.join(n));
        // JSON, and the journal's JSON lines.
        let json = |p: &PathBuf| -> Vec<Value> {
            std::fs::read_to_string(p)
                .unwrap()
                .lines()
                .filter(|l| !l.trim().is_empty())
                .map(|l| {
                    let mut v: Value = serde_json::from_str(l).unwrap();
                    strip(&mut v);
                    v
                })
                .collect()
        };
        let same = if n.ends_with(".json") {
            let mut va: Value =
                serde_json::from_str(&std::fs::read_to_string(&pa).unwrap()).unwrap();
            let mut vb: Value =
                serde_json::from_str(&std::fs::read_to_string(&pb).unwrap()).unwrap();
            strip(&mut va);
            strip(&mut vb);
            va == vb
        } else if n.ends_with(".jsonl") {
            json(&pa) == json(&pb)
        } else if n.ends_with(".csv") {
            let cols = |p: &PathBuf| -> Vec<Vec<String>> {
                let t = std::fs::read_to_string(p).unwrap();
                let rows: Vec<Vec<String>> = t
                    .lines()
                    .map(|l| l.split(',').map(String::from).collect())
                    .collect();
                match rows[0].iter().position(|h| h == "wall_s") {
                    Some(k) => rows
                        .into_iter()
                        .map(|mut r| {
                            r.remove(k);
                            r
                        })
                        .collect(),
                    None => rows,
                }
            };
            cols(&pa) == cols(&pb)
        } else {
            std::fs::read(&pa).unwrap() == std::fs::read(&pb).unwrap()
        };
        if !same {
            diff.push(n.clone());
        }
    }
    (diff, na.len())
}

fn write_case(dir: &Path) -> PathBuf {
    let mut v = shipped_case("fretting.json");
    v["mesh"] = mesh_path("vm272_L3.msh");
    v["stages"][2]["cycles"]["count"] = json!(2);
    v["output"] = json!({"every": 10});
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    path
}

fn run(case: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = stickslip(&args);
    (code, err)
}

/// The states in `dir` by step, in order (a state is named by its step, which counts the
/// sub-steps of cutbacks too: `state_NNNN.json`).
fn states(dir: &Path) -> Vec<(usize, PathBuf)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<(usize, PathBuf)> = entries
        .filter_map(|e| {
            let p = e.unwrap().path();
            let n = p.file_name()?.to_str()?.to_string();
            let k = n
                .strip_prefix("state_")?
                .strip_suffix(".json")?
                .parse()
                .ok()?;
            Some((k, p))
        })
        .collect();
    v.sort();
    v
}

/// The `n`-th state (from 1) in `dir`: its step and path.
fn nth_state(dir: &Path, n: usize) -> (usize, PathBuf) {
    states(dir)
        .into_iter()
        .nth(n - 1)
        .unwrap_or_else(|| panic!("fewer than {n} states in {}", dir.display()))
}

/// Deletes the files of a run's steps after `step`, and those of no step (the `.pvd`, the
/// history and the summary) but the journal, as a run stopped after `step` leaves its
/// directory.
fn keep_up_to(dir: &Path, step: usize) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let s: Option<usize> = name
            .trim_end_matches(|c: char| !c.is_ascii_digit())
            .rsplit(|c: char| !c.is_ascii_digit())
            .next()
            .and_then(|s| s.parse().ok());
        // The journal of step records stays (a resumed run reads its first lines).
        if name == "steps.jsonl" {
            continue;
        }
        if s.is_some_and(|s| s > step) || !name.contains('_') || name.ends_with(".pvd") {
            std::fs::remove_file(&p).unwrap();
        }
    }
}

/// Fig. 2 as shipped but on L6 (built by gmsh when not in `meshes/`): 2 026 contact unknowns,
/// so its first contact starts from the frictionless contact set and the structured solve
/// takes its shortcuts (a converged step's `W μ` from the last solve among them). Cut after
/// step 20 and resumed from its state, it writes what the uninterrupted run writes.
#[test]
fn a_resumed_fig2_on_l6_writes_what_the_uninterrupted_run_writes() {
    common::ensure_mesh("vm272_L6");
    let dir = tempdir("restart-l6");
    let mut v = shipped_case("fig2.json");
    v["mesh"] = mesh_path("vm272_L6.msh");
    let case = dir.join("case.json");
    std::fs::write(&case, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let whole = dir.join("whole");
    let (code, err) = run(&case, &whole, &[]);
    assert_eq!(code, 0, "{err}");
    // The later steps' capacitance systems (from 256 special rows) reuse the LU of each
    // step's first iteration as a GMRES preconditioner, and the resumed run goes through them.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("summary.json")).unwrap())
            .unwrap();
    assert!(
        summary["gmres_iterations"].as_u64().unwrap() > 0,
        "no capacitance system was solved by GMRES"
    );
    let cut = dir.join("cut");
    let (code, err) = run(&case, &cut, &[]);
    assert_eq!(code, 0, "{err}");
    let (at, state) = nth_state(&cut, 2);
    keep_up_to(&cut, at);
    let (code, err) = run(&case, &cut, &["--resume", state.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (diff, files) = differences(&whole, &cut);
    println!("{files} files compared");
    assert!(
        diff.is_empty(),
        "the run resumed at step 20 differs in {diff:?}"
    );
}

#[test]
fn a_resumed_run_writes_what_the_uninterrupted_run_writes() {
    // The largest state over the smallest of the fretting run: the contact state's size is
    // fixed; the numbers' digits and the columns solved from the Delassus block vary.
    const STATE_SPREAD: f64 = 1.5;
    let dir = tempdir("restart");
    let case = write_case(&dir);
    let whole = dir.join("whole");
    let (code, err) = run(&case, &whole, &[]);
    assert_eq!(code, 0, "{err}");
    // The states do not grow with the steps: the records are in the journal.
    let sizes: Vec<u64> = states(&whole)
        .iter()
        .map(|(_, p)| std::fs::metadata(p).unwrap().len())
        .collect();
    println!("state sizes {sizes:?}");
    let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
    assert!(
        sizes.len() >= 5 && *hi as f64 <= STATE_SPREAD * *lo as f64,
        "{sizes:?}"
    );

    // Killed part-way (once a state past step 30 exists), then resumed from the directory.
    let killed = dir.join("killed");
    let args = [
        "run",
        case.to_str().unwrap(),
        "--out",
        killed.to_str().unwrap(),
        "--quiet",
        "--threads",
        "1",
    ];
    common::kill_when(&args, &[], 120, &|| states(&killed).len() >= 4);
    let kept = states(&killed).len();
    println!("killed with {kept} states written");
    let (code, err) = run(&case, &killed, &["--resume", killed.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (diff, files) = differences(&whole, &killed);
    assert!(diff.is_empty(), "the resumed run differs in {diff:?}");

    // Everything after step 40 deleted, resumed from its state file.
    let cut = dir.join("cut");
    let (code, err) = run(&case, &cut, &[]);
    assert_eq!(code, 0, "{err}");
    let (at, state) = nth_state(&cut, 4);
    keep_up_to(&cut, at);
    let (code, err) = run(&case, &cut, &["--resume", state.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (diff2, _) = differences(&whole, &cut);
    assert!(
        diff2.is_empty(),
        "the run resumed at step 40 differs in {diff2:?}"
    );
    validation_row(
        "316-restart",
        "exact restart: fretting, two cycles, L3, a state every 10th nominal step; one run killed part-way, one cut after its fourth state, both resumed",
        "the uninterrupted run",
        &format!(
            "all {files} files (VTU, contact CSV, `history.csv`, `energy.csv`, `summary.json`, states, journal) equal, JSON and CSV apart from wall times (killed with {kept} states written); states of constant size ({} to {} bytes)",
            lo, hi
        ),
        "restart",
    );
}

#[test]
fn bad_states_are_refused_and_nothing_is_written() {
    let dir = tempdir("restart-bad");
    let case = write_case(&dir);
    let src = dir.join("src");
    let (code, err) = run(&case, &src, &[]);
    assert_eq!(code, 0, "{err}");
    // A state of another case (the same case with another load) is refused.
    let mut other: Value = serde_json::from_str(&std::fs::read_to_string(&case).unwrap()).unwrap();
    other["stages"][1]["pilot_x"] = json!({"force": 1.4});
    let other_case = dir.join("other.json");
    std::fs::write(&other_case, other.to_string()).unwrap();
    let (_, state) = nth_state(&src, 4);
    for (name, case, resume, needle) in [
        ("foreign", &other_case, state.clone(), "another case"),
        ("empty-dir", &case, dir.join("nothing"), "holds no state"),
        (
            "corrupt",
            &case,
            dir.join("corrupt.json"),
            "not a stickslip state file",
        ),
    ] {
        std::fs::create_dir_all(dir.join("nothing")).unwrap();
        std::fs::write(dir.join("corrupt.json"), "{\"format\": 1, \"id\": ").unwrap();
        let out = dir.join(format!("out-{name}"));
        let (code, err) = run(case, &out, &["--resume", resume.to_str().unwrap()]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(needle) && err.contains("--resume"),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name} wrote output");
    }
}

#[test]
fn a_state_written_by_another_build_is_refused() {
    // Another build of the same version: the program's bytes with one more at the end (it runs
    // the same; its hash, the build's identity, differs).
    let dir = tempdir("restart-build");
    let case = write_case(&dir);
    let other = dir.join("stickslip-other-build");
    let mut bytes = std::fs::read(env!("CARGO_BIN_EXE_stickslip")).unwrap();
    bytes.push(0);
    std::fs::write(&other, &bytes).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&other, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    // `stickslip run CASE --out OUT --quiet EXTRA…` with the other build.
    let with_other = |out: &Path, extra: &[&str]| {
        std::process::Command::new(&other)
            .env("STICKSLIP_NO_CACHE", "1")
            .args([
                "run",
                case.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .arg("--quiet")
            .args(extra)
            .status()
            .unwrap()
    };
    let src = dir.join("src");
    let status = with_other(&src, &[]);
    assert!(status.success(), "the other build's run: {status}");
    let (_, state) = nth_state(&src, 4);
    let out = dir.join("out");
    let (code, err) = run(&case, &out, &["--resume", state.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("program build") && err.contains("--resume"),
        "{err}"
    );
    assert!(!out.exists(), "a refused resume wrote output");
    // The build that wrote it resumes it.
    let status = with_other(&dir.join("again"), &["--resume", state.to_str().unwrap()]);
    assert!(status.success(), "the other build's resume: {status}");
}

/// A run with a stage integrated in time between two quasi-static ones (Fig. 2's law on L2),
/// cut at a state of the last stage and resumed from it, writes what the uninterrupted run
/// writes, `<case>_time.pvd` of the dynamic stage's steps included (dynamic stages take no
/// checkpoints: the resumed run starts after it).
#[test]
fn a_run_resumed_after_a_dynamic_stage_writes_what_the_uninterrupted_run_writes() {
    let dir = tempdir("restart-dynamic");
    let mut v = shipped_case("fig2.json");
    v["mesh"] = mesh_path("vm272_L2.msh");
    for b in v["bodies"].as_array_mut().unwrap() {
        b["density"] = json!(1.2e-9);
    }
    v["stages"][1] = json!({"name": "in time", "pilot_x": {"force": 0.4},
        "dynamic": {"dt": 5e-6, "duration": 1e-4, "ramp_shape": "smooth"}});
    v["stages"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "quasi-static", "steps": 10, "pilot_x": {"force": 0.8}}));
    v["output"] = json!({"every": 5, "energy": true});
    let case = dir.join("case.json");
    std::fs::write(&case, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let whole = dir.join("whole");
    let (code, err) = run(&case, &whole, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(whole.join("case_time.pvd").is_file());
    let cut = dir.join("cut");
    let (code, err) = run(&case, &cut, &[]);
    assert_eq!(code, 0, "{err}");
    // The last state but one: in the last stage (the dynamic stage's 20 steps follow step 1).
    let all = states(&cut);
    let (at, state) = all[all.len() - 2].clone();
    assert!(at > 21, "state at step {at}");
    keep_up_to(&cut, at);
    let (code, err) = run(&case, &cut, &["--resume", state.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let (diff, files) = differences(&whole, &cut);
    println!("{files} files compared");
    assert!(
        diff.is_empty(),
        "the run resumed at step {at} differs in {diff:?}"
    );
}
