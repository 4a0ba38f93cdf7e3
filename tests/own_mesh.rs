//! The README's "Bring your own mesh" recipe, as shipped: `python3 meshes/two_cylinders.py`
//! builds two half-cylinders of radii 12 mm (lower) and 5 mm (upper) with gmsh, and
//! `stickslip run cases/own_mesh.json` presses them together with P = 2.5 N/mm and then loads
//! them tangentially to Q = 0.25 N/mm = 0.5 μP with Coulomb friction μ = 0.2. Checked:
//!
//! * the Hertz semi-width of `history.csv` at the end of the normal load against
//!   a = sqrt(4PR/(πE*)), 1/R = 1/R1 + 1/R2 (measured +0.03 %, asserted within 0.1 %);
//! * the Cattaneo–Mindlin stick semi-width c = a sqrt(1 − Q/μP) at the end (measured 0.11 h,
//!   h the contact element size; `history.csv`'s c lies midway between two nodes, h/2 apart,
//!   so it is quantised to ±h/4: asserted within 0.25 h);
//! * every self-check `ok`;
//! * `stickslip analytic hertz --case cases/own_mesh.json` finds the radii the script was given
//!   and the same closed-form a.
//!
//! Fails, never skips, when gmsh is missing (`bash scripts/test.sh` installs it).

mod common;
use common::*;
use serde_json::Value;
use stickslip::analytic::cattaneo::CattaneoMindlin;
use stickslip::analytic::hertz::{Geometry, Hertz};

/// The script's default radii: the lower body (the case's `contact.slave`) and the upper one.
const R_LOWER: f64 = 12.0;
const R_UPPER: f64 = 5.0;

#[test]
fn own_mesh_recipe_runs_as_shipped_and_matches_hertz_and_cattaneo_mindlin() {
    // The mesh, as the README says to build it (meshes/two_cylinders.msh, not in git).
    let script = std::process::Command::new("python3")
        .arg("meshes/two_cylinders.py")
        .current_dir(repo())
        .output()
        .expect("python3 runs");
    assert!(
        script.status.success(),
        "`python3 meshes/two_cylinders.py` failed (gmsh is needed: bash scripts/test.sh \
         installs it): {}",
        String::from_utf8_lossy(&script.stderr)
    );
    println!("{}", String::from_utf8_lossy(&script.stdout).trim());

    // The case as shipped, from the repository's root as the README runs it.
    let out = tempdir("own-mesh");
    let (code, _, err) = stickslip(&[
        "run",
        repo().join("cases/own_mesh.json").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "cases/own_mesh.json: {err}");
    let case: Value =
        serde_json::from_str(&std::fs::read_to_string(repo().join("cases/own_mesh.json")).unwrap())
            .unwrap();
    let body = |i: usize, k: &str| case["bodies"][i][k].as_f64().unwrap();
    let p = -case["stages"][0]["pilot_y"]["force"].as_f64().unwrap();
    let q = case["stages"][1]["pilot_x"]["force"].as_f64().unwrap();
    let mu = case["contact"]["friction"]["mu"].as_f64().unwrap();
    let geom = Geometry::from_bodies(
        R_LOWER,
        R_UPPER,
        body(0, "E"),
        body(0, "nu"),
        body(1, "E"),
        body(1, "nu"),
    )
    .unwrap();
    let hertz = Hertz::new(geom, p).unwrap();
    let c_cm = CattaneoMindlin::new(hertz, mu)
        .unwrap()
        .stick_half_width(q)
        .unwrap();

    let run = CaseRun {
        code,
        stderr: err,
        out: out.clone(),
    };
    let history = run.history();
    let stage = history.col("stage");
    let normal_end = history.rows.iter().rfind(|r| r[stage] == 0.0).unwrap();
    let a = normal_end[history.col("a")];
    let c = history.last("c");
    let summary = run.summary();
    let h = summary["friction"]["h_contact"].as_f64().unwrap();
    let a_err = a / hertz.a - 1.0;
    let c_err = (c - c_cm) / h;
    println!(
        "a = {a:.6} against Hertz {:.6} ({:+.3} %); c = {c:.6} against Cattaneo–Mindlin {c_cm:.6} \
         ({c_err:+.3} h, h = {h:.5}); a/h = {:.1}",
        hertz.a,
        100.0 * a_err,
        hertz.a / h
    );
    const A_TOL: f64 = 0.001;
    const C_TOL: f64 = 0.25;
    assert!(
        a_err.abs() < A_TOL,
        "a = {a} against Hertz {}: {:+.3} %",
        hertz.a,
        100.0 * a_err
    );
    assert!(c_err.abs() < C_TOL, "c = {c} against {c_cm}: {c_err:+.3} h");
    for check in summary["checks"].as_array().unwrap() {
        assert_eq!(check["level"], "ok", "{check}");
    }

    // The closed forms from the same case: the radii fitted to the mesh, the same a.
    let (code, json, err) = stickslip(&["analytic", "hertz", "--case", "cases/own_mesh.json"]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&json).unwrap();
    let r = |b: &str| v["scene"][b]["r"].as_f64().unwrap();
    assert!(
        (r("body1") / R_LOWER - 1.0).abs() < 1e-9 && (r("body2") / R_UPPER - 1.0).abs() < 1e-9,
        "radii {} and {} against {R_LOWER} and {R_UPPER}",
        r("body1"),
        r("body2")
    );
    assert!(
        (v["a"].as_f64().unwrap() / hertz.a - 1.0).abs() < 1e-9,
        "{v}"
    );

    validation_row(
        "301-own-mesh",
        "your own mesh, as the README builds it: `python3 meshes/two_cylinders.py` (radii 12 and 5 mm, a/h = 20), `cases/own_mesh.json` (P = 2.5 N/mm, then Q = 0.5 μP with μ = 0.2)",
        "Hertz a (1/R = 1/R1 + 1/R2), Cattaneo–Mindlin c",
        &format!(
            "a {:+.2} % (asserted within {} %); c within {:.2} h (asserted {C_TOL} h); every self-check ok",
            100.0 * a_err,
            100.0 * A_TOL,
            c_err.abs()
        ),
        "own_mesh",
    );
}
