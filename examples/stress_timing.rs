//! Timing of the per-element work after the load steps on a case's mesh (made-up smooth
//! displacement fields): the bodies' `.vtu` topology, the element forces of the summary's
//! equilibrium check (geometry mapped each time, then kept), eight equilibrium checks one at a
//! time and together (`checks::equilibrium_many`), and `Model::nodal_stresses` (serial and
//! parallel) against two and four fields together (`Model::nodal_stresses_many`), with the
//! check that the ways give the same bits:
//! `cargo run --release --example stress_timing -- CASE`.
use std::time::Instant;

/// A call's result and its wall time in ms.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let r = f();
    (r, t.elapsed().as_secs_f64() * 1e3)
}

fn main() {
    use stickslip::checks::{Input, equilibrium, equilibrium_many};
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("CASE"));
    let case = stickslip::case::Case::load(&path).unwrap();
    let model = stickslip::model::Model::build(&case, &path).unwrap();
    // Any smooth fields will do for timing: x-dependent displacements at the free DOFs.
    let n = model.dofs.n_free();
    let us: Vec<Vec<f64>> = (0..8)
        .map(|k| {
            (0..n)
                .map(|i| 1e-3 * ((i % (977 + k)) as f64).sin())
                .collect()
        })
        .collect();
    let u = &us[0];
    let (_, t) = timed(|| stickslip::output::fields::BodiesMesh::new(&model));
    println!("bodies mesh: {t:.2} ms");
    let inps: Vec<Input> = us
        .iter()
        .map(|u| Input {
            model: &model,
            u,
            scale: 1.0,
            state: None,
            records: &[],
            friction: None,
            equilibrium: None,
        })
        .collect();
    for kept in [false, true] {
        if kept {
            let (_, t) = timed(|| model.keep_force_geometry());
            println!("keep force geometry (parallel): {t:.2} ms");
        }
        let (f, t) = timed(|| model.element_forces(u));
        println!(
            "element forces (parallel, geometry kept {kept}): {t:.2} ms ({} elements)",
            f.len()
        );
        for _ in 0..3 {
            let (a, t1) = timed(|| inps.iter().map(equilibrium).collect::<Vec<_>>());
            let (b, t2) = timed(|| equilibrium_many(&inps));
            let same = a
                .iter()
                .zip(&b)
                .all(|(x, y)| x.value.to_bits() == y.value.to_bits());
            println!(
                "8 equilibrium checks, geometry kept {kept}: one at a time {t1:.1} ms, together {t2:.1} ms, same {same}"
            );
        }
    }
    let refs: Vec<&[f64]> = us.iter().map(|u| u.as_slice()).collect();
    for _ in 0..4 {
        for k in [2usize, 4] {
            let one_by_one = |parallel| {
                timed(|| {
                    refs[..k]
                        .iter()
                        .map(|u| model.nodal_stresses(u, parallel))
                        .collect::<Vec<_>>()
                })
            };
            let (a, t1) = one_by_one(false);
            let (p, t2) = one_by_one(true);
            let (b, t3) = timed(|| model.nodal_stresses_many(&refs[..k]));
            let same = a.iter().zip(&b).all(|(x, y)| {
                x.iter()
                    .zip(y)
                    .all(|(u, v)| u.iter().zip(v).all(|(p, q)| p.to_bits() == q.to_bits()))
            }) && a.iter().zip(&p).all(|(x, y)| x == y);
            println!(
                "nodal stresses of {k} fields: one at a time {t1:.1} ms, one at a time on all threads {t2:.1} ms, together {t3:.1} ms, same {same}"
            );
        }
    }
}
