//! The update of a supernode by its descendants: the finished values it reads, each thread's
//! scratch, and the product `L_d,rows D_d L_d,colsᵀ` subtracted at the local rows and columns.

use faer::Par;
use faer::dyn_stack::MemBuffer;

use super::structure::Structure;

/// The values of the finished supernodes that the updates of a supernode read.
pub(super) enum Finished<'a> {
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
    pub(super) fn get(&self, d: usize) -> &[f64] {
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
pub(super) struct Work {
    pub(super) local: Vec<usize>,
    pub(super) upd: Scratch,
    pub(super) mem: MemBuffer,
}

impl Work {
    pub(super) fn new(size: usize, limits: Limits, par: Par) -> Work {
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
pub(super) struct Limits {
    pub(super) cols: usize,
    pub(super) desc_cols: usize,
    pub(super) rows: usize,
}

/// An update's product is formed in blocks of at most `UPDATE_ROWS × UPDATE_COLS` (256 KiB,
/// which the scatter reads back from the cache it was written to).
pub(super) const UPDATE_COLS: usize = 128;
pub(super) const UPDATE_ROWS: usize = 256;

/// The scratch of one update (sized once, from [`Limits`]): the local rows and columns of `s`
/// that it writes, `L_d,cols D_d` for one block of columns and one block of the product.
pub(super) struct Scratch {
    pub(super) row_idx: Vec<usize>,
    pub(super) col_idx: Vec<usize>,
    pub(super) scaled: Vec<f64>,
    pub(super) prod: Vec<f64>,
}

impl Scratch {
    pub(super) fn new(limits: Limits) -> Scratch {
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
pub(super) struct PerThread<T>(Vec<std::sync::Mutex<Option<T>>>);

impl<T> PerThread<T> {
    pub(super) fn new() -> Self {
        PerThread(
            (0..rayon::current_num_threads().max(1))
                .map(|_| std::sync::Mutex::new(None))
                .collect(),
        )
    }

    /// `f` of this thread's value (made by `make` on first use); of a fresh one should a task
    /// already hold it (a task here calls nothing that lets rayon start another on its
    /// thread, so this is not expected).
    pub(super) fn with<R>(&self, make: impl FnOnce() -> T, f: impl FnOnce(&mut T) -> R) -> R {
        use std::sync::TryLockError;
        let i = rayon::current_thread_index().unwrap_or(0) % self.0.len();
        match self.0[i].try_lock() {
            Ok(mut held) => f(held.get_or_insert_with(make)),
            Err(TryLockError::Poisoned(e)) => f(e.into_inner().get_or_insert_with(make)),
            Err(TryLockError::WouldBlock) => f(&mut make()),
        }
    }
}

/// Splits the `ncols` columns of a supernode with `nrows` rows into at most `parts` ranges of
/// about equal lower-triangular area (column `j` has `nrows − j` values to update).
pub(super) fn column_chunks(ncols: usize, nrows: usize, parts: usize) -> Vec<(usize, usize)> {
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
pub(super) fn update(
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
