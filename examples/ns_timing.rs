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
    // A call's result and its wall time in ms.
    fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
        let t = Instant::now();
        let r = f();
        (r, t.elapsed().as_secs_f64() * 1e3)
    }
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
                "{k} fields: serial {t1:.1} ms, parallel {t2:.1} ms, lanes {t3:.1} ms, same {same}"
            );
        }
    }
}
