//! `stickslip sweep`: one case against several friction laws on one shared model. Each law's
//! force-controlled tangential loading passes its peak; the table reports Q_max/P, which must
//! agree with the JKR limit (eq. QJKR at its maximum) within 2 % for Λ = 0.025, the paper's
//! Fig. 6 regime.

mod common;
use common::{run_case, shipped_case_on, sweep_in, tempdir};
use serde_json::{Value, json};
use std::path::Path;

#[test]
fn sweep_reports_the_apparent_friction_of_each_law() {
    let mut v = shipped_case_on("fig2.json", "vm272_L3.msh");
    v["stages"][1] = json!({"steps": 30, "pilot_x": {"force": 3.0}});
    let dir = tempdir("sweep");
    std::fs::write(dir.join("case.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let laws: Vec<Value> = [0.12, 0.15, 0.2].iter().map(|fs| json!({"shape": "ramp", "fs": fs, "fd": 0.1, "lambda": 0.025, "radius": 4.0, "load": 10.0})).collect();
    std::fs::write(
        dir.join("sweep.json"),
        json!({"friction": laws}).to_string(),
    )
    .unwrap();
    let out = dir.join("out");
    let sweep = |laws: &str, out: &Path, extra: &[&str]| sweep_in(&dir, laws, out, extra);
    let (code, _, err) = sweep("sweep.json", &out, &["--quiet"]);
    assert!(code == 0, "{err}");
    let table: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let rows = table["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for r in rows {
        let f = &r["friction"];
        let (fe, jkr) = (
            f["apparent_friction"].as_f64().unwrap(),
            f["apparent_friction_jkr"].as_f64().unwrap(),
        );
        println!("f_s = {}: Q_max/P FE {fe:.5}, JKR {jkr:.5}", f["f_s"]);
        assert!(
            r["status"]
                .as_str()
                .unwrap()
                .starts_with("equilibrium lost"),
            "{}",
            r["status"]
        );
        // Measured +0.02, −0.03, −1.8 %. L3 does not resolve s0 (h = 2.6e-2 against
        // s0/2 = 5.4e-3), where the peak found depends on the loads the cutbacks try: a
        // rounding-level change of the contact solve moves the f_s = 0.2 row between −1.8 %
        // and +0.2 %. The header's 2 % holds for all three.
        assert!((fe / jkr - 1.0).abs() < 0.02, "{fe} vs {jkr}");
        // Every row carries the self-checks of its last converged step.
        let checks = r["checks"].as_array().unwrap();
        let eq = checks.iter().find(|c| c["name"] == "equilibrium").unwrap();
        assert_eq!(eq["level"], "ok", "{eq}");
        assert!(checks.iter().any(|c| c["name"] == "zone_margin"));
    }
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4);
    // Bad sweep input: a clear message and exit status 2.
    std::fs::write(
        dir.join("bad.json"),
        r#"{"friction": [{"shape": "ramp", "fs": 0.1, "fd": 0.2, "delta": 1e-3}]}"#,
    )
    .unwrap();
    let (code, _, err) = sweep("bad.json", &dir.join("o2"), &[]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.json"));
    assert!(!dir.join("o2").exists());
}

/// A load sweep (`stages`: one replacement stage list per load) with the case's own law:
/// Cattaneo–Mindlin at four tangential loads on one model, each stick zone against
/// c = a sqrt(1 − Q/(μP)) within one node spacing (L3, h/2 = 0.013 mm); rows come loads
/// outermost. A sweep file with neither list is refused.
#[test]
fn sweep_over_loads_with_the_case_law() {
    let v = shipped_case_on("vm272_cm.json", "vm272_L3.msh");
    let dir = tempdir("sweep-loads");
    std::fs::write(dir.join("case.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let normal = v["stages"][0].clone();
    let qs: [f64; 4] = [0.5, 1.0, 1.5, 1.9];
    let stages: Vec<Value> = qs
        .iter()
        .map(|q| json!([normal, {"steps": 10, "pilot_x": {"force": q}}]))
        .collect();
    std::fs::write(
        dir.join("loads.json"),
        json!({"stages": stages}).to_string(),
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, err) = sweep_in(&dir, "loads.json", &out, &["--quiet"]);
    assert_eq!(code, 0, "{err}");
    let table: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let rows = table["rows"].as_array().unwrap();
    assert_eq!(rows.len(), qs.len());
    let (mu, p, a): (f64, f64, f64) = (0.2, 10.0, 0.6808);
    for (k, (r, q)) in rows.iter().zip(qs).enumerate() {
        assert_eq!(r["load_index"].as_u64(), Some(k as u64));
        assert_eq!(r["status"], "completed");
        let c = r["c"].as_f64().unwrap();
        let c_cm = a * (1.0 - q / (mu * p)).sqrt();
        println!("Q = {q}: c = {c:.4} (C–M {c_cm:.4})");
        assert!(
            (c - c_cm).abs() < 0.6808 / 25.6 / 2.0,
            "Q {q}: c {c} vs {c_cm}"
        );
    }
    std::fs::write(dir.join("empty.json"), "{}").unwrap();
    let (code, _, err) = sweep_in(&dir, "empty.json", &dir.join("o3"), &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("empty.json") && err.contains("anything to sweep"),
        "{err}"
    );
    assert!(!dir.join("o3").exists());
}

/// Every row of a sweep is what `stickslip run` of its law gives, bit for bit (the last step's
/// b and c, the friction figures, the self-checks, the Newton iterations and factorisations). The rows share
/// their factorised Delassus blocks (on L3 the structured contact solve factorises them), so
/// this holds only if sharing changes no arithmetic.
///
/// On L3; on L4, whose 514 contact unknowns are enough for a first contact to start from
/// the frictionless problem and Hertz's contact set (`NORMAL_FIRST_FROM`), shared by the rows;
/// and on L5, whose 1 018 take the structured solve's shortcuts.
#[test]
fn sweep_rows_are_bit_for_bit_the_single_runs_of_their_laws() {
    for mesh in ["vm272_L3.msh", "vm272_L4.msh", "vm272_L5.msh"] {
        rows_are_their_single_runs(mesh);
    }
}

fn rows_are_their_single_runs(mesh: &str) {
    let mut v = shipped_case_on("fig2.json", mesh);
    v["output"] = json!({"vtu": false});
    let dir = tempdir(&format!("sweep-vs-runs-{mesh}"));
    std::fs::write(dir.join("case.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let laws = [
        json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0}),
        json!({"shape": "step", "fs": 0.2, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0}),
        json!({"shape": "exponential", "fs": 0.12, "fd": 0.1, "lambda": 0.02, "radius": 4.0, "load": 10.0}),
    ];
    std::fs::write(dir.join("laws.json"), json!({"friction": laws}).to_string()).unwrap();
    let out = dir.join("out");
    let (code, _, err) = sweep_in(&dir, "laws.json", &out, &["--quiet", "--no-cache"]);
    assert_eq!(code, 0, "{err}");
    let table: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    let rows = table["rows"].as_array().unwrap();
    assert_eq!(rows.len(), laws.len());
    for (k, (row, law)) in rows.iter().zip(&laws).enumerate() {
        let mut case = v.clone();
        case["contact"]["friction"] = law.clone();
        let run = run_case(&format!("sweep-vs-run-{mesh}-{k}"), &case, &["--no-cache"]);
        let s = run.summary();
        assert_eq!(row["status"], s["status"], "law {k}");
        let last = &s["steps"][40]["contact"];
        assert_eq!(row["steps"], 41, "law {k}");
        for key in ["b", "c"] {
            assert_eq!(row[key], last[key], "law {k}: {key}");
        }
        // Q_max, the apparent friction and the law's scales; the self-checks' values.
        assert_eq!(row["friction"], s["friction"], "law {k}");
        assert_eq!(row["checks"], s["checks"], "law {k}");
        assert_eq!(row["newton_iterations"], s["newton_iterations"], "law {k}");
        assert_eq!(row["lu_factorisations"], s["lu_factorisations"], "law {k}");
        assert!(
            s["lu_factorisations"].as_u64().unwrap() >= 2,
            "law {k}: {}",
            s["lu_factorisations"]
        );
    }
}
