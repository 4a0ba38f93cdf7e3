//! Times faer's dense `L D Lᵀ` and `L Lᵀ` of an SPD matrix of order `m` (default 4034, the
//! constraint block of Fig. 2 on L7) on rayon's threads: `cargo run --release --example
//! dense_block_timing [m]`.
fn main() {
    use faer::dyn_stack::{MemBuffer, MemStack};
    let m: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4034);
    let par = faer::Par::rayon(rayon::current_num_threads());
    let a = faer::Mat::<f64>::from_fn(m, m, |i, j| {
        let d = (i as f64 - j as f64).abs();
        if i == j { m as f64 } else { 1.0 / (1.0 + d) }
    });
    for rep in 0..3 {
        let mut l = a.clone();
        let t = std::time::Instant::now();
        let mut mem = MemBuffer::new(
            faer::linalg::cholesky::ldlt::factor::cholesky_in_place_scratch::<f64>(
                m,
                par,
                Default::default(),
            ),
        );
        faer::linalg::cholesky::ldlt::factor::cholesky_in_place(
            l.as_mut(),
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .unwrap();
        let t_ldlt = t.elapsed().as_secs_f64();
        let mut l = a.clone();
        let t = std::time::Instant::now();
        let mut mem = MemBuffer::new(
            faer::linalg::cholesky::llt::factor::cholesky_in_place_scratch::<f64>(
                m,
                par,
                Default::default(),
            ),
        );
        faer::linalg::cholesky::llt::factor::cholesky_in_place(
            l.as_mut(),
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .unwrap();
        let t_llt = t.elapsed().as_secs_f64();
        let flops = (m as f64).powi(3) / 3.0;
        println!(
            "rep {rep}: m = {m}: LDLT {t_ldlt:.3} s ({:.1} Gflop/s), LLT {t_llt:.3} s ({:.1} Gflop/s)",
            flops / t_ldlt / 1e9,
            flops / t_llt / 1e9
        );
    }
}
