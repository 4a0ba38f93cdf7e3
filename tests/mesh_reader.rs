//! The gmsh reader on the shipped meshes: binary and ASCII files of the same mesh agree,
//! physical names are read, the VM272 ladder halves its arc size per level and reaches
//! h ≤ a/100 with about 45 000 triangles, and the two bodies never share a node.

mod common;
use common::repo;
use stickslip::mesh::{check, gmsh, info};

const A: f64 = 0.6808;

#[test]
fn binary_and_ascii_files_of_one_mesh_agree() {
    let b = gmsh::read(&repo().join("meshes/vm272_L1.msh")).unwrap();
    let a = gmsh::read(&repo().join("meshes/vm272_L1_ascii.msh")).unwrap();
    assert_eq!(a.nodes.len(), b.nodes.len());
    assert_eq!(a.triangles.len(), b.triangles.len());
    for (p, q) in a.nodes.iter().zip(&b.nodes) {
        assert!((p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1]).abs() < 1e-12);
    }
    for (s, t) in a.triangles.iter().zip(&b.triangles) {
        assert_eq!(s.nodes, t.nodes);
    }
    let names: Vec<&str> = a.groups.iter().map(|g| g.name.as_str()).collect();
    for n in [
        "lower_body",
        "upper_body",
        "bottom",
        "top",
        "lower_arc",
        "upper_arc",
    ] {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }
}

/// Arc chord lengths of the elements within |x| ≤ 1.5a of the contact point.
fn arc_h(level: usize) -> (f64, f64, usize) {
    let m = gmsh::read(&repo().join(format!("meshes/vm272_L{level}.msh"))).unwrap();
    check::check(
        &m,
        &["lower_body", "upper_body"],
        &["bottom", "top", "lower_arc", "upper_arc"],
    )
    .unwrap();
    let g = m.group("lower_arc").unwrap();
    let hs: Vec<f64> = g
        .elements
        .iter()
        .map(|&l| m.line_coords(l))
        .filter(|x| x[0][0].abs() <= 1.5 * A + 1e-9 && x[1][0].abs() <= 1.5 * A + 1e-9)
        .map(|x| (x[0][0] - x[1][0]).hypot(x[0][1] - x[1][1]))
        .collect();
    (
        hs.iter().cloned().fold(0.0, f64::max),
        hs.iter().cloned().fold(f64::INFINITY, f64::min),
        m.triangles.len(),
    )
}

#[test]
fn vm272_ladder_halves_the_arc_size_and_reaches_the_papers_resolution() {
    let levels: Vec<(f64, f64, usize)> = (0..=5).map(arc_h).collect();
    for w in levels.windows(2) {
        let ratio = w[0].0 / w[1].0;
        assert!((ratio - 2.0).abs() < 0.1, "arc size ratio {ratio}");
    }
    let finest = levels[5];
    assert!(
        finest.0 <= A / 100.0,
        "finest arc size {} > a/100",
        finest.0
    );
    assert!(
        (40_000..=50_000).contains(&finest.2),
        "finest has {} triangles",
        finest.2
    );
}

#[test]
fn mesh_info_reports_groups_sizes_and_quality() {
    let m = gmsh::read(&repo().join("meshes/vm272_L2.msh")).unwrap();
    let i = info::info(&m);
    assert_eq!(i.triangles, m.triangles.len());
    let body = i.groups.iter().find(|g| g.name == "lower_body").unwrap();
    assert!(body.min_angle_deg.unwrap() > 15.0 && body.min_scaled_jacobian.unwrap() > 0.5);
    let arc = i.groups.iter().find(|g| g.name == "upper_arc").unwrap();
    assert!(arc.h_min < A / 10.0 && arc.h_max > 0.3);
}
