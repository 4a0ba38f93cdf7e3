//! The model cache (`--cache DIR`, `--no-cache`): a hit writes what a cold run writes, byte for
//! byte apart from the timings; a change of anything the linear algebra depends on (a body's
//! E, a support, the mesh bytes, the candidate gap) misses, a change of the friction law or the
//! loads hits; a truncated, corrupted or foreign entry is reported, rebuilt and never used;
//! `--no-cache` writes nothing; the directory stays under its size cap.

mod common;
use common::{mesh_path, repo, shipped_case_on, tempdir};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Keys that measure how the run went rather than what it computed (`factor_flops`: the
/// analysis's count, which a hit does not redo).
const TIMING_KEYS: [&str; 11] = [
    // Counts the journal, whose wall times vary in their digits.
    "output_bytes",
    "factor_flops",
    "t_solve",
    "t_contact",
    "timings_s",
    "contact_solve_s",
    "contact_phases_s",
    "peak_memory_mib",
    "wall_s",
    "output_dir",
    "cache",
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

/// The files of `a` that differ from those of `b` (JSON without the keys above, CSV without
/// `wall_s`, the rest byte for byte), and how many were compared.
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
    let csv = |p: &PathBuf| -> Vec<Vec<String>> {
        let t = std::fs::read_to_string(p).unwrap();
        let mut rows: Vec<Vec<String>> = t
            .lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        if let Some(k) = rows[0].iter().position(|h| h == "wall_s") {
            rows.iter_mut().for_each(|r| {
                r.remove(k);
            });
        }
        rows
    };
    let mut diff = Vec::new();
    for n in &na {
        let (pa, pb) = (a.join(n), b.join(n));
        let same = if n.ends_with(".json") {
            let read = |p: &PathBuf| {
                let mut v: Value =
                    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
                strip(&mut v);
                v
            };
            read(&pa) == read(&pb)
        } else if n.ends_with(".jsonl") {
            // The journal of step records: JSON lines, timings stripped.
            let lines = |p: &PathBuf| -> Vec<Value> {
                std::fs::read_to_string(p)
                    .unwrap()
                    .lines()
                    .map(|l| {
                        let mut v: Value = serde_json::from_str(l).unwrap();
                        strip(&mut v);
                        v
                    })
                    .collect()
            };
            lines(&pa) == lines(&pb)
        } else if n.ends_with(".csv") {
            csv(&pa) == csv(&pb)
        } else {
            std::fs::read(&pa).unwrap() == std::fs::read(&pb).unwrap()
        };
        if !same {
            diff.push(n.clone());
        }
    }
    (diff, na.len())
}

/// The paper's Fig. 2 case on the L1 mesh, shortened.
fn base_case() -> Value {
    let mut v = shipped_case_on("fig2.json", "vm272_L1.msh");
    v["stages"][1]["steps"] = json!(6);
    v["output"] = json!({"every": 3});
    v
}

struct Run {
    code: i32,
    stderr: String,
    out: PathBuf,
}

impl Run {
    fn summary(&self) -> Value {
        serde_json::from_str(&std::fs::read_to_string(self.out.join("summary.json")).unwrap())
            .unwrap()
    }

    fn status(&self) -> String {
        assert_eq!(self.code, 0, "{}", self.stderr);
        self.summary()["cache"]["status"]
            .as_str()
            .unwrap_or("(none)")
            .to_string()
    }
}

/// Runs `case` (written to `dir/case.json`) into `dir/NAME` with `args`, in an environment
/// without the cache's variables, plus `env`.
fn run_env(dir: &Path, name: &str, case: &Value, args: &[&str], env: &[(&str, &str)]) -> Run {
    // The same case file for every run (one after the other): the summary names it, and the
    // output's file names derive from it.
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string_pretty(case).unwrap()).unwrap();
    let out = dir.join(name);
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"));
    cmd.env_remove("STICKSLIP_NO_CACHE")
        .env_remove("STICKSLIP_CACHE_MAX")
        .env_remove("STICKSLIP_CACHE_DIR")
        .env_remove("XDG_CACHE_HOME")
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--log", "warn"])
        .args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    let o = cmd.output().unwrap();
    Run {
        code: o.status.code().unwrap_or(-1),
        stderr: String::from_utf8_lossy(&o.stderr).into(),
        out,
    }
}

/// Runs `case` with the cache in `cache`.
fn run(dir: &Path, name: &str, case: &Value, cache: &Path) -> Run {
    run_env(dir, name, case, &["--cache", cache.to_str().unwrap()], &[])
}

/// The entries (`model-*.bin`) in `cache`.
fn entries(cache: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(cache)
        .map(|rd| {
            rd.map(|e| e.unwrap().path())
                .filter(|p| {
                    let n = p.file_name().unwrap().to_string_lossy();
                    n.starts_with("model-") && n.ends_with(".bin")
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

/// A fresh directory `NAME` for a test (with `cache` in it), the base case, its run without a
/// cache, and the entry a first run writes.
fn cold_and_first_entry(name: &str) -> (PathBuf, PathBuf, Value, Run, PathBuf) {
    let dir = tempdir(name);
    let cache = dir.join("cache");
    let case = base_case();
    let cold = run_env(&dir, "cold", &case, &["--no-cache"], &[]);
    assert_eq!(cold.status(), "off");
    assert_eq!(run(&dir, "first", &case, &cache).status(), "miss");
    let file = entries(&cache).pop().unwrap();
    (dir, cache, case, cold, file)
}

fn assert_same(a: &Run, b: &Run, what: &str) {
    let (diff, n) = differences(&a.out, &b.out);
    assert!(n > 5, "{what}: only {n} files");
    assert!(diff.is_empty(), "{what}: {diff:?} differ");
}

#[test]
fn a_hit_writes_what_a_cold_run_writes_and_a_friction_study_hits() {
    let dir = tempdir("cache-hit");
    let cache = dir.join("cache");
    let case = base_case();
    let cold = run_env(&dir, "cold", &case, &["--no-cache"], &[]);
    assert_eq!(cold.status(), "off");
    assert!(!cache.exists(), "--no-cache wrote to the cache");

    let first = run(&dir, "first", &case, &cache);
    assert_eq!(first.status(), "miss");
    let files = entries(&cache);
    assert_eq!(files.len(), 1);
    let s = first.summary();
    assert_eq!(s["cache"]["path"], json!(files[0].to_str().unwrap()));
    assert_eq!(
        s["cache"]["bytes"].as_u64().unwrap(),
        std::fs::metadata(&files[0]).unwrap().len()
    );

    let second = run(&dir, "second", &case, &cache);
    assert_eq!(second.status(), "hit");
    assert_eq!(second.summary()["cache"]["path"], s["cache"]["path"]);
    // The factorisation's modelled operations come from the analysis: the same count in the
    // cold run and the miss, none on the hit (no analysis). The constraint columns end the
    // factor in one dense block of the `m = 2 n_s + 2` rows (normal and tangential per slave
    // node, and the two grounding rows of the pilot), `m³ / 3`.
    let flops = &s["factor_flops"];
    assert_eq!(cold.summary()["factor_flops"], *flops);
    assert_eq!(second.summary()["factor_flops"], Value::Null);
    let m = 2.0 * s["contact_nodes"].as_f64().unwrap() + 2.0;
    let block = flops["constraint_block"].as_f64().unwrap();
    assert!(
        (block - m.powi(3) / 3.0).abs() <= 1e-9 * block,
        "constraint block {block} against m³/3 with m = {m}"
    );
    assert!(flops["k"].as_f64().unwrap() > 0.0 && flops["coupling"].as_f64().unwrap() > 0.0);
    // A hit skips the analysis's ordering, the factorisation and the condensation.
    assert_eq!(second.summary()["timings_s"]["factorise"], json!(0.0));
    assert_same(&cold, &first, "miss against no cache");
    assert_same(&cold, &second, "hit against no cache");

    // Friction law, loads and output are not part of the key.
    let mut law = case.clone();
    law["contact"]["friction"]["fs"] = json!(0.2);
    law["contact"]["friction"]["lambda"] = json!(0.08);
    let law_hit = run(&dir, "law", &law, &cache);
    assert_eq!(law_hit.status(), "hit");
    let law_cold = run_env(&dir, "law-cold", &law, &["--no-cache"], &[]);
    assert_same(
        &law_cold,
        &law_hit,
        "another friction law, hit against no cache",
    );
    let mut load = case.clone();
    load["stages"][1]["pilot_x"] = json!({"force": 0.5});
    load["stages"][1]["steps"] = json!(4);
    load["output"] = json!({"every": 2});
    assert_eq!(run(&dir, "load", &load, &cache).status(), "hit");
    assert_eq!(entries(&cache).len(), 1);
    // Entries take some 15 MB each: leave nothing behind.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_change_of_what_the_linear_algebra_depends_on_misses() {
    let dir = tempdir("cache-miss");
    let cache = dir.join("cache");
    let case = base_case();
    assert_eq!(run(&dir, "base", &case, &cache).status(), "miss");
    let mut variants: Vec<(&str, Value)> = Vec::new();
    let mut v = case.clone();
    v["bodies"][1]["E"] = json!(210.0);
    variants.push(("E of a body", v));
    let mut v = case.clone();
    v["supports"][0]["uy"] = json!(-1e-4);
    variants.push(("a support", v));
    let mut v = case.clone();
    v["mesh"] = mesh_path("vm272_L1_ascii.msh");
    variants.push(("the mesh bytes (the same mesh in ASCII)", v));
    let mut v = case.clone();
    v["contact"]["candidate_gap"] = json!(0.12);
    variants.push(("the candidate gap", v));
    for (i, (what, v)) in variants.iter().enumerate() {
        let r = run(&dir, &format!("variant{i}"), v, &cache);
        assert_eq!(r.status(), "miss", "{what}");
        assert_eq!(entries(&cache).len(), i + 2, "{what}");
        assert!(!r.stderr.contains("model cache"), "{what}: {}", r.stderr);
    }
    // And each of them hits the second time.
    for (i, (what, v)) in variants.iter().enumerate() {
        assert_eq!(
            run(&dir, &format!("again{i}"), v, &cache).status(),
            "hit",
            "{what}"
        );
    }
    // Entries take some 15 MB each: leave nothing behind.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truncated_corrupted_and_foreign_entries_are_reported_and_rebuilt() {
    let (dir, cache, case, cold, file) = cold_and_first_entry("cache-corrupt");
    let good = std::fs::read(&file).unwrap();

    // The factor values are the first section, from byte 4096 (after the header and its
    // zero padding).
    let damage: [(&str, Vec<u8>, &str); 6] = [
        ("truncated", good[..good.len() / 2].to_vec(), "truncated"),
        (
            "one flipped byte of the factor values",
            {
                let mut b = good.clone();
                b[4096 + 8 * 123 + 3] ^= 0x04;
                b
            },
            "checksum mismatch in section 1 of",
        ),
        (
            "one byte of the header's padding set",
            {
                let mut b = good.clone();
                b[4000] = 0x01;
                b
            },
            "corrupt header (bytes after it not zero)",
        ),
        (
            "one flipped payload byte",
            {
                let mut b = good.clone();
                let k = b.len() - 1000;
                b[k] ^= 0x10;
                b
            },
            "checksum mismatch",
        ),
        (
            "one flipped header byte",
            {
                let mut b = good.clone();
                b[40] ^= 0x01;
                b
            },
            "corrupt header",
        ),
        (
            "foreign",
            b"this is not a model cache file, but it has the name of one".to_vec(),
            "not a stickslip model cache file",
        ),
    ];
    for (i, (what, bytes, why)) in damage.iter().enumerate() {
        std::fs::write(&file, bytes).unwrap();
        let r = run(&dir, &format!("damaged{i}"), &case, &cache);
        assert_eq!(r.status(), "rebuilt", "{what}");
        assert!(
            r.stderr.contains("warning: model cache:") && r.stderr.contains(why),
            "{what}: stderr {}",
            r.stderr
        );
        let note = r.summary()["cache"]["note"].as_str().unwrap().to_string();
        assert!(note.contains(why), "{what}: note {note}");
        assert_same(&cold, &r, what);
        assert_eq!(
            std::fs::read(&file).unwrap(),
            good,
            "{what}: entry not rewritten"
        );
        let again = run(&dir, &format!("again{i}"), &case, &cache);
        assert_eq!(again.status(), "hit", "{what}");
        assert_same(&cold, &again, what);
    }
    // Entries take some 15 MB each: leave nothing behind.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_entry_computed_in_its_file_is_the_entry_written_from_memory() {
    let dir = tempdir("cache-in-place");
    let case = base_case();
    let cold = run_env(&dir, "cold", &case, &["--no-cache"], &[]);
    let in_place = dir.join("cache-in-place");
    let in_memory = dir.join("cache-in-memory");
    let a = run(&dir, "in-place", &case, &in_place);
    let b = run_env(
        &dir,
        "in-memory",
        &case,
        &["--cache", in_memory.to_str().unwrap()],
        &[("STICKSLIP_CACHE_IN_PLACE", "0")],
    );
    assert_eq!((a.status(), b.status()), ("miss".into(), "miss".into()));
    // The factorisation wrote its values in the entry's file where the file system reserves
    // blocks for good (on Linux: ext2/3/4, XFS, tmpfs, as `stat -f` names them), else in
    // memory, and in memory when told to.
    let fs = std::process::Command::new("stat")
        .args(["-f", "-c", "%T"])
        .arg(&dir)
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let reserving = cfg!(target_os = "linux") && ["ext2/ext3", "xfs", "tmpfs"].contains(&&*fs);
    assert_eq!(
        a.summary()["cache"]["factor_in_place"],
        json!(reserving),
        "file system `{fs}`: {}",
        a.stderr
    );
    assert_eq!(b.summary()["cache"]["factor_in_place"], json!(false));
    let (ea, eb) = (entries(&in_place), entries(&in_memory));
    assert_eq!((ea.len(), eb.len()), (1, 1));
    assert!(
        std::fs::read(&ea[0]).unwrap() == std::fs::read(&eb[0]).unwrap(),
        "the two entries differ"
    );
    // Nothing else in either directory (no temporary file left).
    for d in [&in_place, &in_memory] {
        assert_eq!(std::fs::read_dir(d).unwrap().count(), 1, "{}", d.display());
    }
    assert_same(&cold, &a, "factor in the entry's file against no cache");
    assert_same(&cold, &b, "factor in memory against no cache");
    let hit = run(&dir, "hit", &case, &in_place);
    assert_eq!(hit.status(), "hit");
    assert_eq!(hit.summary()["cache"].get("factor_in_place"), None);
    assert_same(&cold, &hit, "a hit of the entry computed in place");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_factorisation_that_fails_leaves_no_entry_and_no_temporary_file() {
    // The upper body a hundred orders of magnitude softer than the lower: its pivots vanish
    // against the lower body's, and the factorisation, computing in the entry's file, fails.
    let dir = tempdir("cache-fails");
    let cache = dir.join("cache");
    let mut case = base_case();
    case["bodies"][1]["E"] = json!(1e-20);
    let r = run(&dir, "soft", &case, &cache);
    assert_eq!(r.code, 3, "{}", r.stderr);
    assert!(r.stderr.contains("not positive definite"), "{}", r.stderr);
    let left: Vec<_> = std::fs::read_dir(&cache)
        .map(|rd| rd.map(|e| e.unwrap().file_name()).collect())
        .unwrap_or_default();
    assert!(left.is_empty(), "left in the cache directory: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_entry_that_cannot_be_written_is_reported_as_not_written() {
    // A directory where the entry's file goes: the lookup cannot read it, the rebuilt entry
    // cannot be renamed over it. The summary says so instead of naming a file that is not
    // there, and the run's results are those of a run without a cache.
    let (dir, cache, case, cold, file) = cold_and_first_entry("cache-unwritable");
    std::fs::remove_file(&file).unwrap();
    std::fs::create_dir(&file).unwrap();
    let r = run(&dir, "blocked", &case, &cache);
    assert_eq!(r.status(), "rebuilt");
    let c = &r.summary()["cache"];
    assert_eq!(c.get("path"), None, "{c}");
    assert_eq!(c.get("factor_in_place"), None, "{c}");
    let note = c["note"].as_str().unwrap();
    assert!(note.contains("not written: "), "{note}");
    assert!(
        r.stderr.contains("could not write") && r.stderr.contains(file.to_str().unwrap()),
        "{}",
        r.stderr
    );
    assert_same(&cold, &r, "an entry that could not be written");
    // The directory is still the only thing there: no temporary file left.
    assert_eq!(std::fs::read_dir(&cache).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn no_cache_writes_nothing_and_the_default_place_comes_from_the_environment() {
    let dir = tempdir("cache-env");
    let case = base_case();
    let env_dir = dir.join("env-cache");
    let home = dir.join("home");
    let e = env_dir.to_str().unwrap();
    let h = home.to_str().unwrap();
    // --no-cache and STICKSLIP_NO_CACHE: nothing read or written anywhere.
    let r = run_env(
        &dir,
        "off",
        &case,
        &["--no-cache"],
        &[("STICKSLIP_CACHE_DIR", e), ("HOME", h)],
    );
    assert_eq!(r.status(), "off");
    let r = run_env(
        &dir,
        "off-env",
        &case,
        &[],
        &[
            ("STICKSLIP_CACHE_DIR", e),
            ("HOME", h),
            ("STICKSLIP_NO_CACHE", "1"),
        ],
    );
    assert_eq!(r.status(), "off");
    assert!(
        !env_dir.exists() && !home.exists(),
        "a bypassed cache wrote"
    );
    // STICKSLIP_CACHE_DIR, else XDG_CACHE_HOME/stickslip, else HOME/.cache/stickslip.
    let r = run_env(
        &dir,
        "env",
        &case,
        &[],
        &[("STICKSLIP_CACHE_DIR", e), ("HOME", h)],
    );
    assert_eq!(r.status(), "miss");
    assert_eq!(entries(&env_dir).len(), 1);
    let xdg = dir.join("xdg");
    let r = run_env(
        &dir,
        "xdg",
        &case,
        &[],
        &[("XDG_CACHE_HOME", xdg.to_str().unwrap()), ("HOME", h)],
    );
    assert_eq!(r.status(), "miss");
    assert_eq!(entries(&xdg.join("stickslip")).len(), 1);
    let r = run_env(&dir, "home", &case, &[], &[("HOME", h)]);
    assert_eq!(r.status(), "miss");
    assert_eq!(entries(&home.join(".cache/stickslip")).len(), 1);
    // Entries take some 15 MB each: leave nothing behind.
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_cache_stays_under_its_cap_and_a_model_without_contact_is_cached_too() {
    let dir = tempdir("cache-cap");
    let cache = dir.join("cache");
    let c = cache.to_str().unwrap();
    let case = base_case();
    let first = run(&dir, "first", &case, &cache);
    assert_eq!(first.status(), "miss");
    let size = first.summary()["cache"]["bytes"].as_u64().unwrap();
    // Room for one entry: the least recently used one goes.
    let cap = (size + size / 2).to_string();
    let mut other = case.clone();
    other["bodies"][0]["E"] = json!(190.0);
    let r = run_env(
        &dir,
        "other",
        &other,
        &["--cache", c],
        &[("STICKSLIP_CACHE_MAX", &cap)],
    );
    assert_eq!(r.status(), "miss");
    let left = entries(&cache);
    assert_eq!(left.len(), 1);
    assert_eq!(
        r.summary()["cache"]["path"],
        json!(left[0].to_str().unwrap())
    );
    // An entry larger than the cap is not written (and the run goes on).
    let r = run_env(
        &dir,
        "small",
        &case,
        &["--cache", c],
        &[("STICKSLIP_CACHE_MAX", "1000")],
    );
    assert_eq!(r.status(), "miss");
    let note = r.summary()["cache"]["note"].as_str().unwrap().to_string();
    assert!(note.contains("exceed the cache cap"), "{note}");
    assert_eq!(entries(&cache), left);

    // A model without contact (the partial factorisation with the pilot's DOFs last).
    let (nodes, tris, sides) = common::structured(6, 4, -1.5, 1.5, 0.0, 2.0, 0.2);
    std::fs::write(
        dir.join("block.msh"),
        common::msh41_sides(&nodes, &[("body", tris)], sides),
    )
    .unwrap();
    let block = json!({"mesh": dir.join("block.msh"), "bodies": [{"group": "body", "E": 200, "nu": 0.3}],
        "supports": [{"group": "bottom", "ux": 0, "uy": 0}], "pilot": {"group": "top"},
        "stages": [{"steps": 2, "pilot_x": {"displacement": 0.01}, "pilot_y": {"force": -1.0}}]});
    let cold = run_env(&dir, "block-cold", &block, &["--no-cache"], &[]);
    assert_eq!(cold.status(), "off");
    assert_eq!(run(&dir, "block1", &block, &cache).status(), "miss");
    let hit = run(&dir, "block2", &block, &cache);
    assert_eq!(hit.status(), "hit");
    assert_same(&cold, &hit, "a model without contact");
    assert!(repo().join("meshes/vm272_L1.msh").exists());
    // Entries take some 15 MB each: leave nothing behind.
    let _ = std::fs::remove_dir_all(&dir);
}
