//! Arrays filled on rayon's threads, element access shared by tasks that touch disjoint
//! elements, and the parallelism of the factorisations.

/// The parallelism of the sparse numeric factorisations and of the product that forms the
/// Delassus operator: all of rayon's threads. Their results do not depend on the number of
/// threads (`tests/determinism.rs`), unlike some of faer's dense kernels, which the program
/// runs sequentially (faer's global parallelism, set by `Model::build_on`).
pub fn factor_parallelism() -> faer::Par {
    match rayon::current_num_threads() {
        0 | 1 => faer::Par::Seq,
        n => faer::Par::rayon(n),
    }
}

/// An `nrows × ncols` matrix whose column `j` is written by `fill(j, column)` over zeros, the
/// columns on rayon's threads with `parallel`, else on the calling thread. Fresh memory costs a
/// page fault per 4 KiB at its first write, which dominates filling it, and faer's `Mat::zeros`
/// and `Mat::from_fn` write on the calling thread alone (the Delassus operator's two m × m
/// arrays: 130 MB each at L7). Sequential where a rayon worker must not wait (a sweep's block
/// store).
pub fn mat_filled(
    nrows: usize,
    ncols: usize,
    parallel: bool,
    fill: impl Fn(usize, &mut [f64]) + Sync,
) -> faer::Mat<f64> {
    mat_filled_in(None, nrows, ncols, parallel, fill)
}

/// [`mat_filled`] in `spare` when it is given with those dimensions (an array made earlier,
/// its pages already in place: [`Spare`]), else in fresh memory. The same values.
pub fn mat_filled_in(
    spare: Option<faer::Mat<f64>>,
    nrows: usize,
    ncols: usize,
    parallel: bool,
    fill: impl Fn(usize, &mut [f64]) + Sync,
) -> faer::Mat<f64> {
    use rayon::prelude::*;
    let mut a = match spare {
        Some(a) if a.nrows() == nrows && a.ncols() == ncols && a.col_stride() >= 0 => a,
        _ => faer::Mat::<f64>::with_capacity(nrows, ncols),
    };
    let cols = SharedMat::of(&mut a);
    let one = |j: usize| {
        // SAFETY: column j lies within the capacity, and only this call touches it; its
        // elements are zeroed before the slice is made, so the slice reads initialised values.
        fill(j, unsafe { cols.zeroed_column(j, nrows) })
    };
    if parallel {
        (0..ncols).into_par_iter().with_min_len(32).for_each(one);
    } else {
        (0..ncols).for_each(one);
    }
    // SAFETY: within the capacity, and every element is written above.
    unsafe { a.set_dims(nrows, ncols) };
    a
}

/// Two `m × m` arrays for the Delassus operator `W` and its Cholesky factor `C`, made (their
/// pages faulted in) on a core that the symbolic analysis leaves idle, for the first numeric
/// factorisation on that analysis to fill instead of fresh memory: at L7 each is 130 MB, whose
/// first touch took 0.1–0.15 s of the factorisation and of the condensation.
#[derive(Clone, Default)]
pub struct Spare(pub(crate) std::sync::Arc<std::sync::Mutex<[Option<faer::Mat<f64>>; 2]>>);

impl Spare {
    /// Both arrays of order `m`, made now (zeros) on rayon's threads.
    pub(crate) fn made(m: usize) -> Spare {
        let make = || mat_filled(m, m, true, |_, _| {});
        let (w, c) = rayon::join(make, make);
        Spare(std::sync::Arc::new(std::sync::Mutex::new([
            Some(w),
            Some(c),
        ])))
    }

    /// Takes array `k` (0: `W`, 1: `C`), if it is still there.
    pub(crate) fn take(&self, k: usize) -> Option<faer::Mat<f64>> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())[k].take()
    }
}

/// A vector of `n` zeros written by rayon's threads: its pages are faulted in on all cores.
/// faer's numeric factorisations clear the factor's values on the calling thread first, which
/// in fresh memory (460 MB at L7) had left a core idle for 0.2–0.4 s of the floor; here the
/// clearing finds the pages in place (L7 numeric factorisation 1.72–1.74 → 1.56–1.64 s).
pub fn vec_in_parallel(n: usize) -> Vec<f64> {
    use rayon::prelude::*;
    let mut v: Vec<f64> = Vec::with_capacity(n);
    v.spare_capacity_mut()
        .par_chunks_mut(1 << 16)
        .for_each(|c| c.fill(std::mem::MaybeUninit::new(0.0)));
    // SAFETY: every element of the capacity was written above.
    unsafe { v.set_len(n) };
    v
}

/// Element access to a matrix from several rayon tasks at once, for loops whose tasks touch
/// disjoint elements (each use states why).
pub(crate) struct SharedMat {
    ptr: *mut f64,
    stride: usize,
}

// SAFETY: the users write disjoint elements from different tasks (see `SharedMat`).
unsafe impl Sync for SharedMat {}

impl SharedMat {
    pub(crate) fn of(a: &mut faer::Mat<f64>) -> SharedMat {
        SharedMat {
            stride: a.col_stride() as usize,
            ptr: a.as_ptr_mut(),
        }
    }

    /// SAFETY: (i, j) in bounds, and no other task writes it meanwhile.
    pub(crate) unsafe fn get(&self, i: usize, j: usize) -> f64 {
        unsafe { *self.ptr.add(i + j * self.stride) }
    }

    /// SAFETY: (i, j) in bounds, and no other task reads or writes it meanwhile.
    pub(crate) unsafe fn set(&self, i: usize, j: usize, v: f64) {
        unsafe { *self.ptr.add(i + j * self.stride) = v }
    }

    /// The first `len` elements of column `j`, zeroed first (they may be uninitialised).
    /// SAFETY: `len` ≤ the stride, column `j` within the allocation, and no other task touches
    /// it while the slice lives.
    #[allow(clippy::mut_from_ref)]
    pub(crate) unsafe fn zeroed_column(&self, j: usize, len: usize) -> &mut [f64] {
        unsafe {
            let p = self.ptr.add(j * self.stride);
            std::ptr::write_bytes(p, 0, len);
            std::slice::from_raw_parts_mut(p, len)
        }
    }
}

/// Side of the tiles in which [`for_tiles_below`] visits an `m × m` array.
pub(crate) const TILE: usize = 64;

/// `visit(i, j)` for every `i > j` below `m` (the strict lower half of an `m × m` array), in
/// [`TILE`] × [`TILE`] tiles so that an array's transposed entry `(j, i)` stays in cache
/// (130 MB arrays at L7); the columns `jb..jb + TILE` go to one of rayon's tasks, which visits
/// them in their row tiles from the diagonal down. A task may thus write the entries below the
/// diagonal in its columns and above it in its rows: no other task reads or writes those.
pub(crate) fn for_tiles_below(m: usize, visit: impl Fn(usize, usize) + Sync) {
    use rayon::prelude::*;
    (0..m.div_ceil(TILE)).into_par_iter().for_each(|b| {
        let jb = b * TILE;
        for ib in (jb..m).step_by(TILE) {
            for j in jb..(jb + TILE).min(m) {
                for i in (j + 1).max(ib)..(ib + TILE).min(m) {
                    visit(i, j);
                }
            }
        }
    });
}

/// [`mat_filled`] of zeros, on rayon's threads.
pub fn zeros_in_parallel(nrows: usize, ncols: usize) -> faer::Mat<f64> {
    mat_filled(nrows, ncols, true, |_, _| {})
}
