//! The command line as a user meets it: every `--help` says what the exit statuses mean, the
//! sweep's help shows the grid form, `analytic … --case CASE` takes the geometry, load and law
//! from a case, one spelling of the friction keys (`fs`, `fd`) in case files and sweep grids
//! with the old one (`f_s`, `f_d`) read with a note, and an error about a group names the key.

mod common;
use common::*;
use serde_json::{Value, json};

/// `stickslip ARGS`, which must exit with `code`; returns (stdout, stderr).
fn expect(args: &[&str], code: i32) -> (String, String) {
    let (c, out, err) = stickslip(args);
    assert_eq!(
        c,
        code,
        "stickslip {}: exit {c}\n{out}\n{err}",
        args.join(" ")
    );
    (out, err)
}

/// `stickslip analytic ARGS` as JSON (exit 0).
fn analytic(args: &[&str]) -> Value {
    let mut all = vec!["analytic"];
    all.extend_from_slice(args);
    let (out, _) = expect(&all, 0);
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

fn num(v: &Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("`{key}` in {v}"))
}

#[test]
fn every_help_gives_the_exit_statuses() {
    let (top, _) = expect(&["--help"], 0);
    for needle in [
        "Exit status",
        "2    bad input",
        "5    run: equilibrium lost",
        "101",
    ] {
        assert!(
            top.contains(needle),
            "stickslip --help lacks `{needle}`:\n{top}"
        );
    }
    let (run, _) = expect(&["run", "--help"], 0);
    for needle in [
        "Exit status",
        "0  the run completed",
        "2  bad input",
        "3  solver failure",
        "4  output error",
        "5  equilibrium lost",
        "--cache <DIR>",
        "--no-cache",
        "--quiet",
        "Print nothing but errors",
    ] {
        assert!(run.contains(needle), "run --help lacks `{needle}`:\n{run}");
    }
    for cmd in ["sweep-merge", "mesh-info", "schema", "analytic"] {
        let (h, _) = expect(&[cmd, "--help"], 0);
        assert!(
            h.contains("Exit status"),
            "{cmd} --help lacks the exit statuses:\n{h}"
        );
    }
}

#[test]
fn sweep_help_shows_the_grid_form_and_describes_quiet() {
    let (h, _) = expect(&["sweep", "--help"], 0);
    for needle in [
        "\"grid\"",
        "\"fs\"",
        "\"fd\"",
        "\"delta\"",
        "\"pilot_x\"",
        "\"stages\"",
        "\"friction\"",
        "Row r = load_index * laws + law_index",
        "Exit status",
        "--shard",
    ] {
        assert!(h.contains(needle), "sweep --help lacks `{needle}`:\n{h}");
    }
    // `--quiet` has a description of its own (on its line, or on the next in a narrow help).
    let quiet: String = h
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("--quiet"))
        .take(2)
        .collect();
    assert!(
        quiet.contains("Print nothing but errors"),
        "sweep --quiet is not described:\n{h}"
    );
}

#[test]
fn analytic_takes_the_scene_from_a_case() {
    // Fig. 2: VM272 on L5, two cylinders of 8 mm, P = 10 N/mm, a ramp law with Λ = 0.05.
    let h = analytic(&["hertz", "--case", "cases/fig2.json"]);
    let vm272 = analytic(&["hertz"]);
    for k in ["a", "p0", "r_eff", "e_star", "load"] {
        assert!(
            (num(&h, k) / num(&vm272, k) - 1.0).abs() < 1e-12,
            "{k}: {h} against {vm272}"
        );
    }
    for b in ["body1", "body2"] {
        let r = h["scene"][b]["r"].as_f64().unwrap();
        assert!((r / 8.0 - 1.0).abs() < 1e-12, "{b}: R = {r}");
    }
    assert_eq!(h["scene"]["body1"]["face"], "lower_arc");
    assert_eq!(h["scene"]["body2"]["group"], "upper_body");
    // The law from the case: the same double C–M state as with the flags.
    let d = analytic(&["dcm", "--case", "cases/fig2.json", "--q-ratio", "0.8"]);
    let f = analytic(&[
        "dcm",
        "--fs",
        "0.15",
        "--fd",
        "0.1",
        "--lambda",
        "0.05",
        "--q-ratio",
        "0.8",
    ]);
    for k in ["c_over_a", "b_over_a", "lambda", "psi"] {
        assert!(
            (num(&d, k) / num(&f, k) - 1.0).abs() < 1e-9,
            "{k}: {} against {}",
            d[k],
            f[k]
        );
    }
    let j = analytic(&["jkr", "--case", "cases/fig2.json"]);
    let jf = analytic(&["jkr", "--psi", "0.0125"]);
    assert!((num(&j, "q_max_ratio") / num(&jf, "q_max_ratio") - 1.0).abs() < 1e-9);
    let a = analytic(&["apparent", "--case", "cases/fig2.json", "--no-dcm"]);
    assert!((num(&a, "chi") - 0.025).abs() < 1e-12 && (num(&a, "fs_over_fd") - 1.5).abs() < 1e-12);
    let law = analytic(&["law", "--case", "cases/fig2.json"]);
    assert_eq!(law["law"]["shape"], "ramp");
    // A flag given as well overrides the case's value.
    let half = analytic(&["hertz", "--case", "cases/fig2.json", "--load", "2.5"]);
    assert!((num(&half, "a") / num(&h, "a") - 0.5).abs() < 1e-12);
    // A flat: the pad-on-flat pair, R = ∞ for the flat face, E and ν of each body.
    let pad = analytic(&["hertz", "--case", "cases/pair_copper_mild_steel.json"]);
    assert_eq!(pad["scene"]["body1"]["r"], "inf");
    assert!((num(&pad, "r_eff") / 25.0 - 1.0).abs() < 1e-9, "{pad}");
    assert!((pad["scene"]["body2"]["e"].as_f64().unwrap() - 110000.0).abs() < 1e-9);
}

#[test]
fn analytic_case_errors_name_what_is_missing() {
    // C–M needs a constant μ: Fig. 2's law weakens.
    let (_, err) = expect(
        &[
            "analytic",
            "cm",
            "--case",
            "cases/fig2.json",
            "--q-ratio",
            "0.5",
        ],
        2,
    );
    assert!(err.contains("--mu is required"), "{err}");
    // A frictionless case has no law for `law`.
    let (_, err) = expect(&["analytic", "law", "--case", "cases/hertz.json"], 2);
    assert!(err.contains("frictionless"), "{err}");
    // A contact face that names a surface: the key is named.
    let dir = tempdir("cli-options-slave");
    let mut case = shipped_case("fig2.json");
    case["mesh"] = mesh_path("vm272_L0.msh");
    case["contact"]["slave"] = json!("lower_body");
    let path = dir.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let (_, err) = expect(&["analytic", "hertz", "--case", path.to_str().unwrap()], 2);
    assert!(
        err.contains("`contact.slave`") && err.contains("`lower_body` is a surface"),
        "{err}"
    );
}

/// The lines of a CSV file without its `wall_s` column.
fn without_wall_time(path: &std::path::Path) -> Vec<String> {
    let csv = std::fs::read_to_string(path).unwrap();
    let wall = csv
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "wall_s")
        .unwrap();
    csv.lines()
        .map(|l| {
            let mut c: Vec<&str> = l.split(',').collect();
            c.remove(wall);
            c.join(",")
        })
        .collect()
}

/// Fig. 2's case on L0, whose friction law is a ramp with Δ given.
fn l0_case(friction: Value) -> Value {
    let mut case = shipped_case("fig2.json");
    case["mesh"] = mesh_path("vm272_L0.msh");
    case["contact"]["friction"] = friction;
    case["stages"][1]["pilot_x"] = json!({"force": 0.4});
    case["stages"][1]["steps"] = json!(4);
    case["output"] = json!({"vtu": false});
    case
}

#[test]
fn friction_keys_have_one_spelling_and_the_old_one_is_read_with_a_note() {
    let law = |fs: &str, fd: &str| json!({"shape": "ramp", fs: 0.15, fd: 0.1, "delta": 3e-4});
    // A case file: `fs`/`fd`, and `f_s`/`f_d` read as those with a note (not with --quiet).
    let new = run_case("spelling-new", &l0_case(law("fs", "fd")), &[]);
    new.assert_ok("fs/fd");
    assert!(!new.stderr.contains("old spelling"), "{}", new.stderr);
    let old = run_case("spelling-old", &l0_case(law("f_s", "f_d")), &[]);
    old.assert_ok("f_s/f_d");
    assert!(
        old.stderr.contains("note:")
            && old
                .stderr
                .contains("`contact.friction.f_s` is the old spelling of `fs`")
            && old.stderr.contains("`contact.friction.f_d`"),
        "{}",
        old.stderr
    );
    assert_eq!(
        without_wall_time(&new.out.join("history.csv")),
        without_wall_time(&old.out.join("history.csv")),
        "the two spellings give another run"
    );
    let quiet = run_case("spelling-quiet", &l0_case(law("f_s", "f_d")), &["--quiet"]);
    quiet.assert_ok("f_s/f_d --quiet");
    assert!(!quiet.stderr.contains("note:"), "{}", quiet.stderr);
    let mut both = law("fs", "fd");
    both["f_s"] = json!(0.2);
    let r = run_case("spelling-both", &l0_case(both), &["--quiet"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("`fs` or its old spelling `f_s`, not both"),
        "{}",
        r.stderr
    );
    assert!(!r.wrote_output());

    // A sweep grid: `fs`/`fd`, and `f_s`/`f_d` with a note; the same table either way.
    let dir = tempdir("spelling-sweep");
    let case = dir.join("case.json");
    std::fs::write(&case, l0_case(law("fs", "fd")).to_string()).unwrap();
    let mut tables = Vec::new();
    for (name, grid) in [
        (
            "new",
            json!({"fs": [0.15, 0.2], "fd": [0.1], "delta": [3e-4]}),
        ),
        (
            "old",
            json!({"f_s": [0.15, 0.2], "f_d": [0.1], "delta": [3e-4]}),
        ),
    ] {
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, json!({ "grid": grid }).to_string()).unwrap();
        let out = dir.join(format!("out-{name}"));
        let (_, err) = expect(
            &[
                "sweep",
                case.to_str().unwrap(),
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            0,
        );
        assert_eq!(
            err.contains("`grid.f_s` is the old spelling of `fs`"),
            name == "old",
            "{name}: {err}"
        );
        tables.push(without_wall_time(&out.join("sweep.csv")));
    }
    assert_eq!(
        tables[0], tables[1],
        "the grid's two spellings give other rows"
    );
    assert_eq!(tables[0].len(), 3, "{:?}", tables[0]);
    let file = dir.join("both.json");
    std::fs::write(
        &file,
        json!({"grid": {"fs": [0.15], "f_s": [0.2], "fd": [0.1], "delta": [3e-4]}}).to_string(),
    )
    .unwrap();
    let (_, err) = expect(
        &[
            "sweep",
            case.to_str().unwrap(),
            file.to_str().unwrap(),
            "--out",
            dir.join("out-both").to_str().unwrap(),
        ],
        2,
    );
    assert!(
        err.contains("`grid.f_s`") && err.contains("not both"),
        "{err}"
    );
}
