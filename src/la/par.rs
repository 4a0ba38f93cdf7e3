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
/// columns on rayon's threads with `parallel` (in groups of at least 32), else on the calling
/// thread. Sequential where a rayon worker must not wait (a sweep's block store).
pub fn mat_filled(
    nrows: usize,
    ncols: usize,
    parallel: bool,
    fill: impl Fn(usize, &mut [f64]) + Sync,
) -> faer::Mat<f64> {
    use rayon::prelude::*;
    let mut a = faer::Mat::<f64>::zeros(nrows, ncols);
    let one = |(j, mut col): (usize, faer::ColMut<'_, f64>)| {
        let col = col
            .as_mut()
            .try_as_col_major_mut()
            .expect("the columns of a Mat are contiguous");
        fill(j, col.as_slice_mut())
    };
    if parallel {
        a.as_mut()
            .par_col_iter_mut()
            .enumerate()
            .with_min_len(32)
            .for_each(one);
    } else {
        a.as_mut().col_iter_mut().enumerate().for_each(one);
    }
    a
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
