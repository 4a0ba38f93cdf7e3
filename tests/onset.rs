//! The onset of sliding (paper §4, Figs. 4–6) with finite elements, on Fig. 2's law
//! (f_s = 0.15, f_d = 0.1, Λ = 0.05, so Ψ = 0.0125: JKR Q_max = 1.0747 f_d P, eq. QJKR):
//! * force control past the peak ends with exit status 5 and reports Q_max, bracketed by
//!   bisection, within 1 % of the JKR limit;
//! * displacement control traces the curve through the peak; its largest sampled Q lies within
//!   the sampling of the force-controlled Q_max; before the peak the two controls give the same
//!   stick zone at the same Q.

mod common;
use common::{run_case, shipped_case, shipped_case_on, validation_row};
use serde_json::{Value, json};

fn run(name: &str, stage: Value) -> (i32, String, Vec<Vec<f64>>, Value) {
    let mut v = shipped_case_on("fig2.json", "vm272_L4.msh");
    v["output"] = json!({"vtu": false});
    v["stages"][1] = stage;
    let r = run_case(name, &v, &[]);
    let (rows, summary) = (r.history().rows, r.summary());
    (r.code, r.stderr, rows, summary)
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

/// Slip control (`pilot_x: {"slip": …}`) traces the softening branch that force and
/// displacement control cannot: past the peak both the force and the pilot displacement turn
/// back while the stick zone keeps shrinking. Checked against the force-controlled run (same
/// peak, same stick zone at the same Q before it) and against the double Cattaneo–Mindlin
/// curve Q(c) of the same law (eqs. Qx, W1), an independent closed form, on both branches.
#[test]
fn slip_control_traces_the_softening_branch() {
    use stickslip::analytic::dcm::DoubleCm;
    let (code, err, force_rows, s) = run(
        "onset-force-2",
        json!({"steps": 40, "pilot_x": {"force": 1.2}}),
    );
    assert_eq!(code, 5, "{err}");
    let q_force = s["friction"]["q_max"].as_f64().unwrap();
    // The load at which force control found no equilibrium (from the status line).
    let status = s["status"].as_str().unwrap();
    let q_fail: f64 = status
        .split("no equilibrium at ")
        .nth(1)
        .unwrap()
        .trim_end_matches(')')
        .parse()
        .unwrap();
    // The shipped slip-controlled case, as it is (VTK output off).
    let mut v = shipped_case("fig2_softening.json");
    v["output"] = json!({"vtu": false});
    let r = run_case("onset-slip", &v, &[]);
    let (code, err, rows) = (r.code, r.stderr.clone(), r.history().rows);
    assert_eq!(code, 0, "{err}");
    // columns: 4 pilot_ux, 6 pilot_fx (Q), 15 c, 20 mean_slip
    let tang: Vec<&Vec<f64>> = rows.iter().filter(|r| r[1] == 1.0).collect();
    let (i_peak, q_peak) = tang
        .iter()
        .enumerate()
        .map(|(i, r)| (i, r[6]))
        .fold((0, 0.0), |m, (i, q)| if q > m.1 { (i, q) } else { m });
    println!(
        "Q_max: force control {q_force:.6} (none at {q_fail:.6}), slip control peak {q_peak:.6} at step {i_peak} of {}",
        tang.len()
    );
    // No step is cut back: the first slip-controlled step used to cycle across the ramp's
    // kink until a cutback; the relaxed update (halved once it stops contracting) settles it.
    // columns: 9 cutbacks
    assert!(
        tang.iter().all(|r| r[9] == 0.0),
        "cutbacks under slip control: {:?}",
        tang.iter().map(|r| r[9]).collect::<Vec<_>>()
    );
    // The mean slip is driven exactly.
    let last = tang.last().unwrap();
    assert!((last[20] - 0.00272).abs() < 1e-12, "mean slip {}", last[20]);
    // Same peak. Force control brackets the load at which its Newton iteration stops
    // converging to one bisection width (the tangential step 0.03 halved 12 times: 7.3e-6);
    // that is a little below the limit point itself, where the Jacobian becomes singular and
    // convergence slows: measured 3e-5 (0.003 %) below the slip-controlled peak. Slip control
    // samples the curve, ΔQ ≈ 2e-4 per step at the top (measured |q_peak − q_force| = 3.2e-5).
    let (fail_tol, peak_tol) = (5e-5, 6e-5);
    assert!(
        q_peak < q_fail + fail_tol,
        "slip-controlled peak {q_peak} above the load without equilibrium {q_fail}"
    );
    assert!(
        (q_peak - q_force).abs() < peak_tol,
        "peaks {q_peak} vs {q_force}"
    );
    // Past the peak: Q falls and c shrinks over several steps …
    let after = &tang[i_peak..];
    assert!(after.len() >= 5, "only {} steps past the peak", after.len());
    for w in after.windows(2) {
        assert!(w[1][6] < w[0][6] + 1e-9, "Q rises past the peak: {:?}", w);
        assert!(w[1][15] <= w[0][15] + 1e-12, "c grows past the peak");
    }
    assert!(last[6] < q_peak - 0.005 && last[15] < 0.5 * tang[i_peak][15]);
    // … and the pilot displacement turns back: displacement control cannot follow (snap-back).
    let ux_max = tang.iter().map(|r| r[4]).fold(f64::MIN, f64::max);
    assert!(
        last[4] < ux_max - 5e-5,
        "pilot displacement {} vs its maximum {ux_max}",
        last[4]
    );
    // Same stick zone at the same Q as force control before the peak (within h/2, L4).
    let h = 0.6808 / 51.2 / 2.0;
    let mut compared = 0;
    let seq: Vec<&Vec<f64>> = std::iter::once(rows.iter().rfind(|r| r[1] == 0.0).unwrap())
        .chain(tang.iter().copied())
        .collect();
    for r in force_rows
        .iter()
        .filter(|r| r[1] == 1.0 && r[6] > 0.1 && r[6] < q_peak - 0.01)
    {
        // Slip control samples Q coarsely at first (uniform slip steps): c(Q) must lie between
        // the stick semi-widths of the two slip-controlled steps around Q (c falls with Q).
        // The state after the normal load (Q = 0) starts the sequence.
        let (q, c) = (r[6], r[15]);
        let i = seq.iter().position(|d| d[6] >= q).unwrap();
        let (lo, hi) = (seq[i][15], seq[i - 1][15]);
        assert!(
            c >= lo - h - 1e-12 && c <= hi + h + 1e-12,
            "at Q = {q}: c {c} outside [{lo}, {hi}] of slip control"
        );
        compared += 1;
    }
    assert!(compared > 20, "{compared}");
    // Against the double Cattaneo–Mindlin curve of the same law (f_s/f_d = 1.5, Λ = 0.05),
    // at the FE stick semi-width: within 1.5 % of f_d P where c ≤ 0.6a (the stick edge is
    // located to ±h/2 and Q(c) is steep there), within 0.3 % on the softening branch.
    let (dcm, weak) = DoubleCm::normalized(1.5, 0.05).unwrap();
    let a = s["friction"]["a_hertz"].as_f64().unwrap();
    let (mut worst, mut worst_soft) = (0.0f64, 0.0f64);
    for (i, r) in tang.iter().enumerate() {
        let ca = r[15] / a;
        if !(0.02..=0.6).contains(&ca) {
            continue;
        }
        let (_, q_dcm, _) = dcm.curve_point(ca, weak).unwrap();
        // FE: f_d P = 1; the dimensionless closed form has a = R = E* = f_d = 1, P = π/4.
        let d = (r[6] - q_dcm / (dcm.fd * dcm.hertz.p_load)).abs();
        worst = worst.max(d);
        if i > i_peak {
            worst_soft = worst_soft.max(d);
        }
    }
    println!(
        "|Q_FE − Q_DCM(c_FE)|/(f_d P): ≤ {worst:.4} (c ≤ 0.6a), ≤ {worst_soft:.4} past the peak"
    );
    let (dcm_tol, soft_tol) = (0.015, 0.003);
    assert!(worst < dcm_tol, "{worst}");
    assert!(worst_soft < soft_tol, "{worst_soft}");
    validation_row(
        "250-onset",
        "slip control through the peak, Fig. 2's law, L4",
        "force control; double C–M Q(c)",
        &format!(
            "peak {q_peak:.6} vs {q_force:.6} f_d P (force control; asserted within {peak_tol:.0e}, and at most {fail_tol:.0e} above {q_fail:.6}, the load at which force control found no equilibrium); c(Q) within the slip-control sampling of the force-controlled c before the peak ({compared} loads); Q(c) within {worst:.3} f_d P of double C–M for c ≤ 0.6a and {worst_soft:.4} f_d P past the peak (asserted {dcm_tol} and {soft_tol}); Q and c fall over the {} steps past the peak, and δ turns back",
            after.len() - 1
        ),
        "onset",
    );
}
