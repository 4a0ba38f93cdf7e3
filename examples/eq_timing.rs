//! Timing of the equilibrium check of eight fields one at a time against eight together
//! (`checks::equilibrium_many`: each element's geometry read once for them), with the element
//! geometry mapped each time and then kept, and the check that both give the same bits:
//! `cargo run --release --example eq_timing -- CASE` (made-up smooth fields).
use std::time::Instant;
fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("CASE"));
    let case = stickslip::case::Case::load(&path).unwrap();
    let model = stickslip::model::Model::build(&case, &path).unwrap();
    let n = model.dofs.n_free();
    let us: Vec<Vec<f64>> = (0..8)
        .map(|k| {
            (0..n)
                .map(|i| 1e-3 * ((i % (977 + k)) as f64).sin())
                .collect()
        })
        .collect();
    let inps: Vec<stickslip::checks::Input> = us
        .iter()
        .map(|u| stickslip::checks::Input {
            model: &model,
            u,
            scale: 1.0,
            state: None,
            records: &[],
            friction: None,
            equilibrium: None,
        })
        .collect();
    for keep in [false, true] {
        if keep {
            model.keep_force_geometry();
        }
        for _ in 0..3 {
            let t = Instant::now();
            let a: Vec<_> = inps.iter().map(stickslip::checks::equilibrium).collect();
            let t1 = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let b = stickslip::checks::equilibrium_many(&inps);
            let t2 = t.elapsed().as_secs_f64();
            let same = a
                .iter()
                .zip(&b)
                .all(|(x, y)| x.value.to_bits() == y.value.to_bits());
            println!(
                "kept {keep}: 8 x one {:.1} ms, 8 lanes {:.1} ms, same {same}",
                t1 * 1e3,
                t2 * 1e3
            );
        }
    }
}
