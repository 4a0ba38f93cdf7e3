//! Sparse symmetric positive-definite solves with faer's supernodal Cholesky factorisation.
//! The symbolic analysis (ordering, elimination tree, supernodes) is done once per sparsity
//! pattern and reused by every numeric factorisation.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};

/// Why a factorisation failed.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    #[error(
        "the stiffness matrix is not positive definite: a body is not held (add a support or a \
         pilot, or check that every body is connected to one) (pivot {pivot} of {n} in the \
         elimination order is not positive)"
    )]
    NotPositiveDefinite { pivot: usize, n: usize },
    #[error("sparse factorisation: not enough memory for {what} of a matrix of order {n}")]
    OutOfMemory { what: &'static str, n: usize },
    #[error("sparse factorisation: an index of a matrix of order {n} overflows")]
    IndexOverflow { n: usize },
    #[error("sparse factorisation: the symbolic analysis is not supernodal")]
    NotSupernodal,
    #[error("sparse factorisation: {len} factor values given for an analysis with {expected}")]
    FactorLength { len: usize, expected: usize },
}

fn sym<'a>(
    n: usize,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
) -> SymbolicSparseColMatRef<'a, usize> {
    SymbolicSparseColMatRef::new_checked(n, n, &col_ptr[..=n], None, &row_idx[..col_ptr[n]])
}

/// Whether the saddle-point factorisations run on the elimination tree's schedule
/// ([`crate::supernodal`]), unless `STICKSLIP_FACTOR=faer`
/// asks for faer's own loop (for comparisons: the same factor within round-off, and `W`
/// formed by the product rather than copied from the factorisation).
pub fn tree_scheduled() -> bool {
    std::env::var("STICKSLIP_FACTOR").map_or(true, |v| v != "faer")
}

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
pub struct Spare(std::sync::Arc<std::sync::Mutex<[Option<faer::Mat<f64>>; 2]>>);

impl Spare {
    /// Both arrays of order `m`, made now (zeros) on rayon's threads.
    fn made(m: usize) -> Spare {
        let make = || mat_filled(m, m, true, |_, _| {});
        let (w, c) = rayon::join(make, make);
        Spare(std::sync::Arc::new(std::sync::Mutex::new([
            Some(w),
            Some(c),
        ])))
    }

    /// Takes array `k` (0: `W`, 1: `C`), if it is still there.
    fn take(&self, k: usize) -> Option<faer::Mat<f64>> {
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

/// Copies the part of a supernode (first column `start`, `ncols` columns, off-diagonal rows
/// `pattern`, entry `(i, j)` of its columns by `at`) at and after row and column `from` into
/// the dense lower triangle `out` of the trailing block (`out[(r − from, c − from)]`).
fn copy_trailing(
    out: &mut faer::Mat<f64>,
    from: usize,
    start: usize,
    ncols: usize,
    pattern: &[usize],
    at: impl Fn(usize, usize) -> f64,
) {
    for j in start.max(from) - start..ncols {
        let col = start + j - from;
        for i in j..ncols {
            out[(start + i - from, col)] = at(i, j);
        }
        for (k, &row) in pattern.iter().enumerate() {
            out[(row - from, col)] = at(ncols + k, j);
        }
    }
}

/// Element access to a matrix from several rayon tasks at once, for loops whose tasks touch
/// disjoint elements (each use states why).
struct SharedMat {
    ptr: *mut f64,
    stride: usize,
}

// SAFETY: the users write disjoint elements from different tasks (see `SharedMat`).
unsafe impl Sync for SharedMat {}

impl SharedMat {
    fn of(a: &mut faer::Mat<f64>) -> SharedMat {
        SharedMat {
            stride: a.col_stride() as usize,
            ptr: a.as_ptr_mut(),
        }
    }

    /// SAFETY: (i, j) in bounds, and no other task writes it meanwhile.
    unsafe fn get(&self, i: usize, j: usize) -> f64 {
        unsafe { *self.ptr.add(i + j * self.stride) }
    }

    /// SAFETY: (i, j) in bounds, and no other task reads or writes it meanwhile.
    unsafe fn set(&self, i: usize, j: usize, v: f64) {
        unsafe { *self.ptr.add(i + j * self.stride) = v }
    }

    /// The first `len` elements of column `j`, zeroed first (they may be uninitialised).
    /// SAFETY: `len` ≤ the stride, column `j` within the allocation, and no other task touches
    /// it while the slice lives.
    #[allow(clippy::mut_from_ref)]
    unsafe fn zeroed_column(&self, j: usize, len: usize) -> &mut [f64] {
        unsafe {
            let p = self.ptr.add(j * self.stride);
            std::ptr::write_bytes(p, 0, len);
            std::slice::from_raw_parts_mut(p, len)
        }
    }
}

/// Side of the tiles in which [`for_tiles_below`] visits an `m × m` array.
const TILE: usize = 64;

/// `visit(i, j)` for every `i > j` below `m` (the strict lower half of an `m × m` array), in
/// [`TILE`] × [`TILE`] tiles so that an array's transposed entry `(j, i)` stays in cache
/// (130 MB arrays at L7); the columns `jb..jb + TILE` go to one of rayon's tasks, which visits
/// them in their row tiles from the diagonal down. A task may thus write the entries below the
/// diagonal in its columns and above it in its rows: no other task reads or writes those.
fn for_tiles_below(m: usize, visit: impl Fn(usize, usize) + Sync) {
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

/// The values of a numeric factorisation: computed in this run, or mapped from a model-cache
/// file and read in place ([`crate::cache::Reader::map_next`]), which spares a hit the copy
/// of hundreds of MB into fresh memory.
pub enum FactorValues {
    Owned(Vec<f64>),
    Mapped(crate::cache::MappedWords),
}

impl std::ops::Deref for FactorValues {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        match self {
            FactorValues::Owned(v) => v,
            FactorValues::Mapped(m) => m.as_f64(),
        }
    }
}

/// Factor values shared between a factorisation and a model-cache writer.
pub type SharedValues = std::sync::Arc<FactorValues>;

/// A sparse Cholesky factorisation `K = L Lᵀ` whose ordering puts a chosen set of *retained*
/// unknowns last, so that the trailing block of `L` is the Cholesky factor of the Schur
/// complement on them:
/// ```text
///   L = [L_II 0; L_RI L_RR],   S = K_RR − K_RI K_II⁻¹ K_IR = L_RR L_RRᵀ .
/// ```
/// The interior unknowns are ordered by AMD; the retained ones keep their order at the end.
/// This gives the condensed stiffness at the cost of one factorisation plus a dense block,
/// instead of one solve per retained unknown.
pub struct PartialCholesky {
    symbolic: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    /// The factor's values, shared with a model-cache writer ([`crate::cache`]).
    values: SharedValues,
    n: usize,
    n_r: usize,
    /// `L_RR`, dense lower triangular, column-major `n_r × n_r`.
    l_rr: faer::Mat<f64>,
}

/// The symbolic analysis of a [`PartialCholesky`], reusable across numeric factorisations.
#[derive(Clone)]
pub struct PartialSymbolic {
    inner: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    n: usize,
    n_r: usize,
}

impl PartialSymbolic {
    /// Orders and analyses an upper-triangular CSC pattern of size `n` whose last `n_r`
    /// unknowns are retained.
    pub fn analyse(
        n: usize,
        n_r: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
    ) -> Result<PartialSymbolic, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::amd;
        let other = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n,
            },
        };
        let n_i = n - n_r;
        // AMD on the interior block (its leading columns are a valid upper CSC matrix).
        let mut fwd = vec![0usize; n];
        let mut inv = vec![0usize; n];
        if n_i > 0 {
            let a_ii = sym(n_i, col_ptr, row_idx);
            let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
                n_i,
                col_ptr[n_i],
            ))
            .map_err(|_| FactorError::OutOfMemory {
                what: "the ordering",
                n,
            })?;
            amd::order_maybe_unsorted(
                &mut fwd[..n_i],
                &mut inv[..n_i],
                a_ii,
                Default::default(),
                MemStack::new(&mut mem),
            )
            .map_err(other)?;
        }
        Self::with_ordering(n, n_r, col_ptr, row_idx, &fwd[..n_i])
    }

    /// As [`Self::analyse`] with a given ordering of the interior unknowns (`fwd[new] = old`,
    /// a permutation of `0..n − n_r`), such as [`Self::ordering`] of an earlier analysis.
    pub fn with_ordering(
        n: usize,
        n_r: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        interior: &[usize],
    ) -> Result<PartialSymbolic, FactorError> {
        use faer::sparse::linalg::{SupernodalThreshold, cholesky};
        let other = |e: faer::sparse::FaerError| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n,
            },
        };
        let mut fwd = interior.to_vec();
        fwd.extend(n - n_r..n);
        let mut inv = vec![0usize; n];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
        let params = cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let inner = cholesky::factorize_symbolic_cholesky(
            sym(n, col_ptr, row_idx),
            Side::Upper,
            cholesky::SymmetricOrdering::Custom(perm),
            params,
        )
        .map_err(other)?;
        Ok(PartialSymbolic {
            inner: std::sync::Arc::new(inner),
            n,
            n_r,
        })
    }

    /// The ordering of the interior unknowns (`fwd[new] = old`).
    pub fn ordering(&self) -> Vec<usize> {
        let perm = self.inner.perm().expect("custom ordering");
        perm.arrays().0[..self.n - self.n_r].to_vec()
    }

    /// Numeric factorisation with these values, and extraction of `L_RR`.
    pub fn factorise(
        &self,
        col_ptr: &[usize],
        row_idx: &[usize],
        values: &[f64],
    ) -> Result<PartialCholesky, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        let n = self.n;
        let a = SparseColMatRef::new(sym(n, col_ptr, row_idx), &values[..col_ptr[n]]);
        let par = factor_parallelism();
        let mut l = vec_in_parallel(self.inner.len_val());
        let mut mem = MemBuffer::try_new(
            self.inner
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .map_err(|_| FactorError::OutOfMemory {
            what: "the numeric factorisation",
            n,
        })?;
        self.inner
            .factorize_numeric_llt(
                &mut l,
                a,
                Side::Upper,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    FactorError::NotPositiveDefinite { pivot: index, n }
                }
            })?;
        self.from_values(std::sync::Arc::new(FactorValues::Owned(l)))
    }

    /// The factorisation with the values of an earlier numeric factorisation on this
    /// analysis ([`PartialCholesky::values`]), and extraction of `L_RR`.
    pub fn from_values(&self, l: SharedValues) -> Result<PartialCholesky, FactorError> {
        use faer::sparse::linalg::cholesky::{SymbolicCholeskyRaw, supernodal::SupernodalLltRef};
        let (n, n_r) = (self.n, self.n_r);
        let n_i = n - n_r;
        if l.len() != self.inner.len_val() {
            return Err(FactorError::FactorLength {
                len: l.len(),
                expected: self.inner.len_val(),
            });
        }
        let mut l_rr = faer::Mat::<f64>::zeros(n_r, n_r);
        if n_r > 0 {
            let SymbolicCholeskyRaw::Supernodal(sn) = self.inner.raw() else {
                return Err(FactorError::NotSupernodal);
            };
            let lref = SupernodalLltRef::new(sn, &l);
            for s in 0..sn.n_supernodes() {
                let node = lref.supernode(s);
                let val = node.val();
                copy_trailing(
                    &mut l_rr,
                    n_i,
                    node.start(),
                    val.ncols(),
                    node.pattern(),
                    |i, j| val[(i, j)],
                );
            }
        }
        Ok(PartialCholesky {
            symbolic: self.inner.clone(),
            values: l,
            n,
            n_r,
            l_rr,
        })
    }
}

impl PartialCholesky {
    pub fn n(&self) -> usize {
        self.n
    }

    pub fn n_retained(&self) -> usize {
        self.n_r
    }

    /// The values of the factor (shared, not copied).
    pub fn values(&self) -> SharedValues {
        self.values.clone()
    }

    /// `L_RR` (dense, lower triangular): `S = L_RR L_RRᵀ`.
    pub fn l_rr(&self) -> faer::MatRef<'_, f64> {
        self.l_rr.as_ref()
    }

    /// Solves `K X = B` in place for a column-major block of `ncols` right-hand sides.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        use faer::dyn_stack::{MemBuffer, MemStack};
        use faer::sparse::linalg::cholesky::LltRef;
        let par = faer::get_global_parallelism();
        let lref = LltRef::new(&self.symbolic, &self.values);
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(ncols, par));
        let m = MatMut::from_column_major_slice_mut(b, self.n, ncols);
        lref.solve_in_place_with_conj(faer::Conj::No, m, par, MemStack::new(&mut mem));
    }

    /// Solves `K x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_block_in_place(b, 1);
    }
}

/// The sparsity pattern and symbolic analysis of the saddle-point matrix of a contact model,
/// ```text
///   A = [K̂  Yᵀ]     (n + m) × (n + m),
///       [Y   0 ]
/// ```
/// with the `m` constraint rows `Y` (mortar gap and slip rows, anchors) ordered after the `n`
/// free DOFs. Eliminating the free DOFs leaves `−W = −Y K̂⁻¹ Yᵀ` in the trailing block, so an
/// `L D Lᵀ` factorisation without pivoting (A is quasi-definite in this order: `K̂` positive
/// definite, `W` positive definite when `Y` has full row rank) gives both the factor of `K̂`
/// (its leading block) and the Delassus operator `W = −L_MM D_MM L_MMᵀ`, with a dense block of
/// order `m` only — instead of the dense Schur complement on every contact DOF (about `2m`)
/// followed by `m` triangular solves with it.
#[derive(Clone)]
pub struct SaddleSymbolic {
    inner: std::sync::Arc<faer::sparse::linalg::cholesky::SymbolicCholesky<usize>>,
    layout: std::sync::Arc<Supernodes>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    n: usize,
    m: usize,
    /// The arrays of the first factorisation's `W` and `C`, made during the analysis.
    spare: Spare,
}

/// A numeric `L D Lᵀ` factorisation of a saddle-point matrix (see [`SaddleSymbolic`]).
pub struct SaddleFactor {
    layout: std::sync::Arc<Supernodes>,
    /// The factor's values, shared with a model-cache writer ([`crate::cache`]); `None` once
    /// released ([`Self::release`]).
    values: std::sync::Mutex<Option<SharedValues>>,
    n: usize,
    m: usize,
    /// Per supernode with columns of `K̂`, the supernode, its columns of `K̂` and its pattern
    /// rows of `K̂` (the solves' plan, found at the first solve: 0.5 ms per solve on L5).
    plan: std::sync::OnceLock<Vec<(usize, usize, usize)>>,
    /// `W = Y K̂⁻¹ Yᵀ` (its lower triangle) as the factorisation found it, the Schur
    /// complement of the constraint block, until [`Self::delassus`] takes it.
    schur: std::sync::Mutex<Option<faer::Mat<f64>>>,
    /// The array of `C` made during the analysis ([`Spare`]), until [`Self::delassus`] fills it.
    spare_c: std::sync::Mutex<Option<faer::Mat<f64>>>,
    /// Wall time of the constraint block within the numeric factorisation (its updates, the
    /// elimination of the top separator's columns from it and its `L D Lᵀ`), seconds; zero
    /// where it was not timed apart (faer's loop, a factor from the model cache).
    pub constraint_block_s: f64,
}

/// The supernodal structure of a symbolic factorisation (forced supernodal at analysis).
fn supernodal(
    s: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
) -> Result<
    &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    FactorError,
> {
    match s.raw() {
        faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Supernodal(sn) => Ok(sn),
        _ => Err(FactorError::NotSupernodal),
    }
}

/// A fill-reducing ordering of the leading `n_lead` columns of an upper CSC pattern (which
/// are themselves a valid upper CSC pattern): `fwd[new] = old`.
fn order_leading(
    n_lead: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    n: usize,
) -> Result<Vec<usize>, FactorError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::amd;
    let mut fwd = vec![0usize; n_lead];
    let mut inv = vec![0usize; n_lead];
    if n_lead == 0 {
        return Ok(fwd);
    }
    let a = sym(n_lead, col_ptr, row_idx);
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
        n_lead,
        col_ptr[n_lead],
    ))
    .map_err(|_| FactorError::OutOfMemory {
        what: "the ordering",
        n,
    })?;
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        a,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| match e {
        faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n },
        _ => FactorError::OutOfMemory {
            what: "the ordering",
            n,
        },
    })?;
    Ok(fwd)
}

/// Constraint rows from which [`Spare`] arrays are made during the analysis (8 MB each).
pub const SPARE_FROM: usize = 1024;

/// Free DOFs from which a contact model's DOFs are ordered by nested dissection rather than
/// AMD: below it AMD's cheaper ordering wins, above it nested dissection's smaller factor does
/// (`cargo bench --bench scaling` with `STICKSLIP_ORDERING`; docs/benchmarks.md).
pub const ND_FROM: usize = 100_000;

/// The ordering policy: `auto` (AMD below [`ND_FROM`] free DOFs, nested dissection from it),
/// or forced by the environment variable `STICKSLIP_ORDERING=amd` or `=nd` (for the
/// comparison in docs/benchmarks.md). Part of the model cache's key.
pub fn ordering_policy() -> &'static str {
    match std::env::var("STICKSLIP_ORDERING").as_deref() {
        Ok("nd") => "nd",
        Ok("amd") => "amd",
        _ => "auto",
    }
}

/// The ordering of the free DOFs of a contact model with `n` free DOFs under
/// [`ordering_policy`].
pub fn ordering_choice(n: usize) -> crate::ordering::Ordering {
    match ordering_policy() {
        "nd" => crate::ordering::Ordering::NestedDissection,
        "amd" => crate::ordering::Ordering::Amd,
        _ if n >= ND_FROM => crate::ordering::Ordering::NestedDissection,
        _ => crate::ordering::Ordering::Amd,
    }
}

impl SaddleSymbolic {
    /// The pattern of `A` from the upper CSC pattern of `K̂` (order `n`) and the rows of `Y`
    /// (free-DOF index, coefficient), and its symbolic analysis: the free DOFs ordered by a
    /// fill-reducing ordering, the constraint rows last in their own order.
    pub fn analyse(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        y_rows: &[Vec<(usize, f64)>],
    ) -> Result<SaddleSymbolic, FactorError> {
        let fwd = match ordering_choice(n) {
            crate::ordering::Ordering::Amd => order_leading(n, col_ptr, row_idx, n + y_rows.len())?,
            crate::ordering::Ordering::NestedDissection => {
                crate::ordering::nested_dissection(n, col_ptr, row_idx)
            }
        };
        crate::trace::mark("ordered");
        Self::with_ordering(n, col_ptr, row_idx, y_rows, &fwd)
    }

    /// As [`Self::analyse`] with a given ordering of the free DOFs (`fwd[new] = old`, a
    /// permutation of `0..n`), such as [`Self::ordering`] of an earlier analysis.
    pub fn with_ordering(
        n: usize,
        col_ptr: &[usize],
        row_idx: &[usize],
        y_rows: &[Vec<(usize, f64)>],
        ordering: &[usize],
    ) -> Result<SaddleSymbolic, FactorError> {
        use faer::sparse::linalg::{SupernodalThreshold, cholesky};
        let m = y_rows.len();
        let size = n + m;
        let mut cp = col_ptr[..=n].to_vec();
        let mut ri = row_idx[..col_ptr[n]].to_vec();
        for row in y_rows {
            let mut rows: Vec<usize> = row.iter().map(|&(r, _)| r).collect();
            rows.sort_unstable();
            rows.dedup();
            ri.extend(rows);
            ri.push(cp.len() - 1); // the (zero) diagonal of the constraint column
            cp.push(ri.len());
        }
        let mut fwd = ordering.to_vec();
        fwd.extend(n..size);
        let mut inv = vec![0usize; size];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new;
        }
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, size);
        let params = cholesky::CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        // faer's symbolic analysis runs on one thread: the arrays of `W` and `C` are made on
        // the other meanwhile (none below `SPARE_FROM` constraint rows).
        let (inner, spare) = rayon::join(
            || {
                cholesky::factorize_symbolic_cholesky(
                    sym(size, &cp, &ri),
                    Side::Upper,
                    cholesky::SymmetricOrdering::Custom(perm),
                    params,
                )
            },
            || {
                if m >= SPARE_FROM {
                    Spare::made(m)
                } else {
                    Spare::default()
                }
            },
        );
        let inner = inner.map_err(|e| match e {
            faer::sparse::FaerError::IndexOverflow => FactorError::IndexOverflow { n: size },
            _ => FactorError::OutOfMemory {
                what: "the symbolic analysis",
                n: size,
            },
        })?;
        crate::trace::mark("symbolic");
        let layout = std::sync::Arc::new(Supernodes::of(&inner)?);
        Ok(SaddleSymbolic {
            inner: std::sync::Arc::new(inner),
            layout,
            col_ptr: cp,
            row_idx: ri,
            n,
            m,
            spare,
        })
    }

    /// The ordering of the free DOFs (`fwd[new] = old`; the constraint rows follow in order).
    pub fn ordering(&self) -> Vec<usize> {
        let perm = self.inner.perm().expect("custom ordering");
        perm.arrays().0[..self.n].to_vec()
    }

    /// Number of nonzeros of the factor `L` (supernodal storage).
    pub fn factor_len(&self) -> usize {
        self.inner.len_val()
    }

    /// Estimated floating-point operations of the numeric factorisation, split into the
    /// elimination of `K̂` itself, its updates of the constraint rows (the fill that couples
    /// `Y` to the separators) and the dense constraint block: `(k, k_to_m, m)`.
    pub fn flops(&self) -> (f64, f64, f64) {
        let sn = supernodal(&self.inner).expect("analysed supernodal");
        let n = self.n;
        let (begin, end) = (sn.supernode_begin(), sn.supernode_end());
        let ptr = sn.col_ptr_for_row_idx();
        let (mut fk, mut fkm, mut fm) = (0.0, 0.0, 0.0);
        for s in 0..sn.n_supernodes() {
            let pattern = &sn.row_idx()[ptr[s]..ptr[s + 1]];
            let w = (end[s] - begin[s]) as f64;
            let wk = (end[s].min(n).saturating_sub(begin[s])) as f64;
            let wm = w - wk;
            let pk = pattern.iter().filter(|&&r| r < n).count() as f64;
            let pm = pattern.len() as f64 - pk;
            // Columns of K̂: their own block and updates of K̂ rows, then of constraint rows.
            fk += wk * wk * wk / 3.0 + wk * wk * pk + wk * pk * pk;
            fkm += wk * wk * (pm + wm) + wk * (pm + wm) * (pm + wm + 2.0 * pk);
            // Constraint columns (all after K̂'s).
            fm += wm * wm * wm / 3.0 + wm * wm * pm + wm * pm * pm;
        }
        (fk, fkm, fm)
    }

    /// Numeric `L D Lᵀ` factorisation with the values of `K̂` (in the pattern given to
    /// [`Self::analyse`]) and the same `Y` rows, in fresh memory.
    pub fn factorise(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
    ) -> Result<SaddleFactor, FactorError> {
        self.factorise_in(k_values, y_rows, None)
    }

    /// Length of the factor's values.
    pub fn len_val(&self) -> usize {
        self.inner.len_val()
    }

    /// [`Self::factorise`] with the values computed in `dest` when given (a new model-cache
    /// entry's file, [`crate::cache::Draft`]; [`Self::len_val`] floats), the same bits.
    pub fn factorise_in(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
        dest: Option<crate::cache::WritableSection>,
    ) -> Result<SaddleFactor, FactorError> {
        self.factorise_using(k_values, y_rows, dest, tree_scheduled())
    }

    /// [`Self::factorise_in`] on the elimination tree's schedule with `tree`, else with
    /// faer's own loop.
    fn factorise_using(
        &self,
        k_values: &[f64],
        y_rows: &[Vec<(usize, f64)>],
        mut dest: Option<crate::cache::WritableSection>,
        tree: bool,
    ) -> Result<SaddleFactor, FactorError> {
        use faer::dyn_stack::{MemBuffer, MemStack};
        let (n, m) = (self.n, self.m);
        let size = n + m;
        // The values of the constraint columns (those of K̂ are `k_values` as they are).
        let kn = self.col_ptr[n];
        let mut y_values = Vec::with_capacity(self.row_idx.len() - kn);
        for (i, row) in y_rows.iter().enumerate() {
            let rows = &self.row_idx[self.col_ptr[n + i]..self.col_ptr[n + i + 1]];
            let start = y_values.len();
            y_values.resize(start + rows.len(), 0.0);
            for &(r, v) in row {
                let p = rows[..rows.len() - 1]
                    .binary_search(&r)
                    .expect("row in the analysed pattern");
                y_values[start + p] += v;
            }
        }
        let par = factor_parallelism();
        assert!(
            dest.as_ref()
                .is_none_or(|d| d.len() == self.inner.len_val()),
            "a factor's destination of another length"
        );
        crate::trace::mark("factor: values gathered");
        let mut owned = Vec::new();
        let l: &mut [f64] = match &mut dest {
            Some(d) => {
                // Its pages faulted in on all cores, as `vec_in_parallel` does: those of a new
                // file read as zeros, so populating them is enough where the kernel can.
                let populated = tree && d.populate();
                let v = d.as_mut_f64();
                if !populated {
                    use rayon::prelude::*;
                    v.par_chunks_mut(1 << 16).for_each(|c| c.fill(0.0));
                }
                v
            }
            None => {
                owned = vec_in_parallel(self.inner.len_val());
                &mut owned
            }
        };
        crate::trace::mark("factor: values cleared");
        let mut schur = None;
        if tree {
            let lower = crate::supernodal::LowerCsc::permuted(
                &self.col_ptr,
                &self.row_idx,
                |p| {
                    if p < kn {
                        k_values[p]
                    } else {
                        y_values[p - kn]
                    }
                },
                &self.layout.fwd,
            );
            crate::trace::mark("factor: lower triangle permuted");
            let st = crate::supernodal::Structure {
                begin: &self.layout.begin,
                row_ptr: &self.layout.row_ptr,
                rows: &self.layout.rows,
                val_ptr: &self.layout.val_ptr,
            };
            schur = crate::supernodal::factorise(&st, lower, l, par, Some((n, self.spare.take(0))))
                .map_err(|pivot| FactorError::NotPositiveDefinite { pivot, n })?;
            if schur.is_none() {
                crate::trace::mark("factor: constraint block not in the root (W by the product)");
            }
        } else {
            let mut values = Vec::with_capacity(self.row_idx.len());
            values.extend_from_slice(&k_values[..kn]);
            values.extend_from_slice(&y_values);
            let a = SparseColMatRef::new(sym(size, &self.col_ptr, &self.row_idx), &values);
            let mut mem = MemBuffer::try_new(
                self.inner
                    .factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            )
            .map_err(|_| FactorError::OutOfMemory {
                what: "the numeric factorisation",
                n: size,
            })?;
            self.inner
                .factorize_numeric_ldlt(
                    l,
                    a,
                    Side::Upper,
                    Default::default(),
                    par,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .map_err(|e| match e {
                    faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                        FactorError::NotPositiveDefinite { pivot: index, n }
                    }
                })?;
        }
        let values = match dest {
            Some(d) => FactorValues::Mapped(d.into_mapped()),
            None => FactorValues::Owned(owned),
        };
        let mut f = self.from_values(std::sync::Arc::new(values))?;
        f.spare_c = std::sync::Mutex::new(self.spare.take(1));
        if let Some((w, seconds)) = schur {
            f.constraint_block_s = seconds;
            *f.schur.lock().unwrap_or_else(|p| p.into_inner()) = Some(w);
        }
        let values = f.values();
        // K̂ must be positive definite: every pivot of its block positive (a body that nothing
        // holds gives a vanishing or negative one).
        let mut dmax: f64 = 0.0;
        for s in 0..f.layout.n_supernodes() {
            let node = f.layout.node(s, &values);
            for j in 0..node.ncols {
                let col = node.start + j;
                if col >= n {
                    break;
                }
                let d = node.at(j, j);
                dmax = dmax.max(d.abs());
                if d.partial_cmp(&(1e-14 * dmax)) != Some(std::cmp::Ordering::Greater) {
                    return Err(FactorError::NotPositiveDefinite { pivot: col, n });
                }
            }
        }
        Ok(f)
    }

    /// The factorisation with the values of an earlier numeric factorisation on this analysis
    /// ([`SaddleFactor::values`]).
    pub fn from_values(&self, l: SharedValues) -> Result<SaddleFactor, FactorError> {
        SaddleFactor::from_layout(self.layout.clone(), l, self.n, self.m)
    }
}

/// The supernodal layout of a saddle factor, which its solves and its Delassus operator read:
/// copied out of faer's symbolic analysis, or restored from the model cache (so that a cache hit
/// needs no symbolic analysis). Supernode `s` has the columns `begin[s]..begin[s + 1]`, the
/// off-diagonal rows `rows[row_ptr[s]..row_ptr[s + 1]]` (ascending) and its values at
/// `val_ptr[s]..val_ptr[s + 1]` of the factor's values, column-major with its columns' rows
/// then the off-diagonal rows (the diagonal block holds `D` on its diagonal under a unit
/// lower triangle). `fwd[new] = old` is the ordering of the saddle-point matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Supernodes {
    pub begin: Vec<usize>,
    pub row_ptr: Vec<usize>,
    pub rows: Vec<usize>,
    pub val_ptr: Vec<usize>,
    pub fwd: Vec<usize>,
}

/// One supernode of a [`Supernodes`] layout with its values.
struct Node<'a> {
    start: usize,
    ncols: usize,
    nrows: usize,
    pattern: &'a [usize],
    val: &'a [f64],
}

impl Node<'_> {
    /// Column `c` (all `nrows` rows).
    fn col(&self, c: usize) -> &[f64] {
        &self.val[c * self.nrows..(c + 1) * self.nrows]
    }

    fn at(&self, i: usize, j: usize) -> f64 {
        self.val[j * self.nrows + i]
    }
}

impl Supernodes {
    /// The layout of a supernodal symbolic analysis with a custom ordering.
    fn of(
        s: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    ) -> Result<Supernodes, FactorError> {
        let sn = supernodal(s)?;
        let nsup = sn.n_supernodes();
        let mut begin = sn.supernode_begin().to_vec();
        begin.push(sn.supernode_end().last().copied().unwrap_or(0));
        let mut row_ptr = Vec::with_capacity(nsup + 1);
        let mut rows = Vec::new();
        row_ptr.push(0);
        for k in 0..nsup {
            rows.extend_from_slice(sn.supernode(k).pattern());
            row_ptr.push(rows.len());
        }
        let fwd = s.perm().expect("custom ordering").arrays().0.to_vec();
        Ok(Supernodes {
            begin,
            row_ptr,
            rows,
            val_ptr: sn.col_ptr_for_val().to_vec(),
            fwd,
        })
    }

    fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    /// Length of the factor's values.
    pub fn len_val(&self) -> usize {
        self.val_ptr.last().copied().unwrap_or(0)
    }

    /// Supernode `s` with the factor's `values`.
    fn node<'a>(&'a self, s: usize, values: &'a [f64]) -> Node<'a> {
        let (start, end) = (self.begin[s], self.begin[s + 1]);
        let pattern = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
        Node {
            start,
            ncols: end - start,
            nrows: end - start + pattern.len(),
            pattern,
            val: &values[self.val_ptr[s]..self.val_ptr[s + 1]],
        }
    }

    /// `Err` with what is wrong if this is not the layout of a saddle factor with `n` free DOFs
    /// and `m` constraint rows (supernodes that tile `0..n + m`, value ranges that fit their
    /// shapes, ascending
    /// off-diagonal rows below each supernode, an ordering that is a permutation with the free
    /// DOFs first); the length of the values is checked against [`Self::len_val`] by
    /// [`SaddleFactor::from_layout`], whose layout must pass this.
    pub fn check(&self, n: usize, m: usize) -> Result<(), String> {
        let size = n + m;
        let nsup = self.begin.len().saturating_sub(1);
        if self.begin.last() != Some(&size) {
            return Err("supernodes do not tile the columns".into());
        }
        if self.begin.first() != Some(&0) || self.begin.windows(2).any(|w| w[0] >= w[1]) {
            return Err("supernodes do not tile the columns".into());
        }
        if self.row_ptr.len() != nsup + 1
            || self.val_ptr.len() != nsup + 1
            || self.row_ptr[0] != 0
            || self.val_ptr[0] != 0
            || self.row_ptr[nsup] != self.rows.len()
        {
            return Err("supernode pointers".into());
        }
        for s in 0..nsup {
            let pattern = self
                .rows
                .get(self.row_ptr[s]..self.row_ptr[s + 1])
                .ok_or("supernode pointers")?;
            let ncols = self.begin[s + 1] - self.begin[s];
            if self.val_ptr[s + 1].checked_sub(self.val_ptr[s])
                != Some((ncols + pattern.len()) * ncols)
            {
                return Err("supernode values".into());
            }
            if pattern.first().is_some_and(|&r| r < self.begin[s + 1])
                || pattern.last().is_some_and(|&r| r >= size)
                || pattern.windows(2).any(|w| w[0] >= w[1])
            {
                return Err("supernode rows".into());
            }
        }
        let mut seen = vec![false; size];
        if self.fwd.len() != size
            || !self.fwd.iter().enumerate().all(|(k, &i)| {
                (i < n) == (k < n) && i < size && !std::mem::replace(&mut seen[i], true)
            })
        {
            return Err("ordering".into());
        }
        Ok(())
    }
}

/// `Σ a_i b_i` in four interleaved partial sums (which the compiler vectorises).
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Asks for the cache lines of `v`, to be read once (a hint: no effect on results).
///
/// Non-temporal (`NTA`): the recovery sweeps stream the factor's 132 MB (L5) through the
/// caches while the contact Newton, on the other core, works on a Delassus operator and block
/// factor of a few MB that otherwise lose their place in the shared L3 to it. With `T0`
/// against `NTA` (a switch in a build not kept, the same binary in alternating runs of
/// `benches/ab.sh`, Fig. 2 on L5): wall − floor 0.282 → 0.266 s (`cold`, 14 pairs) and 0.311
/// → 0.294 s (`first`, 16 pairs); the sweep alone unchanged (`examples/recovery_timing`,
/// 18–20 ms for one column either way); L7 `cold` 1.427 against 1.422 (4 pairs).
///
/// From the last line to the first: the backward sweep goes down the factor's memory, and
/// requests that go down with it all the way (not up within each supernode) let the
/// processor's own stream prefetch follow. The backward loop alone on L5 (a scratch program
/// timing it on the factor of Fig. 2, not kept): 12.4–13.0 ms with the lines requested
/// upwards, 10.8–10.9 ms downwards with the pattern-row sums first (below); a plain read of
/// the same bytes, supernodes from the last, 9.6–10.0 ms going up within each and 4.3 ms
/// going down throughout.
#[inline(always)]
fn prefetch(v: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for line in v.chunks(8).rev() {
        // SAFETY: a prefetch reads nothing and cannot fault; the address is in `v`.
        unsafe {
            std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_NTA }>(
                line.as_ptr().cast(),
            )
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

/// The downward prefetch of the backward sweeps (see [`sweep_leading_body`]): the values of the
/// supernodes solved next, requested up to 8 KB below the one being solved.
struct Ahead {
    /// The first supernode requested so far.
    next: usize,
    /// Bytes requested below the supernode being solved.
    fetched: usize,
}

impl Ahead {
    const BYTES: usize = 8 << 10;

    fn new(nsup: usize) -> Ahead {
        Ahead {
            next: nsup,
            fetched: 0,
        }
    }

    /// Supernode `i` (of `nodes`, going down) is solved next: requests what follows it.
    #[inline(always)]
    fn at(&mut self, nodes: &[(usize, usize, usize, Node<'_>)], i: usize) {
        let bytes = |(_, wk, _, node): &(usize, usize, usize, Node<'_>)| wk * node.nrows * 8;
        if self.next > i {
            (self.next, self.fetched) = (i, 0);
        } else {
            self.fetched -= bytes(&nodes[i]);
        }
        while self.next > 0 && self.fetched < Self::BYTES {
            self.next -= 1;
            let (_, wk, _, next) = &nodes[self.next];
            prefetch(&next.val[..wk * next.nrows]);
            self.fetched += bytes(&nodes[self.next]);
        }
    }
}

/// The forward, diagonal and backward sweeps of `K̂ X = B` with the leading block of a saddle
/// factor (`nodes`: per supernode of K its first column, its columns of K, the pattern rows of
/// K and its values), in place on the permuted columns `x` of length `size` each.
fn sweep_leading(nodes: &[(usize, usize, usize, Node<'_>)], x: &mut [f64], size: usize) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() {
        // SAFETY: the processor has AVX2 (checked at run time).
        return unsafe { sweep_leading_avx2(nodes, x, size) };
    }
    sweep_leading_body(nodes, x, size)
}

/// [`sweep_leading`] compiled for AVX2 (the same operations in the same order, so the same
/// bits: Rust does not contract `a * b + c` into a fused multiply-add).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sweep_leading_avx2(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [f64],
    size: usize,
) {
    sweep_leading_body(nodes, x, size)
}

#[inline(always)]
fn sweep_leading_body(nodes: &[(usize, usize, usize, Node<'_>)], x: &mut [f64], size: usize) {
    // Each supernode is read once for all the columns (the factor is tens to hundreds of MB
    // and the sweeps are memory-bound); each column sees the same operations in the same
    // order as when it is solved alone.
    let mut t = Vec::new();
    // Forward: L_KK y = b; the off-diagonal rows of a supernode are gathered into `t` and
    // scattered once.
    for (start, wk, kp, node) in nodes {
        let (pat, w) = (&node.pattern[..*kp], node.ncols);
        for x in x.chunks_exact_mut(size) {
            // A supernode whose entries are all zero changes nothing (the right-hand sides of
            // recoveries are zero outside the retained DOFs, and so stay most supernodes).
            if x[*start..start + wk].iter().all(|&v| v == 0.0) {
                continue;
            }
            t.clear();
            t.resize(*kp, 0.0);
            for c in 0..*wk {
                let xc = x[start + c];
                if xc == 0.0 {
                    continue;
                }
                let col = node.col(c);
                for r in c + 1..*wk {
                    x[start + r] -= col[r] * xc;
                }
                for (tk, lk) in t.iter_mut().zip(&col[w..w + kp]) {
                    *tk += lk * xc;
                }
            }
            for (&row, tk) in pat.iter().zip(&t) {
                x[row] -= tk;
            }
        }
    }
    // D and backward: x = L_KK⁻ᵀ D⁻¹ y, supernode by supernode from the last; the pattern's
    // values gathered into `t` once. Each entry is divided by its pivot just before its own
    // column is read (a pass of its own over the diagonals cost a cache miss per column).
    // The values of the supernodes solved next are requested 8 KB ahead: the sweep goes down
    // the factor's memory, a few KB per supernode, and the hardware's prefetch does not follow
    // it from one supernode to the one before (without: 17.4 ms for this loop on L5, with:
    // 11.6 ms; [`Ahead`]). Within a supernode the sums over its pattern rows (most of its
    // values) are formed first, column after column in memory order, and the dependent
    // diagonal-block sums after: one column's recovery 17.4 → 15.2 ms on L5 with the
    // downward prefetch (`examples/recovery_timing`, five alternating runs each). The same
    // operations on each entry, so the same bits.
    let mut ahead = Ahead::new(nodes.len());
    let mut below = Vec::new();
    for (i, (start, wk, kp, node)) in nodes.iter().enumerate().rev() {
        let (pat, w) = (&node.pattern[..*kp], node.ncols);
        ahead.at(nodes, i);
        for x in x.chunks_exact_mut(size) {
            // Plain loops, not `extend` over a `map`: the closure's loop was compiled outside
            // this function, without its AVX2 (perf annotate of `examples/recovery_timing`;
            // the same bits either way).
            t.clear();
            for &row in pat {
                t.push(x[row]);
            }
            // The sums over the pattern rows first, from the first column (the supernode's
            // memory in order), then the diagonal block's, which depend on the columns after.
            below.clear();
            for c in 0..*wk {
                below.push(dot(&node.col(c)[w..w + kp], &t));
            }
            for c in (0..*wk).rev() {
                let col = node.col(c);
                // Both sums as (vectorised) dot products: the one over the diagonal block
                // was a chain of dependent scalar updates, most of the sweep's time.
                let mut acc = x[start + c] / col[c];
                acc -= dot(&col[c + 1..*wk], &x[start + c + 1..start + wk]);
                acc -= below[c];
                x[start + c] = acc;
            }
        }
    }
}

/// [`sweep_leading`] of `R` columns at once, interleaved (`x[i][j]`: entry `i` of column `j`):
/// the gathers and scatters of a supernode's pattern rows touch one cache line for all the
/// columns instead of one per column, and the loops run across the columns in vector
/// registers. Each column sees the operations of [`sweep_leading_body`] in its order, so the
/// same bits as solved alone: the skipped columns of the forward sweep (a zero multiplier)
/// keep their entries by a select, and the sums are [`dot`]'s, lane by lane.
fn sweep_leading_lanes<const R: usize>(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [[f64; R]],
) {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::avx2() {
        // SAFETY: the processor has AVX2 (checked at run time).
        return unsafe { sweep_leading_lanes_avx2(nodes, x) };
    }
    sweep_leading_lanes_body(nodes, x)
}

/// [`sweep_leading_lanes`] compiled for AVX2 (the same operations in the same order).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sweep_leading_lanes_avx2<const R: usize>(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [[f64; R]],
) {
    sweep_leading_lanes_body(nodes, x)
}

/// [`dot`] of `a` with each lane of `b`.
#[inline(always)]
fn dot_lanes<const R: usize>(a: &[f64], b: &[[f64; R]]) -> [f64; R] {
    let mut acc = [[0.0; R]; 4];
    let n4 = a.len() / 4 * 4;
    for (x, y) in a[..n4].chunks_exact(4).zip(b[..n4].chunks_exact(4)) {
        for k in 0..4 {
            for j in 0..R {
                acc[k][j] += x[k] * y[k][j];
            }
        }
    }
    std::array::from_fn(|j| {
        let tail: f64 = a[n4..].iter().zip(&b[n4..]).map(|(x, y)| x * y[j]).sum();
        (acc[0][j] + acc[1][j]) + (acc[2][j] + acc[3][j]) + tail
    })
}

#[inline(always)]
fn sweep_leading_lanes_body<const R: usize>(
    nodes: &[(usize, usize, usize, Node<'_>)],
    x: &mut [[f64; R]],
) {
    let mut t: Vec<[f64; R]> = Vec::new();
    // Forward, as in `sweep_leading_body`: a lane whose multiplier is zero is skipped there,
    // so its entries are kept here (`t` starts at +0 and can only stay +0 or move away from
    // zero, so adding a zero product to it changes nothing).
    for (start, wk, kp, node) in nodes {
        let (start, wk, kp) = (*start, *wk, *kp);
        let (pat, w) = (&node.pattern[..kp], node.ncols);
        if x[start..start + wk].iter().flatten().all(|&v| v == 0.0) {
            continue;
        }
        t.clear();
        t.resize(kp, [0.0; R]);
        for c in 0..wk {
            let xc = x[start + c];
            if xc.iter().all(|&v| v == 0.0) {
                continue;
            }
            let col = node.col(c);
            for (xr, &l) in x[start + c + 1..start + wk].iter_mut().zip(&col[c + 1..wk]) {
                for j in 0..R {
                    let v = xr[j] - l * xc[j];
                    xr[j] = if xc[j] == 0.0 { xr[j] } else { v };
                }
            }
            for (tk, &lk) in t.iter_mut().zip(&col[w..w + kp]) {
                for j in 0..R {
                    tk[j] += lk * xc[j];
                }
            }
        }
        for (&row, tk) in pat.iter().zip(&t) {
            for j in 0..R {
                x[row][j] -= tk[j];
            }
        }
    }
    // D and backward, with the prefetch of `sweep_leading_body`.
    let mut ahead = Ahead::new(nodes.len());
    let mut below: Vec<[f64; R]> = Vec::new();
    for (i, (start, wk, kp, node)) in nodes.iter().enumerate().rev() {
        let (start, wk, kp) = (*start, *wk, *kp);
        let (pat, w) = (&node.pattern[..kp], node.ncols);
        ahead.at(nodes, i);
        t.clear();
        for &row in pat {
            t.push(x[row]);
        }
        below.clear();
        for c in 0..wk {
            below.push(dot_lanes(&node.col(c)[w..w + kp], &t));
        }
        for c in (0..wk).rev() {
            let col = node.col(c);
            let d = dot_lanes(&col[c + 1..wk], &x[start + c + 1..start + wk]);
            let xc = &mut x[start + c];
            for j in 0..R {
                let mut acc = xc[j] / col[c];
                acc -= d[j];
                acc -= below[c][j];
                xc[j] = acc;
            }
        }
    }
}

/// Solves the permuted columns `cols` (column-major, `size` each) with the leading block:
/// one column alone, more `R` at a time interleaved (the same bits).
fn sweep_columns(nodes: &[(usize, usize, usize, Node<'_>)], cols: &mut [f64], size: usize) {
    fn group<const R: usize>(
        nodes: &[(usize, usize, usize, Node<'_>)],
        cols: &mut [f64],
        size: usize,
    ) {
        let k = cols.len() / size;
        let mut x = vec![[0.0; R]; size];
        for (j, c) in cols.chunks_exact(size).enumerate() {
            for (xi, v) in x.iter_mut().zip(c) {
                xi[j] = *v;
            }
        }
        sweep_leading_lanes(nodes, &mut x);
        for (j, c) in cols.chunks_exact_mut(size).enumerate().take(k) {
            for (xi, v) in x.iter().zip(c) {
                *v = xi[j];
            }
        }
    }
    for g in cols.chunks_mut(8 * size) {
        match g.len() / size {
            1 => sweep_leading(nodes, g, size),
            2 => group::<2>(nodes, g, size),
            3 | 4 => group::<4>(nodes, g, size),
            _ => group::<8>(nodes, g, size),
        }
    }
}

impl SaddleFactor {
    /// The factorisation of a saddle-point matrix with `n` free DOFs and `m` constraint rows
    /// from its supernodal layout and values (a model-cache hit: no symbolic analysis).
    pub fn from_layout(
        layout: std::sync::Arc<Supernodes>,
        values: SharedValues,
        n: usize,
        m: usize,
    ) -> Result<SaddleFactor, FactorError> {
        if values.len() != layout.len_val() {
            return Err(FactorError::FactorLength {
                len: values.len(),
                expected: layout.len_val(),
            });
        }
        Ok(SaddleFactor {
            layout,
            values: std::sync::Mutex::new(Some(values)),
            n,
            m,
            plan: std::sync::OnceLock::new(),
            schur: std::sync::Mutex::new(None),
            spare_c: std::sync::Mutex::new(None),
            constraint_block_s: 0.0,
        })
    }

    /// The supernodal layout (shared, not copied).
    pub fn layout(&self) -> std::sync::Arc<Supernodes> {
        self.layout.clone()
    }

    /// The values of the factor (shared, not copied).
    ///
    /// # Panics
    /// Once the values are released ([`Self::release`]).
    pub fn values(&self) -> SharedValues {
        self.values
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
            .expect("a saddle factor's values used after their release")
    }

    /// Gives up this factor's hold on its values: once the solves that started before have
    /// ended (and a model-cache writer has written them), the memory can be freed, on the
    /// caller's schedule, while the rest of the model is still in use (a run releases the
    /// factor once its last field is recovered, so that freeing hundreds of MB overlaps the
    /// output and the summary instead of following them). Any later solve panics.
    pub fn release(&self) -> Option<SharedValues> {
        self.values.lock().unwrap_or_else(|p| p.into_inner()).take()
    }

    /// Order of `K̂`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Solves `K̂ X = B` in place for a column-major block of `ncols` right-hand sides: the
    /// sweeps of the leading block of the factor only, the columns split over rayon's threads.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        self.solve_block(b, ncols, true);
    }

    /// As [`Self::solve_block_in_place`] in one sweep on the calling thread, which reads the
    /// factor once for all the columns (the output writer's recoveries: two columns cost 1.3
    /// times one on L7, `examples/recovery_timing`, where two threads would read it twice and
    /// take the core the contact solve runs on). The same bits.
    pub fn solve_block_in_place_one_sweep(&self, b: &mut [f64], ncols: usize) {
        self.solve_block(b, ncols, false);
    }

    fn solve_block(&self, b: &mut [f64], ncols: usize, split: bool) {
        let (n, m) = (self.n, self.m);
        let size = n + m;
        if n == 0 || ncols == 0 {
            return;
        }
        let values = self.values();
        let fwd = &self.layout.fwd;
        // Permuted copy, constraint rows zero (they are never read below).
        let mut x = vec![0.0; size * ncols];
        for j in 0..ncols {
            for i in 0..n {
                x[j * size + i] = b[j * n + fwd[i]];
            }
        }
        let nodes = self.leading_nodes(&values);
        // Each column sees the same operations in the same order whether it is solved alone
        // or with others, on any thread: the columns are split over the threads in groups of
        // up to eight, each group one read of the factor with its columns interleaved
        // (`sweep_columns`). Fewer columns stay together on this thread: two interleaved cost
        // 18 ms on L5 against 14 ms for one alone (`examples/recovery_timing`), where two
        // threads with one each read the factor twice, both memory-bound, and take the core
        // that the other preparations of the end of a run need.
        let threads = if split {
            rayon::current_num_threads().clamp(1, ncols.div_ceil(8).max(1))
        } else {
            1
        };
        let per = ncols.div_ceil(threads).max(1);
        if threads > 1 {
            use rayon::prelude::*;
            x.par_chunks_mut(size * per)
                .for_each(|cols| sweep_columns(&nodes, cols, size));
        } else {
            sweep_columns(&nodes, &mut x, size);
        }
        // Back in the original order (`fwd` maps the first n positions onto the free DOFs).
        for j in 0..ncols {
            for i in 0..n {
                b[j * n + fwd[i]] = x[j * size + i];
            }
        }
    }

    /// Per supernode of K: its first column, the columns of K in it, the pattern rows of K
    /// (the constraint rows come last in every pattern) and its `values`.
    fn leading_nodes<'a>(&'a self, values: &'a [f64]) -> Vec<(usize, usize, usize, Node<'a>)> {
        let n = self.n;
        let plan = self.plan.get_or_init(|| {
            (0..self.layout.n_supernodes())
                .map(|s| (s, self.layout.node(s, values)))
                .take_while(|(_, node)| node.start < n)
                .map(|(s, node)| {
                    let kp = node.pattern.partition_point(|&r| r < n);
                    (s, node.ncols.min(n - node.start), kp)
                })
                .collect()
        });
        plan.iter()
            .map(|&(s, wk, kp)| {
                let node = self.layout.node(s, values);
                (node.start, wk, kp, node)
            })
            .collect()
    }

    /// Solves `K̂ x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        self.solve_block_in_place(b, 1);
    }

    /// The Delassus operator `W = Y K̂⁻¹ Yᵀ = −L_MM D_MM L_MMᵀ` (dense, `m × m`, in the order
    /// of the constraint rows), or `None` when a pivot of the constraint block is not negative
    /// (`Y` is rank-deficient, or `W` is too ill-conditioned for the unpivoted factorisation
    /// to be trusted). With `keep_factor`, also `C = L_MM (−D_MM)^½`, a lower Cholesky factor
    /// of `W` (`W = C Cᵀ`, its strictly upper part zero): the leading `p × p` block of `C` is
    /// the Cholesky factor of the leading block `W[..p, ..p]`, for every `p`, with no
    /// factorisation (see `contact::PrefixFactor`).
    pub fn delassus(&self, keep_factor: bool) -> Option<(faer::Mat<f64>, Option<faer::Mat<f64>>)> {
        use faer::linalg::matmul::triangular::{BlockStructure, matmul};
        let m = self.m;
        let schur = self.schur.lock().unwrap_or_else(|p| p.into_inner()).take();
        // The array made for `C` during the analysis: filled below, or freed with this call on
        // the paths that do not need it (not kept by the factor for the rest of the run).
        let spare_c = self
            .spare_c
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take();
        if let Some(mut w) = schur {
            // W as the factorisation found it (its lower triangle): no product.
            let values = self.values();
            if !negative_pivots(&self.d_mm(&values)) {
                return None;
            }
            let ws = SharedMat::of(&mut w);
            // SAFETY: (j, i) is above the diagonal in this task's rows, (i, j) below it in
            // its columns: no task writes what another reads or writes.
            for_tiles_below(m, |i, j| unsafe { ws.set(j, i, ws.get(i, j)) });
            crate::trace::mark("delassus: from the factorisation");
            if !keep_factor {
                return Some((w, None));
            }
            // The factorisation copies W only where the constraint columns end the root.
            let c = self
                .c_from_root(&values, spare_c)
                .expect("W copied from the root supernode");
            return Some((w, Some(c)));
        }
        let mut l = self.l_mm();
        crate::trace::mark("delassus: L_MM gathered");
        if !negative_pivots(&(0..m).map(|i| l[(i, i)]).collect::<Vec<_>>()) {
            return None;
        }
        // One array holds both operands of W = −B Lᵀ: B = L D in its lower half (D on the
        // diagonal) and Lᵀ in its strict upper half, which the product reads as unit upper
        // triangular (a copy of L for B would cost another m × m array: 130 MB at L7). On
        // rayon's threads: 3.9 → 2.4 ms on L5 (medians of 8 runs) against a loop by columns on
        // one thread.
        let ls = SharedMat::of(&mut l);
        for_tiles_below(m, |i, j| {
            // SAFETY: (i, j) is below the diagonal in this task's columns, (j, i) above it in
            // its rows, and no task writes the diagonal.
            unsafe {
                let v = ls.get(i, j);
                ls.set(j, i, v);
                ls.set(i, j, v * ls.get(j, j));
            }
        });
        crate::trace::mark("delassus: L D");
        let mut w = zeros_in_parallel(m, m);
        matmul(
            w.as_mut(),
            BlockStructure::TriangularLower,
            faer::Accum::Replace,
            l.as_ref(),
            BlockStructure::TriangularLower,
            l.as_ref(),
            BlockStructure::UnitTriangularUpper,
            -1.0,
            factor_parallelism(),
        );
        crate::trace::mark("delassus: product");
        // The upper half from the lower.
        let ws = SharedMat::of(&mut w);
        // SAFETY: (j, i) is above the diagonal in this task's rows, (i, j) below it in its
        // columns: no task writes what another reads or writes.
        for_tiles_below(m, |i, j| unsafe { ws.set(j, i, ws.get(i, j)) });
        crate::trace::mark("delassus: symmetric");
        if !keep_factor {
            return Some((w, None));
        }
        Some((w, Some(cholesky_of_w(l))))
    }

    /// `L_MM` (dense, lower) with `D_MM` on its diagonal, from the constraint columns'
    /// supernodes.
    fn l_mm(&self) -> faer::Mat<f64> {
        let (n, m) = (self.n, self.m);
        let values = self.values();
        let mut l = zeros_in_parallel(m, m);
        for s in 0..self.layout.n_supernodes() {
            let node = self.layout.node(s, &values);
            copy_trailing(&mut l, n, node.start, node.ncols, node.pattern, |i, j| {
                node.at(i, j)
            });
        }
        l
    }

    /// `C = L_MM (−D_MM)^½` (lower, as [`cholesky_of_w`] gives it, the same bits) read
    /// straight from the last supernode when it holds every constraint column (as on every
    /// mesh of the ladder), else `None`; in `spare` when given ([`Spare`]).
    fn c_from_root(&self, values: &[f64], spare: Option<faer::Mat<f64>>) -> Option<faer::Mat<f64>> {
        let (n, m) = (self.n, self.m);
        let node = self
            .layout
            .node(self.layout.n_supernodes().checked_sub(1)?, values);
        if node.start > n || !node.pattern.is_empty() || node.start + node.ncols != n + m {
            return None;
        }
        let kk = n - node.start;
        Some(mat_filled_in(spare, m, m, true, |j, col| {
            let sj = (-node.at(kk + j, kk + j)).sqrt();
            col[j] = sj;
            for i in j + 1..m {
                col[i] = node.at(kk + i, kk + j) * sj;
            }
        }))
    }

    /// `D_MM`, the pivots of the constraint columns.
    fn d_mm(&self, values: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut d = Vec::with_capacity(self.m);
        for s in 0..self.layout.n_supernodes() {
            let node = self.layout.node(s, values);
            for j in 0..node.ncols {
                if node.start + j >= n {
                    d.push(node.at(j, j));
                }
            }
        }
        d
    }
}

/// Whether the constraint block's pivots `d` are all negative to working precision (`W`
/// positive definite, `Y` of full row rank).
fn negative_pivots(d: &[f64]) -> bool {
    let dmax = d.iter().map(|x| x.abs()).fold(0.0, f64::max);
    d.iter()
        .all(|x| x.partial_cmp(&(-1e-13 * dmax)) == Some(std::cmp::Ordering::Less))
}

/// `C = L_MM (−D_MM)^½` from `l`, which holds `D_MM` on its diagonal and `L_MMᵀ` (unit
/// diagonal) in its strict upper half: a lower Cholesky factor of `W`.
fn cholesky_of_w(mut l: faer::Mat<f64>) -> faer::Mat<f64> {
    let m = l.nrows();
    // C from the same array: column j of L (unit diagonal) is the strict upper half's row
    // j, scaled by (−d_j)^½; the strict upper half is cleared.
    let s: Vec<f64> = (0..m).map(|j| (-l[(j, j)]).sqrt()).collect();
    let ls = SharedMat::of(&mut l);
    // SAFETY: (i, j) is below the diagonal in this task's columns, (j, i) above it in its
    // rows: no task writes what another reads or writes.
    for_tiles_below(m, |i, j| unsafe { ls.set(i, j, ls.get(j, i) * s[j]) });
    for (j, &sj) in s.iter().enumerate() {
        l[(j, j)] = sj;
    }
    {
        use rayon::prelude::*;
        l.par_col_chunks_mut(TILE)
            .enumerate()
            .for_each(|(b, cols)| {
                let mut cols = cols;
                for c in 0..cols.ncols() {
                    let j = b * TILE + c;
                    for i in 0..j {
                        cols[(i, c)] = 0.0;
                    }
                }
            });
    }
    l
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The first factorisation on an analysis with at least [`SPARE_FROM`] constraint rows
    /// fills the arrays made during the analysis ([`Spare`]); a second one, on fresh memory,
    /// gives the same `W` and `C` bit for bit.
    #[test]
    fn the_arrays_made_during_the_analysis_give_the_same_delassus_operator() {
        let (n, m) = (1300, SPARE_FROM + 8);
        let (cp, ri, kv, _) = small_saddle(n);
        let y: Rows = (0..m).map(|i| vec![(i, 1.0), (i + 1, -0.5)]).collect();
        let sym = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
        let delassus = || {
            let f = sym.factorise(&kv, &y).unwrap();
            let (w, c) = f.delassus(true).expect("W positive definite");
            (w, c.expect("C from the root"))
        };
        let spare = |k: usize| sym.spare.0.lock().unwrap()[k].is_some();
        assert!(spare(0) && spare(1), "made during the analysis");
        let (w1, c1) = delassus();
        assert!(!spare(0) && !spare(1), "taken by the first factorisation");
        let (w2, c2) = delassus();
        assert_eq!(w1, w2);
        assert_eq!(c1, c2);
        // Without `C`, the factor does not keep its array either (130 MB at L7).
        let sym2 = SaddleSymbolic::analyse(n, &cp, &ri, &y).unwrap();
        let f = sym2.factorise(&kv, &y).unwrap();
        assert!(f.spare_c.lock().unwrap().is_some(), "handed to the factor");
        let (w3, c3) = f.delassus(false).expect("W positive definite");
        assert!(c3.is_none() && w3 == w1);
        assert!(f.spare_c.lock().unwrap().is_none(), "freed with W");
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
        let w_ref =
            |i: usize, j: usize| -> f64 { y[i].iter().map(|&(r, v)| v * solved[j][r]).sum() };
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
        let fwd = crate::ordering::nested_dissection(n, &col_ptr, &row_idx);
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
        assert!(
            (0..m * m).all(|k| w_alone[(k % m, k / m)].to_bits() == w[(k % m, k / m)].to_bits())
        );
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
        let st = crate::supernodal::Structure {
            begin: &lay.begin,
            row_ptr: &lay.row_ptr,
            rows: &lay.rows,
            val_ptr: &lay.val_ptr,
        };
        let (subtrees, top, widest) = crate::supernodal::schedule_shape(&st);
        assert!(
            subtrees >= 4 && top >= 2,
            "{subtrees} subtrees, {top} top supernodes"
        );
        assert!(
            widest >= crate::supernodal::SPLIT_COLUMNS,
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
    /// over), give each the bits of its own sweep on a grid's saddle factor, on either
    /// instruction set: among them a
    /// zero column, a column of negative zeros (whose entries the forward sweep must leave as
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
        let instruction_sets: &[&str] = if cfg!(target_arch = "x86_64") && crate::simd::avx2() {
            &["baseline", "avx2"]
        } else {
            &["baseline"]
        };
        for &set in instruction_sets {
            for ncols in 1..=9 {
                let mut x: Vec<f64> = (0..ncols).flat_map(column).collect();
                if set == "baseline" {
                    // `sweep_columns` without its run-time choice: the interleaved body itself.
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

    /// The sweeps compiled for AVX2 give the baseline's bits (and solve the system), on a 2-D
    /// grid whose supernodes have pattern rows enough for the vectorised sums.
    #[test]
    fn the_sweeps_give_the_same_bits_on_either_instruction_set() {
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
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            let mut wide = b.clone();
            // SAFETY: the processor has AVX2 (checked just above).
            unsafe { sweep_leading_avx2(&nodes, &mut wide, size) };
            assert!(
                wide.iter()
                    .zip(&base)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "AVX2 and baseline sweeps differ"
            );
        }
    }
}
