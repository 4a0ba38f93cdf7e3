//! Times the nested-dissection ordering of the stiffness of both VM272 half-cylinders
//! (`bottom` and `top` clamped, as in `benches/ordering.rs`) on one thread and on rayon's pool,
//! best of `REPEAT` (default 5), and prints a hash of the permutation, so that two builds can be
//! compared for the same ordering: `cargo run --release --example nd_timing -- MESH [REPEAT]`.
use std::time::Instant;

#[path = "../benches/common/clamped.rs"]
mod clamped;

fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).expect("MESH"));
    let repeat: usize = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let k = clamped::stiffness(&path);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut best = [f64::INFINITY; 2];
    let mut hash = 0u64;
    for _ in 0..repeat {
        for (i, best) in best.iter_mut().enumerate() {
            let t = Instant::now();
            let fwd = if i == 0 {
                one.install(|| {
                    stickslip::la::ordering::nested_dissection(k.n, &k.col_ptr, &k.row_idx)
                })
            } else {
                stickslip::la::ordering::nested_dissection(k.n, &k.col_ptr, &k.row_idx)
            };
            *best = best.min(t.elapsed().as_secs_f64());
            let h = fwd.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &v| {
                (h ^ v as u64).wrapping_mul(0x0100_0000_01b3)
            });
            assert!(hash == 0 || hash == h, "the ordering changed between runs");
            hash = h;
        }
    }
    println!(
        "{}: n = {}, nested dissection best of {repeat}: {:.3} s on one thread, {:.3} s on {} threads; permutation hash {hash:016x}",
        path.display(),
        k.n,
        best[0],
        best[1],
        rayon::current_num_threads()
    );
}
