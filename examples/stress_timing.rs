//! Timing of the per-element work after the load steps on a case's mesh (a made-up smooth
//! displacement field): the bodies' `.vtu` topology, the element forces of the summary's
//! equilibrium check (geometry mapped each time, then kept), and `Model::nodal_stresses`
//! (serial and parallel): `cargo run --release --example stress_timing -- CASE`.
use std::time::Instant;

fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("CASE"));
    let case = stickslip::case::Case::load(&path).unwrap();
    let model = stickslip::model::Model::build(&case, &path).unwrap();
    // Any smooth field will do for timing: x-dependent displacements at the free DOFs.
    let n = model.dofs.n_free();
    let u: Vec<f64> = (0..n).map(|i| 1e-3 * ((i % 977) as f64).sin()).collect();
    // One timed call, printed with its label.
    let timed = |label: &str, f: &mut dyn FnMut() -> String| {
        let t = Instant::now();
        let note = f();
        println!("{label}: {:.2} ms {note}", t.elapsed().as_secs_f64() * 1e3);
    };
    timed("bodies mesh", &mut || {
        stickslip::output::fields::BodiesMesh::new(&model);
        String::new()
    });
    timed("element forces (parallel, geometry each time)", &mut || {
        format!("({} elements)", model.element_forces(&u).len())
    });
    timed("keep force geometry (parallel)", &mut || {
        model.keep_force_geometry();
        String::new()
    });
    timed("element forces (kept geometry)", &mut || {
        format!("({} elements)", model.element_forces(&u).len())
    });
    for parallel in [false, true] {
        let mut best = f64::INFINITY;
        let mut check = 0.0;
        for _ in 0..7 {
            let t = Instant::now();
            let s = model.nodal_stresses(&u, parallel);
            best = best.min(t.elapsed().as_secs_f64());
            check = s.iter().map(|v| v[0]).sum::<f64>();
        }
        println!(
            "nodal stresses, parallel = {parallel}: best of 7 {:.2} ms (checksum {check:e})",
            best * 1e3
        );
    }
}
