//! Bad input gets a clear message naming the file, key, group or element, a non-zero exit
//! status, and no output. Each test feeds one bad input to the `stickslip` binary.

mod common;
use common::*;
use std::path::PathBuf;

/// A unit square, 2×2 cells, as MSH 4.1 text with groups body, bottom, right, top, left.
fn square_msh() -> String {
    let (nodes, tris, sides) = structured(2, 2, 0.0, 1.0, 0.0, 1.0, 0.0);
    msh41_sides(&nodes, &[("body", tris)], sides)
}

/// Two unit squares side by side, [0,1]×[0,1] and [1,2]×[0,1], 1 cell each, sharing the nodes
/// of their common edge: nodes, the triangles of each square and the four sides.
#[allow(clippy::type_complexity)]
fn two_squares() -> (
    Vec<[f64; 2]>,
    Vec<[usize; 6]>,
    Vec<[usize; 6]>,
    [Vec<[usize; 3]>; 4],
) {
    let (nodes, tris, sides) = structured(2, 1, 0.0, 2.0, 0.0, 1.0, 0.0);
    let (left, right): (Vec<_>, Vec<_>) = tris.into_iter().partition(|t| {
        nodes[t[0]][0] < 1.0 - 1e-9 && nodes[t[1]][0] < 1.0 + 1e-9 && nodes[t[2]][0] < 1.0 + 1e-9
    });
    (nodes, left, right, sides)
}

const GOOD_CASE: &str = r#"{
  "mesh": "mesh.msh",
  "bodies": [{ "group": "body", "E": 1.0, "nu": 0.3 }],
  "supports": [{ "group": "bottom", "ux": 0.0, "uy": 0.0 }],
  "tractions": [{ "group": "top", "kind": "uniform", "ty": -1.0 }],
  "stages": [{ "steps": 2, "traction_scale": 1.0 }]
}"#;

/// Writes a case and a mesh into a fresh directory, runs it, and returns
/// (exit code, stderr, whether the output directory exists).
fn run_case(name: &str, case: &str, mesh: &str) -> (i32, String, bool) {
    let dir = tempdir(name);
    std::fs::write(dir.join("mesh.msh"), mesh).unwrap();
    let r = run_case_in(&dir, "case.json", case, &["--quiet"]);
    let wrote = r.wrote_output();
    (r.code, r.stderr, wrote)
}

/// Asserts that the case is refused with exit status 2, a message containing every needle, and
/// no output; returns the needles, quoted, for the validation table.
fn assert_refused(name: &str, case: &str, mesh: &str, needles: &[&str]) -> String {
    let (code, err, wrote) = run_case(name, case, mesh);
    assert_eq!(code, 2, "{name}: exit status (stderr: {err})");
    for n in needles {
        assert!(
            err.contains(n),
            "{name}: message should contain `{n}`, got: {err}"
        );
    }
    assert!(!wrote, "{name}: output was written");
    quoted(needles)
}

/// `“a”, “b”`.
fn quoted(needles: &[&str]) -> String {
    needles
        .iter()
        .map(|n| format!("“{n}”"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[test]
fn good_case_runs_and_writes_everything() {
    let (code, err, wrote) = run_case("good", GOOD_CASE, &square_msh());
    assert_eq!(code, 0, "{err}");
    assert!(wrote);
    let dir = tempdir("good2");
    std::fs::write(dir.join("mesh.msh"), square_msh()).unwrap();
    let r = run_case_in(&dir, "case.json", GOOD_CASE, &["--quiet", "--threads", "1"]);
    assert_eq!(r.code, 0);
    let out = &r.out;
    for f in [
        "case.pvd",
        "case_0001.vtu",
        "case_0002.vtu",
        "summary.json",
        "history.csv",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    // No temporary files are left behind.
    let leftovers: Vec<PathBuf> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Runs `cases/vm272_cm.json` on L1 (eleven steps, each written) into a fresh directory in
/// which a directory stands where step `blocked`'s `.vtu` goes; asserts exit status 4 and a
/// message naming that file, and returns the output directory.
fn run_with_step_file_blocked(label: &str, blocked: usize) -> PathBuf {
    let dir = tempdir(label);
    let case = dir.join("case.json");
    let v = shipped_case_on("vm272_cm.json", "vm272_L1.msh");
    std::fs::write(&case, serde_json::to_string(&v).unwrap()).unwrap();
    let out = dir.join("out");
    let name = format!("case_{blocked:04}.vtu");
    std::fs::create_dir_all(out.join(&name)).unwrap();
    let (code, _, err) = stickslip(&[
        "run",
        case.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 4, "{err}");
    assert!(
        err.contains(&name) && err.contains("cannot write output"),
        "{err}"
    );
    out
}

/// A step whose file cannot be written (a directory in its place) stops the run with exit
/// status 4 and a message naming the file, although the steps are written on a thread of
/// their own while the next ones are solved: the files of the steps before it, each whole,
/// and nothing of it or after it (no later step, state, history or summary).
#[test]
fn write_error_stops_the_run_with_the_earlier_steps_kept() {
    let out = run_with_step_file_blocked("write-error", 3);
    assert_eq!(
        file_names(&out),
        [
            "case.pvd",
            "case_0001.vtu",
            "case_0002.vtu",
            "case_0003.vtu",
            "case_contact_0001.vtu",
            "case_contact_0002.vtu",
            "contact_0001.csv",
            "contact_0002.csv",
            "state_0001.json",
            "state_0002.json",
            "steps.jsonl",
        ]
    );
    let pvd = std::fs::read_to_string(out.join("case.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 4, "{pvd}");
    assert!(out.join("case_0003.vtu").is_dir());
}

/// The same at the end of the run, where the summary's equilibrium check waits on a thread of
/// its own for the last step's field: a write that fails at the step before the last (the last
/// is then never prepared) or at the last (its field was recovered first) stops the run with
/// exit status 4 naming the file, the earlier steps whole, no summary or history, and nothing
/// temporary left.
#[test]
fn write_error_at_the_last_steps_stops_the_run() {
    for blocked in [10, 11] {
        let out = run_with_step_file_blocked(&format!("write-error-last-{blocked}"), blocked);
        let names = file_names(&out);
        for step in 1..blocked {
            for f in [
                format!("case_{step:04}.vtu"),
                format!("state_{step:04}.json"),
            ] {
                assert!(names.contains(&f), "{f} missing: {names:?}");
            }
        }
        for absent in [
            format!("state_{blocked:04}.json"),
            "case_0012.vtu".to_string(),
            "summary.json".into(),
            "history.csv".into(),
        ] {
            assert!(!names.contains(&absent), "{absent} written: {names:?}");
        }
        assert!(
            !names.iter().any(|n| n.contains(".tmp")),
            "temporary files left: {names:?}"
        );
    }
}

#[test]
fn unknown_key_is_named_with_its_line() {
    let case = GOOD_CASE.replace("\"steps\": 2", "\"steps\": 2, \"stpes\": 3");
    let named = assert_refused(
        "unknown-key",
        &case,
        &square_msh(),
        &["case.json", "unknown field `stpes`", "line 6"],
    );
    validation_row(
        "070-cli-unknown-key",
        "bad input: unknown key in the case file",
        "—",
        &format!("exit 2, no output; the message names {named}"),
        "cli_errors",
    );
}

#[test]
fn out_of_range_values_name_the_key() {
    let msh = square_msh();
    // (name, text in GOOD_CASE, replacement, needles)
    let cases: [(&str, &str, &str, &[&str]); 6] = [
        ("nu", "\"nu\": 0.3", "\"nu\": 0.5", &["bodies[0].nu", "0.5"]),
        ("E", "\"E\": 1.0", "\"E\": -2.0", &["bodies[0].E", "-2"]),
        (
            "steps",
            "\"steps\": 2",
            "\"steps\": 0",
            &["stages[0].steps"],
        ),
        (
            "huge",
            "\"ty\": -1.0",
            "\"ty\": -1e400",
            &["case.json", "line 5"],
        ),
        (
            "hertz-a",
            "\"kind\": \"uniform\", \"ty\": -1.0",
            "\"kind\": \"hertz\", \"p0\": 1.0, \"a\": 0.0",
            &["tractions[0].a"],
        ),
        (
            "pilot-missing",
            "\"steps\": 2,",
            "\"steps\": 2, \"pilot_x\": {\"force\": 1.0},",
            &["stages[0].pilot_x", "no `pilot`"],
        ),
    ];
    let mut named = Vec::new();
    for (name, from, to, needles) in cases {
        named.push(assert_refused(
            name,
            &GOOD_CASE.replace(from, to),
            &msh,
            needles,
        ));
    }
    validation_row(
        "071-cli-ranges",
        "bad input: values out of range (ν = 0.5, E < 0, zero steps, a traction of 1e400, Hertz a = 0, a pilot load without a pilot)",
        "—",
        &format!(
            "exit 2, no output, for each of the {}; the messages name {}",
            named.len(),
            named.join("; ")
        ),
        "cli_errors",
    );
}

#[test]
fn missing_and_empty_groups_are_named() {
    let msh = square_msh();
    let missing = assert_refused(
        "missing",
        &GOOD_CASE.replace("\"group\": \"body\"", "\"group\": \"lower_body\""),
        &msh,
        &[
            "mesh.msh",
            "`lower_body` is not in the mesh",
            "its groups: bottom, right, top, left, body",
        ],
    );
    // A name declared in $PhysicalNames but with no elements.
    let empty = msh.replacen(
        "$PhysicalNames\n5\n",
        "$PhysicalNames\n6\n1 77 \"ghost\"\n",
        1,
    );
    let empty = assert_refused(
        "empty",
        &GOOD_CASE.replace("\"group\": \"top\"", "\"group\": \"ghost\""),
        &empty,
        &["`ghost` is empty"],
    );
    let wrong = assert_refused(
        "wrongdim",
        &GOOD_CASE.replace("\"group\": \"bottom\"", "\"group\": \"body\""),
        &msh,
        &["`body` is a surface"],
    );
    validation_row(
        "072-cli-groups",
        "bad input: missing group, empty group, a surface where a curve goes",
        "—",
        &format!("exit 2, no output, for each; the messages name {missing}; {empty}; {wrong}"),
        "cli_errors",
    );
}

#[test]
fn old_and_first_order_meshes_say_how_to_fix_them() {
    let msh22 = std::fs::read_to_string(repo().join("meshes/vm272_L0_msh22.msh")).unwrap();
    let old = assert_refused(
        "msh22",
        GOOD_CASE,
        &msh22,
        &["MSH format 2.2", "re-export it as MSH 4.1", "-format msh41"],
    );
    let lin = std::fs::read_to_string(repo().join("meshes/vm272_first_order.msh")).unwrap();
    let first = assert_refused(
        "first-order",
        GOOD_CASE,
        &lin,
        &["first-order mesh", "Mesh.ElementOrder = 2"],
    );
    validation_row(
        "073-cli-old-meshes",
        "bad input: MSH 2.2 file, first-order mesh",
        "—",
        &format!("exit 2, no output, for each; the messages say how to fix it: {old}; {first}"),
        "cli_errors",
    );
}

#[test]
fn corrupt_and_truncated_meshes_are_refused() {
    let msh = square_msh();
    let cut = &msh[..msh.len() * 2 / 3];
    let truncated = assert_refused("truncated", GOOD_CASE, cut, &["mesh.msh", "cannot parse"]);
    let not_msh = assert_refused("not-msh", GOOD_CASE, "hello\n", &["not a gmsh mesh file"]);
    let dir = tempdir("nofile");
    let (code, _, err) = stickslip(&["run", dir.join("nope.json").to_str().unwrap()]);
    assert_eq!(code, 2);
    let needles = ["nope.json", "cannot read"];
    assert!(needles.iter().all(|n| err.contains(n)), "{err}");
    validation_row(
        "074-cli-corrupt-mesh",
        "bad input: truncated mesh file, a file that is not a mesh, a missing case file",
        "—",
        &format!(
            "exit 2, no output, for each; the messages name {truncated}; {not_msh}; {}",
            quoted(&needles)
        ),
        "cli_errors",
    );
}

#[test]
fn bodies_sharing_nodes_are_refused() {
    // Two squares side by side that share their common edge's nodes.
    let (nodes, left, right, _) = two_squares();
    let msh = msh41(&nodes, &[("a", left), ("b", right)], &[]);
    let case = r#"{"mesh": "mesh.msh", "bodies": [{"group": "a", "E": 1, "nu": 0.3}, {"group": "b", "E": 1, "nu": 0.3}], "stages": [{"steps": 1}]}"#;
    let named = assert_refused("shared", case, &msh, &["bodies `a` and `b` share node"]);
    validation_row(
        "075-cli-shared-nodes",
        "bad input: two bodies sharing nodes",
        "—",
        &format!("exit 2, no output; the message names {named}"),
        "cli_errors",
    );
}

#[test]
fn badly_curved_elements_are_named_and_clockwise_ones_are_reoriented() {
    let (mut nodes, tris, sides) = structured(2, 2, 0.0, 1.0, 0.0, 1.0, 0.0);
    // Reverse the first triangle (clockwise in the file): it is reoriented and runs.
    let mut cw = tris.clone();
    cw[0] = stickslip::shapes::tri6::REVERSE.map(|k| cw[0][k]);
    let msh = msh41_sides(&nodes, &[("body", cw)], sides.clone());
    let (code, err, _) = run_case("cw", GOOD_CASE, &msh);
    assert_eq!(code, 0, "{err}");
    let dir = tempdir("cw-info");
    std::fs::write(dir.join("m.msh"), &msh).unwrap();
    let (code, out, _) = stickslip(&["mesh-info", dir.join("m.msh").to_str().unwrap()]);
    assert_eq!(code, 0);
    let reoriented = "\"reoriented_triangles\": 1";
    assert!(out.contains(reoriented), "{out}");
    // Push a mid-edge node of an interior edge far across its element: the Jacobian turns negative.
    let m = tris[0][4];
    nodes[m] = [nodes[m][0] - 0.45, nodes[m][1] + 0.45];
    let msh = msh41_sides(&nodes, &[("body", tris)], sides);
    let named = assert_refused(
        "jacobian",
        GOOD_CASE,
        &msh,
        &["element 9", "Jacobian is not positive"],
    );
    validation_row(
        "076-cli-jacobian",
        "bad input: a mid-edge node pushed across its element (bad Jacobian); a clockwise triangle",
        "—",
        &format!(
            "bad Jacobian: exit 2, no output, the message names {named}; clockwise: reoriented (`mesh-info`: {reoriented}) and the case runs (exit 0)"
        ),
        "cli_errors",
    );
}

#[test]
fn unsupported_element_types_are_named() {
    let msh = square_msh();
    // Turn the block of 3-node lines of group `left` into 2-node lines (type 1).
    let lines: Vec<&str> = msh.lines().collect();
    let pos = lines.iter().position(|l| l.starts_with("1 4 8 ")).unwrap();
    let mut out: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
    out[pos] = out[pos].replacen("1 4 8 ", "1 4 1 ", 1);
    let count: usize = out[pos].split_whitespace().nth(3).unwrap().parse().unwrap();
    for k in pos + 1..=pos + count {
        let v: Vec<&str> = out[k].split_whitespace().collect();
        out[k] = format!("{} {} {}", v[0], v[1], v[2]);
    }
    let bad = out.join("\n") + "\n";
    let (code, err, wrote) = run_case("lin2", GOOD_CASE, &bad);
    assert_eq!(code, 2, "{err}");
    let needles = ["gmsh type 1", "element "];
    assert!(needles.iter().all(|n| err.contains(n)), "{err}");
    assert!(!wrote);
    validation_row(
        "077-cli-element-type",
        "bad input: unsupported element type (2-node lines)",
        "—",
        &format!(
            "exit {code}, no output; the message names {}",
            quoted(&needles)
        ),
        "cli_errors",
    );
}

#[test]
fn support_on_the_pilot_face_is_refused() {
    let case = GOOD_CASE.replace(
        "\"stages\"",
        "\"pilot\": {\"group\": \"bottom\"},\n  \"stages\"",
    );
    let named = assert_refused(
        "pilot-support",
        &case,
        &square_msh(),
        &["both supported (group `bottom`)", "rigid pilot face"],
    );
    validation_row(
        "078-cli-pilot-support",
        "bad input: a support on the pilot face",
        "—",
        &format!("exit 2, no output; the message names {named}"),
        "cli_errors",
    );
}

#[test]
fn load_on_a_body_not_in_use_is_refused() {
    let (nodes, left, right, sides) = two_squares();
    let msh = msh41_sides(&nodes, &[("a", left), ("b", right)], sides);
    let case = r#"{"mesh": "mesh.msh", "bodies": [{"group": "a", "E": 1, "nu": 0.3}],
      "supports": [{"group": "left", "ux": 0, "uy": 0}],
      "tractions": [{"group": "right", "kind": "uniform", "tx": 1}], "stages": [{"steps": 1, "traction_scale": 1}]}"#;
    let named = assert_refused(
        "dangling",
        case,
        &msh,
        &["group `right` is not an edge of any triangle"],
    );
    validation_row(
        "079-cli-unused-body",
        "bad input: a load on a body not in use",
        "—",
        &format!("exit 2, no output; the message names {named}"),
        "cli_errors",
    );
}

#[test]
fn an_unheld_pilot_under_force_control_fails_cleanly() {
    // The pilot drives the whole (only) body, with no support: no equilibrium under force.
    let case = r#"{"mesh": "mesh.msh", "bodies": [{"group": "body", "E": 1, "nu": 0.3}],
      "pilot": {"group": "top"}, "stages": [{"steps": 1, "pilot_y": {"force": -1.0}}]}"#;
    let (code, err, _) = run_case("unheld", case, &square_msh());
    assert_eq!(code, 3, "{err}");
    let needles = ["not held", "not positive definite"];
    assert!(needles.iter().any(|n| err.contains(n)), "{err}");
    validation_row(
        "080-cli-unheld-pilot",
        "bad input: a pilot under force control holding an otherwise unsupported body",
        "—",
        &format!(
            "exit {code} (solver failure) with a message naming {}",
            quoted(&needles).replace(", ", " or ")
        ),
        "cli_errors",
    );
}

#[test]
fn slip_control_without_friction_or_on_y_is_refused() {
    // The square case has a pilot but no contact: slip control has nothing to drive.
    let case = GOOD_CASE.replace(
        "\"stages\"",
        "\"pilot\": {\"group\": \"top\"},\n  \"stages\"",
    );
    for (name, ctl) in [
        ("slip-x", "\"pilot_x\": {\"slip\": 0.01},"),
        ("slip-y", "\"pilot_y\": {\"slip\": 0.01},"),
    ] {
        assert_refused(
            name,
            &case.replace("\"steps\": 2,", &format!("\"steps\": 2, {ctl}")),
            &square_msh(),
            &["stages[0].pilot_", "slip control drives `pilot_x` only"],
        );
    }
}

#[test]
fn a_closed_output_pipe_ends_quietly() {
    // `stickslip mesh-info … | head -1`: the reader goes away before the JSON is written.
    for args in [
        vec!["mesh-info", "meshes/vm272_L5.msh"],
        vec!["analytic", "jkr-curve", "--psi", "0.1", "--n", "200000"],
    ] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
            // No model cache: tests leave the user's cache directory alone.
            .env("STICKSLIP_NO_CACHE", "1")
            .args(&args)
            .current_dir(common::repo())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    }
}
