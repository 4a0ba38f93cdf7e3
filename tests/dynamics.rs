//! Time integration (generalised-α with the consistent tri6 mass) against closed forms:
//! plane P and S waves in a strip (arrival times within 1 % of `x/c_p` and `x/c_s`,
//! converging in h and Δt together), energy conservation of a free elastic vibration over
//! 1 000 steps with ρ∞ = 1, and the scheme's dissipation with ρ∞ < 1 booked apart.
//!
//! The strip is [0, 10] × [0, 1] with square cells of side h split into 6-node triangles.
//! With `uy = 0` on its long sides a normal traction on its left end sends a wave of uniaxial
//! strain, `u_x(x, t) = v (t − x/c_p)` behind the front with `c_p = sqrt((λ + 2μ)/ρ)` and
//! `v = p/(ρ c_p)`; with `ux = 0` there a shear traction sends `u_y = v (t − x/c_s)`,
//! `c_s = sqrt(μ/ρ)`, `v = τ/(ρ c_s)`. Both are exact plane-strain solutions of the strip. The
//! arrival time at the probe line `x = 5` is the intercept of a least-squares line through
//! the probe's displacement after the front has passed (and before its reflection returns),
//! which the discrete front's dispersion does not move to first order.

mod common;
use common::*;
use stickslip::case::Case;
use stickslip::driver::{LogLevel, simulate};
use stickslip::energy::EnergyMeter;
use stickslip::model::Model;

const E: f64 = 1.0;
const NU: f64 = 0.25;
const RHO: f64 = 1.0;

fn lame() -> (f64, f64) {
    (
        E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)),
        E / (2.0 * (1.0 + NU)),
    )
}

/// Writes the strip with `n` cells across its height and returns its directory.
fn strip(name: &str, n: usize) -> std::path::PathBuf {
    let dir = tempdir(name);
    let (nodes, tris, sides) = structured(10 * n, n, 0.0, 10.0, 0.0, 1.0, 0.0);
    std::fs::write(
        dir.join("strip.msh"),
        msh41_sides(&nodes, &[("body", tris)], sides),
    )
    .unwrap();
    dir
}

/// The mean displacement component `c` of each probe line `x = xs[i]` after every step, with
/// its time.
fn probe_history(dir: &std::path::Path, case: &Case, c: usize, xs: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let model = Model::build(case, &dir.join("case.json")).unwrap();
    let probes: Vec<Vec<usize>> = xs
        .iter()
        .map(|x| {
            (0..model.mesh.nodes.len())
                .filter(|&k| (model.mesh.nodes[k][0] - x).abs() < 1e-9)
                .collect()
        })
        .collect();
    assert!(probes.iter().all(|p| p.len() > 2));
    let mut out = vec![Vec::new(); xs.len()];
    simulate(&model, case, None, LogLevel::Error, &mut |ev| {
        let u = ev.u.expect("a dynamic step has its field");
        let t = ev.record.physical_time.expect("integrated in time");
        for (p, o) in probes.iter().zip(&mut out) {
            let mean = p
                .iter()
                .map(|&k| model.dofs.displacement(k, u)[c])
                .sum::<f64>()
                / p.len() as f64;
            o.push((t, mean));
        }
        Ok(())
    })
    .unwrap();
    out
}

/// The intercept `t_a` and slope of the least-squares line through the `(t, u)` with `t` in
/// `[t0, t1]`.
fn arrival(hist: &[(f64, f64)], t0: f64, t1: f64) -> (f64, f64) {
    let pts: Vec<&(f64, f64)> = hist.iter().filter(|(t, _)| *t >= t0 && *t <= t1).collect();
    let n = pts.len() as f64;
    let (st, su) = pts.iter().fold((0.0, 0.0), |(a, b), (t, u)| (a + t, b + u));
    let (mt, mu) = (st / n, su / n);
    let (sxy, sxx) = pts.iter().fold((0.0, 0.0), |(a, b), (t, u)| {
        (a + (t - mt) * (u - mu), b + (t - mt) * (t - mt))
    });
    let slope = sxy / sxx;
    (mt - mu / slope, slope)
}

/// A strip case: one dynamic stage with the traction (`kind`: `tx` or `ty`) applied at the
/// first step and held, Δt = `dt`, the long sides held in `held`.
fn wave_case(dir: &std::path::Path, kind: &str, held: &str, dt: f64, duration: f64) -> Case {
    let json = format!(
        r#"{{"mesh": "strip.msh",
          "bodies": [{{"group": "body", "E": {E}, "nu": {NU}, "density": {RHO}}}],
          "supports": [{{"group": "bottom", "{held}": 0}}, {{"group": "top", "{held}": 0}},
                       {{"group": "right", "ux": 0, "uy": 0}}],
          "tractions": [{{"group": "left", "kind": "uniform", "{kind}": 1.0}}],
          "stages": [{{"name": "wave", "traction_scale": 1.0,
                       "dynamic": {{"dt": {dt}, "duration": {duration}, "ramp": 0, "rho_inf": 1.0}}}}]}}"#
    );
    std::fs::write(dir.join("case.json"), &json).unwrap();
    let case: Case = serde_json::from_str(&json).unwrap();
    case.validate("case.json").unwrap();
    case
}

/// On the ladder of `n` cells across (Δt = h / (2c)): the relative errors of the wave speed
/// measured between the probe lines x = 2.5 and x = 5 (the difference of their arrival
/// times), of the arrival time at x = 5 less the load's onset (a step load in the scheme's
/// balance at mid-step acts as a ramp over the first step: its onset is Δt/2), and of the
/// particle speed behind the front.
fn wave_errors(kind: &str, held: &str, c: f64, comp: usize, name: &str) -> Vec<[f64; 3]> {
    let v_exact = 1.0 / (RHO * c);
    // The reflection from the far end (x = 10) is back at the probe x at (20 − x)/c.
    let t_back = |x: f64| (20.0 - x) / c;
    [2usize, 4, 8]
        .iter()
        .map(|&n| {
            let h = 1.0 / n as f64;
            let dt = 0.5 * h / c;
            let dir = strip(&format!("{name}-{n}"), n);
            let case = wave_case(&dir, kind, held, dt, t_back(2.5) - 1.0 / c);
            let hist = probe_history(&dir, &case, comp, &[2.5, 5.0]);
            // Lines through the displacement from two cell-crossings after each front.
            let (t1, _) = arrival(&hist[0], 2.5 / c + 2.0 / c, t_back(2.5) - 1.0 / c);
            let (t2, slope) = arrival(&hist[1], 5.0 / c + 2.0 / c, t_back(5.0) - 1.0 / c);
            let e_c = (2.5 / (t2 - t1) - c).abs() / c;
            let e_t = (t2 - 0.5 * dt - 5.0 / c).abs() / (5.0 / c);
            let e_v = (slope.abs() - v_exact).abs() / v_exact;
            eprintln!(
                "{name}: n = {n}, h = {h}, Δt = {dt:.4}: speed {:.6} (exact {c:.6}, error {e_c:.2e}), arrival at x = 5 {t2:.5} (exact {:.5} + Δt/2, error {e_t:.2e}), particle speed error {e_v:.2e}",
                2.5 / (t2 - t1),
                5.0 / c
            );
            [e_c, e_t, e_v]
        })
        .collect()
}

/// Every level within 1 % in speed and arrival (measured: 2e-3 and 8e-4 at h = 0.5), the
/// finest within 1e-4 (measured 1e-5 to 5e-5), the errors falling over the ladder; the
/// validation row `key` for the wave `wave` (speed `c`).
fn assert_waves(errs: &[[f64; 3]], key: &str, wave: &str, c: &str) {
    for e in errs {
        assert!(e.iter().all(|x| *x < 0.01), "{errs:?}");
    }
    assert!(errs[2].iter().all(|x| *x < 1e-4), "{errs:?}");
    for w in errs.windows(2) {
        assert!(w[1][0] < w[0][0], "speed error does not fall: {errs:?}");
        assert!(w[1][1] < w[0][1], "arrival error does not fall: {errs:?}");
    }
    let col = |k: usize| {
        errs.iter()
            .map(|e| sci(e[k]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    validation_row(
        key,
        &format!(
            "{wave} wave in a strip (generalised-α, ρ∞ = 1, consistent mass), step traction, h = 0.5, 0.25, 0.125 with Δt = h/(2c)"
        ),
        &format!("{c}; arrival 5/c + Δt/2; particle speed τ/(ρc)"),
        &format!(
            "speed error {} (asserted < 1 %, finest < 1e-4, falling); arrival {}; particle speed {}",
            col(0),
            col(1),
            col(2)
        ),
        "dynamics",
    );
}

#[test]
fn p_wave_arrives_at_x_over_c_p_within_one_percent_converging_in_h_and_dt() {
    let (l, m) = lame();
    let c_p = ((l + 2.0 * m) / RHO).sqrt();
    assert_waves(
        &wave_errors("tx", "uy", c_p, 0, "pwave"),
        "400-p-wave",
        "P",
        "c_p = sqrt((λ + 2μ)/ρ)",
    );
}

#[test]
fn s_wave_arrives_at_x_over_c_s_within_one_percent_converging_in_h_and_dt() {
    let (_, m) = lame();
    let c_s = (m / RHO).sqrt();
    assert_waves(
        &wave_errors("ty", "ux", c_s, 1, "swave"),
        "401-s-wave",
        "S",
        "c_s = sqrt(μ/ρ)",
    );
}

/// The strip's case: held in y on its long sides and at its far end, stretched in one
/// quasi-static step by a traction on its left end, then the stages `after` (JSON text).
fn stretched_strip(after: &str) -> String {
    format!(
        r#"{{"mesh": "strip.msh",
          "bodies": [{{"group": "body", "E": {E}, "nu": {NU}, "density": {RHO}}}],
          "supports": [{{"group": "bottom", "uy": 0}}, {{"group": "top", "uy": 0}},
                       {{"group": "right", "ux": 0, "uy": 0}}],
          "tractions": [{{"group": "left", "kind": "uniform", "tx": -1.0}}],
          "stages": [{{"name": "stretch", "steps": 1, "traction_scale": 1.0}}, {after}]}}"#
    )
}

/// The strip stretched quasi-statically, then released: a free vibration with no external
/// work after the release step.
fn released(
    dir: &std::path::Path,
    rho_inf: f64,
    steps: usize,
) -> Vec<stickslip::energy::EnergyRow> {
    let (l, m) = lame();
    let c_p = ((l + 2.0 * m) / RHO).sqrt();
    let dt = 0.5 * 0.5 / c_p;
    let json = stretched_strip(&format!(
        r#"{{"name": "free", "traction_scale": 0.0,
             "dynamic": {{"dt": {dt}, "duration": {}, "ramp": 0, "rho_inf": {rho_inf}}}}}"#,
        dt * steps as f64
    ));
    std::fs::write(dir.join("case.json"), &json).unwrap();
    let case: Case = serde_json::from_str(&json).unwrap();
    case.validate("case.json").unwrap();
    let model = Model::build(&case, &dir.join("case.json")).unwrap();
    let mut meter = EnergyMeter::new(&model);
    simulate(&model, &case, None, LogLevel::Error, &mut |ev| {
        meter.step(&model, ev);
        Ok(())
    })
    .unwrap();
    meter.rows
}

#[test]
fn a_free_vibration_keeps_its_energy_over_1000_steps_with_rho_inf_one() {
    let dir = strip("energy-conserved", 2);
    let rows = released(&dir, 1.0, 1000);
    assert_eq!(rows.len(), 1001);
    // After the release step (row 1) nothing works on the strip.
    let total = |r: &stickslip::energy::EnergyRow| r.elastic + r.kinetic;
    let e1 = total(&rows[1]);
    let worst = rows[1..]
        .iter()
        .map(|r| (total(r) - e1).abs() / e1)
        .fold(0.0, f64::max);
    eprintln!(
        "energy after the release {e1:.6e}, largest relative drift over 1000 steps {worst:.2e}"
    );
    assert!(worst < 1e-12, "drift {worst:.3e}");
    // It vibrates: the energy moves between its two forms.
    let k_max = rows.iter().map(|r| r.kinetic).fold(0.0, f64::max);
    assert!(k_max > 0.3 * e1, "{k_max} vs {e1}");
    // The balance closes to round-off: the scheme dissipates nothing.
    let num = rows.last().unwrap().numerical;
    assert!(num.abs() < 1e-12 * e1, "numerical dissipation {num:.3e}");
    validation_row(
        "402-energy-conserved",
        "free vibration of a strip released from a static stretch, ρ∞ = 1, 1 000 steps",
        "total energy ½vᵀMv + ½uᵀKu constant (the trapezoidal rule's energy identity)",
        &format!(
            "largest relative drift {} (asserted < 1e-12); `numerical` {}",
            sci(worst),
            sci(num.abs() / e1)
        ),
        "dynamics",
    );
}

#[test]
fn with_rho_inf_below_one_the_energy_lost_is_booked_as_the_schemes_dissipation() {
    let dir = strip("energy-dissipated", 2);
    let total = |r: &stickslip::energy::EnergyRow| r.elastic + r.kinetic;
    let mut drops = Vec::new();
    for rho in [0.9, 0.5] {
        let rows = released(&dir, rho, 400);
        let (first, last) = (&rows[1], rows.last().unwrap());
        let drop = total(first) - total(last);
        let booked = last.numerical - first.numerical;
        eprintln!(
            "ρ∞ = {rho}: energy {:.6e} → {:.6e}, drop {drop:.4e}, booked as numerical {booked:.4e}, quasi-static residual {:.2e}",
            total(first),
            total(last),
            last.residual
        );
        assert!(drop > 0.0);
        assert!(
            (booked - drop).abs() <= 1e-12 * total(first),
            "{booked} vs {drop}"
        );
        assert!(last.residual.abs() <= 1e-12 * total(first));
        drops.push(drop);
    }
    // The lower ρ∞, the more the high frequencies are damped.
    assert!(drops[1] > drops[0], "{drops:?}");
    validation_row(
        "403-energy-dissipated",
        "the same vibration with ρ∞ = 0.9 and 0.5, 400 steps",
        "the energy lost booked as the scheme's `numerical` dissipation, the quasi-static residual untouched; more loss at lower ρ∞",
        &format!(
            "lost {:.2e} and {:.2e} (asserted > 0, increasing), booked to 1e-12",
            drops[0], drops[1]
        ),
        "dynamics",
    );
}

/// Fig. 2's law on VM272 L2 with the density of a polymer (units mm, N, s: ρ in t/mm³); the
/// tangential stage replaced by `tangential`.
fn fig2_with(tangential: serde_json::Value) -> serde_json::Value {
    let mut v = shipped_case_on("fig2.json", "vm272_L2.msh");
    for b in v["bodies"].as_array_mut().unwrap() {
        b["density"] = serde_json::json!(1.2e-9);
    }
    v["stages"][1] = tangential;
    v["output"] = serde_json::json!({"vtu": false, "contact_csv": false});
    v
}

/// The rows of stage 1 of a run's history: columns `x` and `y`.
fn stage1(r: &CaseRun, x: &str, y: &str) -> (Vec<f64>, Vec<f64>) {
    let t = r.history();
    let (s, cx, cy) = (t.col("stage"), t.col(x), t.col(y));
    t.rows
        .iter()
        .filter(|row| row[s] == 1.0)
        .map(|row| (row[cx], row[cy]))
        .unzip()
}

/// Linear interpolation of `(xs, ys)` (`xs` increasing) at `x`.
fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let k = xs.partition_point(|v| *v < x).clamp(1, xs.len() - 1);
    let w = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
    ys[k - 1] + w * (ys[k] - ys[k - 1])
}

/// A tangential force ramped slowly (smoothly over 0.1 s, about 400 periods of the bodies'
/// lowest mode and 4e4 times a / c_s) in a dynamic stage follows the quasi-static
/// Q–displacement curve within 0.1 % (measured 7.5e-5 relative to the largest displacement
/// with ρ∞ = 1 over 0.1 s; inertia's share falls with the ramp time: 1.4e-2 over a linear
/// ramp of 4e-3 s at another density).
#[test]
fn a_slow_force_ramp_in_time_follows_the_quasi_static_curve() {
    let qs = run_case(
        "qs-force",
        &fig2_with(serde_json::json!({"name": "t", "steps": 200, "pilot_x": {"force": 0.8}})),
        &["--quiet", "--no-cache"],
    );
    qs.assert_ok("quasi-static");
    let mut v = fig2_with(serde_json::json!({"name": "t", "pilot_x": {"force": 0.8},
        "dynamic": {"dt": 5e-4, "duration": 0.1, "rho_inf": 1.0, "ramp_shape": "smooth"}}));
    v["output"]["energy"] = serde_json::json!(true);
    let dy = run_case("dyn-force", &v, &["--quiet", "--no-cache"]);
    dy.assert_ok("dynamic");
    // With ρ∞ = 1 the balance closes to round-off with friction too: the scheme dissipates
    // nothing, the friction's dissipation is all in `dissipation`.
    let e = Table::read(&dy.out.join("energy.csv"));
    let (num, work, dis) = (
        e.last("numerical"),
        e.last("work_pilot"),
        e.last("dissipation"),
    );
    eprintln!(
        "ρ∞ = 1 with friction: numerical {num:.2e} of the pilot's work {work:.4e} (friction dissipated {dis:.3e})"
    );
    assert!(num.abs() < 1e-12 * work, "{num:.3e}");
    assert!(dis > 1e-6 * work);

    let (q_s, u_s) = stage1(&qs, "pilot_fx", "pilot_ux");
    let (q_d, u_d) = stage1(&dy, "pilot_fx", "pilot_ux");
    let u_max = u_s.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = q_d
        .iter()
        .zip(&u_d)
        .filter(|(q, _)| **q > q_s[0])
        .map(|(q, u)| (u - interp(&q_s, &u_s, *q)).abs() / u_max)
        .fold(0.0, f64::max);
    eprintln!("force ramp in time: largest displacement difference {worst:.2e} of the largest");
    assert!(worst < 1e-3, "{worst:.3e}");
    validation_row(
        "404-quasi-static-force",
        "Fig. 2's law on VM272 L2, the tangential force ramped smoothly in time over 0.1 s (ρ∞ = 1)",
        "the quasi-static Q–displacement curve (200 steps); the energy balance with friction",
        &format!(
            "displacement within {} of the largest (asserted < 1e-3); `numerical` {} of the work",
            sci(worst),
            sci(num.abs() / work)
        ),
        "dynamics",
    );
}

/// The peak tangential force Q_max reached in time under slip control (the mean slip ramped
/// smoothly over 0.08 s, ρ∞ = 0.5) is the quasi-static one within 0.1 % (measured 7.1e-5),
/// and so is the force along the rising branch from a slip of 1e-4 (measured ≤ 8.4e-4 of
/// Q_max, against a linear interpolation of the 200 quasi-static steps). Slip control in time needs ρ∞ < 1: the constraint on the mean slip leaves the
/// mode it drives undamped, and with ρ∞ = 1 the pilot force diverges.
#[test]
fn q_max_reached_slowly_in_time_is_the_quasi_static_one() {
    let qs = run_case(
        "qs-slip",
        &fig2_with(serde_json::json!({"name": "t", "steps": 200, "pilot_x": {"slip": 0.003}})),
        &["--quiet", "--no-cache"],
    );
    qs.assert_ok("quasi-static");
    let dy = run_case(
        "dyn-slip",
        &fig2_with(serde_json::json!({"name": "t", "pilot_x": {"slip": 0.003},
            "dynamic": {"dt": 4e-4, "duration": 0.08, "rho_inf": 0.5, "ramp_shape": "smooth"}})),
        &["--quiet", "--no-cache"],
    );
    dy.assert_ok("dynamic");
    let (s_s, q_s) = stage1(&qs, "mean_slip", "pilot_fx");
    let (s_d, q_d) = stage1(&dy, "mean_slip", "pilot_fx");
    let peak = |q: &[f64]| q.iter().cloned().fold(f64::MIN, f64::max);
    let (qm_s, qm_d) = (peak(&q_s), peak(&q_d));
    let k_peak = q_s.iter().position(|q| *q == qm_s).unwrap();
    let rel = (qm_d / qm_s - 1.0).abs();
    let worst = s_d
        .iter()
        .zip(&q_d)
        .filter(|(s, _)| **s >= 1e-4 && **s <= s_s[k_peak])
        .map(|(s, q)| (q - interp(&s_s, &q_s, *s)).abs() / qm_s)
        .fold(0.0, f64::max);
    eprintln!(
        "Q_max quasi-static {qm_s:.6}, in time {qm_d:.6} (relative {rel:.2e}); rising branch within {worst:.2e}"
    );
    assert!(rel < 1e-3);
    assert!(worst < 1e-3, "{worst:.3e}");
    validation_row(
        "405-quasi-static-qmax",
        "Fig. 2's law on VM272 L2 under slip control in time (smooth ramp over 0.08 s, ρ∞ = 0.5)",
        "the quasi-static Q_max and rising branch (200 steps)",
        &format!(
            "Q_max within {} (asserted < 1e-3); rising branch within {} of Q_max (asserted < 1e-3)",
            sci(rel),
            sci(worst)
        ),
        "dynamics",
    );
}

#[test]
fn a_dynamic_stage_without_a_density_names_the_body() {
    let mut v = fig2_with(serde_json::json!({"name": "t", "pilot_x": {"force": 0.8},
        "dynamic": {"dt": 1e-3, "duration": 0.01}}));
    v["bodies"][1].as_object_mut().unwrap().remove("density");
    let r = run_case("no-density", &v, &["--quiet", "--no-cache"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("bodies[1].density")
            && r.stderr.contains("upper_body")
            && r.stderr.contains("stages[1]"),
        "{}",
        r.stderr
    );
    assert!(!r.wrote_output());
    // The switch on a lost equilibrium needs the densities too.
    let mut v = shipped_case("fig2_event.json");
    v["bodies"][0].as_object_mut().unwrap().remove("density");
    let r = run_case("no-density-event", &v, &["--quiet", "--no-cache"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("bodies[0].density") && r.stderr.contains("on_lost_equilibrium"),
        "{}",
        r.stderr
    );
}

#[test]
fn bad_time_steps_are_refused_with_the_key() {
    for (dynamic, key) in [
        (
            serde_json::json!({"dt": 0.0, "duration": 0.01}),
            "stages[1].dynamic.dt",
        ),
        (
            serde_json::json!({"dt": 1e-3, "duration": 1e-4}),
            "stages[1].dynamic.duration",
        ),
        (
            serde_json::json!({"dt": 1e-9, "duration": 1.0}),
            "stages[1].dynamic.duration",
        ),
        (
            serde_json::json!({"dt": 1e-3, "duration": 0.01, "rho_inf": 1.5}),
            "stages[1].dynamic.rho_inf",
        ),
        (
            serde_json::json!({"dt": 1e-3, "duration": 0.01, "ramp": 0.02}),
            "stages[1].dynamic.ramp",
        ),
    ] {
        let v = fig2_with(
            serde_json::json!({"name": "t", "pilot_x": {"force": 0.8}, "dynamic": dynamic}),
        );
        let r = run_case("bad-dt", &v, &["--quiet", "--no-cache"]);
        assert_eq!(r.code, 2, "{key}: {}", r.stderr);
        assert!(r.stderr.contains(key), "{key}: {}", r.stderr);
        assert!(!r.wrote_output());
    }
    // Steps are the time steps of a dynamic stage: given as well, they are refused.
    let v = fig2_with(
        serde_json::json!({"name": "t", "steps": 10, "pilot_x": {"force": 0.8},
        "dynamic": {"dt": 1e-3, "duration": 0.01}}),
    );
    let r = run_case("steps-and-dt", &v, &["--quiet", "--no-cache"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("remove `steps`"), "{}", r.stderr);
}

/// A time step through which a shear wave crosses more than one contact element is warned of,
/// with the numbers and the Δt that resolves it.
#[test]
fn a_time_step_too_coarse_for_the_fronts_is_warned_of_with_the_numbers() {
    let v = fig2_with(serde_json::json!({"name": "t", "pilot_x": {"force": 0.8},
        "dynamic": {"dt": 1e-6, "duration": 1e-5, "ramp": 0}}));
    let r = run_case("coarse-dt", &v, &["--no-cache"]);
    r.assert_ok("coarse Δt");
    // h ≈ 0.05 mm along the contact on L2, c_s = 2.53e5 mm/s: c_s Δt / h ≈ 5.
    let line = r
        .stderr
        .lines()
        .find(|l| l.contains("c_s Δt / h"))
        .unwrap_or_else(|| panic!("no warning: {}", r.stderr));
    assert!(
        line.contains("Δt = 1.000e-6") && line.contains("a Δt below"),
        "{line}"
    );
    let fine = fig2_with(serde_json::json!({"name": "t", "pilot_x": {"force": 0.8},
        "dynamic": {"dt": 1e-7, "duration": 1e-6, "ramp": 0}}));
    let r = run_case("fine-dt", &fine, &["--no-cache"]);
    r.assert_ok("fine Δt");
    assert!(!r.stderr.contains("c_s Δt / h"), "{}", r.stderr);
}

/// `until: "rest"`: a released strip whose vibration the scheme damps (ρ∞ = 0 with steps far
/// longer than its periods) comes to rest, the stage ends there, and the next quasi-static
/// stage goes on from that state.
#[test]
fn a_stage_that_comes_to_rest_ends_and_the_next_goes_on() {
    let dir = strip("rest", 2);
    let mut json: serde_json::Value = serde_json::from_str(&stretched_strip(
        r#"{"name": "release", "traction_scale": 0.0,
            "dynamic": {"dt": 50.0, "duration": 5000.0, "ramp": 0, "rho_inf": 0.0,
                        "until": "rest", "rest_window": 5}},
           {"name": "stretch again", "steps": 2, "traction_scale": 0.5}"#,
    ))
    .unwrap();
    json["output"] = serde_json::json!({"vtu": false, "energy": true});
    let json = json.to_string();
    let r = run_case_in(&dir, "case.json", &json, &["--quiet", "--no-cache"]);
    r.assert_ok("rest");
    let s = r.summary();
    let e = &s["events"][0];
    assert_eq!(e["end"], serde_json::json!("rest"), "{e}");
    let steps = e["steps"].as_u64().unwrap();
    assert!(steps < 100, "{steps} steps: the stage did not end at rest");
    let h = r.history();
    let stage = h.col("stage");
    assert_eq!(h.rows.last().unwrap()[stage], 2.0);
    // The last stage is quasi-static: at rest, half the stretch.
    assert_eq!(h.last("kinetic"), 0.0);
    let u_end = h.last("t");
    assert!(u_end > 0.0 && u_end < 5000.0, "{u_end}");
}

/// A time step whose contact Newton does not converge is taken as two of half the size:
/// Fig. 2's law on L2 past Q_max with a time step of 5e-6 s (c_s Δt / h ≈ 10, steel-like
/// density): a few steps are halved, once and twice, and the event still ends in gross sliding.
#[test]
fn a_time_step_that_fails_is_taken_in_halves() {
    let mut v = fig2_with(serde_json::json!({"name": "t", "steps": 40, "pilot_x": {"force": 1.2}}));
    for b in v["bodies"].as_array_mut().unwrap() {
        b["density"] = serde_json::json!(7.85e-9);
    }
    v["on_lost_equilibrium"] = serde_json::json!({"dynamic": {"dt": 5e-6, "duration": 2e-3,
        "rho_inf": 0.9, "until": "rest"}});
    let r = run_case("halved", &v, &["--no-cache"]);
    assert_eq!(r.code, 5, "{}", r.stderr);
    assert!(r.stderr.contains("two steps of Δt/2"), "{}", r.stderr);
    assert_eq!(
        r.summary()["events"][0]["end"],
        serde_json::json!("sliding")
    );
    let h = r.history();
    let (t, halvings) = (h.col("t"), h.col("cutbacks"));
    let halved: Vec<&Vec<f64>> = h
        .rows
        .iter()
        .filter(|x| x[t] > 0.0 && x[halvings] > 0.0)
        .collect();
    eprintln!("{} time steps halved", halved.len());
    assert!(!halved.is_empty());
    // A halved step ends between two of the stage's steps: at a quarter or three quarters of
    // Δt (twice halved), or at its middle.
    for row in &halved {
        let k = row[t] / 5e-6;
        let frac = k - k.floor();
        assert!(
            [0.25, 0.5, 0.75].iter().any(|f| (frac - f).abs() < 1e-6)
                || !(1e-6..=1.0 - 1e-6).contains(&frac),
            "t = {}",
            row[t]
        );
    }
}
