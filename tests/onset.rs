//! The onset of sliding (paper §4, Figs. 4–6) with finite elements, on Fig. 2's law
//! (f_s = 0.15, f_d = 0.1, Λ = 0.05, so Ψ = 0.0125: JKR Q_max = 1.0747 f_d P, eq. QJKR):
//! * force control past the peak ends with exit status 5 and reports Q_max, bracketed by
//!   bisection, within 1 % of the JKR limit;
//! * displacement control traces the curve through the peak; its largest sampled Q lies within
//!   the sampling of the force-controlled Q_max; before the peak the two controls give the same
//!   stick zone at the same Q.

mod common;
use common::{repo, tempdir};
use serde_json::{Value, json};

fn run(name: &str, stage: Value) -> (i32, String, Vec<Vec<f64>>, Value) {
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(repo().join("cases/fig2.json")).unwrap())
            .unwrap();
    v["mesh"] = json!(repo().join("meshes/vm272_L4.msh").to_str().unwrap());
    v["output"] = json!({"vtu": false});
    v["stages"][1] = stage;
    let dir = tempdir(name);
    std::fs::write(dir.join("case.json"), serde_json::to_string(&v).unwrap()).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args([
            "run",
            dir.join("case.json").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let rows = hist
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    let summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into(),
        rows,
        summary,
    )
}

#[test]
fn force_and_displacement_control_find_the_same_peak() {
    let (code, err, force_rows, s) = run(
        "onset-force",
        json!({"steps": 40, "pilot_x": {"force": 1.2}}),
    );
    assert_eq!(code, 5, "{err}");
    assert!(
        err.contains("equilibrium lost") && err.contains("Q_max"),
        "{err}"
    );
    let f = &s["friction"];
    let q_force = f["q_max"].as_f64().unwrap();
    let jkr = f["apparent_friction_jkr"].as_f64().unwrap() * 10.0;
    assert!(
        s["status"]
            .as_str()
            .unwrap()
            .starts_with("equilibrium lost")
    );
    // Displacement control through the peak (pilot_ux ≈ 0.037 mm there), finely sampled.
    let (code, err, disp_rows, _) = run(
        "onset-disp",
        json!({"steps": 200, "pilot_x": {"displacement": 0.04}}),
    );
    assert_eq!(code, 0, "{err}");
    // columns: 4 pilot_ux, 6 pilot_fx, 15 c
    let q_disp = disp_rows.iter().map(|r| r[6]).fold(0.0, f64::max);
    println!(
        "Q_max: force control {q_force:.5}, displacement control (sampled) {q_disp:.5}, JKR {jkr:.5}"
    );
    assert!(
        (q_force / jkr - 1.0).abs() < 0.01,
        "force-controlled Q_max {q_force} vs JKR {jkr}"
    );
    assert!(
        q_disp <= q_force + 1e-6 && q_force - q_disp < 0.003,
        "peaks {q_force} vs {q_disp}"
    );
    // Past the peak the displacement-controlled load falls back to gross sliding, Q = f_d P.
    let last = disp_rows.last().unwrap()[6];
    assert!((last - 1.0).abs() < 1e-6, "final Q {last}");
    // Same stick zone at the same Q before the peak (within one node spacing, h/2).
    let h = 0.6808 / 51.2 / 2.0;
    let mut compared = 0;
    for r in force_rows
        .iter()
        .filter(|r| r[1] == 1.0 && r[6] > 0.1 && r[6] < 1.0)
    {
        let (q, c) = (r[6], r[15]);
        let i = disp_rows.iter().position(|d| d[6] >= q).unwrap();
        let (d0, d1) = (&disp_rows[i - 1], &disp_rows[i]);
        let c_d = if (d1[6] - q).abs() < (q - d0[6]).abs() {
            d1[15]
        } else {
            d0[15]
        };
        assert!(
            (c - c_d).abs() <= h + 1e-12,
            "at Q = {q}: c {c} (force) vs {c_d} (displacement)"
        );
        compared += 1;
    }
    assert!(compared > 20);
}
