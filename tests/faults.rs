//! Faults during output: a run killed (SIGKILL) while it writes, and a run that fills its disk
//! (a 40 MB tmpfs mounted by the test; root only, as in CI — elsewhere the test says it cannot
//! mount one and fails). Each leaves:
//! * every file under its final name complete (each `.vtu` parses whole, each JSON and CSV
//!   parses, every file the `.pvd` names exists): files are written under temporary names and
//!   renamed into place;
//! * the last written step's state, from which `--resume` finishes the run with the answers
//!   of the uninterrupted run (`history.csv` apart from wall times);
//!
//! and the full disk a clear message naming the file (exit 4). A run killed while it writes its
//! model-cache entry leaves a cache the next run uses or rebuilds, with the same answers.
//!
//! Case: VM272 C–M on L3, 20 tangential steps, every step written (3.9 MB a step).

mod common;
use common::vtu::Vtu;
use common::*;
use serde_json::Value;
use std::path::Path;

fn case(dir: &Path) -> std::path::PathBuf {
    let mut v = shipped_case_on("vm272_cm.json", "vm272_L3.msh");
    v["stages"][1]["steps"] = 20.into();
    v["output"] = serde_json::json!({"every": 1});
    let p = dir.join("case.json");
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

/// Every file of `out` under a final name is whole; returns the highest state's step.
fn complete_files(out: &Path) -> usize {
    let mut last_state = 0;
    for name in file_names(out) {
        let p = out.join(&name);
        if name.starts_with('.') || name.contains(".tmp") {
            continue;
        }
        if name.ends_with(".vtu") {
            Vtu::read(&p).unwrap_or_else(|e| panic!("{name} is not whole: {e}"));
        } else if name.ends_with(".json") {
            let _: Value = serde_json::from_str(&std::fs::read_to_string(&p).unwrap())
                .unwrap_or_else(|e| panic!("{name} is not whole: {e}"));
            if let Some(k) = name
                .strip_prefix("state_")
                .and_then(|s| s.strip_suffix(".json"))
            {
                last_state = last_state.max(k.parse().unwrap());
            }
        } else if name.ends_with(".csv") {
            let _ = Table::read(&p);
        } else if name.ends_with(".pvd") {
            let pvd = std::fs::read_to_string(&p).unwrap();
            assert!(
                pvd.trim_end().ends_with("</VTKFile>"),
                "{name} is not whole"
            );
            for l in pvd.lines().filter(|l| l.contains("file=\"")) {
                let f = l.split("file=\"").nth(1).unwrap();
                let f = &f[..f.find('"').unwrap()];
                assert!(out.join(f).exists(), "{name} names {f}, which is not there");
            }
        }
    }
    last_state
}

/// `history.csv` without wall times, each value as text (a column that does not apply holds
/// `NaN`, which a comparison of numbers would call different from itself).
fn answers(out: &Path) -> Vec<Vec<String>> {
    let t = Table::read(&out.join("history.csv"));
    let wall = t.col("wall_s");
    t.rows
        .into_iter()
        .map(|mut r| {
            r.remove(wall);
            r.iter().map(|v| format!("{v:e}")).collect()
        })
        .collect()
}

/// A fresh directory `name` with the case and the uninterrupted run of it (`DIR/whole`).
fn setup(name: &str) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    let dir = tempdir(name);
    let case = case(&dir);
    let whole = dir.join("whole");
    let (code, err) = run(&case, &whole, &["--quiet"]);
    assert_eq!(code, 0, "{err}");
    (dir, case, whole)
}

fn run(case: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args = vec![
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = stickslip(&args);
    (code, err)
}

#[test]
fn a_run_killed_while_it_writes_leaves_whole_files_and_resumes() {
    let (dir, case, whole) = setup("faults-kill");
    // Killed at several points of its writing: once the state of step k exists, at once.
    for k in [1usize, 6, 13] {
        let out = dir.join(format!("killed-{k}"));
        let marker = out.join(format!("state_{k:04}.json"));
        let args = [
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ];
        kill_when(&args, &[], 120, &|| marker.exists());
        let last = complete_files(&out);
        println!("killed after state {k}: last whole state {last}");
        assert!(
            last >= k,
            "state {k} was seen, yet the last whole state is {last}"
        );
        let (code, err) = run(&case, &out, &["--quiet", "--resume", out.to_str().unwrap()]);
        assert_eq!(code, 0, "resume after a kill at state {k}: {err}");
        assert_eq!(
            answers(&out),
            answers(&whole),
            "resumed after a kill at state {k}"
        );
        complete_files(&out);
    }
}

/// Mounts a tmpfs of `mb` MiB on `dir`; unmounted when dropped.
struct Tmpfs(std::path::PathBuf);

impl Tmpfs {
    fn mount(dir: &Path, mb: usize) -> Tmpfs {
        std::fs::create_dir_all(dir).unwrap();
        let st = std::process::Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={mb}m"), "tmpfs"])
            .arg(dir)
            .status()
            .expect("mount runs");
        assert!(
            st.success(),
            "cannot mount a tmpfs on {} (the full-disk test needs root, as CI has)",
            dir.display()
        );
        Tmpfs(dir.to_path_buf())
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount").arg(&self.0).status();
    }
}

#[test]
fn a_full_disk_stops_the_run_with_whole_files_and_a_resumable_state() {
    let (dir, case, whole) = setup("faults-full");
    let disk = dir.join("disk");
    // Room for the files a run has in flight at once (a batch of four steps of 4 MB and the
    // next batch begun ahead, ≈ 32 MB: with 40 MB a loaded machine could fill the disk before
    // the first step was whole), and well short of the run's 84 MB.
    let fs = Tmpfs::mount(&disk, 56);
    let out = disk.join("out");
    let (code, err) = run(&case, &out, &["--quiet"]);
    println!("{err}");
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains("cannot write output") && err.contains(out.to_str().unwrap()),
        "{err}"
    );
    assert!(err.contains("No space left"), "{err}");
    let last = complete_files(&out);
    assert!((1..21).contains(&last), "last whole state {last}");
    // Resumed on a disk with room, from the last state the full disk kept.
    let moved = dir.join("moved");
    std::fs::create_dir_all(&moved).unwrap();
    for name in file_names(&out) {
        if !name.contains(".tmp") {
            std::fs::copy(out.join(&name), moved.join(&name)).unwrap();
        }
    }
    drop(fs);
    let (code, err) = run(
        &case,
        &moved,
        &["--quiet", "--resume", moved.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(answers(&moved), answers(&whole));
}

/// A run killed while it writes its model-cache entry (a temporary entry file in the cache
/// directory at the moment of the kill): the next run with that cache completes with the
/// answers of a run without a cache (the partial entry is never used).
#[test]
fn a_run_killed_while_it_writes_the_cache_leaves_a_usable_cache() {
    let (dir, case, plain) = setup("faults-cache");
    let cache = dir.join("cache");
    let temporaries = |d: &Path| -> usize {
        std::fs::read_dir(d).map_or(0, |r| {
            r.filter(|e| {
                let n = e
                    .as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .to_string();
                n.contains(".tmp")
            })
            .count()
        })
    };
    // Poll the cache directory and kill the run while a temporary entry is there.
    let mut caught = false;
    for attempt in 0..5 {
        let _ = std::fs::remove_dir_all(&cache);
        let out = dir.join(format!("killed-{attempt}"));
        let args = [
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--cache",
            cache.to_str().unwrap(),
        ];
        let seen = kill_when(&args, &[("STICKSLIP_NO_CACHE", "")], 60, &|| {
            temporaries(&cache) > 0
        });
        if !seen {
            continue;
        }
        caught = true;
        let again = dir.join(format!("again-{attempt}"));
        let mut args = vec![
            "run",
            case.to_str().unwrap(),
            "--out",
            again.to_str().unwrap(),
        ];
        args.extend(["--quiet", "--cache", cache.to_str().unwrap()]);
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
            .env_remove("STICKSLIP_NO_CACHE")
            .args(&args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "the run after the kill: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            answers(&again),
            answers(&plain),
            "after a kill during the cache write"
        );
        break;
    }
    assert!(
        caught,
        "no run was caught writing its cache entry in 5 tries"
    );
}
