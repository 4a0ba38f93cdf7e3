//! Timing of the condensation onto the arc DOFs within |x| < X of the contact point:
//! `cargo run --release --example schur_timing -- LEVEL X`.
use std::time::Instant;
use stickslip::assembly::{self, UpperCsc};
use stickslip::condense::Condensed;
use stickslip::dofs::{DofMap, SupportSpec};
use stickslip::elasticity::Material;
use stickslip::la::PartialSymbolic;

fn main() {
    let lvl: usize = std::env::args().nth(1).expect("LEVEL").parse().unwrap();
    let xw: f64 = std::env::args().nth(2).expect("X").parse().unwrap();
    let mesh =
        stickslip::mesh::gmsh::read(std::path::Path::new(&format!("meshes/vm272_L{lvl}.msh")))
            .unwrap();
    let mat = Material { e: 200.0, nu: 0.3 };
    let mut elems = vec![];
    for b in ["lower_body", "upper_body"] {
        for &e in &mesh.group(b).unwrap().elements {
            elems.push((e, mat));
        }
    }
    let active = vec![true; mesh.nodes.len()];
    let bottom = mesh.group_nodes(mesh.group("bottom").unwrap());
    let top = mesh.group_nodes(mesh.group("top").unwrap());
    let mut ret = vec![];
    for g in ["lower_arc", "upper_arc"] {
        for n in mesh.group_nodes(mesh.group(g).unwrap()) {
            if mesh.nodes[n][0].abs() < xw {
                ret.push(n);
            }
        }
    }
    let sup = [SupportSpec {
        group: "bottom",
        nodes: &bottom,
        value: [Some(0.0), Some(0.0)],
    }];
    let dofs = DofMap::build(&mesh.node_tags, &active, &sup, Some(("top", &top)), &ret).unwrap();
    let t = Instant::now();
    let mut k = UpperCsc::pattern(&mesh, &elems, &dofs);
    assembly::assemble_stiffness(&mesh, &elems, &dofs, &mut k);
    let ta = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let sym =
        PartialSymbolic::analyse(dofs.n_free(), dofs.n_retained, &k.col_ptr, &k.row_idx).unwrap();
    let tsym = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let c = Condensed::build(&k, dofs.n_interior, &[0, 1], &sym).unwrap();
    println!(
        "L{lvl} retained {} assemble {ta:.3} analyse {tsym:.3} factorise+L_RR {:.3}",
        c.n_r,
        t.elapsed().as_secs_f64()
    );
}
