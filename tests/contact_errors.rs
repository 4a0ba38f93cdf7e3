//! Bad contact input: a clear message naming the key or group, a non-zero exit status, and no
//! output. And the mesh-resolution warning of a slip-weakening run whose elements are larger
//! than s0/2.

mod common;
use common::{run_case_in, shipped_case_on, tempdir, validation_row};
use serde_json::{Value, json};

fn run_edited(name: &str, edit: &dyn Fn(&mut Value)) -> (i32, String, bool) {
    let mut v = shipped_case_on("hertz.json", "vm272_L0.msh");
    edit(&mut v);
    let text = serde_json::to_string_pretty(&v).unwrap();
    let r = run_case_in(&tempdir(name), "case.json", &text, &[]);
    let wrote = r.wrote_output();
    (r.code, r.stderr, wrote)
}

/// Asserts exit status 2, every needle in the message and no output; returns the needles,
/// quoted, for the validation table.
fn refused(name: &str, edit: &dyn Fn(&mut Value), needles: &[&str]) -> String {
    let (code, err, wrote) = run_edited(name, edit);
    assert_eq!(code, 2, "{name}: {err}");
    for n in needles {
        assert!(err.contains(n), "{name}: `{n}` not in: {err}");
    }
    assert!(!wrote, "{name}: output written");
    needles
        .iter()
        .map(|n| format!("“{n}”"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[test]
fn bad_contact_input_is_named() {
    let named = [
        refused(
            "same",
            &|v| v["contact"]["master"] = json!("lower_arc"),
            &["contact.master", "must differ"],
        ),
        refused(
            "nogroup",
            &|v| v["contact"]["slave"] = json!("arc"),
            &["`arc` is not in the mesh"],
        ),
        refused(
            "penalty",
            &|v| v["contact"]["penalty"] = json!(-1.0),
            &["contact.penalty"],
        ),
        refused(
            "method",
            &|v| v["contact"]["method"] = json!("lagrange"),
            &["unknown variant `lagrange`"],
        ),
        refused(
            "shape",
            &|v| v["contact"]["friction"] = json!({"shape": "linear", "fs": 0.2}),
            &["friction", "linear"],
        ),
        refused(
            "preset",
            &|v| v["contact"]["friction"] = json!({"preset": "gold-gold"}),
            &["gold-gold"],
        ),
        refused(
            "fd>fs",
            &|v| {
                v["contact"]["friction"] =
                    json!({"shape": "ramp", "fs": 0.1, "fd": 0.2, "delta": 1e-3})
            },
            &["friction"],
        ),
        refused(
            "table",
            &|v| v["contact"]["friction"] = json!({"shape": "table", "rows": [[0.0, 0.2]]}),
            &["friction"],
        ),
        refused(
            "lambda",
            &|v| {
                v["contact"]["friction"] =
                    json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0})
            },
            &["`load`"],
        ),
        // A zone that cannot be found: the faces are far apart for this tiny candidate gap.
        refused(
            "zone",
            &|v| {
                v["contact"]["slave"] = json!("bottom");
                v["supports"] = json!([{"group": "lower_arc", "ux": 0.0, "uy": 0.0}]);
                v["contact"]["candidate_gap"] = json!(1e-6);
            },
            &["no slave node of `bottom`"],
        ),
    ];
    validation_row(
        "340-contact-errors",
        "bad contact input (same groups, unknown slave group, negative penalty, unknown method/shape/preset, f_d > f_s, one-row table, missing Λ data, empty zone)",
        "—",
        &format!(
            "exit 2, no output, for each of the {}; the messages name {}",
            named.len(),
            named.join("; ")
        ),
        "contact_errors",
    );
}

#[test]
fn unresolved_transition_zone_is_warned_about() {
    let (code, err, _) = run_edited("warn", &|v| {
        v["contact"]["friction"] = json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0});
        v["stages"] = json!([{"steps": 1, "pilot_x": {"force": 0.0}, "pilot_y": {"force": -10.0}}, {"steps": 2, "pilot_x": {"force": 0.4}}]);
    });
    assert_eq!(code, 0, "{err}");
    let needles = ["warning: the contact elements", "not resolved"];
    assert!(needles.iter().all(|n| err.contains(n)), "{err}");
    validation_row(
        "341-s0-warning",
        "the s0 resolution warning: Fig. 2's law (Λ = 0.05) on L0",
        "—",
        &format!(
            "completes (exit {code}) with a warning containing “{}” … “{}”",
            needles[0], needles[1]
        ),
        "contact_errors",
    );
}

/// A bad friction law is refused with the case, before the mesh is read or anything assembled:
/// here the mesh does not even exist, and the message is about the law.
#[test]
fn bad_friction_law_is_refused_before_the_mesh_is_read() {
    for (name, law, needle) in [
        ("preset-early", json!({"preset": "gold-gold"}), "gold-gold"),
        (
            "shape-early",
            json!({"shape": "linear", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 10.0}),
            "linear",
        ),
        (
            "lambda-early",
            json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": -0.05, "radius": 4.0, "load": 10.0}),
            "`lambda`",
        ),
    ] {
        let (code, err, wrote) = run_edited(name, &|v| {
            v["mesh"] = json!("/nonexistent/mesh.msh");
            v["contact"]["friction"] = law.clone();
        });
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains("contact.friction") && err.contains(needle) && !err.contains("mesh.msh"),
            "{name}: {err}"
        );
        assert!(!wrote, "{name}: output written");
    }
}
