//! The rigid pilot: every node of the pilot face shares two DOFs, so the face translates
//! without rotating. Checked against an independent solve in which the same face is moved by
//! Dirichlet elimination, and for consistency between force and displacement control.

mod common;
use common::*;
use stickslip::case::{Case, Control};
use stickslip::elasticity::Material;
use stickslip::model::Model;

fn block_model(dir: &std::path::Path) -> Model {
    let (nodes, tris, sides) = structured(6, 4, -1.5, 1.5, 0.0, 2.0, 0.2);
    std::fs::write(
        dir.join("m.msh"),
        msh41_sides(&nodes, &[("body", tris)], sides),
    )
    .unwrap();
    let json = r#"{"mesh": "m.msh", "bodies": [{"group": "body", "E": 200, "nu": 0.3}],
      "supports": [{"group": "bottom", "ux": 0, "uy": 0}], "pilot": {"group": "top"},
      "stages": [{"steps": 1}]}"#;
    let case: Case = serde_json::from_str(json).unwrap();
    Model::build(&case, &dir.join("case.json")).unwrap()
}

#[test]
fn pilot_matches_a_dirichlet_solve_of_the_same_rigid_motion() {
    let dir = tempdir("pilot-dirichlet");
    let model = block_model(&dir);
    let d = [0.013, -0.021];
    let (u, p) = model
        .solve_step(
            0.0,
            [Control::Displacement(d[0]), Control::Displacement(d[1])],
        )
        .unwrap();
    let p = p.unwrap();
    assert_eq!([p.ux, p.uy], d);
    // Independent: prescribe d on every top node by elimination.
    let mesh = &model.mesh;
    let top = mesh.group_nodes(mesh.group("top").unwrap());
    let bottom = mesh.group_nodes(mesh.group("bottom").unwrap());
    let mat = Material { e: 200.0, nu: 0.3 };
    let (dofs, v) = solve_linear(
        mesh,
        mat,
        &|n| {
            if top.contains(&n) {
                [Some(d[0]), Some(d[1])]
            } else if bottom.contains(&n) {
                [Some(0.0); 2]
            } else {
                [None; 2]
            }
        },
        None,
    );
    let mut worst: f64 = 0.0;
    for n in 0..mesh.nodes.len() {
        let (a, b) = (model.dofs.displacement(n, &u), dofs.displacement(n, &v));
        worst = worst.max((a[0] - b[0]).abs().max((a[1] - b[1]).abs()));
    }
    println!(
        "pilot vs Dirichlet: largest nodal difference {worst:.2e} (displacements of order 2e-2)"
    );
    // Measured 1.0e-17.
    let tol = 5e-17;
    assert!(worst < tol, "pilot vs Dirichlet: {worst:e}");
    // Every top node moved exactly as the pilot.
    for &n in &top {
        assert_eq!(model.dofs.displacement(n, &u), d);
    }
    validation_row(
        "060-pilot",
        "rigid pilot vs Dirichlet elimination of the same motion",
        "second method",
        &format!(
            "largest nodal displacement difference {worst:.1e} (asserted < {tol:.0e}; displacements of order 2e-2); all {} pilot-face nodes move exactly as the pilot",
            top.len()
        ),
        "pilot",
    );
}

#[test]
fn force_and_displacement_control_agree() {
    let dir = tempdir("pilot-control");
    let model = block_model(&dir);
    let f = [1.7, -10.0];
    let (_, p) = model
        .solve_step(0.0, [Control::Force(f[0]), Control::Force(f[1])])
        .unwrap();
    let p = p.unwrap();
    assert!((p.fx - f[0]).abs() < 1e-12 && (p.fy - f[1]).abs() < 1e-12);
    let (_, q) = model
        .solve_step(
            0.0,
            [Control::Displacement(p.ux), Control::Displacement(p.uy)],
        )
        .unwrap();
    let q = q.unwrap();
    assert!(
        (q.fx - f[0]).abs() < 1e-9 * f[1].abs() && (q.fy - f[1]).abs() < 1e-9 * f[1].abs(),
        "{q:?}"
    );
    // Mixed: force in y, displacement in x.
    let (_, m) = model
        .solve_step(0.0, [Control::Displacement(p.ux), Control::Force(f[1])])
        .unwrap();
    let m = m.unwrap();
    assert!(
        (m.fx - f[0]).abs() < 1e-9 * f[1].abs() && (m.uy - p.uy).abs() < 1e-9 * p.uy.abs(),
        "{m:?}"
    );
}
