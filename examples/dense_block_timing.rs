//! Times faer's dense `L D Lᵀ` (as the constraint block is factorised) of an SPD matrix of order
//! `m` (default 4034, the constraint block of Fig. 2 on L7) on rayon's threads, three times:
//! `cargo run --release --example dense_block_timing [m]`.
fn main() {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::ldlt::factor::{cholesky_in_place, cholesky_in_place_scratch};
    let m: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4034);
    let par = faer::Par::rayon(rayon::current_num_threads());
    let a = faer::Mat::<f64>::from_fn(m, m, |i, j| {
        let d = (i as f64 - j as f64).abs();
        if i == j { m as f64 } else { 1.0 / (1.0 + d) }
    });
    let flops = (m as f64).powi(3) / 3.0;
    for rep in 0..3 {
        let mut f = a.clone();
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(m, par, Default::default()));
        let t = std::time::Instant::now();
        cholesky_in_place(
            f.as_mut(),
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .expect("positive definite");
        let s = t.elapsed().as_secs_f64();
        println!(
            "rep {rep}: m = {m}: L D Lᵀ {s:.3} s ({:.1} Gflop/s)",
            flops / s / 1e9
        );
    }
}
