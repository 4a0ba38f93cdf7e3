//! Rupture on a long planar interface (`cases/rupture_pmma.json`, docs/dynamics.md): the
//! weakened patches of a stage, the refusal of bad ones, and the fronts' energy balance and
//! speed on a ladder of interface meshes.
//!
//! The shipped case itself (h = 1 mm) is run as shipped in `tests/shipped_cases.rs`, which
//! checks `G = Γ` per speed band there. Here the case runs on `blocks_h2.msh` (h = 2 mm, Δt
//! doubled so that `c_s Δt / h` is the shipped 0.5) and on the shipped mesh, writing no field
//! (`history.csv` holds every time step's fronts): the measured `G/Γ` converges as h falls, and
//! the front arrives at the same times on both. With `STICKSLIP_RUPTURE_FINE=1` the ladder adds
//! `blocks_h05.msh` (h = 0.5 mm, made on demand; about 10 minutes on 2 cores).

mod common;
use common::rupture::{Sample, Track, bands, samples, tracks, wave_speeds};
use common::*;
use serde_json::{Value, json};

/// The shipped case on mesh `mesh` (a file of `meshes/`) with time step `dt` and no fields.
fn variant(mesh: &str, dt: f64) -> Value {
    let mut v = shipped_case_on("rupture_pmma.json", mesh);
    v["stages"][2]["dynamic"]["dt"] = json!(dt);
    v["output"] = json!({"every": 100000, "vtu": false, "contact_csv": false, "energy": true});
    v
}

/// The spontaneous samples of a run: more than 4 mm ahead of the patch forced at 67 m/s to
/// 40 mm, within the fine mesh (see `tests/shipped_cases.rs`).
fn spontaneous(t: &[Track; 2]) -> Vec<Sample> {
    let forced = |t: f64| (6.7e4 * t).min(40.0);
    t.iter()
        .flat_map(|tr| samples(tr, 15))
        .filter(|x| x.ell - forced(x.t) > 4.0 && x.ell <= 200.0 && x.ratio.is_finite())
        .collect()
}

/// The first time the right front reaches `ell`.
fn arrival(t: &Track, ell: f64) -> f64 {
    t.t[t
        .ell
        .iter()
        .position(|&x| x >= ell)
        .expect("the front gets there")]
}

#[test]
fn the_energy_release_rate_at_the_fronts_converges_to_the_fracture_energy() {
    let (_, _, c_r) = wave_speeds();
    let mut levels = vec![("h2", 2.0, 7.4e-7), ("h1", 1.0, 3.7e-7)];
    if std::env::var("STICKSLIP_RUPTURE_FINE").is_ok_and(|v| v == "1") {
        ensure_mesh("blocks_h05");
        levels.push(("h05", 0.5, 1.85e-7));
    }
    let mut worst = Vec::new();
    let mut runs = Vec::new();
    for (tag, h, dt) in &levels {
        let run = run_case(
            &format!("rupture-{tag}"),
            &variant(&format!("blocks_{tag}.msh"), *dt),
            &[],
        );
        run.assert_ok(tag);
        let t = tracks(&run.history());
        let s = spontaneous(&t);
        let b = bands(&s, c_r);
        let w = b.iter().map(|x| (x.2 - 1.0).abs()).fold(0.0, f64::max);
        for (lo, n, mean, min, max) in &b {
            println!("h = {h}: v/c_R {lo:.1}: {n} samples, G/Γ {mean:.4} [{min:.4}, {max:.4}]");
        }
        let v_max = s.iter().map(|x| x.v).fold(0.0, f64::max) / c_r;
        println!("h = {h}: worst band |G/Γ − 1| = {w:.4}, fastest front {v_max:.3} c_R");
        worst.push(w);
        runs.push(t);
    }
    // The worst band's error falls with h (measured 5.9 % at h = 2 mm and 2.3 % at 1 mm: an
    // observed order of 1.4).
    let order = (worst[0] / worst[1]).log2();
    println!("observed order of the worst band's |G/Γ − 1|: {order:.2}");
    assert!(worst[1] < 0.03 && worst[0] < 0.07, "{worst:?}");
    assert!(order > 1.0, "{worst:?}");
    // The front reaches 40, 100 and 200 mm at the same times on both meshes, to 0.5 % of the
    // time since the patch began (measured 1.1–1.9 µs of 460–620 µs).
    for ell in [40.0, 100.0, 200.0] {
        let (a, b) = (arrival(&runs[0][1], ell), arrival(&runs[1][1], ell));
        println!("front at {ell} mm: t = {a:.4e} s (h = 2), {b:.4e} s (h = 1)");
        assert!((a - b).abs() < 5e-3 * b, "{ell}: {a} {b}");
    }
    equation_of_motion(&runs[1]);
    validation_row(
        "470-rupture-energy-release-rate",
        "Rupture fronts, PMMA-like blocks: G (dynamic J-integral) / Γ per speed band 0.1–0.9 c_R, worst band",
        "Γ = ½ (f_s − f_d) p D_c of the law",
        &format!(
            "worst band |G/Γ − 1|: {:.1} % at h = 2 mm, {:.1} % at h = 1 mm (observed order {order:.1}; asserted < 7 %, < 3 %, order > 1)",
            100.0 * worst[0],
            100.0 * worst[1]
        ),
        "rupture",
    );
}

/// The front speed against Freund's equation of motion of a semi-infinite crack,
/// `G_static(ℓ) (1 − v/c_R) = Γ`, with the static energy release rate of a crack of
/// half-length ℓ under the stress drop `τ0 − f_d p`, `G_static = π (1 − ν) (τ0 − f_d p)² ℓ / (2μ)`
/// (`p = Γ/(W/p)` at the front). The measured bilateral front runs ahead of it: the equation's
/// speed is reached at a shorter ℓ (measured at h = 1 mm: 0.57 c_R at ℓ = 50 mm where it gives
/// 0.38; 0.90 at 100 mm where it gives 0.70), and the factor that closes the balance,
/// `Γ/G_static`, follows `sqrt(1 − v/c_R)` within 10 % instead of `1 − v/c_R`.
fn equation_of_motion(t: &[Track; 2]) {
    let (_, _, c_r) = wave_speeds();
    let s = samples(&t[1], 15);
    let mu = common::rupture::E / (2.0 * (1.0 + common::rupture::NU));
    let (tau0, fd, w_p) = (0.485, 0.1, 0.5e-3);
    let mut rows = Vec::new();
    for ell in [40.0, 50.0, 60.0, 80.0, 100.0] {
        let x = s.iter().find(|x| x.ell >= ell).unwrap();
        let i = t[1].t.iter().position(|&tt| tt == x.t).unwrap();
        let gamma = t[1].gamma[i];
        let p = gamma / w_p;
        let g_static =
            std::f64::consts::PI * (1.0 - common::rupture::NU) * (tau0 - fd * p).powi(2) * x.ell
                / (2.0 * mu);
        let (v, eom) = (x.v / c_r, (1.0 - gamma / g_static).max(0.0));
        let needed = gamma / g_static;
        println!(
            "ℓ = {:.1} mm: v = {v:.3} c_R, equation of motion {eom:.3} c_R; Γ/G_static = {needed:.3}, sqrt(1 − v/c_R) = {:.3}",
            x.ell,
            (1.0 - v).sqrt()
        );
        assert!(v > eom, "ℓ = {}: {v} against {eom}", x.ell);
        assert!(
            (needed / (1.0 - v).sqrt() - 1.0).abs() < 0.1,
            "ℓ = {}",
            x.ell
        );
        rows.push(format!("{:.0} mm: {v:.2} vs {eom:.2}", x.ell));
    }
    validation_row(
        "471-rupture-equation-of-motion",
        "Rupture fronts: speed against half-length ℓ, h = 1 mm",
        "Freund's equation of motion G_static(ℓ)(1 − v/c_R) = Γ (semi-infinite crack)",
        &format!("v/c_R measured vs equation: {}", rows.join("; ")),
        "rupture",
    );
}

#[test]
fn a_whole_patch_weakens_as_its_stage_starts_and_a_growing_one_at_its_speed() {
    // Sheared to 0.2 MPa, below f_d p: nothing slips, and the patches show alone.
    let mut v = shipped_case_on("rupture_pmma.json", "blocks_h2.msh");
    v["stages"][1]["pilot_x"] = json!({"force": 240.0});
    for t in v["tractions"].as_array_mut().unwrap() {
        let s = t["ty"].as_f64().unwrap().signum();
        t["ty"] = json!(0.2 * s);
    }
    v["stages"][2] = json!({"name": "grow", "weaken": [{"x": [-30.0, 30.0], "slip": 0.002, "speed": 1.0e6}],
                            "dynamic": {"dt": 7.4e-7, "duration": 1.48e-5, "rho_inf": 0.9}});
    v["stages"].as_array_mut().unwrap().insert(
        2,
        json!({"name": "whole", "steps": 1, "weaken": [{"x": [100.0, 120.0], "slip": 0.004}]}),
    );
    v["output"] = json!({"every": 1, "vtu": false});
    let run = run_case("rupture-patches", &v, &[]);
    run.assert_ok("patches");
    let c = run.contact(5);
    let (x, s) = (c.col("x"), c.col("slip_mu"));
    for r in &c.rows {
        let inside = (100.0..=120.0).contains(&r[x]);
        assert_eq!(
            r[s],
            if inside { 0.004 } else { 0.0 },
            "whole patch, x = {}",
            r[x]
        );
    }
    // 20 steps of 0.74 µs at 1 m/ms: the growing patch spans |x| ≤ 14.8 mm.
    let c = run.last_contact();
    for r in &c.rows {
        let (xr, sr) = (r[x], r[s]);
        if xr.abs() <= 14.8 - 1e-6 {
            assert!(sr >= 0.002, "x = {xr}: {sr}");
        } else if xr.abs() > 15.8 && !(100.0..=120.0).contains(&xr) {
            assert!(sr < 0.002, "x = {xr}: {sr}");
        }
    }
}

#[test]
fn bad_patches_are_refused_before_anything_is_written() {
    let cases: [(&str, Value, &str); 3] = [
        (
            "no-node",
            json!([{"x": [5000.0, 6000.0], "slip": 0.002}]),
            "`stages[2].weaken[0].x` = [5000, 6000]: holds no node of the slave group `lower_face`",
        ),
        (
            "negative",
            json!([{"x": [-1.0, 1.0], "slip": -1.0}]),
            "`stages[2].weaken[0].slip` = -1",
        ),
        (
            "slow",
            json!([{"x": [-1.0, 1.0], "slip": 0.002, "speed": 0.0}]),
            "`stages[2].weaken[0].speed` = 0",
        ),
    ];
    for (tag, patches, want) in cases {
        let mut v = shipped_case_on("rupture_pmma.json", "blocks_h2.msh");
        v["stages"][2]["weaken"] = patches;
        let run = run_case(&format!("rupture-bad-{tag}"), &v, &[]);
        assert_eq!(run.code, 2, "{tag}: {}", run.stderr);
        assert!(run.stderr.contains(want), "{tag}: {}", run.stderr);
        assert!(!run.wrote_output(), "{tag}: output written");
    }
    // A sweep's loads are stage lists of their own: their patches are checked the same way.
    let case = shipped_case_on("rupture_pmma.json", "blocks_h2.msh");
    let mut stages = case["stages"].clone();
    stages[2]["weaken"] = json!([{"x": [5000.0, 6000.0], "slip": 0.002}]);
    let dir = tempdir("rupture-bad-sweep");
    std::fs::write(dir.join("case.json"), case.to_string()).unwrap();
    std::fs::write(
        dir.join("loads.json"),
        json!({"stages": [stages]}).to_string(),
    )
    .unwrap();
    let out = dir.join("out");
    let (code, _, err) = sweep_in(&dir, "loads.json", &out, &["--quiet"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("loads.json: load 0")
            && err.contains("`stages[2].weaken[0].x` = [5000, 6000]"),
        "{err}"
    );
    assert!(!out.exists(), "sweep output written");
    // A growing patch needs time: a quasi-static stage refuses `speed`.
    let mut v = shipped_case_on("rupture_pmma.json", "blocks_h2.msh");
    v["stages"][1]["weaken"] = json!([{"x": [-1.0, 1.0], "slip": 0.002, "speed": 1.0}]);
    let run = run_case("rupture-bad-static", &v, &[]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("`stages[1].weaken[0].speed` = 1: a growing patch needs time"),
        "{}",
        run.stderr
    );
    // Without friction there is nothing to weaken.
    let mut v = shipped_case_on("rupture_pmma.json", "blocks_h2.msh");
    v["contact"].as_object_mut().unwrap().remove("friction");
    let run = run_case("rupture-bad-frictionless", &v, &[]);
    assert_eq!(run.code, 2, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("`stages[2].weaken[0].slip` = 0.002: needs a friction law"),
        "{}",
        run.stderr
    );
}
