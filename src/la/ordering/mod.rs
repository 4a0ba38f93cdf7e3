//! Fill-reducing orderings of a symmetric sparse matrix for its Cholesky factorisation:
//! faer's approximate minimum degree ([`Ordering::Amd`]) and a nested dissection built here
//! ([`Ordering::NestedDissection`]), which faer 0.24 does not have.
//!
//! Nested dissection, as done by [`nested_dissection`]:
//!
//! 1. **Compression.** Unknowns with the same closed adjacency (the x and y DOFs of a node)
//!    are merged into one weighted vertex. Candidates are found by a hash of the closed
//!    neighbourhood; the merge is then checked exactly (every edge of the matrix graph is an
//!    edge of the blown-up vertex graph, and the two graphs have the same number of edges),
//!    and dropped if the check fails.
//! 2. **Dissection** of the vertex graph, one subgraph at a time, each cut multilevel:
//!    * coarsening by heavy-edge matching (vertices visited in a fixed pseudo-random order)
//!      down to about [`NdOptions::coarsest`] vertices; matching keeps components, so a
//!      disconnected subgraph is recognised on its coarsest graph and split into its
//!      components, ordered one after the other;
//!    * on the coarsest graph, vertex separators from the breadth-first level structures of
//!      [`NdOptions::initial_tries`] roots (a pseudo-peripheral vertex first): the lightest
//!      level, pruned to its vertices with a neighbour in the next level, whose sides are
//!      within the balance bound [`NdOptions::max_part_fraction`];
//!    * the best [`NdOptions::candidates`] of them are projected back level by level and
//!      improved on each by Fiduccia–Mattheyses passes (a separator vertex moves into a side
//!      and pulls its neighbours on the other side into the separator; the best state of a
//!      pass is kept); the best candidate wins.
//!
//!    The order is: part 1, part 2, separator last.
//! 3. **Leaves** (subgraphs of at most [`NdOptions::leaf_size`] vertices, or that cannot be
//!    cut) are ordered by faer's AMD on the leaf together with its halo (the neighbouring
//!    separator vertices, joined into a clique), so that the leaf's boundary is not taken
//!    for cheap and eliminated first.
//! 4. **Expansion**: each vertex's DOFs are numbered consecutively, in increasing order.
//!
//! The result depends only on the pattern: every cut is computed from its subgraph alone
//! (with a fixed pseudo-random seed), so the same pattern gives the same permutation on every
//! run and with any number of threads. The two parts of a large subgraph (and its
//! components) are ordered in parallel on rayon's pool.

mod dissect;
mod graph;
mod leaf;
mod options;
mod refine;
#[cfg(test)]
mod tests;

use dissect::dissect;
use graph::compress;
use leaf::amd_order;
pub use leaf::try_amd_order;
pub use options::NdOptions;

/// Which fill-reducing ordering to compute.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Ordering {
    /// faer's approximate minimum degree.
    #[default]
    Amd,
    /// [`nested_dissection`] with the default [`NdOptions`].
    NestedDissection,
}

impl Ordering {
    /// A short name: `AMD` or `ND`.
    pub fn name(self) -> &'static str {
        match self {
            Ordering::Amd => "AMD",
            Ordering::NestedDissection => "ND",
        }
    }
}

/// Fill-reducing ordering of kind `kind` of the symmetric matrix with this upper-triangular
/// CSC pattern; `fwd[new] = old`, as [`nested_dissection`].
///
/// # Panics
/// If faer's AMD runs out of memory or overflows its indices.
pub fn order(kind: Ordering, n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    match kind {
        Ordering::Amd => amd_order(n, col_ptr, row_idx),
        Ordering::NestedDissection => nested_dissection(n, col_ptr, row_idx),
    }
}

/// Fill-reducing ordering of a symmetric matrix given by its upper-triangular CSC pattern
/// (entries (r, c) with r <= c; the diagonal may or may not be present).
/// Returns `fwd` with fwd[new] = old, in the convention faer's `PermRef::new_checked(fwd, inv, n)`
/// expects for `SymmetricOrdering::Custom` (verify the convention by a test).
///
/// Entries with r > c are ignored; rows may be unsorted and repeated. See the module
/// documentation for the algorithm.
///
/// # Panics
/// If `col_ptr` has fewer than `n + 1` entries, if `n` does not fit in 32 bits, or if faer's
/// AMD (on a leaf) runs out of memory.
pub fn nested_dissection(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    nested_dissection_with(n, col_ptr, row_idx, &NdOptions::default())
}

/// [`nested_dissection`] with explicit tuning.
pub fn nested_dissection_with(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    opts: &NdOptions,
) -> Vec<usize> {
    assert!(col_ptr.len() > n, "col_ptr has fewer than n + 1 entries");
    if n == 0 {
        return Vec::new();
    }
    let (g, dof_ptr, dofs) = compress(n, col_ptr, row_idx);
    let nv = g.n();
    let ids: Vec<u32> = (0..nv as u32).collect();
    let vorder = dissect(g.clone(), ids, opts, &g);
    debug_assert_eq!(vorder.len(), nv);
    let mut fwd = Vec::with_capacity(n);
    for &v in &vorder {
        let v = v as usize;
        fwd.extend_from_slice(&dofs[dof_ptr[v]..dof_ptr[v + 1]]);
    }
    debug_assert_eq!(fwd.len(), n);
    fwd
}

/// Column counts of the Cholesky factor `L` of `P A Pᵀ` (`(P A Pᵀ)[i][j] = A[fwd[i]][fwd[j]]`),
/// diagonal included, from the upper-triangular CSC pattern of `A` (entries with r > c are
/// ignored). `Σ counts` is nnz(L) and `Σ counts²` the usual flop measure of the factorisation.
pub fn cholesky_column_counts(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    fwd: &[usize],
) -> Vec<usize> {
    assert_eq!(fwd.len(), n);
    let mut inv = vec![usize::MAX; n];
    for (k, &o) in fwd.iter().enumerate() {
        assert!(o < n && inv[o] == usize::MAX, "fwd is not a permutation");
        inv[o] = k;
    }
    // Upper pattern of P A Pᵀ, column by column (rows unsorted, duplicates harmless).
    let mut cp = vec![0usize; n + 1];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r < c {
                cp[inv[r].max(inv[c]) + 1] += 1;
            }
        }
    }
    for j in 0..n {
        cp[j + 1] += cp[j];
    }
    let mut ri = vec![0u32; cp[n]];
    let mut next = cp.clone();
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            if r < c {
                let (i, j) = (inv[r].min(inv[c]), inv[r].max(inv[c]));
                ri[next[j]] = i as u32;
                next[j] += 1;
            }
        }
    }
    // Row subtrees of the elimination tree (Liu): each step adds one entry of L.
    const NONE: usize = usize::MAX;
    let mut parent = vec![NONE; n];
    let mut visited = vec![NONE; n];
    let mut counts = vec![1usize; n];
    for j in 0..n {
        visited[j] = j;
        for &i in &ri[cp[j]..cp[j + 1]] {
            let mut i = i as usize;
            while visited[i] != j {
                visited[i] = j;
                counts[i] += 1;
                if parent[i] == NONE {
                    parent[i] = j;
                }
                i = parent[i];
            }
        }
    }
    counts
}

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
pub fn ordering_choice(n: usize) -> Ordering {
    match ordering_policy() {
        "nd" => Ordering::NestedDissection,
        "amd" => Ordering::Amd,
        _ if n >= ND_FROM => Ordering::NestedDissection,
        _ => Ordering::Amd,
    }
}
