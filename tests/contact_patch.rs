//! Contact patch test: two flat blocks with non-matching meshes, one pressed onto the other by a
//! uniform pressure, transmit it exactly (to round-off) through the mortar interface, with
//! either face as slave. The exact solution is a linear displacement field (uniaxial strain),
//! which both meshes represent, so the contact pressure must equal the applied one at every
//! slave node, vertex and mid-edge alike.

mod common;
use common::*;

fn blocks() -> String {
    // Lower block [0,2]×[0,1], 5×3 cells; upper block [0,2]×[1,2], 7×4 cells, both distorted.
    let (n1, t1, s1) = structured(5, 3, 0.0, 2.0, 0.0, 1.0, 0.3);
    let (n2, t2, s2) = structured(7, 4, 0.0, 2.0, 1.0, 2.0, 0.3);
    let off = n1.len();
    let mut nodes = n1;
    nodes.extend(n2);
    let shift = |v: &Vec<[usize; 3]>| v.iter().map(|e| e.map(|k| k + off)).collect::<Vec<_>>();
    let t2: Vec<[usize; 6]> = t2.iter().map(|t| t.map(|k| k + off)).collect();
    let [b1, _, top1, l1] = s1;
    let [b2, _, top2, l2] = &s2;
    msh41(
        &nodes,
        &[("lower", t1), ("upper", t2)],
        &[
            ("bottom", b1),
            ("lower_top", top1),
            ("lower_left", l1),
            ("upper_bottom", shift(b2)),
            ("top", shift(top2)),
            ("upper_left", shift(l2)),
        ],
    )
}

fn case(slave: &str, master: &str) -> String {
    format!(
        r#"{{"mesh": "mesh.msh",
  "bodies": [{{"group": "lower", "E": 70.0, "nu": 0.3}}, {{"group": "upper", "E": 200.0, "nu": 0.25}}],
  "supports": [{{"group": "bottom", "uy": 0.0}}, {{"group": "lower_left", "ux": 0.0}}, {{"group": "upper_left", "ux": 0.0}}],
  "tractions": [{{"group": "top", "kind": "uniform", "ty": -3.0}}],
  "contact": {{"slave": "{slave}", "master": "{master}"}},
  "stages": [{{"steps": 1, "traction_scale": 1.0}}]}}"#
    )
}

fn pressures(slave: &str, master: &str) -> Vec<(f64, f64)> {
    let dir = tempdir(&format!("patch-{slave}"));
    std::fs::write(dir.join("mesh.msh"), blocks()).unwrap();
    std::fs::write(dir.join("case.json"), case(slave, master)).unwrap();
    let out = dir.join("out");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        .args([
            "run",
            dir.join("case.json").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .status()
        .unwrap();
    assert!(st.success());
    let text = std::fs::read_to_string(out.join("contact_0001.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[2])
        })
        .collect()
}

#[test]
fn uniform_pressure_crosses_a_non_matching_interface_exactly() {
    for (slave, master) in [("lower_top", "upper_bottom"), ("upper_bottom", "lower_top")] {
        let p = pressures(slave, master);
        assert!(p.len() >= 11, "{slave}: {} slave nodes", p.len());
        let worst = p.iter().map(|(_, v)| (v - 3.0).abs()).fold(0.0, f64::max);
        assert!(
            worst < 1e-10 * 3.0,
            "slave {slave}: max |p − 3| = {worst:e}"
        );
    }
}
