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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{MatMut, Par};

/// A symmetric matrix's lower triangle in the factor's (permuted) numbering, as the
/// factorisation reads it: in parts, each in compressed columns of its own; a column's entries
/// are those of all the parts.
pub struct LowerCsc {
    parts: Vec<LowerPart>,
}

/// One part of a [`LowerCsc`]: `col_ptr` has the matrix's order plus one pointers.
struct LowerPart {
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
}

impl LowerCsc {
    /// The lower triangle of `P A Pᵀ` from the upper triangle of `A` in compressed columns
    /// (`col_ptr`, `row_idx`, the value of entry `p` given by `value(p)`; entries below the
    /// diagonal are ignored), where `fwd[new] = old`. One part per range of `A`'s columns
    /// (about equal numbers of entries), made on rayon's threads; the factorisation adds each
    /// entry to a value of its own, so their order does not matter.
    pub fn permuted(
        col_ptr: &[usize],
        row_idx: &[usize],
        value: impl Fn(usize) -> f64 + Sync,
        fwd: &[usize],
    ) -> Self {
        use rayon::prelude::*;
        const PARTS: usize = 4;
        let size = fwd.len();
        let mut inv = vec![0u32; size];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new as u32;
        }
        // (column, row) of the entry (r, c) of the upper triangle, r ≤ c.
        let place = |r: usize, c: usize| {
            let (pr, pc) = (inv[r], inv[c]);
            if pr >= pc { (pc, pr) } else { (pr, pc) }
        };
        // Source columns in parts of about equal numbers of entries.
        let nnz_in = col_ptr[size];
        let bounds: Vec<usize> = (0..=PARTS)
            .map(|t| {
                col_ptr[..=size]
                    .partition_point(|&p| p < t * nnz_in / PARTS)
                    .min(size)
            })
            .collect();
        let parts = bounds
            .par_windows(2)
            .map(|w| {
                // Entries per destination column, then their offsets: `ptr[col]` is where
                // the next entry of `col` goes, the end of the column once all are placed.
                let mut ptr = vec![0u32; size + 1];
                for c in w[0]..w[1] {
                    for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                        if r <= c {
                            ptr[place(r, c).0 as usize + 1] += 1;
                        }
                    }
                }
                for j in 0..size {
                    ptr[j + 1] = ptr[j]
                        .checked_add(ptr[j + 1])
                        .expect("fewer than 2³² entries in a part");
                }
                let nnz = ptr[size] as usize;
                let (mut rows, mut values) = (vec![0u32; nnz], vec![0.0; nnz]);
                for c in w[0]..w[1] {
                    for p in col_ptr[c]..col_ptr[c + 1] {
                        let r = row_idx[p];
                        if r <= c {
                            let (col, row) = place(r, c);
                            let q = &mut ptr[col as usize];
                            rows[*q as usize] = row;
                            values[*q as usize] = value(p);
                            *q += 1;
                        }
                    }
                }
                // Each pointer now holds its column's end: shifted back to the starts.
                ptr.copy_within(0..size, 1);
                ptr[0] = 0;
                LowerPart {
                    col_ptr: ptr,
                    row_idx: rows,
                    values,
                }
            })
            .collect();
        LowerCsc { parts }
    }
}

/// The supernodal structure the factorisation needs: supernode `s` has the columns
/// `begin[s]..begin[s + 1]`, the off-diagonal rows `rows[row_ptr[s]..row_ptr[s + 1]]`
/// (ascending) and its values at `val_ptr[s]..` (column-major, its own rows then the others).
pub struct Structure<'a> {
    pub begin: &'a [usize],
    pub row_ptr: &'a [usize],
    pub rows: &'a [usize],
    pub val_ptr: &'a [usize],
}

impl Structure<'_> {
    /// Panics unless the supernodes tile the columns in order, each pattern is ascending and
    /// below its supernode, and each supernode's values have its shape, one after the other.
    fn check(&self) {
        let nsup = self.n_supernodes();
        assert!(self.row_ptr.len() == nsup + 1 && self.val_ptr.len() == nsup + 1);
        assert!(self.begin.first() == Some(&0) && self.val_ptr.first() == Some(&0));
        for s in 0..nsup {
            assert!(self.begin[s] < self.begin[s + 1], "supernode {s} is empty");
            let p = self.pattern(s);
            assert!(
                p.windows(2).all(|w| w[0] < w[1])
                    && p.first().is_none_or(|&r| r >= self.begin[s + 1]),
                "supernode {s}'s rows are not ascending below it"
            );
            assert!(
                p.last().is_none_or(|&r| r < *self.begin.last().unwrap()),
                "supernode {s} has a row outside the matrix"
            );
            let n = self.ncols(s);
            assert_eq!(
                self.val_ptr[s + 1] - self.val_ptr[s],
                n * (n + p.len()),
                "supernode {s}'s values"
            );
        }
    }

    fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    fn pattern(&self, s: usize) -> &[usize] {
        &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    fn ncols(&self, s: usize) -> usize {
        self.begin[s + 1] - self.begin[s]
    }
}

/// The elimination tree's schedule: the descendants that update each supernode, the
/// independent subtrees and the supernodes above them.
struct Schedule {
    /// Per supernode, the supernodes whose rows reach into its columns (ascending).
    desc_ptr: Vec<usize>,
    desc: Vec<u32>,
    /// Disjoint subtrees (their supernodes ascending), the largest first.
    subtrees: Vec<Vec<usize>>,
    /// Per supernode in a subtree, its place in the subtree's list.
    slot: Vec<u32>,
    /// The supernodes in no subtree, ascending.
    top: Vec<usize>,
}

/// Subtrees are split until none has more than this share of the tree's work (a fixed share,
/// so that the schedule, like the values, does not depend on the number of threads).
const SPLIT_SHARE: f64 = 1.0 / 16.0;

/// A top supernode's updates are split over its columns from this many columns.
pub const SPLIT_COLUMNS: usize = 32;

/// A split top supernode's updates are applied in this many ranges of its columns: a fixed
/// number, so that every update's shape, and with it the order of the sums in faer's product,
/// does not depend on the number of threads.
const SPLIT_PARTS: usize = 8;

impl Schedule {
    fn of(st: &Structure) -> Schedule {
        let nsup = st.n_supernodes();
        let size = *st.begin.last().unwrap_or(&0);
        let mut sn_of = vec![0u32; size];
        for s in 0..nsup {
            sn_of[st.begin[s]..st.begin[s + 1]].fill(s as u32);
        }
        // Descendants per supernode, by counting (d ascending, so each list is ascending).
        let targets = |d: usize, f: &mut dyn FnMut(usize)| {
            let mut last = u32::MAX;
            for &r in st.pattern(d) {
                let s = sn_of[r];
                if s != last {
                    f(s as usize);
                    last = s;
                }
            }
        };
        let mut desc_ptr = vec![0usize; nsup + 1];
        for d in 0..nsup {
            targets(d, &mut |s| desc_ptr[s + 1] += 1);
        }
        for s in 0..nsup {
            desc_ptr[s + 1] += desc_ptr[s];
        }
        let mut next = desc_ptr[..nsup].to_vec();
        let mut desc = vec![0u32; desc_ptr[nsup]];
        for d in 0..nsup {
            targets(d, &mut |s| {
                desc[next[s]] = d as u32;
                next[s] += 1;
            });
        }
        // The tree (a supernode's parent holds its first off-diagonal row) and its work.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); nsup];
        let mut roots = Vec::new();
        let mut work = vec![0.0f64; nsup];
        for s in 0..nsup {
            let (w, p) = (st.ncols(s) as f64, st.pattern(s).len() as f64);
            work[s] += w * w * w / 3.0 + w * w * p + w * p * p + 1.0;
            match st.pattern(s).first() {
                Some(&r) => {
                    let parent = sn_of[r] as usize;
                    work[parent] += work[s];
                    children[parent].push(s);
                }
                None => roots.push(s),
            }
        }
        let total: f64 = roots.iter().map(|&s| work[s]).sum();
        // Split the largest subtree until every one is at most a share of the whole.
        let mut open: Vec<usize> = roots;
        let mut top = Vec::new();
        while let Some((i, &s)) = open
            .iter()
            .enumerate()
            .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]).then(b.1.cmp(a.1)))
            .filter(|(_, s)| work[**s] > SPLIT_SHARE * total)
        {
            open.swap_remove(i);
            top.push(s);
            open.extend_from_slice(&children[s]);
        }
        open.sort_by(|&a, &b| work[b].total_cmp(&work[a]).then(a.cmp(&b)));
        let subtrees: Vec<Vec<usize>> = open
            .iter()
            .map(|&root| {
                let mut nodes = Vec::new();
                let mut stack = vec![root];
                while let Some(s) = stack.pop() {
                    nodes.push(s);
                    stack.extend_from_slice(&children[s]);
                }
                nodes.sort_unstable();
                nodes
            })
            .collect();
        top.sort_unstable();
        // Each subtree holds the descendants of its supernodes (its task reads no other).
        let mut tree_of = vec![usize::MAX; nsup];
        let mut slot = vec![u32::MAX; nsup];
        for (t, nodes) in subtrees.iter().enumerate() {
            for (i, &s) in nodes.iter().enumerate() {
                tree_of[s] = t;
                slot[s] = i as u32;
            }
        }
        for (t, nodes) in subtrees.iter().enumerate() {
            for &s in nodes {
                let d = &desc[desc_ptr[s]..desc_ptr[s + 1]];
                assert!(
                    d.iter().all(|&d| tree_of[d as usize] == t),
                    "supernode {s}'s descendants are not in its subtree"
                );
            }
        }
        Schedule {
            desc_ptr,
            desc,
            subtrees,
            slot,
            top,
        }
    }

    fn descendants(&self, s: usize) -> &[u32] {
        &self.desc[self.desc_ptr[s]..self.desc_ptr[s + 1]]
    }
}

/// The shape of the schedule of `st` (for tests): the number of subtrees, the number of top
/// supernodes and the widest top supernode's columns.
#[cfg(test)]
pub(crate) fn schedule_shape(st: &Structure) -> (usize, usize, usize) {
    let sc = Schedule::of(st);
    let widest = sc.top.iter().map(|&s| st.ncols(s)).max().unwrap_or(0);
    (sc.subtrees.len(), sc.top.len(), widest)
}

/// The values of the finished supernodes that the updates of a supernode read.
enum Finished<'a> {
    /// A subtree's task: the values of its supernodes before the current one (`nodes`, in
    /// ascending order), supernode `d`'s at `slot[d]`.
    Subtree {
        nodes: &'a [usize],
        slot: &'a [u32],
        values: &'a [&'a mut [f64]],
    },
    /// The top supernodes: all the values before the current supernode's.
    Prefix {
        val_ptr: &'a [usize],
        values: &'a [f64],
    },
}

impl Finished<'_> {
    /// Supernode `d`'s values (panics unless `d` is among the finished ones).
    fn get(&self, d: usize) -> &[f64] {
        match self {
            Finished::Subtree {
                nodes,
                slot,
                values,
            } => {
                let i = slot[d] as usize;
                assert!(nodes[i] == d, "supernode {d} is not in the subtree");
                &values[i][..]
            }
            Finished::Prefix { val_ptr, values } => &values[val_ptr[d]..val_ptr[d + 1]],
        }
    }
}

/// One thread's working arrays: the local row of each row of the supernode being factorised,
/// the scratch of its updates and the dense factorisation's scratch.
struct Work {
    local: Vec<usize>,
    upd: Scratch,
    mem: MemBuffer,
}

impl Work {
    fn new(size: usize, limits: Limits, par: Par) -> Work {
        let req = faer::linalg::cholesky::ldlt::factor::cholesky_in_place_scratch::<f64>(
            limits.cols,
            par,
            Default::default(),
        );
        Work {
            local: vec![usize::MAX; size],
            upd: Scratch::new(limits),
            mem: MemBuffer::new(req),
        }
    }
}

/// The sizes of the working arrays: the columns of the largest supernode, and of the largest
/// with rows below it (a descendant), and the largest pattern (rows below a supernode).
#[derive(Clone, Copy)]
struct Limits {
    cols: usize,
    desc_cols: usize,
    rows: usize,
}

/// An update's product is formed in blocks of at most `UPDATE_ROWS × UPDATE_COLS` (256 KiB,
/// which the scatter reads back from the cache it was written to).
const UPDATE_COLS: usize = 128;
const UPDATE_ROWS: usize = 256;

/// The scratch of one update (sized once, from [`Limits`]): the local rows and columns of `s`
/// that it writes, `L_d,cols D_d` for one block of columns and one block of the product.
struct Scratch {
    row_idx: Vec<usize>,
    col_idx: Vec<usize>,
    scaled: Vec<f64>,
    prod: Vec<f64>,
}

impl Scratch {
    fn new(limits: Limits) -> Scratch {
        let cols = UPDATE_COLS.min(limits.rows);
        Scratch {
            row_idx: Vec::with_capacity(limits.rows),
            col_idx: Vec::with_capacity(limits.rows),
            scaled: vec![0.0; limits.desc_cols * cols],
            prod: vec![0.0; UPDATE_ROWS.min(limits.rows) * cols],
        }
    }
}

/// One value per rayon thread, made on its first use there.
struct PerThread<T>(Vec<std::sync::Mutex<Option<T>>>);

impl<T> PerThread<T> {
    fn new() -> Self {
        PerThread(
            (0..rayon::current_num_threads().max(1))
                .map(|_| std::sync::Mutex::new(None))
                .collect(),
        )
    }

    /// `f` of this thread's value (made by `make` on first use); of a fresh one should a task
    /// already hold it (a task here calls nothing that lets rayon start another on its
    /// thread, so this is not expected).
    fn with<R>(&self, make: impl FnOnce() -> T, f: impl FnOnce(&mut T) -> R) -> R {
        use std::sync::TryLockError;
        let i = rayon::current_thread_index().unwrap_or(0) % self.0.len();
        match self.0[i].try_lock() {
            Ok(mut held) => f(held.get_or_insert_with(make)),
            Err(TryLockError::Poisoned(e)) => f(e.into_inner().get_or_insert_with(make)),
            Err(TryLockError::WouldBlock) => f(&mut make()),
        }
    }
}

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

/// Splits the `ncols` columns of a supernode with `nrows` rows into at most `parts` ranges of
/// about equal lower-triangular area (column `j` has `nrows − j` values to update).
fn column_chunks(ncols: usize, nrows: usize, parts: usize) -> Vec<(usize, usize)> {
    let area = |j: usize| (nrows - j) as f64;
    let total: f64 = (0..ncols).map(area).sum();
    let mut out = Vec::with_capacity(parts);
    let (mut start, mut acc) = (0, 0.0);
    for j in 0..ncols {
        acc += area(j);
        if acc >= total * (out.len() + 1) as f64 / parts as f64 && j + 1 < ncols {
            out.push((start, j + 1));
            start = j + 1;
        }
    }
    out.push((start, ncols));
    out
}

/// The update of supernode `s` by its descendant `d`, restricted to `s`'s columns `c0..c1`:
///
/// ```text
/// L_s[r, c] −= Σ_k L_d[r, k] D_d[k] L_d[c, k]     r ≥ c, both rows of d's pattern,
///                                               c among s's columns c0..c1
/// ```
///
/// (`r`, `c` mapped to `s`'s local rows and columns). The product is formed by faer's matrix
/// product, sequentially, in blocks of [`UPDATE_COLS`] columns `c` (with the rows `r` from the
/// block's first column down, in blocks of [`UPDATE_ROWS`]) into `scratch`, and each block is
/// subtracted from `L_s` at once (its lower part). The blocks depend on the update's shape
/// alone, so an element's value does not depend on the thread that computes it.
///
/// `ld` holds `d`'s values, `ls` those of `s`'s columns `c0..c1`.
#[allow(clippy::too_many_arguments)]
fn update(
    st: &Structure,
    ld: &[f64],
    ls: &mut [f64],
    s: usize,
    d: usize,
    local: &[usize],
    scratch: &mut Scratch,
    (c0, c1): (usize, usize),
) {
    use faer::linalg::matmul::matmul;
    use faer::{Accum, MatMut, MatRef};
    let (s_start, s_end) = (st.begin[s], st.begin[s + 1]);
    let s_nrows = (s_end - s_start) + st.pattern(s).len();
    let d_pattern = st.pattern(d);
    let d_ncols = st.ncols(d);
    let d_nrows = d_ncols + d_pattern.len();
    // The rows of `d` in `s`'s columns `c0..c1` and below them.
    let lo = d_pattern.partition_point(|&r| r < s_start + c0);
    let mid = d_pattern[lo..].partition_point(|&r| r < s_start + c1);
    if mid == 0 {
        return;
    }
    let Scratch {
        row_idx,
        col_idx,
        scaled,
        prod,
    } = scratch;
    row_idx.clear();
    row_idx.extend(
        d_pattern[lo..]
            .iter()
            .map(|&r| if r < s_end { r - s_start } else { local[r] }),
    );
    col_idx.clear();
    col_idx.extend(d_pattern[lo..lo + mid].iter().map(|&r| r - s_start - c0));
    // Every row inside `s`'s block (a row of `d` below `s` that is not in `s`'s pattern would
    // be written outside it).
    assert!(
        row_idx.iter().all(|&r| r < s_nrows),
        "supernode {d}'s rows are not in supernode {s}'s pattern"
    );
    assert_eq!(ld.len(), d_nrows * d_ncols);
    assert_eq!(ls.len(), (c1 - c0) * s_nrows);
    let nrows = d_pattern.len() - lo;
    // `L_d`'s rows from the first in `c0..c1` down (`nrows × d_ncols`, column stride
    // `d_nrows`), its column `k` starting at `first(k)`.
    let first = |k: usize| k * d_nrows + d_ncols + lo;
    let below =
        MatRef::from_column_major_slice_with_stride(&ld[first(0)..], nrows, d_ncols, d_nrows);
    for j0 in (0..mid).step_by(UPDATE_COLS) {
        let w = (mid - j0).min(UPDATE_COLS);
        // `L_d[j0..j0 + w, :] D_d` (`w × d_ncols`, column-major).
        let scaled = &mut scaled[..w * d_ncols];
        for (k, col) in scaled.chunks_exact_mut(w).enumerate() {
            let dk = ld[k * d_nrows + k];
            for (x, &v) in col.iter_mut().zip(&ld[first(k) + j0..][..w]) {
                *x = v * dk;
            }
        }
        let rhs = MatRef::from_column_major_slice(&*scaled, w, d_ncols).transpose();
        for i0 in (j0..nrows).step_by(UPDATE_ROWS) {
            let h = (nrows - i0).min(UPDATE_ROWS);
            let prod = &mut prod[..h * w];
            matmul(
                MatMut::from_column_major_slice_mut(&mut *prod, h, w),
                Accum::Replace,
                below.subrows(i0, h),
                rhs,
                1.0,
                Par::Seq,
            );
            // Column `j0 + j` takes the rows from its own down.
            for (j, p) in prod.chunks_exact(h).enumerate() {
                let from = (j0 + j).max(i0);
                let c = col_idx[j0 + j];
                let dst = &mut ls[c * s_nrows..(c + 1) * s_nrows];
                for (&r, &x) in row_idx[from..i0 + h].iter().zip(&p[from - i0..]) {
                    dst[r] -= x;
                }
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
        assert!(n - k > 2 * super::UPDATE_ROWS.max(super::UPDATE_COLS));
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
