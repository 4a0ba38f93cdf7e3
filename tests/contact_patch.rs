//! Contact patch test: two flat blocks with non-matching meshes, one pressed onto the other by a
//! uniform pressure, transmit it exactly (to round-off) through the mortar interface, with
//! either face as slave. The exact solution is a linear displacement field (uniaxial strain),
//! which both meshes represent, so the contact pressure must equal the applied one at every
//! slave node, vertex and mid-edge alike.

mod common;
use common::*;

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
    // Lower block [0,2]×[0,1], 5×3 cells; upper block [0,2]×[1,2], 7×4 cells, both distorted.
    std::fs::write(dir.join("mesh.msh"), two_blocks([5, 3], [7, 4], 1.0, 0.3)).unwrap();
    let r = run_case_in(&dir, "case.json", &case(slave, master), &["--quiet"]);
    r.assert_ok(slave);
    r.contact(1).rows.iter().map(|v| (v[0], v[2])).collect()
}

#[test]
fn uniform_pressure_crosses_a_non_matching_interface_exactly() {
    // Largest |p − 3|/3 at a slave node, bounded per slave face (measured 0 with the lower face
    // slave, 3.3e-13 with the upper).
    let mut rel = Vec::new();
    for (slave, master, tol) in [
        ("lower_top", "upper_bottom", 1e-15),
        ("upper_bottom", "lower_top", 1e-12),
    ] {
        let p = pressures(slave, master);
        assert!(p.len() >= 11, "{slave}: {} slave nodes", p.len());
        let worst = p.iter().map(|(_, v)| (v - 3.0).abs()).fold(0.0, f64::max);
        println!(
            "slave {slave}: {} nodes, max |p − 3|/3 = {:.2e}",
            p.len(),
            worst / 3.0
        );
        assert!(worst < tol * 3.0, "slave {slave}: max |p − 3| = {worst:e}");
        rel.push((p.len(), worst / 3.0, tol));
    }
    validation_row(
        "130-contact-patch",
        "contact patch test: two flat blocks, non-matching distorted meshes, uniform pressure; either face slave",
        "exact",
        &format!(
            "nodal pressures equal the applied one to {} relative with the lower face slave ({} nodes; asserted < {:.0e}), {} with the upper ({} nodes; asserted < {:.0e})",
            sci(rel[0].1),
            rel[0].0,
            rel[0].2,
            sci(rel[1].1),
            rel[1].0,
            rel[1].2
        ),
        "contact_patch",
    );
}
