//! The same case run on one thread and on two gives bit-identical results: every
//! `contact_NNNN.csv` and every `.vtu` file (bodies and contact surface) must be byte for byte
//! the same. Cases: `cases/vm272_cm.json` (normal load, then Cattaneo–Mindlin tangential
//! loading, 11 steps) on the mesh `vm272_L2`, and `cases/fig2.json` as shipped (L5), where the
//! factorisation and the contact Newton's dense kernels are large enough for faer to run them
//! in parallel (before the dense kernels were kept sequential, this one differed at 1e-10).
//!
//! On a difference the test names the file, and for a CSV the column, the row and the largest
//! absolute and relative difference; for a `.vtu` the data array of its appended section (or
//! the XML header) holding the first differing byte.

mod common;
use common::*;
use serde_json::json;
use std::path::{Path, PathBuf};

fn run(dir: &Path, case: &Path, threads: usize) -> PathBuf {
    let out = dir.join(format!("out{threads}"));
    let (code, _, err) = stickslip(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        &threads.to_string(),
        "--quiet",
        // Both runs build the model: a cache hit would skip the factorisation.
        "--no-cache",
    ]);
    assert!(code == 0, "--threads {threads}: exit {code}: {err}");
    out
}

/// Files compared: the contact CSVs and every `.vtu`, sorted by name.
fn compared_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| (n.starts_with("contact_") && n.ends_with(".csv")) || n.ends_with(".vtu"))
        .collect();
    v.sort();
    v
}

/// For two CSV tables: (column, row, |a − b|, relative) of the largest difference per column.
fn csv_diff(a: &str, b: &str) -> Vec<String> {
    let head: Vec<&str> = a.lines().next().unwrap_or("").split(',').collect();
    let rows = |s: &str| -> Vec<Vec<f64>> {
        s.lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    let (ra, rb) = (rows(a), rows(b));
    if ra.len() != rb.len() {
        return vec![format!("{} rows against {}", ra.len(), rb.len())];
    }
    let mut out = Vec::new();
    for (c, name) in head.iter().enumerate() {
        let mut worst = (0usize, 0.0f64, 0.0f64);
        let scale = ra.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
        for (i, (x, y)) in ra.iter().zip(&rb).enumerate() {
            let d = (x[c] - y[c]).abs();
            if d > worst.1 || (x[c].to_bits() != y[c].to_bits() && worst.1 == 0.0) {
                worst = (i, d, d / scale.max(1e-300));
            }
        }
        if ra
            .iter()
            .zip(&rb)
            .any(|(x, y)| x[c].to_bits() != y[c].to_bits())
        {
            out.push(format!(
                "column `{name}`: largest difference {:.3e} ({:.3e} of the column's largest value) at row {}",
                worst.1, worst.2, worst.0 + 1
            ));
        }
    }
    out
}

/// What holds byte `pos` of a `.vtu` (the XML header, or a data array of the appended
/// section), read from the file `a`.
fn vtu_array_at(a: &[u8], pos: usize) -> String {
    match common::vtu::Vtu::parse(a) {
        Ok(v) => v.what_holds(pos),
        Err(e) => format!("(unreadable: {e})"),
    }
}

/// Runs the shipped case `name` on `mesh` with one thread and with two and asserts that the
/// files match (expecting `csvs` contact CSVs and `vtus` .vtu files); returns their counts.
fn one_and_two_threads(name: &str, mesh: &str, csvs: usize, vtus: usize) -> (usize, usize) {
    let dir = tempdir(&format!("determinism-{mesh}"));
    let v = shipped_case_on(name, mesh);
    let case = dir.join(name);
    std::fs::write(&case, serde_json::to_string_pretty(&v).unwrap()).unwrap();

    let o1 = run(&dir, &case, 1);
    let o2 = run(&dir, &case, 2);
    for (o, n) in [(&o1, 1), (&o2, 2)] {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(o.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(
            s["threads"],
            json!(n),
            "summary.json of the --threads {n} run"
        );
        if name == "fig2.json" {
            // The README's figures for the shipped Fig. 2 (the first contact from Hertz's
            // contact set, the structured solve's shortcuts from L5): 179 Newton iterations
            // (180 without the shortcuts), 2 Delassus blocks factorised.
            assert_eq!(s["newton_iterations"], json!(179), "--threads {n}");
            assert_eq!(s["lu_factorisations"], json!(2), "--threads {n}");
        }
    }
    let (f1, f2) = (compared_files(&o1), compared_files(&o2));
    assert_eq!(f1, f2, "the two runs wrote different sets of files");
    let counts = (
        f1.iter().filter(|n| n.ends_with(".csv")).count(),
        f1.iter().filter(|n| n.ends_with(".vtu")).count(),
    );
    assert!(
        counts == (csvs, vtus),
        "expected {csvs} contact CSVs and {vtus} .vtu files, got {f1:?}"
    );
    let mut diffs = Vec::new();
    for name in &f1 {
        let a = std::fs::read(o1.join(name)).unwrap();
        let b = std::fs::read(o2.join(name)).unwrap();
        if a == b {
            continue;
        }
        if name.ends_with(".csv") {
            let d = csv_diff(&String::from_utf8_lossy(&a), &String::from_utf8_lossy(&b));
            diffs.push(format!("{name}: {}", d.join("; ")));
        } else {
            let pos = a
                .iter()
                .zip(&b)
                .position(|(x, y)| x != y)
                .unwrap_or(a.len().min(b.len()));
            diffs.push(format!(
                "{name}: first difference at byte {pos}, in {} (sizes {} and {})",
                vtu_array_at(&a, pos),
                a.len(),
                b.len()
            ));
        }
    }
    // history.csv too, without its wall-clock column.
    let history = |o: &Path| -> Vec<String> {
        let t = std::fs::read_to_string(o.join("history.csv")).unwrap();
        let head: Vec<&str> = t.lines().next().unwrap().split(',').collect();
        let wall = head.iter().position(|c| *c == "wall_s");
        t.lines()
            .map(|l| {
                l.split(',')
                    .enumerate()
                    .filter(|(i, _)| Some(*i) != wall)
                    .map(|(_, x)| x)
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect()
    };
    let (h1, h2) = (history(&o1), history(&o2));
    if h1 != h2 {
        diffs.push(format!(
            "history.csv (without wall_s): {}",
            csv_diff(&h1.join("\n"), &h2.join("\n")).join("; ")
        ));
    }
    println!(
        "compared {} files and history.csv between --threads 1 and --threads 2: {} differ",
        f1.len(),
        diffs.len()
    );
    assert!(
        diffs.is_empty(),
        "--threads 1 and --threads 2 differ (outputs kept in {}):\n{}",
        dir.display(),
        diffs.join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
    counts
}

#[test]
fn one_and_two_threads_give_identical_files() {
    let (csvs, vtus) = one_and_two_threads("vm272_cm.json", "vm272_L2.msh", 11, 22);
    validation_row(
        "320-determinism",
        "the same case with `--threads 1` and `--threads 2`",
        "—",
        &format!(
            "byte-identical contact CSV and VTU files ({csvs} CSVs, {vtus} .vtu), and history.csv without its wall-clock column"
        ),
        "determinism",
    );
}

#[test]
fn one_and_two_threads_give_identical_files_on_the_shipped_fig2() {
    let (csvs, vtus) = one_and_two_threads("fig2.json", "vm272_L5.msh", 5, 10);
    validation_row(
        "321-determinism-l5",
        "`cases/fig2.json` (L5, 182 518 DOFs) with `--threads 1` and `--threads 2`",
        "—",
        &format!(
            "byte-identical contact CSV and VTU files ({csvs} CSVs, {vtus} .vtu), and history.csv without its wall-clock column"
        ),
        "determinism",
    );
}
