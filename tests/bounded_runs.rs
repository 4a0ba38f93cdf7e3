//! Runs that end: the load paths that used to stall or spin are refused before their first
//! step or stop with a clear message, and the written steps land on the stage's nominal loads
//! whatever the cutbacks between them (the shipped cases themselves run, bounded, in
//! tests/shipped_cases.rs).

mod common;
use common::*;
use serde_json::json;

fn names(dir: &std::path::Path) -> Vec<String> {
    if !dir.exists() {
        return Vec::new();
    }
    file_names(dir)
}

/// A frictionless contact whose pilot leaves `pilot_x` force-controlled: nothing holds the
/// upper body along x. Refused before the first step, naming the key, exit 2, nothing written.
#[test]
fn a_free_pilot_axis_is_refused_before_the_first_step() {
    let mut v = shipped_case_on("hertz.json", "vm272_L0.msh");
    v["stages"][0]["pilot_x"] = json!({"force": 0.0});
    let r = run_case("free-axis", &v, &[]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("`pilot_x`"), "{}", r.stderr);
    assert!(r.stderr.contains("displacement"), "{}", r.stderr);
    assert!(!r.stderr.contains("cutting"), "cut back: {}", r.stderr);
    assert_eq!(
        names(&r.out),
        Vec::<String>::new(),
        "written: {:?}",
        names(&r.out)
    );
    // The same axis left out of the stage (force-controlled at zero by default).
    let mut v = shipped_case_on("hertz.json", "vm272_L0.msh");
    v["stages"][0].as_object_mut().unwrap().remove("pilot_x");
    let r = run_case("free-axis-default", &v, &[]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("`pilot_x`"), "{}", r.stderr);
}

/// One proportional stage from no load asking Q/P = 0.25 with μ = 0.2: no load of it has an
/// equilibrium. Refused at once with the ratio and μ (exit 2), not bracketed to "Q_max = 0".
#[test]
fn a_path_above_the_friction_coefficient_at_every_load_is_refused() {
    let mut v = shipped_case_on("vm272_cm.json", "vm272_L1.msh");
    v["stages"] = json!([{"name": "both", "steps": 4,
        "pilot_x": {"force": 2.5}, "pilot_y": {"force": -10.0}}]);
    let r = run_case("beyond-mu", &v, &[]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("Q/P = 0.250000"), "{}", r.stderr);
    assert!(r.stderr.contains("0.200000"), "{}", r.stderr);
    assert!(!r.stderr.contains("Q_max = 0"), "{}", r.stderr);
    assert!(!r.stderr.contains("cutting"), "{}", r.stderr);
    // Below μ the same path runs.
    v["stages"][0]["pilot_x"] = json!({"force": 1.5});
    let r = run_case("below-mu", &v, &["--quiet"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
}

/// The mild steel / copper pair as shipped (one normal step, then 50 steps to 1.05 f_s P,
/// every 10th nominal step written): the cutbacks near the peak insert sub-steps, yet every
/// written step but the last (the state before the lost equilibrium) is at a nominal load k/50
/// of the stage; the run ends (exit 5) with the bracket's attempts counted.
#[test]
fn written_steps_land_on_nominal_loads_after_cutbacks() {
    let dir = tempdir("nominal");
    let (code, _, err) = stickslip_env(
        &[
            "run",
            repo()
                .join("cases/pair_mild_steel_copper.json")
                .to_str()
                .unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ],
        &[("STICKSLIP_NO_CACHE", "1")],
    );
    assert_eq!(code, 5, "{err}");
    let t = Table::read(&dir.join("history.csv"));
    let cut: f64 = t.rows.iter().map(|r| r[t.col("cutbacks")]).sum();
    assert!(cut > 0.0, "no cutbacks: the test needs some");
    let pvd = std::fs::read_to_string(dir.join("pair_mild_steel_copper.pvd")).unwrap();
    let times: Vec<f64> = pvd
        .lines()
        .filter(|l| l.contains("part=\"0\""))
        .map(|l| {
            let s = l.split("timestep=\"").nth(1).unwrap();
            s[..s.find('"').unwrap()].parse().unwrap()
        })
        .collect();
    println!("written times {times:?}, {cut} cutbacks");
    assert!(times.len() >= 3, "{times:?}");
    // Stage 0 (the normal load) is nominal step 1; step k of the tangential stage is nominal
    // step 1 + k of the case, and `output.every` = 10 picks those that are multiples of 10.
    for tm in &times[..times.len() - 1] {
        let k = (tm - 1.0) * 50.0;
        assert!(
            (k - k.round()).abs() < 1e-6 && (1 + k.round() as usize).is_multiple_of(10),
            "written at {tm}: not the nominal load of every 10th step"
        );
    }
    assert!(err.contains("attempts"), "{err}");
}

/// `"vtu": false` keeps the contact tables unless `"contact_csv": false`.
#[test]
fn contact_tables_follow_their_own_switch() {
    let mut v = shipped_case_on("vm272_cm.json", "vm272_L1.msh");
    v["output"] = json!({"vtu": false});
    let r = run_case("csv-on", &v, &["--quiet"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let n = names(&r.out);
    assert!(n.iter().any(|f| f.starts_with("contact_")), "{n:?}");
    assert!(!n.iter().any(|f| f.ends_with(".vtu")), "{n:?}");
    v["output"] = json!({"vtu": false, "contact_csv": false});
    let r = run_case("csv-off", &v, &["--quiet"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let n = names(&r.out);
    assert!(!n.iter().any(|f| f.starts_with("contact_")), "{n:?}");
}

/// A surface given where a curve is needed names the case key that gave it.
#[test]
fn a_surface_for_a_curve_names_the_key() {
    let mut v = shipped_case_on("hertz.json", "vm272_L0.msh");
    v["contact"]["slave"] = json!("lower_body");
    let r = run_case("surface-for-curve", &v, &[]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("`contact.slave`: physical group `lower_body` is a surface"),
        "{}",
        r.stderr
    );
}

/// A run projected to write more than the limit says so before its first step, with the
/// estimate, which is within a fifth of what it then writes (`vm272_cm` on L3, every step).
#[test]
fn a_large_output_is_announced_with_a_fair_estimate() {
    let mut v = shipped_case_on("vm272_cm.json", "vm272_L3.msh");
    v["stages"][1]["steps"] = json!(10);
    v["output"] = json!({"every": 1});
    let dir = tempdir("output-warning");
    let case = dir.join("case.json");
    std::fs::write(&case, v.to_string()).unwrap();
    let out = dir.join("out");
    let (code, _, err) = stickslip_env(
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        &[("STICKSLIP_OUTPUT_WARN", "1000000")],
    );
    assert_eq!(code, 0, "{err}");
    let line = err
        .lines()
        .find(|l| l.starts_with("warning: this run will write about"))
        .unwrap_or_else(|| panic!("no warning: {err}"));
    assert!(
        err.find(line).unwrap() < err.find("step 1 ").unwrap_or(usize::MAX),
        "the warning comes after the first step: {err}"
    );
    let projected: f64 = line
        .split(" bytes)")
        .next()
        .unwrap()
        .rsplit('(')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let written = s["output_bytes"].as_f64().unwrap();
    println!("projected {projected:e} bytes, written {written:e}");
    assert!(
        (projected / written - 1.0).abs() < 0.2,
        "projected {projected} against {written} written"
    );
    // Below the limit: no warning.
    let (code, _, err) = stickslip_env(
        &[
            "run",
            case.to_str().unwrap(),
            "--out",
            dir.join("quiet").to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("will write about"), "{err}");
}
