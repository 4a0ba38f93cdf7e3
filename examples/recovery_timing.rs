//! Timing of the recovery solve (`Condensed::recover_total_many`) for 1, 2, 4, 8 and 16
//! right-hand sides on one thread, and the check that a column solved with others equals it
//! solved alone: `cargo run --release --example recovery_timing -- CASE`.
use std::time::Instant;

fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("CASE"));
    let case = stickslip::case::Case::load(&path).unwrap();
    let model = stickslip::model::Model::build(&case, &path).unwrap();
    let nr = model.dofs.n_retained;
    let f = model.load(1.0);
    if let stickslip::condense::Factor::Saddle(sf) = &model.condensed.chol {
        let layout = sf.layout();
        let n = model.dofs.n_free();
        let (mut used, mut total) = (0usize, 0usize);
        for s in 0..layout.begin.len() - 1 {
            let (b, e) = (layout.begin[s], layout.begin[s + 1]);
            let pat = &layout.rows[layout.row_ptr[s]..layout.row_ptr[s + 1]];
            let nrows = e - b + pat.len();
            total += nrows * (e - b);
            if b < n {
                let kp = pat.partition_point(|&r| r < n);
                used += (e.min(n) - b) * (e - b + kp);
            }
        }
        let mut hist = [0usize; 14];
        for s in 0..layout.begin.len() - 1 {
            let w = layout.begin[s + 1] - layout.begin[s];
            hist[((usize::BITS - w.leading_zeros()) as usize - 1).min(13)] += 1;
        }
        println!(
            "supernodes: {}, by width 1, 2-3, 4-7, ... (the last from 8192 up): {:?}",
            layout.begin.len() - 1,
            hist
        );
        println!(
            "factor values: {} MB, of which the K̂ solves read {} MB ({:.0} %)",
            total * 8 / 1_000_000,
            used * 8 / 1_000_000,
            100.0 * used as f64 / total as f64
        );
    }
    let column = |j: usize| {
        let r: Vec<f64> = (0..nr)
            .map(|i| ((i * 7919 + j * 104729) % 1000) as f64 * 1e-3 - 0.5)
            .collect();
        (f.clone(), r)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let alone: Vec<Vec<f64>> = (0..16)
            .map(|j| {
                model
                    .condensed
                    .recover_total_many(&[column(j)], true)
                    .remove(0)
            })
            .collect();
        for k in [1usize, 2, 4, 8, 16] {
            let cases: Vec<_> = (0..k).map(column).collect();
            let mut best = f64::INFINITY;
            let mut out = Vec::new();
            for _ in 0..5 {
                let t = Instant::now();
                out = model.condensed.recover_total_many(&cases, true);
                best = best.min(t.elapsed().as_secs_f64());
            }
            let same = out
                .iter()
                .zip(&alone)
                .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
            println!(
                "{k:2} columns: {:7.2} ms, {:6.2} ms per column, equal to alone: {same}",
                best * 1e3,
                best * 1e3 / k as f64
            );
        }
    });
}
