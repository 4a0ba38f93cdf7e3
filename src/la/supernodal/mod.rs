//! The numeric `L D Lᵀ` of a supernodal analysis (the saddle-point matrix of a contact model),
//! left-looking as faer's `factorize_supernodal_numeric_ldlt`, with faer's public dense
//! kernels, scheduled on rayon's threads by the elimination tree:
//!
//! * **independent subtrees** of the supernodal elimination tree (a nested-dissection
//!   ordering gives many) are factorised at the same time, each on one thread with sequential
//!   kernels;
//! * **the supernodes above them** (the top separators and the dense block of the constraint
//!   rows) are factorised in turn; the updates from their descendants are applied on all
//!   threads by splitting the supernode's columns, each element still receiving the
//!   descendants' updates one after the other in the same order; their dense `L D Lᵀ` and
//!   triangular solve use faer's parallel kernels.
//!
//! faer's own loop takes the supernodes one after the other and parallelises inside each
//! update: on the L5–L7 ladders most updates are small (supernodes of 2–7 columns), and the
//! synchronisation of each costs more than it gains (the 2-thread numeric factorisation at L5
//! is no faster than the 1-thread one, with ~180 000 futex calls at L7).
//!
//! The update of supernode `s` by a descendant `d` ([`update`]) is a dense product
//! `L_d,rows D_d L_d,colsᵀ` formed in a per-thread scratch block by `faer::linalg::matmul`
//! and subtracted from `L_s` at the local rows and columns of `d`'s pattern. The factor is
//! faer's within round-off: both solve the saddle-point system to a backward error near the
//! unit round-off (`la::saddle::tests::the_tree_scheduled_factor_is_faers_within_round_off_and_the_same_on_any_threads`).
//! Where the root holds the constraint block (a saddle-point matrix), it is factorised in two
//! stages (the top separator's columns, then the block, with `W` copied in between). The
//! values do not depend on the number of threads: the partition into subtrees and the
//! column ranges of the split updates are fixed by the tree alone, every update is a
//! sequential product of a shape fixed by the tree, and the dense kernels split their work
//! without changing any sum's order.

mod schedule;
mod structure;
mod update;

pub use schedule::SPLIT_COLUMNS;
use schedule::SPLIT_PARTS;
use schedule::Schedule;
#[cfg(test)]
pub(crate) use schedule::schedule_shape;
pub use structure::{LowerCsc, Structure};
use update::{Finished, Limits, PerThread, Scratch, Work, column_chunks, update};

use faer::dyn_stack::MemStack;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, Par};

/// The numeric factorisation of `a` (its lower triangle in the factor's numbering) into `l`
/// (zeros on entry, [`Structure::val_ptr`]'s last length): `Err(column)` at a zero pivot
/// (the first in the order the supernodes ran, which may differ from faer's when several
/// fail). `par` is the parallelism of the top supernodes' dense kernels; the
/// subtrees and the updates use all of rayon's threads. With `schur_from = Some(n)`, also
/// the Schur complement of the trailing columns `n..` (its lower triangle, negated:
/// `Y K̂⁻¹ Yᵀ` for the saddle-point matrix of `K̂` and `Y`) where they all lie in the last
/// supernode (the dense block of the constraint rows, as on every mesh of the ladder):
/// that block as its descendants left it, less the elimination of the supernode's own
/// columns before `n` (a rank update instead of the product `L_MM D_MM L_MMᵀ`), with the
/// wall time of that block (its updates, the elimination and its `L D Lᵀ`, in seconds).
pub fn factorise(
    st: &Structure,
    a: LowerCsc,
    l: &mut [f64],
    par: Par,
    schur_from: Option<usize>,
) -> Result<Option<(faer::Mat<f64>, f64)>, usize> {
    use rayon::prelude::*;
    let nsup = st.n_supernodes();
    let size = *st.begin.last().unwrap_or(&0);
    assert_eq!(l.len(), *st.val_ptr.last().unwrap_or(&0));
    assert!(a.parts.iter().all(|p| p.col_ptr.len() == size + 1));
    st.check();
    debug_assert!(l.iter().step_by(4096).all(|&x| x == 0.0), "zeros on entry");
    let schedule = Schedule::of(st);
    let limits = Limits {
        cols: (0..nsup).map(|s| st.ncols(s)).max().unwrap_or(0),
        desc_cols: (0..nsup)
            .filter(|&s| !st.pattern(s).is_empty())
            .map(|s| st.ncols(s))
            .max()
            .unwrap_or(0),
        rows: (0..nsup).map(|s| st.pattern(s).len()).max().unwrap_or(0),
    };
    // The Schur complement of the trailing columns `n..`, where they end the last
    // supernode (the root: the dense block of the constraint rows, with or without the top
    // separator's columns before them).
    let last = nsup.checked_sub(1);
    let mut schur = schur_from
        .zip(last)
        .filter(|(n, s)| *n < size && st.begin[*s] <= *n && st.pattern(*s).is_empty())
        .map(|(n, s)| Schur {
            s,
            kk: n - st.begin[s],
            w: None,
            seconds: 0.0,
        });
    // Every supernode's values apart, and each subtree's handed to its task (in the order of
    // its list): a task writes the values of its own supernodes and reads only theirs.
    let mut pieces: Vec<Option<&mut [f64]>> = Vec::with_capacity(nsup);
    let mut rest = &mut *l;
    for s in 0..nsup {
        let (piece, after) =
            std::mem::take(&mut rest).split_at_mut(st.val_ptr[s + 1] - st.val_ptr[s]);
        pieces.push(Some(piece));
        rest = after;
    }
    let tasks: Vec<(&[usize], Vec<&mut [f64]>)> = schedule
        .subtrees
        .iter()
        .map(|nodes| {
            let values = nodes
                .iter()
                .map(|&s| pieces[s].take().expect("in one subtree"));
            (&nodes[..], values.collect())
        })
        .collect();
    drop(pieces);
    // One set of working arrays per thread that runs a subtree (the row map alone is 8 bytes
    // per row), made on its first subtree.
    let works = PerThread::new();
    // The subtrees, each on one thread; the first failure by supernode is the one reported.
    let failed = tasks
        .into_par_iter()
        .map(|(nodes, mut values)| {
            works.with(
                || Work::new(size, limits, Par::Seq),
                |work| {
                    for (i, &s) in nodes.iter().enumerate() {
                        // The subtree holds `s`'s descendants (`Schedule::of`), earlier in it.
                        let (done, rest) = values.split_at_mut(i);
                        let finished = Finished::Subtree {
                            nodes,
                            slot: &schedule.slot,
                            values: done,
                        };
                        supernode(
                            st,
                            Some(&a),
                            &schedule,
                            &finished,
                            rest[0],
                            s,
                            work,
                            Par::Seq,
                            None,
                            None,
                        )?;
                    }
                    Ok(())
                },
            )
        })
        .filter_map(Result::err)
        .min();
    if let Some(column) = failed {
        return Err(column);
    }
    drop(works);
    crate::trace::mark(format_args!(
        "factor: {} subtrees, then {} top supernodes",
        schedule.subtrees.len(),
        schedule.top.len()
    ));
    let mut work = Work::new(size, limits, par);
    let pool = PerThread::new();
    let mut a = Some(a);
    for &s in &schedule.top {
        // Every descendant of `s` comes before it (its rows are below its columns).
        let (done, rest) = l.split_at_mut(st.val_ptr[s]);
        let ls = &mut rest[..st.val_ptr[s + 1] - st.val_ptr[s]];
        if schur.as_ref().is_some_and(|w| w.s == s) {
            // The root, last: its columns of `a` now, and `a` freed before its dense block
            // is worked on (the peak memory of the run at L7).
            let root = a.take().expect("the root is the last supernode");
            scatter(st, &root, s, &work.local, ls);
        }
        let finished = Finished::Prefix {
            val_ptr: st.val_ptr,
            values: done,
        };
        supernode(
            st,
            a.as_ref(),
            &schedule,
            &finished,
            ls,
            s,
            &mut work,
            par,
            Some((&pool, limits)),
            schur.as_mut().filter(|w| w.s == s),
        )?;
    }
    Ok(schur.and_then(|w| w.w.map(|m| (m, w.seconds))))
}

/// Factorises supernode `s` into its values `ls`: its columns of `a`, the updates of its
/// descendants (`finished`) in ascending order, its dense `L D Lᵀ`, the solve of its
/// off-diagonal rows and their scaling by `D⁻¹`. With `split` (scratch for each thread), the
/// updates are applied on rayon's threads, each on a range of the columns.
#[allow(clippy::too_many_arguments)]
fn supernode(
    st: &Structure,
    a: Option<&LowerCsc>,
    schedule: &Schedule,
    finished: &Finished,
    ls: &mut [f64],
    s: usize,
    work: &mut Work,
    par: Par,
    split: Option<(&PerThread<Scratch>, Limits)>,
    schur: Option<&mut Schur>,
) -> Result<(), usize> {
    let (s_start, s_end) = (st.begin[s], st.begin[s + 1]);
    let s_pattern = st.pattern(s);
    let s_ncols = s_end - s_start;
    let s_nrows = s_ncols + s_pattern.len();
    assert_eq!(ls.len(), s_nrows * s_ncols);
    for (i, &row) in s_pattern.iter().enumerate() {
        work.local[row] = i + s_ncols;
    }
    if let Some(a) = a {
        scatter(st, a, s, &work.local, ls);
    }
    let desc = schedule.descendants(s);
    // The descendants' updates of the columns `c0..c1` (their values `cols`).
    let columns =
        |(c0, c1): (usize, usize), cols: &mut [f64], local: &[usize], scratch: &mut Scratch| {
            for &d in desc {
                let d = d as usize;
                update(st, finished.get(d), cols, s, d, local, scratch, (c0, c1));
            }
        };
    // The updates of the columns `c0..c1`, with `split` on rayon's threads in ranges of
    // about equal area (each element still takes its updates in the same order).
    let updates = |(c0, c1): (usize, usize), ls: &mut [f64], work: &mut Work| {
        if c0 == c1 {
            return;
        }
        let cols = &mut ls[c0 * s_nrows..c1 * s_nrows];
        match split.filter(|_| c1 - c0 >= SPLIT_COLUMNS) {
            Some((pool, limits)) => {
                use rayon::prelude::*;
                let mut rest = cols;
                let parts: Vec<_> = column_chunks(c1 - c0, s_nrows - c0, SPLIT_PARTS)
                    .into_iter()
                    .map(|(a, b)| {
                        let (part, after) =
                            std::mem::take(&mut rest).split_at_mut((b - a) * s_nrows);
                        rest = after;
                        ((a + c0, b + c0), part)
                    })
                    .collect();
                let local = &work.local;
                parts.into_par_iter().for_each(|(range, part)| {
                    pool.with(
                        || Scratch::new(limits),
                        |scratch| columns(range, part, local, scratch),
                    )
                });
            }
            None => columns((c0, c1), cols, &work.local, &mut work.upd),
        }
    };
    let factored = match schur {
        None => {
            updates((0, s_ncols), ls, work);
            ldlt(
                block(ls, s_nrows, s_ncols).split_at_row_mut(s_ncols).0,
                par,
                MemStack::new(&mut work.mem),
            )
        }
        Some(w) => {
            // The root: its separator columns first (they need only their own updates), then
            // the constraint block, timed apart.
            updates((0, w.kk), ls, work);
            w.factorise_leading(
                block(ls, s_nrows, s_ncols),
                par,
                MemStack::new(&mut work.mem),
            )
            .and_then(|()| {
                let t = std::time::Instant::now();
                updates((w.kk, s_ncols), ls, work);
                let r = w.factorise_block(
                    block(ls, s_nrows, s_ncols),
                    par,
                    MemStack::new(&mut work.mem),
                );
                w.seconds = t.elapsed().as_secs_f64();
                r
            })
        }
    };
    if let Err(index) = factored {
        for &row in s_pattern {
            work.local[row] = usize::MAX;
        }
        return Err(index + s_start);
    }
    let (mut top, mut bot) = block(ls, s_nrows, s_ncols).split_at_row_mut(s_ncols);
    for j in 0..s_ncols {
        for i in 0..j {
            top[(i, j)] = 0.0;
        }
    }
    off_diagonal(top.rb(), bot.rb_mut(), par);
    for &row in s_pattern {
        work.local[row] = usize::MAX;
    }
    Ok(())
}

/// A supernode's values `ls` as its `nrows × ncols` column-major block.
fn block(ls: &mut [f64], nrows: usize, ncols: usize) -> MatMut<'_, f64> {
    MatMut::from_column_major_slice_mut(ls, nrows, ncols)
}

/// faer's dense `L D Lᵀ` of `a` in place: `Err(column)` at a zero pivot.
fn ldlt(a: MatMut<'_, f64>, par: Par, stack: &mut MemStack) -> Result<(), usize> {
    use faer::linalg::cholesky::ldlt::factor::{LdltError, cholesky_in_place};
    match cholesky_in_place(a, Default::default(), par, stack, Default::default()) {
        Err(LdltError::ZeroPivot { index }) => Err(index),
        Ok(_) => Ok(()),
    }
}

/// The off-diagonal rows `bot` of a supernode whose diagonal block `top` is factorised (unit
/// lower `L` with `D` on its diagonal, zeros above it): `bot L⁻ᵀ D⁻¹`.
fn off_diagonal(top: faer::MatRef<'_, f64>, mut bot: MatMut<'_, f64>, par: Par) {
    faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
        top,
        bot.rb_mut().transpose_mut(),
        par,
    );
    for j in 0..top.ncols() {
        let d = top[(j, j)].recip();
        for i in 0..bot.nrows() {
            bot[(i, j)] *= d;
        }
    }
}

/// The Schur complement `S` of the trailing columns `n..` of the matrix, taken from the last
/// supernode `s` (the root, without off-diagonal rows), which holds `kk` columns before `n`:
/// `w = −S` (lower triangle), for the saddle-point matrix `W = Y K̂⁻¹ Yᵀ`.
struct Schur {
    s: usize,
    kk: usize,
    w: Option<faer::Mat<f64>>,
    /// Wall time of the constraint block: the updates of its columns, the elimination of the
    /// leading columns from it and its `L D Lᵀ`.
    seconds: f64,
}

impl Schur {
    /// The first stage of the root's dense `L D Lᵀ`, once the updates of its `kk` leading
    /// columns (the top separator's) are in: those columns factorised, with the rows of the
    /// constraint block below them (`L_MK`).
    fn factorise_leading(
        &mut self,
        a: MatMut<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), usize> {
        let kk = self.kk;
        if kk == 0 {
            return Ok(());
        }
        // The solve reads the unit lower triangle only; `supernode` clears the upper one.
        let (mut a_kk, _, a_mk, _) = a.split_at_mut(kk, kk);
        ldlt(a_kk.rb_mut(), par, stack)?;
        off_diagonal(a_kk.rb(), a_mk, par);
        Ok(())
    }

    /// The second stage, once the updates of the constraint columns are in: the leading
    /// columns eliminated from the constraint block (`A_MM −= L_MK D_K L_MKᵀ`, one rank update
    /// on the lower triangle), `w = −A_MM` copied, and the block factorised. The same factor
    /// as one `L D Lᵀ` of the whole root within round-off, with the rank update done once
    /// instead of again on a copy of the block taken before it.
    fn factorise_block(
        &mut self,
        a: MatMut<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), usize> {
        use faer::linalg::matmul::triangular::{BlockStructure, matmul};
        let kk = self.kk;
        let (a_kk, _, a_mk, mut a_mm) = a.split_at_mut(kk, kk);
        if kk > 0 {
            let m = a_mk.nrows();
            let (l_kk, l_mk) = (a_kk.rb(), a_mk.rb());
            // B = L_MK D_K: A_MM −= B L_MKᵀ.
            let b = crate::la::par::mat_filled(m, kk, true, |k, col| {
                let d = l_kk[(k, k)];
                for (i, x) in col.iter_mut().enumerate() {
                    *x = l_mk[(i, k)] * d;
                }
            });
            matmul(
                a_mm.rb_mut(),
                BlockStructure::TriangularLower,
                faer::Accum::Add,
                b.as_ref(),
                BlockStructure::Rectangular,
                l_mk.transpose(),
                BlockStructure::Rectangular,
                -1.0,
                par,
            );
        }
        let m = a_mm.nrows();
        let view = a_mm.rb();
        self.w = Some(crate::la::par::mat_filled(m, m, true, |j, col| {
            for i in j..m {
                col[i] = -view[(i, j)];
            }
        }));
        ldlt(a_mm, par, stack).map_err(|i| i + kk)
    }
}

/// Adds the columns of `a` in supernode `s` to its values `ls` (`local`: the local row of each
/// of its off-diagonal rows).
fn scatter(st: &Structure, a: &LowerCsc, s: usize, local: &[usize], ls: &mut [f64]) {
    let (s_start, s_end) = (st.begin[s], st.begin[s + 1]);
    let s_nrows = (s_end - s_start) + st.pattern(s).len();
    for j in s_start..s_end {
        let col = (j - s_start) * s_nrows;
        for part in &a.parts {
            for p in part.col_ptr[j] as usize..part.col_ptr[j + 1] as usize {
                let i = part.row_idx[p] as usize;
                if i < j {
                    continue;
                }
                let ix = if i >= s_end { local[i] } else { i - s_start };
                assert!(ix < s_nrows, "an entry outside supernode {s}'s pattern");
                ls[col + ix] += part.values[p];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    /// A dense symmetric positive-definite matrix as two supernodes (5 columns, then 595
    /// whose updates are split): the update of the second by the first spans several blocks
    /// of columns and of rows; the factor reproduces the matrix to a backward error near the
    /// unit round-off, as faer's dense `L D Lᵀ` does, and is the same bits on one and two
    /// threads.
    #[test]
    fn a_dense_matrix_in_two_supernodes_gives_the_dense_factor() {
        use faer::Mat;
        let (n, k) = (600, 5);
        assert!(n - k > 2 * super::update::UPDATE_ROWS.max(super::update::UPDATE_COLS));
        let b = Mat::from_fn(n, 8, |i, j| {
            (((i * 37 + j * 101) % 61) as f64 - 30.0) / 30.0
        });
        let a = Mat::from_fn(n, n, |i, j| {
            (0..8).map(|t| b[(i, t)] * b[(j, t)]).sum::<f64>() + if i == j { 2.0 } else { 0.0 }
        });
        // The upper triangle in compressed columns.
        let col_ptr: Vec<usize> = (0..=n).map(|j| j * (j + 1) / 2).collect();
        let row_idx: Vec<usize> = (0..n).flat_map(|j| 0..=j).collect();
        let value = |p: usize| {
            let j = col_ptr.partition_point(|&q| q <= p) - 1;
            a[(row_idx[p], j)]
        };
        let fwd: Vec<usize> = (0..n).collect();
        let rows: Vec<usize> = (k..n).collect();
        let (begin, row_ptr) = ([0, k, n], [0, n - k, n - k]);
        let val_ptr = [0, k * n, k * n + (n - k) * (n - k)];
        let st = super::Structure {
            begin: &begin,
            row_ptr: &row_ptr,
            rows: &rows,
            val_ptr: &val_ptr,
        };
        let factor = |threads: usize| {
            let mut l = vec![0.0; val_ptr[2]];
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let lower = super::LowerCsc::permuted(&col_ptr, &row_idx, value, &fwd);
                    super::factorise(&st, lower, &mut l, faer::Par::Seq, None).unwrap()
                });
            l
        };
        let l = factor(1);
        let l2 = factor(2);
        assert!(l.iter().zip(&l2).all(|(x, y)| x.to_bits() == y.to_bits()));
        let mut dense = a.clone();
        super::ldlt(
            dense.as_mut(),
            faer::Par::Seq,
            faer::dyn_stack::MemStack::new(&mut faer::dyn_stack::MemBuffer::new(
                faer::linalg::cholesky::ldlt::factor::cholesky_in_place_scratch::<f64>(
                    n,
                    faer::Par::Seq,
                    Default::default(),
                ),
            )),
        )
        .unwrap();
        // Column `j` of the factor in the supernodal values, from its diagonal down.
        let ours = |j: usize| -> &[f64] {
            if j < k {
                &l[j * n + j..(j + 1) * n]
            } else {
                let m = n - k;
                &l[val_ptr[1] + (j - k) * m + (j - k)..val_ptr[1] + (j - k + 1) * m]
            }
        };
        let (mut diff2, mut norm2) = (0.0, 0.0);
        for j in 0..n {
            for (i, x) in (j..n).zip(ours(j)) {
                diff2 += (x - dense[(i, j)]).powi(2);
                norm2 += dense[(i, j)].powi(2);
            }
        }
        let relative = (diff2 / norm2).sqrt();
        // ‖A − L D Lᵀ‖_F / ‖A‖_F of a factor given by its columns.
        let residual = |col: &dyn Fn(usize) -> Vec<f64>| {
            let cols: Vec<Vec<f64>> = (0..n).map(col).collect();
            let (mut r2, mut a2) = (0.0, 0.0);
            for j in 0..n {
                for i in j..n {
                    let mut x = 0.0;
                    for t in 0..=j {
                        let (li, lj) = (cols[t][i - t], cols[t][j - t]);
                        let (li, lj) =
                            (if i == t { 1.0 } else { li }, if j == t { 1.0 } else { lj });
                        x += li * cols[t][0] * lj;
                    }
                    r2 += (a[(i, j)] - x).powi(2);
                    a2 += a[(i, j)].powi(2);
                }
            }
            (r2 / a2).sqrt()
        };
        let eta = residual(&|j| ours(j).to_vec());
        let eta_dense = residual(&|j| (j..n).map(|i| dense[(i, j)]).collect());
        // Measured: 7.0e-16 and 5.3e-16 for faer's dense factor; the factors 2.7e-15 apart
        // (the matrix's condition number is about 10³).
        assert!(
            eta <= 2e-15,
            "backward error {eta:e} (the dense factor's {eta_dense:e})"
        );
        assert!(relative <= 1e-14, "{relative:e} from the dense factor");
    }

    #[test]
    fn column_chunks_tile_the_columns() {
        for (ncols, nrows, parts) in [(1, 1, 8), (32, 40, 8), (1000, 4000, 8), (33, 33, 2)] {
            let c = super::column_chunks(ncols, nrows, parts);
            assert!(c.len() <= parts && !c.is_empty());
            assert_eq!(c[0].0, 0);
            assert_eq!(c.last().unwrap().1, ncols);
            assert!(c.windows(2).all(|w| w[0].1 == w[1].0 && w[0].0 < w[0].1));
        }
    }
}
