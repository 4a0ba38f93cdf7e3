//! Timing of the nodal stresses of two and four fields: one at a time on this thread, one at
//! a time on all threads, and together (`Model::nodal_stresses_many`: each element's gradients
//! mapped once for them), and the check that all give the same bits:
//! `cargo run --release --example ns_timing -- CASE` (made-up smooth fields).
use std::time::Instant;
fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("CASE"));
    let case = stickslip::case::Case::load(&path).unwrap();
    let model = stickslip::model::Model::build(&case, &path).unwrap();
    let n = model.dofs.n_free();
    let us: Vec<Vec<f64>> = (0..4)
        .map(|k| {
            (0..n)
                .map(|i| 1e-3 * ((i % (977 + k)) as f64).sin())
                .collect()
        })
        .collect();
    let refs: Vec<&[f64]> = us.iter().map(|u| u.as_slice()).collect();
    for _ in 0..4 {
        for k in [2usize, 4] {
            let t = Instant::now();
            let a: Vec<_> = refs[..k]
                .iter()
                .map(|u| model.nodal_stresses(u, false))
                .collect();
            let t1 = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let p: Vec<_> = refs[..k]
                .iter()
                .map(|u| model.nodal_stresses(u, true))
                .collect();
            let t2 = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let b = model.nodal_stresses_many(&refs[..k]);
            let t3 = t.elapsed().as_secs_f64();
            let same = a.iter().zip(&b).all(|(x, y)| {
                x.iter()
                    .zip(y)
                    .all(|(u, v)| u.iter().zip(v).all(|(p, q)| p.to_bits() == q.to_bits()))
            }) && a.iter().zip(&p).all(|(x, y)| x == y);
            println!(
                "{k} fields: serial {:.1} ms, parallel {:.1} ms, lanes {:.1} ms, same {same}",
                t1 * 1e3,
                t2 * 1e3,
                t3 * 1e3
            );
        }
    }
}
