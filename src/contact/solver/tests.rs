use super::block::*;
use super::factors::*;
use super::system::*;
use crate::la::dense::tests::{product, w_and_mu};
use faer::Mat;

/// A set of unknowns is served by the prefix factor when it fills its leading set but for
/// at most one in 64, and is large enough.
#[test]
fn the_leading_set_of_a_prefix_factor_holds_the_unknowns_with_few_others() {
    let m = 1000;
    let order: Vec<usize> = (0..m).rev().collect();
    let pf = PrefixFactor::new(Mat::zeros(1, 1), order.clone());
    let first = |p: usize| order[..p].to_vec();
    assert_eq!(leading_set(&pf, &first(640)), Some(640));
    // Ten holes in 640: 640 / 64 = 10 allowed; eleven are not.
    let holes = |k: usize| -> Vec<usize> { first(640).into_iter().skip(k).collect() };
    assert_eq!(leading_set(&pf, &holes(10)), Some(640));
    assert_eq!(leading_set(&pf, &holes(11)), None);
    // Too small to be worth it.
    assert_eq!(leading_set(&pf, &first(PREFIX_MIN - 1)), None);
    assert_eq!(leading_set(&pf, &first(PREFIX_MIN)), Some(PREFIX_MIN));
}

/// A block factorised on rayon's threads has the bits of the sequential factorisation, in
/// pools of 2, 3 and 4 threads, at sizes that cross faer's blocking thresholds, with a
/// subset of the unknowns (so the copy gathers rows and columns) and the rows outside.
#[test]
fn the_block_factor_has_the_same_bits_on_any_number_of_threads() {
    for n in [60usize, 700, 1300] {
        let (a, _) = w_and_mu(n);
        let mut w = &a * &a;
        for i in 0..n {
            w[(i, i)] += 1.0;
        }
        let unk: Vec<usize> = (0..n).filter(|i| i % 7 != 3).rev().collect();
        let seq = Block::factorise(&w, &unk, false).expect("positive definite");
        for threads in [2, 3, 4] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            let par = pool
                .install(|| Block::factorise(&w, &unk, true))
                .expect("positive definite");
            let (ls, lp) = (seq.l(), par.l());
            for j in 0..unk.len() {
                for i in j..unk.len() {
                    assert_eq!(ls[(i, j)].to_bits(), lp[(i, j)].to_bits(), "n {n}");
                }
            }
            assert_eq!(seq.out_rows, par.out_rows);
            assert_eq!(seq.w_out, par.w_out);
        }
    }
}

/// Columns of the identity solved with the forward sweep on the trailing block only (from
/// the first column's position) are `K⁻¹ e_q` as the whole solve gives them, to round-off,
/// and checked against `K` itself; from position 0 it is the whole solve, bit for bit.
#[test]
fn unit_columns_solved_below_their_first_row_are_the_columns_of_the_inverse() {
    let n = 300;
    let (a, _) = w_and_mu(n);
    // Symmetric positive definite: A² plus a multiple of the identity.
    let mut w = &a * &a;
    for i in 0..n {
        w[(i, i)] += 1.0;
    }
    let unk: Vec<usize> = (0..n).collect();
    let block = Block::factorise(&w, &unk, false).expect("positive definite");
    let qs = [180usize, 211, 250, 299];
    let unit = || {
        let mut e = Mat::<f64>::zeros(n, qs.len());
        for (c, &q) in qs.iter().enumerate() {
            e[(q, c)] = 1.0;
        }
        e
    };
    let (mut whole, mut below, mut from0) = (unit(), unit(), unit());
    block.solve_in_place(&mut whole);
    block.solve_in_place_below(&mut below, 180);
    block.solve_in_place_below(&mut from0, 0);
    let scale = (0..n).fold(0.0f64, |m, i| m.max(whole[(i, 0)].abs()));
    for c in 0..qs.len() {
        for i in 0..n {
            assert_eq!(whole[(i, c)].to_bits(), from0[(i, c)].to_bits());
            assert!((whole[(i, c)] - below[(i, c)]).abs() <= 1e-12 * scale);
        }
        // K g = e_q.
        for i in 0..n {
            let r: f64 = (0..n).map(|j| w[(i, j)] * below[(j, c)]).sum();
            let e = if i == qs[c] { 1.0 } else { 0.0 };
            assert!((r - e).abs() <= 1e-9, "row {i} of K g_{}: {r}", qs[c]);
        }
    }
}

#[test]
fn recalled_products_are_those_of_the_predicted_forces_and_refused_otherwise() {
    let m = 40;
    let (w, mu0) = w_and_mu(m);
    let mu1: Vec<f64> = mu0.iter().map(|v| 1.1 * v + 0.05).collect();
    let mut cache = LuCache::default();
    // Nothing kept: no recall.
    assert!(cache.recall_w_mu(&mu1, &w).is_none());
    cache.remember_w_mu(mu0.clone(), product(&w, &mu0));
    cache.remember_w_mu(mu1.clone(), product(&w, &mu1));
    // The last converged forces themselves: their product as kept.
    assert_eq!(cache.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
    // The predictor's start, with the first three entries clipped to zero.
    let t = 0.75;
    let mut mu: Vec<f64> = mu1.iter().zip(&mu0).map(|(a, b)| a + t * (a - b)).collect();
    mu[..3].iter_mut().for_each(|v| *v = 0.0);
    // Without the announced factor it is not recognised.
    assert!(cache.recall_w_mu(&mu, &w).is_none());
    cache.predict_with(Some(t));
    let got = cache.recall_w_mu(&mu, &w).expect("recalled");
    let want = product(&w, &mu);
    let scale = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for (g, x) in got.iter().zip(&want) {
        assert!((g - x).abs() <= 1e-13 * scale, "{g} against {x}");
    }
    // The factor is used once.
    assert!(cache.recall_w_mu(&mu, &w).is_none());
    // Forces off the prediction in more than an eighth of the entries: not recalled.
    let mut off = mu.clone();
    off[..m / 8 + 1].iter_mut().for_each(|v| *v += 1e-3);
    cache.predict_with(Some(t));
    assert!(cache.recall_w_mu(&off, &w).is_none());
    // A checkpoint records them and a replay of the record restores them: a resumed run
    // recalls what the uninterrupted one does.
    let rec = cache.checkpoint().expect("products kept");
    let mut resumed = LuCache::default();
    assert!(resumed.replay(&w, None, &rec));
    assert_eq!(resumed.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
    // A step's end keeps them too.
    cache.end_step();
    assert_eq!(cache.recall_w_mu(&mu1, &w), Some(product(&w, &mu1)));
}
