use super::layout::*;
use super::symbolic::*;
use super::*;
use crate::la::base::{FactorError, supernodal};
use crate::la::values::FactorValues;

/// Constraint rows: (free-DOF index, coefficient) per row.
type Rows = Vec<Vec<(usize, f64)>>;

/// A tridiagonal K̂ of order `n` (upper CSC pattern and values) and two constraint rows.
fn small_saddle(n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>, Rows) {
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for j in 0..n {
        if j > 0 {
            row_idx.push(j - 1);
            values.push(-1.0);
        }
        row_idx.push(j);
        values.push(2.5);
        col_ptr.push(row_idx.len());
    }
    let y = vec![vec![(3, 1.0), (4, -1.0)], vec![(n - 1, 1.0)]];
    (col_ptr, row_idx, values, y)
}

/// The factor of [`small_saddle`] of order `n`, with its constraint rows.
fn small_saddle_factor(n: usize) -> (SaddleFactor, Rows) {
    let (cp, ri, kv, y) = small_saddle(n);
    let sym = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
    let f = sym.factorise(&kv, &y).unwrap();
    (f, y)
}

/// Two factorisations on one analysis (a thousand constraint rows, so that `W` comes from the
/// root supernode) give the same `W` and `C` bit for bit, `W` with and without `C` alike, and
/// `W` is the Delassus operator.
#[test]
fn factorisations_on_one_analysis_give_the_same_delassus_operator() {
    let (n, m) = (1300, 1032);
    let (cp, ri, kv, _) = small_saddle(n);
    let y: Rows = (0..m).map(|i| vec![(i, 1.0), (i + 1, -0.5)]).collect();
    let sym = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
    let delassus = || {
        let f = sym.factorise(&kv, &y).unwrap();
        let (w, c) = f.delassus(true).expect("W positive definite");
        (w, c.expect("C from the root"))
    };
    let (w1, c1) = delassus();
    let (w2, c2) = delassus();
    assert_eq!(w1, w2);
    assert_eq!(c1, c2);
    let sym2 = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
    let f = sym2.factorise(&kv, &y).unwrap();
    let (w3, c3) = f.delassus(false).expect("W positive definite");
    assert!(c3.is_none() && w3 == w1);
    // And it is the Delassus operator: W e_0 = Y K̂⁻¹ Yᵀ e_0.
    let mut x = vec![0.0; n];
    for &(r, v) in &y[0] {
        x[r] += v;
    }
    sym.factorise(&kv, &y).unwrap().solve_in_place(&mut x);
    for (i, row) in y.iter().enumerate().take(40) {
        let yi: f64 = row.iter().map(|&(r, v)| v * x[r]).sum();
        assert!(
            (yi - w1[(i, 0)]).abs() <= 1e-12 * w1[(0, 0)],
            "{i}: {yi} vs {}",
            w1[(i, 0)]
        );
    }
}

#[test]
fn a_released_factor_hands_over_its_values_once_and_solves_no_more() {
    let n = 12;
    let (f, _) = small_saddle_factor(n);
    let mut x = vec![1.0; n];
    f.solve_in_place(&mut x);
    // A solve that holds the values keeps them alive past the release.
    let held = f.values();
    let released = f.release().expect("held until now");
    assert!(std::sync::Arc::ptr_eq(&held, &released));
    assert_eq!(std::sync::Arc::strong_count(&released), 2);
    drop(held);
    assert!(
        std::sync::Arc::try_unwrap(released).is_ok(),
        "the last holder"
    );
    assert!(f.release().is_none(), "released once");
    let after = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut x = vec![1.0; n];
        f.solve_in_place(&mut x);
    }));
    assert!(after.is_err(), "a solve after the release panics");
}

/// On a fully dense saddle-point matrix (one supernode of `n + m` columns) the modelled
/// operations are the dense `L D Lᵀ`'s `(n + m)³ / 3`, split as `n³ / 3` for `K̂`,
/// `n² m + n m²` for the coupling and `m³ / 3` for the constraint block; without
/// constraint rows only the first is left.
#[test]
fn the_modelled_operations_of_a_dense_saddle_point_matrix_are_the_dense_count() {
    let n = 7;
    let (mut col_ptr, mut row_idx) = (vec![0], Vec::new());
    for j in 0..n {
        row_idx.extend(0..=j);
        col_ptr.push(row_idx.len());
    }
    for m in [0usize, 3] {
        let y: Rows = (0..m)
            .map(|k| (0..n).map(|r| (r, 1.0 + (r * k) as f64)).collect())
            .collect();
        let sym = SaddleSymbolic::analyse(n, &col_ptr, &row_idx, &y).unwrap();
        let (k, coupling, block) = sym.flops();
        let (nf, mf) = (n as f64, m as f64);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert!(close(k, nf.powi(3) / 3.0), "m = {m}: K̂ {k}");
        assert!(
            close(coupling, nf * nf * mf + nf * mf * mf),
            "m = {m}: {coupling}"
        );
        assert!(close(block, mf.powi(3) / 3.0), "m = {m}: block {block}");
        assert!(close(k + coupling + block, (nf + mf).powi(3) / 3.0));
    }
}

/// Two blocks of `w` unknowns joined only through a separator of `s` (in that order), and
/// `m` constraint rows on the first block and the separator: the supernodes are the two
/// blocks (the first with the separator's and the constraints' rows below it, the second
/// with the separator's only) and the root (the separator with the constraint columns),
/// and the modelled operations are those three fronts' counts.
#[test]
fn the_modelled_operations_follow_the_rows_below_each_supernode() {
    let (w, sep, m) = (24usize, 8usize, 6usize);
    let n = 2 * w + sep;
    let (mut col_ptr, mut row_idx) = (vec![0], Vec::new());
    for j in 0..n {
        let block_start = if j < w {
            0
        } else if j < 2 * w {
            w
        } else {
            0
        };
        row_idx.extend(block_start..=j);
        col_ptr.push(row_idx.len());
    }
    let y: Rows = (0..m)
        .map(|k| vec![(0, 1.0), (1, 0.5), (2 * w + k, 1.0)])
        .collect();
    let identity: Vec<usize> = (0..n).collect();
    let sym = SaddleSymbolic::with_ordering(n, &col_ptr, &row_idx, &y, &identity).unwrap();
    let (k, coupling, block) = sym.flops();
    // The partition the counts below assume (blocks large enough that the supernodes are
    // not amalgamated).
    let sn = supernodal(&sym.inner).unwrap();
    assert_eq!(sn.supernode_begin(), &[0, w, 2 * w][..]);
    assert_eq!(sn.supernode_end(), &[w, 2 * w, n + m][..]);
    let (wf, sf, mf) = (w as f64, sep as f64, m as f64);
    let own = wf.powi(3) / 3.0 + wf * wf * sf + wf * sf * sf;
    let k_ref = 2.0 * own + sf.powi(3) / 3.0;
    let coupling_ref = wf * wf * mf + wf * mf * (mf + 2.0 * sf) + sf * sf * mf + sf * mf * mf;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    assert!(close(k, k_ref), "K̂ {k} against {k_ref}");
    assert!(
        close(coupling, coupling_ref),
        "coupling {coupling} against {coupling_ref}"
    );
    assert!(close(block, mf.powi(3) / 3.0), "block {block}");
}

#[test]
fn the_constraint_block_gives_the_delassus_operator_and_its_cholesky_factor() {
    let n = 40;
    let (cp, ri, kv, _) = small_saddle(n);
    // Six constraint rows that overlap (W dense), as contact rows do.
    let y: Rows = (0..6)
        .map(|k| {
            vec![
                (5 * k + 2, 1.0),
                (5 * k + 3, -0.5),
                (20 + k, 0.3 + 0.1 * k as f64),
            ]
        })
        .collect();
    let m = y.len();
    let sym = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
    let f = sym.factorise(&kv, &y).unwrap();
    // W by solves: W_ij = y_i · K̂⁻¹ y_j.
    let solved: Vec<Vec<f64>> = y
        .iter()
        .map(|row| {
            let mut x = vec![0.0; n];
            row.iter().for_each(|&(r, v)| x[r] += v);
            f.solve_in_place(&mut x);
            x
        })
        .collect();
    let w_ref = |i: usize, j: usize| -> f64 { y[i].iter().map(|&(r, v)| v * solved[j][r]).sum() };
    let (w, c) = f.delassus(true).unwrap();
    let c = c.expect("kept");
    // `delassus` takes the Schur complement the factorisation left: a second factor.
    let again = sym.factorise(&kv, &y).unwrap();
    let (w_alone, none) = again.delassus(false).unwrap();
    assert!(none.is_none());
    let wmax = (0..m).map(|i| w_ref(i, i).abs()).fold(0.0, f64::max);
    for i in 0..m {
        for j in 0..m {
            assert!((w[(i, j)] - w_ref(i, j)).abs() < 1e-13 * wmax, "W[{i},{j}]");
            assert_eq!(w[(i, j)].to_bits(), w_alone[(i, j)].to_bits());
            let cct: f64 = (0..m).map(|k| c[(i, k)] * c[(j, k)]).sum();
            assert!((cct - w[(i, j)]).abs() < 1e-13 * wmax, "C Cᵀ[{i},{j}]");
            if j > i {
                assert_eq!(c[(i, j)], 0.0, "C is lower triangular");
            }
        }
    }
}

#[test]
fn the_layout_solves_like_the_matrix_and_its_check_refuses_broken_ones() {
    let n = 40;
    let (f, y) = small_saddle_factor(n);
    let layout = f.layout();
    assert_eq!(layout.check(n, y.len()), Ok(()));
    // K̂ x = b through the layout, against the tridiagonal product.
    let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let mut x = b.clone();
    f.solve_in_place(&mut x);
    for i in 0..n {
        let kx = 2.5 * x[i]
            - if i > 0 { x[i - 1] } else { 0.0 }
            - if i + 1 < n { x[i + 1] } else { 0.0 };
        assert!((kx - b[i]).abs() < 1e-12, "row {i}: {kx} against {}", b[i]);
    }
    // A layout restored from the same arrays gives the same bits.
    let again = SaddleFactor::from_layout(
        std::sync::Arc::new((*layout).clone()),
        f.values(),
        n,
        y.len(),
    )
    .unwrap();
    let mut x2 = b.clone();
    again.solve_in_place(&mut x2);
    assert!(x.iter().zip(&x2).all(|(a, c)| a.to_bits() == c.to_bits()));
    // Broken layouts.
    let broken = |edit: &dyn Fn(&mut Supernodes)| {
        let mut l = (*layout).clone();
        edit(&mut l);
        l.check(n, y.len())
    };
    assert!(broken(&|l| *l.begin.last_mut().unwrap() -= 1).is_err());
    assert!(broken(&|l| l.fwd[0] = l.fwd[1]).is_err());
    // A constraint row among the free DOFs.
    assert!(broken(&|l| l.fwd.swap(0, n)).is_err());
    // Row pointers that go back (and past the rows).
    assert!(broken(&|l| l.row_ptr[1] = l.rows.len() + 7).is_err());
    assert!(broken(&|l| *l.val_ptr.last_mut().unwrap() += 1).is_err());
    let with_rows = (0..layout.begin.len() - 1)
        .find(|&s| layout.row_ptr[s + 1] - layout.row_ptr[s] >= 2)
        .expect("a supernode with two off-diagonal rows");
    assert!(broken(&|l| l.rows.swap(l.row_ptr[with_rows], l.row_ptr[with_rows] + 1)).is_err());
    assert!(broken(&|l| l.rows[l.row_ptr[with_rows]] = l.begin[with_rows]).is_err());
    // A value array of another length is refused.
    let short = std::sync::Arc::new(FactorValues::Owned(vec![0.0; layout.len_val() - 1]));
    assert!(SaddleFactor::from_layout(layout.clone(), short, n, y.len()).is_err());
}

/// A 70 × 70 grid's `K̂` (upper CSC pattern and values) with 120 constraint rows, ordered
/// by nested dissection: independent subtrees under top separators and a constraint block
/// wide enough for the split updates.
fn grid_saddle() -> (
    usize,
    Vec<usize>,
    Vec<usize>,
    Vec<f64>,
    Rows,
    SaddleSymbolic,
) {
    let side = 70;
    let n = side * side;
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for j in 0..n {
        let (r, c) = (j / side, j % side);
        if r > 0 {
            row_idx.push(j - side);
            values.push(-1.0 - 0.003 * (j % 11) as f64);
        }
        if c > 0 {
            row_idx.push(j - 1);
            values.push(-1.0 - 0.01 * (j % 7) as f64);
        }
        row_idx.push(j);
        values.push(4.5 + 0.001 * (j % 5) as f64);
        col_ptr.push(row_idx.len());
    }
    let y: Vec<Vec<(usize, f64)>> = (0..120)
        .map(|i| vec![(40 * i, 1.0), (40 * i + 1, -0.3 - 0.001 * i as f64)])
        .collect();
    let fwd = crate::la::ordering::nested_dissection(n, &col_ptr, &row_idx);
    let sym = SaddleSymbolic::with_ordering(n, &col_ptr, &row_idx, &y, &fwd).unwrap();
    (n, col_ptr, row_idx, values, y, sym)
}

/// The Schur complement that the tree-scheduled factorisation copies out of the
/// constraint block is the Delassus operator: against the product `−L_MM D_MM L_MMᵀ` of
/// faer's factor (round-off apart) and against solves; `C` is the same either way.
#[test]
fn the_schur_complement_copied_by_the_factorisation_is_the_delassus_operator() {
    let (n, _, _, values, y, sym) = grid_saddle();
    let m = y.len();
    let tree = sym.factorise_using(&values, &y, None, true).unwrap();
    assert!(
        tree.schur.lock().unwrap().is_some(),
        "copied by the factorisation"
    );
    let faer = sym.factorise_using(&values, &y, None, false).unwrap();
    assert!(faer.schur.lock().unwrap().is_none());
    let (w, c) = tree.delassus(true).unwrap();
    let (w_product, c_product) = faer.delassus(true).unwrap();
    let wmax = (0..m).map(|i| w[(i, i)].abs()).fold(0.0, f64::max);
    let (c, cp) = (c.as_ref().unwrap(), c_product.as_ref().unwrap());
    let cmax = (0..m).map(|i| cp[(i, i)].abs()).fold(0.0, f64::max);
    let (mut worst_w, mut worst_c) = (0.0f64, 0.0f64);
    for j in 0..m {
        for i in 0..m {
            assert_eq!(w[(i, j)].to_bits(), w[(j, i)].to_bits(), "symmetric");
            worst_w = worst_w.max((w[(i, j)] - w_product[(i, j)]).abs());
            // The root's constraint block is factorised apart from the separator's
            // columns before it: C is the product path's within round-off.
            worst_c = worst_c.max((c[(i, j)] - cp[(i, j)]).abs());
            if i < j {
                assert_eq!(c[(i, j)], 0.0, "C lower");
            }
        }
    }

    assert!(worst_w <= 4e-15 * wmax, "W differs by {worst_w:e}");
    assert!(worst_c <= 4e-15 * cmax, "C differs by {worst_c:e}");
    for (i, j) in [(0, 0), (3, 17), (60, 61), (119, 2)] {
        let mut x = vec![0.0; n];
        y[j].iter().for_each(|&(r, v)| x[r] += v);
        faer.solve_in_place(&mut x);
        let w_ref: f64 = y[i].iter().map(|&(r, v)| v * x[r]).sum();
        assert!(
            (w[(i, j)] - w_ref).abs() < 1e-12 * wmax,
            "W[{i},{j}] against solves"
        );
    }
    // Without the factor C, the pivots come from the factor's values.
    let again = sym.factorise_using(&values, &y, None, true).unwrap();
    let (w_alone, none) = again.delassus(false).unwrap();
    assert!(none.is_none());
    assert!((0..m * m).all(|k| w_alone[(k % m, k / m)].to_bits() == w[(k % m, k / m)].to_bits()));
}

/// `x = A⁻¹ b` for the saddle-point matrix `A = [K̂ Yᵀ; Y 0]` from its factor `P A Pᵀ =
/// L D Lᵀ` (supernodal layout `lay`, values `l`: unit `L` below the diagonal, `D` on it).
fn saddle_solve(lay: &Supernodes, l: &[f64], b: &[f64]) -> Vec<f64> {
    let nsup = lay.begin.len() - 1;
    let mut x: Vec<f64> = lay.fwd.iter().map(|&old| b[old]).collect();
    let node = |s: usize| {
        let (c0, w) = (lay.begin[s], lay.begin[s + 1] - lay.begin[s]);
        let pattern = &lay.rows[lay.row_ptr[s]..lay.row_ptr[s + 1]];
        (
            c0,
            w,
            w + pattern.len(),
            pattern,
            &l[lay.val_ptr[s]..lay.val_ptr[s + 1]],
        )
    };
    // The local row `i` of a supernode starting at `c0` with `w` columns.
    let row = |c0: usize, w: usize, pattern: &[usize], i: usize| {
        if i < w { c0 + i } else { pattern[i - w] }
    };
    for s in 0..nsup {
        let (c0, w, nrows, pattern, v) = node(s);
        for j in 0..w {
            let xj = x[c0 + j];
            for i in j + 1..nrows {
                x[row(c0, w, pattern, i)] -= v[j * nrows + i] * xj;
            }
        }
    }
    for s in 0..nsup {
        let (c0, w, nrows, _, v) = node(s);
        for j in 0..w {
            x[c0 + j] /= v[j * nrows + j];
        }
    }
    for s in (0..nsup).rev() {
        let (c0, w, nrows, pattern, v) = node(s);
        for j in (0..w).rev() {
            let dot: f64 = (j + 1..nrows)
                .map(|i| v[j * nrows + i] * x[row(c0, w, pattern, i)])
                .sum();
            x[c0 + j] -= dot;
        }
    }
    let mut out = vec![0.0; b.len()];
    for (new, &old) in lay.fwd.iter().enumerate() {
        out[old] = x[new];
    }
    out
}

/// The backward error `‖A x − b‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` of `x` for the saddle-point
/// matrix of `K̂` (upper triangle in compressed columns) and the rows `y`.
fn saddle_backward_error(
    (n, col_ptr, row_idx, values): (usize, &[usize], &[usize], &[f64]),
    y: &[Vec<(usize, f64)>],
    x: &[f64],
    b: &[f64],
) -> f64 {
    let size = n + y.len();
    let (mut ax, mut row_sum) = (vec![0.0; size], vec![0.0; size]);
    let mut entry = |i: usize, j: usize, v: f64| {
        ax[i] += v * x[j];
        row_sum[i] += v.abs();
    };
    for c in 0..n {
        for p in col_ptr[c]..col_ptr[c + 1] {
            let r = row_idx[p];
            entry(r, c, values[p]);
            if r != c {
                entry(c, r, values[p]);
            }
        }
    }
    for (i, yi) in y.iter().enumerate() {
        for &(c, v) in yi {
            entry(n + i, c, v);
            entry(c, n + i, v);
        }
    }
    let norm = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let residual: Vec<f64> = ax.iter().zip(b).map(|(a, b)| a - b).collect();
    norm(&residual) / (norm(&row_sum) * norm(x) + norm(b))
}

/// The factorisation on the elimination tree's schedule (`crate::supernodal`) is faer's
/// within round-off: on a 2-D grid ordered by nested dissection (independent subtrees
/// under the top separators) with 120 constraint rows, whose dense block takes the updates
/// split over its columns, both factors solve the saddle-point system to a backward error
/// near the unit round-off, and their values differ by a few units of it in relative
/// norm (the update products are formed in another order). Its values are the same bits
/// on one, two or three threads.
#[test]
fn the_tree_scheduled_factor_is_faers_within_round_off_and_the_same_on_any_threads() {
    let (n, col_ptr, row_idx, values, y, sym) = grid_saddle();
    let lay = &sym.layout;
    let st = crate::la::supernodal::Structure {
        begin: &lay.begin,
        row_ptr: &lay.row_ptr,
        rows: &lay.rows,
        val_ptr: &lay.val_ptr,
    };
    let (subtrees, top, widest) = crate::la::supernodal::schedule_shape(&st);
    assert!(
        subtrees >= 4 && top >= 2,
        "{subtrees} subtrees, {top} top supernodes"
    );
    assert!(
        widest >= crate::la::supernodal::SPLIT_COLUMNS,
        "widest top {widest}"
    );
    let root_start = lay.begin[lay.begin.len() - 2];
    assert!(
        root_start < sym.n && *lay.begin.last().unwrap() == sym.n + sym.m,
        "a root holding separator columns before the constraint block"
    );
    let pool = |k| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(k)
            .build()
            .unwrap()
    };
    let factor = |k: usize, tree: bool| -> Vec<f64> {
        let f = pool(k)
            .install(|| sym.factorise_using(&values, &y, None, tree))
            .unwrap();
        f.values().to_vec()
    };
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
    let (faer, tree) = (factor(1, false), factor(1, true));
    assert!(faer.iter().any(|&x| x != 0.0));
    for k in [2, 3] {
        assert!(
            bits(&factor(k, true)) == bits(&tree),
            "{k} threads: not 1 thread's bits"
        );
    }
    let (norm2, diff2) = faer.iter().zip(&tree).fold((0.0, 0.0), |(a, d), (x, y)| {
        (a + x * x, d + (x - y) * (x - y))
    });
    let relative = (diff2 / norm2).sqrt();
    // Measured: 1.5e-17, where perturbing every value by up to 3e-10 gives a backward
    // error of 2e-11.
    assert!(
        relative <= 1e-16,
        "factors differ by {relative:e} in relative norm"
    );
    let size = n + y.len();
    let b: Vec<f64> = (0..size)
        .map(|i| ((i * 7919) % 1000) as f64 * 1e-3 - 0.5)
        .collect();
    for (name, l) in [("faer's", &faer), ("the tree-scheduled", &tree)] {
        let x = saddle_solve(lay, l, &b);
        let eta = saddle_backward_error((n, &col_ptr, &row_idx, &values), &y, &x, &b);
        // Measured: 5.0e-17 for either.
        assert!(eta <= 2e-16, "{name} factor: backward error {eta:e}");
    }
}

/// A zero pivot in one of the subtrees is an error naming the column where faer's loop
/// names it: one DOF of the grid cut loose with a zero diagonal.
#[test]
fn a_zero_pivot_is_reported_by_either_loop_at_the_same_column() {
    let (n, col_ptr, row_idx, mut values, y, sym) = grid_saddle();
    let loose = 1234;
    assert!(y.iter().flatten().all(|&(r, _)| r != loose));
    for c in 0..n {
        for p in col_ptr[c]..col_ptr[c + 1] {
            if c == loose || row_idx[p] == loose {
                values[p] = 0.0;
            }
        }
    }
    let pivot = |tree: bool| match sym.factorise_using(&values, &y, None, tree) {
        Err(FactorError::NotPositiveDefinite { pivot, n: order }) => {
            assert_eq!(order, n);
            pivot
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a zero pivot factorised"),
    };
    let at = pivot(false);
    assert_eq!(sym.layout.fwd[at], loose, "faer names the loose DOF");
    assert_eq!(pivot(true), at);
}

/// Columns swept together, interleaved (two, four or eight at a time, with a lane left
/// over), give each the bits of its own sweep on a grid's saddle factor: among them a zero
/// column, a column of negative zeros (whose entries the forward sweep must leave as
/// they are, as the one-column sweep skips them) and columns zero in most supernodes.
#[test]
fn interleaved_columns_give_the_bits_of_one_column_at_a_time() {
    let (n, _, _, values, y, sym) = grid_saddle();
    let f = sym.factorise(&values, &y).unwrap();
    let size = n + y.len();
    let vals = f.values();
    let nodes = f.leading_nodes(&vals);
    // Nine columns: dense, zero, negative zeros, sparse (a few entries), and more dense.
    let column = |k: usize| -> Vec<f64> {
        (0..size)
            .map(|i| match k {
                _ if i >= n => 0.0,
                1 => 0.0,
                2 => -0.0,
                3 if i % 97 != 5 => 0.0,
                4 if i % 2 == 0 => -0.0,
                _ => ((i * 7919 + k * 104_729) % 1000) as f64 * 1e-3 - 0.5,
            })
            .collect()
    };
    let alone: Vec<Vec<f64>> = (0..9)
        .map(|k| {
            let mut x = column(k);
            sweep_leading_body(&nodes, &mut x, size);
            x
        })
        .collect();
    assert!(
        alone[2].iter().any(|v| v.to_bits() == (-0.0f64).to_bits()),
        "a column of negative zeros keeps some"
    );
    // The interleaved body itself, and `sweep_columns` (groups of eight and fewer).
    for set in ["lanes", "columns"] {
        for ncols in 1..=9 {
            let mut x: Vec<f64> = (0..ncols).flat_map(column).collect();
            if set == "lanes" {
                for g in x.chunks_mut(8 * size) {
                    let k = g.len() / size;
                    let mut lanes = vec![[0.0; 8]; size];
                    for (j, c) in g.chunks_exact(size).enumerate() {
                        for (xi, v) in lanes.iter_mut().zip(c) {
                            xi[j] = *v;
                        }
                    }
                    sweep_leading_lanes_body(&nodes, &mut lanes);
                    for (j, c) in g.chunks_exact_mut(size).enumerate().take(k) {
                        for (xi, v) in lanes.iter().zip(c) {
                            *v = xi[j];
                        }
                    }
                }
            } else {
                sweep_columns(&nodes, &mut x, size);
            }
            for (k, got) in x.chunks_exact(size).enumerate() {
                assert!(
                    got.iter()
                        .zip(&alone[k])
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{set}: column {k} of {ncols} swept together differs from its own sweep"
                );
            }
        }
    }
}

/// The sweeps solve the system to round-off on a 2-D grid whose supernodes have pattern rows
/// enough for the four-way sums.
#[test]
fn the_sweeps_solve_the_system() {
    let side = 24;
    let n = side * side;
    let (mut col_ptr, mut row_idx, mut values) = (vec![0], Vec::new(), Vec::new());
    for j in 0..n {
        let (r, c) = (j / side, j % side);
        if r > 0 {
            row_idx.push(j - side);
            values.push(-1.0);
        }
        if c > 0 {
            row_idx.push(j - 1);
            values.push(-1.0 - 0.01 * (j % 7) as f64);
        }
        row_idx.push(j);
        values.push(4.5);
        col_ptr.push(row_idx.len());
    }
    let y = vec![vec![(3, 1.0), (40, -1.0)], vec![(n - 1, 1.0)]];
    let sym = SaddleSymbolic::analyse(n, &col_ptr, &row_idx, &y).unwrap();
    let f = sym.factorise(&values, &y).unwrap();
    let size = n + y.len();
    let b: Vec<f64> = (0..3 * size)
        .map(|i| {
            if i % size < n {
                ((i * 7919) % 1000) as f64 * 1e-3 - 0.5
            } else {
                0.0
            }
        })
        .collect();
    let vals = f.values();
    let nodes = f.leading_nodes(&vals);
    assert!(
        nodes.iter().any(|(_, _, kp, _)| *kp >= 8),
        "some pattern long enough for the vector loops"
    );
    let mut base = b.clone();
    sweep_leading_body(&nodes, &mut base, size);
    // The solution solves the (permuted) system: K̂ x = b for the first column.
    let fwd = &f.layout.fwd;
    let mut x = vec![0.0; n];
    let mut rhs = vec![0.0; n];
    for i in 0..n {
        x[fwd[i]] = base[i];
        rhs[fwd[i]] = b[i];
    }
    for j in 0..n {
        for k in col_ptr[j]..col_ptr[j + 1] {
            let i = row_idx[k];
            rhs[j] -= values[k] * x[i];
            if i != j {
                rhs[i] -= values[k] * x[j];
            }
        }
    }
    assert!(rhs.iter().all(|r| r.abs() < 1e-12), "residual");
}
