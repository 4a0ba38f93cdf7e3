//! Ordering benchmark: faer's AMD against [`stickslip::la::ordering::nested_dissection`] on the
//! real stiffness matrix of both VM272 half-cylinders (faces `bottom` and `top` clamped, so
//! that both bodies are held without a pilot), levels of the mesh ladder.
//!
//! Per level and ordering: the time to order (nested dissection also on one thread, and
//! checked to give the same permutation), faer's supernodal symbolic analysis with that
//! ordering, the numeric `L Lᵀ` factorisation (best of `ORDERING_REPEAT` runs, default 3),
//! the exact nnz(L) and the flop count `Σ_j colcount(j)²` (elimination-tree column counts);
//! then the least-squares slopes of log(factorisation time) and log(flops) against log(DOFs).
//! The table is printed and written to `out/bench/ordering.md`.
//!
//! Run: `cargo bench --bench ordering`. Environment: `ORDERING_LEVELS` (default `4-7`, or a
//! list such as `5,6`), `STICKSLIP_THREADS` (default 2), `ORDERING_REPEAT` (default 3).
//! Levels 6 and 7 are not in the repository: `python3 meshes/generate.py vm272_L6 vm272_L7`.

use std::path::PathBuf;
use std::time::Instant;
use stickslip::assembly::UpperCsc;

#[path = "common/clamped.rs"]
mod clamped;
use clamped::stiffness;
use stickslip::la::ordering::{self, Ordering};

fn levels() -> Vec<usize> {
    let s = std::env::var("ORDERING_LEVELS").unwrap_or_else(|_| "4-7".into());
    let mut out = Vec::new();
    for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let bad = || panic!("ORDERING_LEVELS: cannot read `{part}` (use e.g. `4-7` or `4,6`)");
        if let Some((a, b)) = part.split_once('-') {
            let (a, b): (usize, usize) = (
                a.trim().parse().unwrap_or_else(|_| bad()),
                b.trim().parse().unwrap_or_else(|_| bad()),
            );
            out.extend(a..=b);
        } else {
            out.push(part.parse().unwrap_or_else(|_| bad()));
        }
    }
    out
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .map(|v| {
            v.parse()
                .unwrap_or_else(|_| panic!("{name}: not a number: {v}"))
        })
        .unwrap_or(default)
}

struct Row {
    level: usize,
    n: usize,
    kind: Ordering,
    t_order: f64,
    t_order_1: f64,
    t_symbolic: f64,
    t_numeric: f64,
    nnz_l: u64,
    flops: f64,
}

fn measure(level: usize, k: &UpperCsc, kind: Ordering, repeat: usize) -> Row {
    use faer::Side;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::{SupernodalThreshold, cholesky};
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
    let n = k.n;
    let t = Instant::now();
    let fwd = ordering::order(kind, n, &k.col_ptr, &k.row_idx);
    let t_order = t.elapsed().as_secs_f64();
    // Nested dissection orders on rayon's pool: its time on one thread too (the same
    // permutation; AMD is sequential anyway).
    let t_order_1 = if kind == Ordering::NestedDissection {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("pool");
        let t = Instant::now();
        let fwd1 = pool.install(|| ordering::order(kind, n, &k.col_ptr, &k.row_idx));
        let t1 = t.elapsed().as_secs_f64();
        assert!(
            fwd1 == fwd,
            "ND differs between 1 and {} threads",
            rayon::current_num_threads()
        );
        t1
    } else {
        t_order
    };
    let mut inv = vec![0usize; n];
    for (i, &o) in fwd.iter().enumerate() {
        inv[o] = i;
    }
    let counts = ordering::cholesky_column_counts(n, &k.col_ptr, &k.row_idx, &fwd);
    let nnz_l: u64 = counts.iter().map(|&c| c as u64).sum();
    let flops: f64 = counts.iter().map(|&c| (c as f64) * (c as f64)).sum();

    let sym = SymbolicSparseColMatRef::new_checked(n, n, &k.col_ptr, None, &k.row_idx);
    let t = Instant::now();
    let symbolic = cholesky::factorize_symbolic_cholesky(
        sym,
        Side::Upper,
        cholesky::SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, n)),
        cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        },
    )
    .expect("symbolic analysis");
    let t_symbolic = t.elapsed().as_secs_f64();

    let a = SparseColMatRef::new(sym, &k.values);
    let par = faer::get_global_parallelism();
    let mut l = vec![0.0f64; symbolic.len_val()];
    let mut mem =
        MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()));
    let mut t_numeric = f64::INFINITY;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        symbolic
            .factorize_numeric_llt(
                &mut l,
                a,
                Side::Upper,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .expect("the stiffness is positive definite");
        t_numeric = t_numeric.min(t.elapsed().as_secs_f64());
    }
    Row {
        level,
        n,
        kind,
        t_order,
        t_order_1,
        t_symbolic,
        t_numeric,
        nnz_l,
        flops,
    }
}

/// Least-squares slope of log y against log x.
fn slope(pts: &[(f64, f64)]) -> f64 {
    let m = pts.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = pts.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / m, ly.iter().sum::<f64>() / m);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn main() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let threads = env_usize("STICKSLIP_THREADS", 2);
    let repeat = env_usize("ORDERING_REPEAT", 3);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("rayon pool");
    faer::set_global_parallelism(if threads <= 1 {
        faer::Par::Seq
    } else {
        faer::Par::rayon(threads)
    });
    let mut md = String::new();
    let mut line = |s: String| {
        println!("{s}");
        md.push_str(&s);
        md.push('\n');
    };
    line(
        "| level | DOFs | ordering | order s | order s, 1 thread | symbolic s | factorise s | nnz(L) | flops Σ colcount² |"
            .into(),
    );
    line("|---|---|---|---|---|---|---|---|---|".into());
    let mut rows = Vec::new();
    for level in levels() {
        let path = repo.join(format!("meshes/vm272_L{level}.msh"));
        if !path.exists() {
            eprintln!(
                "skipping L{level}: {} is missing (build it with `python3 meshes/generate.py vm272_L{level}`)",
                path.display()
            );
            continue;
        }
        let k = stiffness(&path);
        for kind in [Ordering::Amd, Ordering::NestedDissection] {
            let r = measure(level, &k, kind, repeat);
            line(format!(
                "| L{} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {:.3e} |",
                r.level,
                r.n,
                r.kind.name(),
                r.t_order,
                r.t_order_1,
                r.t_symbolic,
                r.t_numeric,
                r.nnz_l,
                r.flops
            ));
            rows.push(r);
        }
    }
    line(String::new());
    for kind in [Ordering::Amd, Ordering::NestedDissection] {
        let rs: Vec<&Row> = rows.iter().filter(|r| r.kind == kind).collect();
        if rs.len() >= 2 {
            let t: Vec<(f64, f64)> = rs.iter().map(|r| (r.n as f64, r.t_numeric)).collect();
            let f: Vec<(f64, f64)> = rs.iter().map(|r| (r.n as f64, r.flops)).collect();
            line(format!(
                "{}: factorisation time ∝ N^{:.2}, flops ∝ N^{:.2} (levels {})",
                kind.name(),
                slope(&t),
                slope(&f),
                rs.iter()
                    .map(|r| format!("L{}", r.level))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    line(format!(
        "\n(threads: {threads}, set STICKSLIP_THREADS, for the factorisation and ND's ordering (AMD's is \
         sequential); factorisation: faer supernodal LLᵀ, best of {repeat}; symbolic: faer's \
         supernodal analysis with the given ordering)"
    ));
    let out = repo.join("out/bench");
    std::fs::create_dir_all(&out).expect("out/bench");
    std::fs::write(out.join("ordering.md"), md).expect("write out/bench/ordering.md");
    println!("written: {}", out.join("ordering.md").display());
}
