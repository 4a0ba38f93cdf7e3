//! The stiffness of both VM272 half-cylinders with `bottom` and `top` clamped (both bodies held
//! without a pilot): the matrix `benches/ordering.rs` and `examples/nd_timing.rs` order.
use stickslip::assembly::{self, UpperCsc};
use stickslip::dofs::{DofMap, SupportSpec};
use stickslip::elasticity::Material;

/// The stiffness of both bodies (E = 200, ν = 0.3) with `bottom` and `top` clamped.
pub fn stiffness(path: &std::path::Path) -> UpperCsc {
    let mesh = stickslip::mesh::gmsh::read(path).expect("mesh");
    let mat = Material { e: 200.0, nu: 0.3 };
    let mut elems = Vec::new();
    for body in ["lower_body", "upper_body"] {
        let g = mesh.group(body).expect("body group");
        elems.extend(g.elements.iter().map(|&e| (e, mat)));
    }
    let mut active = vec![false; mesh.nodes.len()];
    for (e, _) in &elems {
        for &n in &mesh.triangles[*e].nodes {
            active[n] = true;
        }
    }
    let bottom = mesh.group_nodes(mesh.group("bottom").expect("group bottom"));
    let top = mesh.group_nodes(mesh.group("top").expect("group top"));
    let sup = [
        SupportSpec {
            group: "bottom",
            nodes: &bottom,
            value: [Some(0.0), Some(0.0)],
        },
        SupportSpec {
            group: "top",
            nodes: &top,
            value: [Some(0.0), Some(0.0)],
        },
    ];
    let dofs = DofMap::build(&mesh.node_tags, &active, &sup, None, &[]).expect("dofs");
    let mut k = UpperCsc::pattern(&mesh, &elems, &dofs);
    assembly::assemble_stiffness(&mesh, &elems, &dofs, &mut k);
    k
}
