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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

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

/// faer's AMD of the pattern `A + Aᵀ` (rows may be unsorted).
fn amd_order(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    let mut fwd = vec![0usize; n];
    let mut inv = vec![0usize; n];
    if n == 0 {
        return fwd;
    }
    let a = SymbolicSparseColMatRef::new_unsorted_checked(
        n,
        n,
        &col_ptr[..=n],
        None,
        &row_idx[..col_ptr[n]],
    );
    let mut mem = MemBuffer::new(amd::order_maybe_unsorted_scratch::<usize>(n, col_ptr[n]));
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        a,
        Default::default(),
        MemStack::new(&mut mem),
    )
    .expect("AMD ordering failed (out of memory or index overflow)");
    fwd
}

/// Tuning of [`nested_dissection_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct NdOptions {
    /// Subgraphs of at most this many vertices (compressed nodes) are ordered by AMD.
    pub leaf_size: usize,
    /// Largest part weight, as a fraction of the subgraph's weight (0.5 < f < 1).
    pub max_part_fraction: f64,
    /// Coarsening stops at this many vertices.
    pub coarsest: usize,
    /// Initial separators tried on the coarsest graph (level structures of as many roots).
    pub initial_tries: usize,
    /// The best this many initial separators are refined level by level …
    pub candidates: usize,
    /// … on the levels of at most this many vertices; beyond, only the best one.
    pub candidates_up_to: usize,
    /// At most this many Fiduccia–Mattheyses passes per level.
    pub fm_passes: usize,
    /// A pass stops after this many moves without a better separator.
    pub fm_patience: usize,
}

impl Default for NdOptions {
    fn default() -> Self {
        NdOptions {
            leaf_size: 128,
            max_part_fraction: 0.6,
            coarsest: 120,
            initial_tries: 8,
            candidates: 2,
            candidates_up_to: 2000,
            fm_passes: 6,
            fm_patience: 100,
        }
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

/// A vertex- and edge-weighted graph: symmetric adjacency without self loops.
#[derive(Clone)]
struct Graph {
    xadj: Vec<usize>,
    adj: Vec<u32>,
    /// Edge weights, parallel to `adj`; empty when they are all 1.
    ew: Vec<u32>,
    /// Vertex weights (number of DOFs).
    vw: Vec<u32>,
}

impl Graph {
    #[inline]
    fn n(&self) -> usize {
        self.vw.len()
    }

    #[inline]
    fn nbrs(&self, v: usize) -> &[u32] {
        &self.adj[self.xadj[v]..self.xadj[v + 1]]
    }

    fn total(&self) -> u64 {
        self.vw.iter().map(|&w| w as u64).sum()
    }

    /// The subgraphs induced by the parts `part[v] < nparts` (other vertices are dropped),
    /// each with its vertices in increasing order, and their numbers in `self`.
    fn split(&self, part: &[u32], nparts: usize) -> Vec<(Graph, Vec<u32>)> {
        let n = self.n();
        let mut nv = vec![0usize; nparts];
        let mut ne = vec![0usize; nparts];
        for v in 0..n {
            let p = part[v] as usize;
            if p < nparts {
                nv[p] += 1;
                ne[p] += self.xadj[v + 1] - self.xadj[v];
            }
        }
        let mut local = vec![0u32; n];
        let mut out: Vec<(Graph, Vec<u32>)> = (0..nparts)
            .map(|p| {
                let mut xadj = Vec::with_capacity(nv[p] + 1);
                xadj.push(0);
                (
                    Graph {
                        xadj,
                        adj: Vec::with_capacity(ne[p]),
                        ew: Vec::new(),
                        vw: Vec::with_capacity(nv[p]),
                    },
                    Vec::with_capacity(nv[p]),
                )
            })
            .collect();
        for v in 0..n {
            let p = part[v] as usize;
            if p < nparts {
                local[v] = out[p].1.len() as u32;
                out[p].1.push(v as u32);
            }
        }
        let weighted = !self.ew.is_empty();
        for v in 0..n {
            let p = part[v] as usize;
            if p >= nparts {
                continue;
            }
            let g = &mut out[p].0;
            for k in self.xadj[v]..self.xadj[v + 1] {
                let u = self.adj[k] as usize;
                if part[u] as usize == p {
                    g.adj.push(local[u]);
                    if weighted {
                        g.ew.push(self.ew[k]);
                    }
                }
            }
            g.xadj.push(g.adj.len());
            g.vw.push(self.vw[v]);
        }
        out
    }

    /// Weight of edge `k` (position in `adj`).
    #[inline]
    fn ew(&self, k: usize) -> u32 {
        if self.ew.is_empty() { 1 } else { self.ew[k] }
    }
}

#[inline]
fn mix(x: u64) -> u64 {
    // splitmix64 finaliser
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

type Compressed = (Graph, Vec<usize>, Vec<usize>);

/// Merges indistinguishable DOFs into vertices (see the module documentation).
/// The vertex graph, and the DOFs of each vertex (`dofs[dof_ptr[v]..dof_ptr[v + 1]]`).
fn compress(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Compressed {
    assert!(
        n < u32::MAX as usize,
        "matrix too large for 32-bit vertex indices"
    );
    let col = |c: usize| &row_idx[col_ptr[c]..col_ptr[c + 1]];
    // Closed-neighbourhood hash and degree; distinct off-diagonal edges.
    let hv: Vec<u64> = (0..n as u64).map(mix).collect();
    let mut h = hv.clone();
    let mut deg = vec![0u32; n];
    let mut mark = vec![usize::MAX; n];
    let mut n_edges = 0u64;
    for c in 0..n {
        for &r in col(c) {
            if r >= c || mark[r] == c {
                continue;
            }
            mark[r] = c;
            n_edges += 1;
            deg[r] += 1;
            deg[c] += 1;
            h[r] = h[r].wrapping_add(hv[c]);
            h[c] = h[c].wrapping_add(hv[r]);
        }
    }
    let mut idx: Vec<u32> = (0..n as u32).collect();
    idx.sort_unstable_by_key(|&i| (h[i as usize], deg[i as usize], i));
    let mut rep: Vec<u32> = (0..n as u32).collect();
    for run in
        idx.chunk_by(|&a, &b| (h[a as usize], deg[a as usize]) == (h[b as usize], deg[b as usize]))
    {
        for &i in &run[1..] {
            rep[i as usize] = run[0];
        }
    }
    drop((hv, h, deg, idx));
    if let Some(g) = quotient(n, col_ptr, row_idx, &rep, n_edges, &mut mark) {
        return g;
    }
    let rep: Vec<u32> = (0..n as u32).collect();
    quotient(n, col_ptr, row_idx, &rep, n_edges, &mut mark).expect("the trivial grouping")
}

/// The vertex graph of the grouping `rep` (DOF → representative, the smallest DOF of its
/// group), or `None` if the groups are not indistinguishable.
fn quotient(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
    rep: &[u32],
    n_edges: u64,
    mark: &mut [usize],
) -> Option<Compressed> {
    let col = |c: usize| &row_idx[col_ptr[c]..col_ptr[c + 1]];
    let mut vid = vec![0u32; n];
    let mut nv = 0usize;
    for i in 0..n {
        let r = rep[i] as usize;
        if r == i {
            vid[i] = nv as u32;
            nv += 1;
        } else {
            vid[i] = vid[r];
        }
    }
    let mut w = vec![0u32; nv];
    for i in 0..n {
        w[vid[i] as usize] += 1;
    }
    // Edges between representatives.
    mark.fill(usize::MAX);
    let mut xadj = vec![0usize; nv + 1];
    for c in 0..n {
        if rep[c] as usize != c {
            continue;
        }
        for &r in col(c) {
            if r >= c || mark[r] == c || rep[r] as usize != r {
                continue;
            }
            mark[r] = c;
            xadj[vid[r] as usize + 1] += 1;
            xadj[vid[c] as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        xadj[v + 1] += xadj[v];
    }
    let mut adj = vec![0u32; xadj[nv]];
    let mut next = xadj.clone();
    mark.fill(usize::MAX);
    for c in 0..n {
        if rep[c] as usize != c {
            continue;
        }
        for &r in col(c) {
            if r >= c || mark[r] == c || rep[r] as usize != r {
                continue;
            }
            mark[r] = c;
            let (vr, vc) = (vid[r] as usize, vid[c] as usize);
            adj[next[vr]] = vc as u32;
            next[vr] += 1;
            adj[next[vc]] = vr as u32;
            next[vc] += 1;
        }
    }
    drop(next);
    // Sorted neighbour lists: the ordering does not depend on the order of the rows.
    for v in 0..nv {
        adj[xadj[v]..xadj[v + 1]].sort_unstable();
    }
    // Exact check: every edge of the DOF graph is an edge of the blown-up vertex graph, and
    // the two have the same number of edges.
    if nv < n {
        let mut expected = 0u64;
        for v in 0..nv {
            let s = w[v] as u64;
            expected += s * (s - 1) / 2;
            for &u in &adj[xadj[v]..xadj[v + 1]] {
                if (u as usize) < v {
                    expected += s * w[u as usize] as u64;
                }
            }
        }
        if expected != n_edges {
            return None;
        }
        let mut qmark = vec![u32::MAX; nv];
        mark.fill(usize::MAX);
        for c in 0..n {
            let vc = vid[c];
            qmark[vc as usize] = c as u32;
            for &u in &adj[xadj[vc as usize]..xadj[vc as usize + 1]] {
                qmark[u as usize] = c as u32;
            }
            for &r in col(c) {
                if r < c && qmark[vid[r] as usize] != c as u32 {
                    return None;
                }
            }
        }
    }
    let mut dof_ptr = vec![0usize; nv + 1];
    for v in 0..nv {
        dof_ptr[v + 1] = dof_ptr[v] + w[v] as usize;
    }
    let mut dofs = vec![0usize; n];
    let mut next = dof_ptr.clone();
    for i in 0..n {
        let v = vid[i] as usize;
        dofs[next[v]] = i;
        next[v] += 1;
    }
    Some((
        Graph {
            xadj,
            adj,
            ew: Vec::new(),
            vw: w,
        },
        dof_ptr,
        dofs,
    ))
}

/// Side of a vertex in a bisection.
const A: u8 = 0;
const B: u8 = 1;
const SEP: u8 = 2;

/// How a graph is cut.
enum Cut {
    /// It is disconnected: the component of each vertex, and their number.
    Components(Vec<u32>, usize),
    /// A vertex separator: the side of each vertex (`A`, `B` or `SEP`).
    Separator(Vec<u8>),
}

/// Subgraphs of at least this many vertices have their parts ordered in parallel (the
/// result does not depend on it).
const PARALLEL_MIN: usize = 4096;

/// The nested-dissection order of the graph `g`, whose vertices are the vertices `ids`
/// (increasing) of the whole compressed graph `top`: those ids in elimination order.
fn dissect(g: Graph, ids: Vec<u32>, opts: &NdOptions, top: &Graph) -> Vec<u32> {
    let n = g.n();
    if n <= opts.leaf_size.max(3) {
        return leaf(&g, &ids, top);
    }
    let to_ids = |l: Vec<u32>| l.iter().map(|&v| ids[v as usize]).collect::<Vec<u32>>();
    match bisect(&g, opts) {
        Cut::Components(comp, ncomp) => {
            let subs: Vec<(Graph, Vec<u32>)> = g
                .split(&comp, ncomp)
                .into_iter()
                .map(|(sub, local)| (sub, to_ids(local)))
                .collect();
            drop(g);
            let orders: Vec<Vec<u32>> = if n >= PARALLEL_MIN {
                use rayon::prelude::*;
                subs.into_par_iter()
                    .map(|(sub, sub_ids)| dissect(sub, sub_ids, opts, top))
                    .collect()
            } else {
                subs.into_iter()
                    .map(|(sub, sub_ids)| dissect(sub, sub_ids, opts, top))
                    .collect()
            };
            orders.concat()
        }
        Cut::Separator(side) => {
            let na = side.iter().filter(|&&s| s == A).count();
            let nb = side.iter().filter(|&&s| s == B).count();
            if na == 0 || nb == 0 {
                // No cut was found: a leaf after all.
                return leaf(&g, &ids, top);
            }
            let sep: Vec<u32> = (0..n).filter(|&v| side[v] == SEP).map(|v| ids[v]).collect();
            let part: Vec<u32> = side.iter().map(|&s| s as u32).collect();
            let mut parts = g.split(&part, 2);
            drop(g);
            let (gb, lb) = parts.pop().unwrap();
            let (ga, la) = parts.pop().unwrap();
            let (ia, ib) = (to_ids(la), to_ids(lb));
            let (oa, ob) = if n >= PARALLEL_MIN {
                rayon::join(|| dissect(ga, ia, opts, top), || dissect(gb, ib, opts, top))
            } else {
                (dissect(ga, ia, opts, top), dissect(gb, ib, opts, top))
            };
            let mut out = Vec::with_capacity(n);
            out.extend_from_slice(&oa);
            out.extend_from_slice(&ob);
            out.extend_from_slice(&sep);
            out
        }
    }
}

/// Connected components: the component of each vertex (numbered in the order of their
/// smallest vertex) and their number.
fn components(g: &Graph) -> (Vec<u32>, usize) {
    let n = g.n();
    let mut comp = vec![u32::MAX; n];
    let mut queue = Vec::with_capacity(n);
    let mut nc = 0u32;
    for s in 0..n {
        if comp[s] != u32::MAX {
            continue;
        }
        comp[s] = nc;
        queue.clear();
        queue.push(s as u32);
        let mut head = 0;
        while head < queue.len() {
            let v = queue[head] as usize;
            head += 1;
            for &u in g.nbrs(v) {
                if comp[u as usize] == u32::MAX {
                    comp[u as usize] = nc;
                    queue.push(u);
                }
            }
        }
        nc += 1;
    }
    (comp, nc as usize)
}

/// Cuts `g`, multilevel: the graph is coarsened by heavy-edge matching (which keeps its
/// components: they are found on the coarsest graph); a connected coarsest graph is cut by
/// level-structure separators from several roots, the best `opts.candidates` of which are
/// refined level by level on the way back (only the best one beyond
/// `opts.candidates_up_to` vertices).
fn bisect(g: &Graph, opts: &NdOptions) -> Cut {
    let maxpw = ((g.total() as f64) * opts.max_part_fraction).ceil() as i64;
    let maxvw = (1.5 * g.total() as f64 / opts.coarsest.max(1) as f64).ceil() as u64;
    let mut coarse: Vec<(Graph, Vec<u32>)> = Vec::new();
    let mut seed = 0x2545_F491_4F6C_DD1Du64 ^ g.n() as u64;
    loop {
        let cur = coarse.last().map_or(g, |c| &c.0);
        if cur.n() <= opts.coarsest {
            break;
        }
        let (c, cmap) = coarsen(cur, maxvw, &mut seed);
        if c.n() as f64 > 0.95 * cur.n() as f64 {
            break;
        }
        coarse.push((c, cmap));
    }
    let coarsest = coarse.last().map_or(g, |c| &c.0);
    let (mut comp, ncomp) = components(coarsest);
    if ncomp > 1 {
        for (_, cmap) in coarse.iter().rev() {
            comp = cmap.iter().map(|&c| comp[c as usize]).collect();
        }
        return Cut::Components(comp, ncomp);
    }
    let mut ws = Workspace::new(g.n());
    // Candidates: (score, side, weights) on the current level.
    let mut cands: Vec<(Score, Vec<u8>, [i64; 3])> = initial_separators(coarsest, maxpw, opts)
        .into_iter()
        .take(opts.candidates.max(1))
        .map(|side| {
            let pw = part_weights(coarsest, &side);
            (score(&pw, maxpw), side, pw)
        })
        .collect();
    let best_of =
        |cands: &[(Score, Vec<u8>, [i64; 3])]| (0..cands.len()).min_by_key(|&i| (cands[i].0, i));
    for level in (0..=coarse.len()).rev() {
        let fine = if level == 0 { g } else { &coarse[level - 1].0 };
        if fine.n() > opts.candidates_up_to && cands.len() > 1 {
            let b = best_of(&cands).unwrap();
            cands.swap(0, b);
            cands.truncate(1);
        }
        for (s, side, pw) in cands.iter_mut() {
            let mut seps = Vec::new();
            if level < coarse.len() {
                let cmap = &coarse[level].1;
                *side = cmap.iter().map(|&c| side[c as usize]).collect();
            }
            seps.extend((0..fine.n() as u32).filter(|&v| side[v as usize] == SEP));
            *s = refine(fine, side, pw, &mut seps, maxpw, opts, &mut ws);
        }
    }
    match best_of(&cands) {
        Some(b) => Cut::Separator(cands.swap_remove(b).1),
        None => Cut::Separator(vec![SEP; g.n()]),
    }
}

/// xorshift64*
fn next_random(s: &mut u64) -> u64 {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    s.wrapping_mul(0x2545_F491_4F6C_DD1D)
}

/// One level of coarsening: heavy-edge matching (vertices visited in a pseudo-random order
/// from `seed`, coarse vertices no heavier than `maxvw`), and the coarse graph with summed
/// vertex and edge weights; `cmap[v]` is the coarse vertex of `v`.
fn coarsen(g: &Graph, maxvw: u64, seed: &mut u64) -> (Graph, Vec<u32>) {
    let n = g.n();
    let mut perm: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (((next_random(seed) >> 32) * (i as u64 + 1)) >> 32) as usize;
        perm.swap(i, j);
    }
    let unit = g.ew.is_empty();
    let mut mate = vec![NONE; n];
    for &v in &perm {
        let v = v as usize;
        if mate[v] != NONE {
            continue;
        }
        let mut best = v;
        let mut best_w = 0u32;
        for k in g.xadj[v]..g.xadj[v + 1] {
            let u = g.adj[k] as usize;
            if mate[u] == NONE && g.ew(k) > best_w && g.vw[v] as u64 + g.vw[u] as u64 <= maxvw {
                best = u;
                best_w = g.ew(k);
                if unit {
                    break; // all edges weigh 1: the first free neighbour is a heaviest
                }
            }
        }
        mate[v] = best as u32;
        mate[best] = v as u32;
    }
    let mut cmap = vec![NONE; n];
    let mut cn = 0u32;
    for v in 0..n {
        if cmap[v] == NONE {
            cmap[v] = cn;
            cmap[mate[v] as usize] = cn;
            cn += 1;
        }
    }
    let cn = cn as usize;
    let mut c = Graph {
        xadj: Vec::with_capacity(cn + 1),
        adj: Vec::with_capacity(g.adj.len()),
        ew: Vec::with_capacity(g.adj.len()),
        vw: Vec::with_capacity(cn),
    };
    c.xadj.push(0);
    let mut slot = vec![NONE; cn];
    for v in 0..n {
        let cv = cmap[v] as usize;
        if cv != c.vw.len() {
            continue; // the second vertex of a pair
        }
        let start = c.adj.len();
        let u = mate[v] as usize;
        let mut w = g.vw[v];
        let members = if u == v { [v, v] } else { [v, u] };
        for (m, &x) in members.iter().enumerate() {
            if m == 1 {
                if u == v {
                    break;
                }
                w += g.vw[x];
            }
            for k in g.xadj[x]..g.xadj[x + 1] {
                let cu = cmap[g.adj[k] as usize] as usize;
                if cu == cv {
                    continue;
                }
                let s = slot[cu];
                if s != NONE && s as usize >= start {
                    c.ew[s as usize] += g.ew(k);
                } else {
                    slot[cu] = c.adj.len() as u32;
                    c.adj.push(cu as u32);
                    c.ew.push(g.ew(k));
                }
            }
        }
        c.vw.push(w);
        c.xadj.push(c.adj.len());
    }
    (c, cmap)
}

/// Breadth-first level structure of `g` from `root`: the vertices in visiting order,
/// `level_ptr` (level k is `order[level_ptr[k]..level_ptr[k + 1]]`) and the level of each
/// vertex in `dist`.
fn bfs(g: &Graph, root: usize, order: &mut Vec<u32>, level_ptr: &mut Vec<usize>, dist: &mut [u32]) {
    dist.fill(u32::MAX);
    order.clear();
    level_ptr.clear();
    level_ptr.push(0);
    order.push(root as u32);
    dist[root] = 0;
    let mut start = 0;
    let mut lvl = 0u32;
    while start < order.len() {
        let end = order.len();
        level_ptr.push(end);
        lvl += 1;
        for i in start..end {
            let v = order[i] as usize;
            for &u in g.nbrs(v) {
                if dist[u as usize] == u32::MAX {
                    dist[u as usize] = lvl;
                    order.push(u);
                }
            }
        }
        start = end;
    }
}

/// Smaller is better: (infeasible, separator weight, imbalance).
type Score = (bool, i64, i64);

fn score(pw: &[i64; 3], maxpw: i64) -> Score {
    (pw[0].max(pw[1]) > maxpw, pw[2], (pw[0] - pw[1]).abs())
}

fn part_weights(g: &Graph, side: &[u8]) -> [i64; 3] {
    let mut pw = [0i64; 3];
    for v in 0..g.n() {
        pw[side[v] as usize] += g.vw[v] as i64;
    }
    pw
}

/// Level-structure separators of the (small, connected) graph `g` from
/// `opts.initial_tries` roots (a pseudo-peripheral vertex, then vertices spread over the
/// numbering), distinct, best first.
fn initial_separators(g: &Graph, maxpw: i64, opts: &NdOptions) -> Vec<Vec<u8>> {
    let n = g.n();
    let (mut order, mut level_ptr, mut dist) = (Vec::new(), Vec::new(), vec![0u32; n]);
    // Pseudo-peripheral vertex (George & Liu).
    let mut root = 0usize;
    bfs(g, root, &mut order, &mut level_ptr, &mut dist);
    for _ in 0..8 {
        let nlev = level_ptr.len() - 1;
        let cand = *order[level_ptr[nlev - 1]..]
            .iter()
            .min_by_key(|&&v| (g.xadj[v as usize + 1] - g.xadj[v as usize], v))
            .unwrap() as usize;
        bfs(g, cand, &mut order, &mut level_ptr, &mut dist);
        root = cand;
        if level_ptr.len() - 1 <= nlev {
            break;
        }
    }
    let tries = opts.initial_tries.max(1);
    let mut all: Vec<(Score, usize, Vec<u8>)> = Vec::new();
    let mut side = vec![SEP; n];
    for t in 0..tries {
        let r = if t == 0 {
            root
        } else {
            (t - 1) * n / (tries - 1).max(1)
        };
        bfs(g, r, &mut order, &mut level_ptr, &mut dist);
        if level_separator(g, &order, &level_ptr, &dist, maxpw, &mut side)
            && !all.iter().any(|a| a.2 == side)
        {
            all.push((score(&part_weights(g, &side), maxpw), t, side.clone()));
        }
    }
    all.sort_by_key(|a| (a.0, a.1));
    all.into_iter().map(|a| a.2).collect()
}

/// A separator from a level structure: the level of smallest weight, pruned to its vertices
/// with a neighbour in the next level, whose sides respect `maxpw` (else the level where the
/// cumulative weight crosses half). False if there are fewer than three levels.
fn level_separator(
    g: &Graph,
    order: &[u32],
    level_ptr: &[usize],
    dist: &[u32],
    maxpw: i64,
    side: &mut [u8],
) -> bool {
    let nlev = level_ptr.len() - 1;
    if nlev < 3 {
        return false;
    }
    let total = g.total() as i64;
    let touches_next = |v: u32, k: u32| {
        g.nbrs(v as usize)
            .iter()
            .any(|&u| dist[u as usize] == k + 1)
    };
    let mut best: Option<(i64, i64, usize)> = None;
    let mut half = None;
    let mut before = 0i64;
    for k in 0..nlev {
        let level = &order[level_ptr[k]..level_ptr[k + 1]];
        let lw: i64 = level.iter().map(|&v| g.vw[v as usize] as i64).sum();
        if half.is_none() && 2 * (before + lw) > total {
            half = Some(k);
        }
        if k >= 1 && k + 1 < nlev {
            let sep: i64 = level
                .iter()
                .filter(|&&v| touches_next(v, k as u32))
                .map(|&v| g.vw[v as usize] as i64)
                .sum();
            let wa = before + lw - sep;
            let wb = total - before - lw;
            let key = (sep, (wa - wb).abs(), k);
            if wa.max(wb) <= maxpw && best.is_none_or(|b| (key.0, key.1) < (b.0, b.1)) {
                best = Some(key);
            }
        }
        before += lw;
    }
    let k = best.map_or_else(|| half.unwrap_or(nlev / 2).clamp(1, nlev - 2), |b| b.2) as u32;
    for v in 0..g.n() {
        let d = dist[v];
        side[v] = if d < k {
            A
        } else if d > k {
            B
        } else if touches_next(v as u32, k) {
            SEP
        } else {
            A
        };
    }
    true
}

/// An indexed max-heap of vertices keyed by gain (ties: the smaller vertex first).
struct Heap {
    heap: Vec<(i64, u32)>,
    /// Position of each vertex in `heap`, or `NONE`.
    loc: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl Heap {
    fn new(n: usize) -> Self {
        Heap {
            heap: Vec::new(),
            loc: vec![NONE; n],
        }
    }

    #[inline]
    fn above(a: (i64, u32), b: (i64, u32)) -> bool {
        a.0 > b.0 || (a.0 == b.0 && a.1 < b.1)
    }

    fn top(&self) -> Option<(i64, u32)> {
        self.heap.first().copied()
    }

    fn set(&mut self, v: u32, key: i64) {
        let p = self.loc[v as usize];
        if p == NONE {
            self.heap.push((key, v));
            let i = self.heap.len() - 1;
            self.loc[v as usize] = i as u32;
            self.up(i);
        } else {
            let old = self.heap[p as usize].0;
            self.heap[p as usize].0 = key;
            if key > old {
                self.up(p as usize);
            } else {
                self.down(p as usize);
            }
        }
    }

    fn remove(&mut self, v: u32) {
        let p = self.loc[v as usize];
        if p == NONE {
            return;
        }
        let p = p as usize;
        self.loc[v as usize] = NONE;
        let last = self.heap.pop().unwrap();
        if p < self.heap.len() {
            self.heap[p] = last;
            self.loc[last.1 as usize] = p as u32;
            self.up(p);
            let p = self.loc[last.1 as usize] as usize;
            self.down(p);
        }
    }

    fn clear(&mut self) {
        for &(_, v) in &self.heap {
            self.loc[v as usize] = NONE;
        }
        self.heap.clear();
    }

    fn up(&mut self, mut i: usize) {
        let x = self.heap[i];
        while i > 0 {
            let p = (i - 1) / 2;
            if !Self::above(x, self.heap[p]) {
                break;
            }
            self.heap[i] = self.heap[p];
            self.loc[self.heap[i].1 as usize] = i as u32;
            i = p;
        }
        self.heap[i] = x;
        self.loc[x.1 as usize] = i as u32;
    }

    fn down(&mut self, mut i: usize) {
        let n = self.heap.len();
        let x = self.heap[i];
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let c = if l + 1 < n && Self::above(self.heap[l + 1], self.heap[l]) {
                l + 1
            } else {
                l
            };
            if !Self::above(self.heap[c], x) {
                break;
            }
            self.heap[i] = self.heap[c];
            self.loc[self.heap[i].1 as usize] = i as u32;
            i = c;
        }
        self.heap[i] = x;
        self.loc[x.1 as usize] = i as u32;
    }
}

/// Scratch of [`refine`], sized for the finest graph of a bisection and reused on every
/// level.
struct Workspace {
    heaps: [Heap; 2],
    gain: Vec<[i64; 2]>,
    locked: Vec<bool>,
    mark: Vec<bool>,
}

impl Workspace {
    fn new(n: usize) -> Self {
        Workspace {
            heaps: [Heap::new(n), Heap::new(n)],
            gain: vec![[0; 2]; n],
            locked: vec![false; n],
            mark: vec![false; n],
        }
    }
}

/// Fiduccia–Mattheyses refinement of the vertex separator `side` of `g` (two-sided: a
/// separator vertex moves into either side, its neighbours on the other side enter the
/// separator), keeping the best state of each pass. `pw` are the weights of the sides and
/// the separator, `seps` the separator's vertices; both are kept up to date. Returns the
/// final score.
fn refine(
    g: &Graph,
    side: &mut [u8],
    pw: &mut [i64; 3],
    seps: &mut Vec<u32>,
    maxpw: i64,
    opts: &NdOptions,
    ws: &mut Workspace,
) -> Score {
    let w = |v: u32| g.vw[v as usize] as i64;
    // Gain of moving separator vertex v to side t: its weight less the weight of its
    // neighbours on the other side (which enter the separator).
    let gains = |side: &[u8], v: u32| {
        let mut pull = [0i64; 2];
        for &u in g.nbrs(v as usize) {
            let s = side[u as usize];
            if s != SEP {
                pull[s as usize] += w(u);
            }
        }
        [w(v) - pull[1], w(v) - pull[0]]
    };
    let Workspace {
        heaps,
        gain,
        locked,
        mark,
    } = ws;
    let mut moves: Vec<(u32, u8, usize)> = Vec::new();
    let mut pulled: Vec<u32> = Vec::new();
    let mut moved: Vec<u32> = Vec::new();
    for _ in 0..opts.fm_passes {
        let start_score = score(pw, maxpw);
        let limit = (seps.len() / 2).clamp(5, opts.fm_patience.max(5));
        for &v in seps.iter() {
            let gv = gains(side, v);
            gain[v as usize] = gv;
            heaps[0].set(v, gv[0]);
            heaps[1].set(v, gv[1]);
        }
        // Move log: (vertex, side it moved to, end of the vertices it pulled in `pulled`).
        moves.clear();
        pulled.clear();
        moved.clear();
        let mut best = (start_score, 0usize);
        let mut since_best = 0usize;
        loop {
            let mut cand: [Option<(i64, u32)>; 2] = [None, None];
            for t in 0..2 {
                if let Some((gv, v)) = heaps[t].top()
                    && pw[t] + w(v) <= maxpw
                {
                    cand[t] = Some((gv, v));
                }
            }
            let to = match (cand[0], cand[1]) {
                (None, None) => break,
                (Some(_), None) => 0,
                (None, Some(_)) => 1,
                (Some(a), Some(b)) => usize::from(!(a.0 > b.0 || (a.0 == b.0 && pw[0] <= pw[1]))),
            };
            let (_, v) = cand[to].unwrap();
            let other = 1 - to;
            heaps[0].remove(v);
            heaps[1].remove(v);
            side[v as usize] = to as u8;
            locked[v as usize] = true;
            moved.push(v);
            pw[2] -= w(v);
            pw[to] += w(v);
            // Separator neighbours of v now pull v if they move to `other`.
            for &x in g.nbrs(v as usize) {
                let xi = x as usize;
                if side[xi] == SEP && !locked[xi] {
                    gain[xi][other] -= w(v);
                    heaps[other].set(x, gain[xi][other]);
                }
            }
            // v's neighbours on the other side enter the separator.
            for &u in g.nbrs(v as usize) {
                let ui = u as usize;
                if side[ui] != other as u8 {
                    continue;
                }
                side[ui] = SEP;
                pw[other] -= w(u);
                pw[2] += w(u);
                pulled.push(u);
                for &x in g.nbrs(ui) {
                    let xi = x as usize;
                    if side[xi] == SEP && !locked[xi] {
                        gain[xi][to] += w(u);
                        heaps[to].set(x, gain[xi][to]);
                    }
                }
                if !locked[ui] {
                    let gu = gains(side, u);
                    gain[ui] = gu;
                    heaps[0].set(u, gu[0]);
                    heaps[1].set(u, gu[1]);
                }
            }
            moves.push((v, to as u8, pulled.len()));
            let s = score(pw, maxpw);
            if s < best.0 {
                best = (s, moves.len());
                since_best = 0;
            } else {
                since_best += 1;
                if since_best > limit {
                    break;
                }
            }
        }
        heaps[0].clear();
        heaps[1].clear();
        // Roll back to the best state.
        while moves.len() > best.1 {
            let (v, to, end) = moves.pop().unwrap();
            let begin = moves.last().map_or(0, |m| m.2);
            let other = 1 - to;
            for &u in &pulled[begin..end] {
                side[u as usize] = other;
                pw[other as usize] += w(u);
                pw[2] -= w(u);
            }
            pulled.truncate(begin);
            side[v as usize] = SEP;
            pw[to as usize] -= w(v);
            pw[2] += w(v);
        }
        for &v in &moved {
            locked[v as usize] = false;
        }
        // The separator now: the old one less the vertices that left it, plus those pulled
        // in (and not rolled back), once each.
        let mut next = Vec::with_capacity(seps.len() + pulled.len());
        for &v in seps.iter().chain(moved.iter()).chain(pulled.iter()) {
            if side[v as usize] == SEP && !mark[v as usize] {
                mark[v as usize] = true;
                next.push(v);
            }
        }
        for &v in &next {
            mark[v as usize] = false;
        }
        *seps = next;
        if best.0 >= start_score {
            break;
        }
    }
    score(pw, maxpw)
}

/// Orders `g` (vertices `ids`, increasing, of the compressed graph `top`) by faer's AMD on
/// its pattern together with its halo: the vertices of earlier separators next to it, joined
/// into a clique (they are eliminated after it). Without them, the leaf's boundary vertices
/// would look cheap and be eliminated first, filling the leaf's interior with the separators.
/// Returns `ids` in elimination order.
fn leaf(g: &Graph, ids: &[u32], top: &Graph) -> Vec<u32> {
    const MAX_CLIQUE: usize = 512;
    let m = g.n();
    let inside = |u: u32| ids.binary_search(&u).ok();
    let mut halo: Vec<u32> = Vec::new();
    for &v in ids {
        halo.extend(
            top.nbrs(v as usize)
                .iter()
                .filter(|&&u| inside(u).is_none()),
        );
    }
    halo.sort_unstable();
    halo.dedup();
    let h = halo.len();
    let total = m + h;
    let mut col_ptr = Vec::with_capacity(total + 1);
    let clique = if h <= MAX_CLIQUE {
        h * h.saturating_sub(1) / 2
    } else {
        0
    };
    let mut row_idx = Vec::with_capacity(g.adj.len() / 2 + 8 * h + clique);
    col_ptr.push(0usize);
    for c in 0..m {
        row_idx.extend(g.nbrs(c).iter().map(|&u| u as usize).filter(|&u| u < c));
        col_ptr.push(row_idx.len());
    }
    for (j, &x) in halo.iter().enumerate() {
        row_idx.extend(top.nbrs(x as usize).iter().filter_map(|&u| inside(u)));
        if clique > 0 {
            row_idx.extend(m..m + j);
        }
        col_ptr.push(row_idx.len());
    }
    let fwd: Vec<usize> = if total <= 2 {
        (0..total).collect()
    } else {
        amd_order(total, &col_ptr, &row_idx)
    };
    fwd.iter().filter(|&&i| i < m).map(|&i| ids[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact check of the compression refuses a grouping of DOFs that are not
    /// indistinguishable, and accepts one that is.
    #[test]
    fn quotient_checks_the_grouping() {
        // Path 0 - 1 - 2: 0 and 2 have the same open neighbourhood, not the same closed one.
        let (cp, ri) = (vec![0, 1, 3, 5], vec![0, 0, 1, 1, 2]);
        let mut mark = vec![0; 3];
        assert!(quotient(3, &cp, &ri, &[0, 1, 0], 2, &mut mark).is_none());
        assert!(quotient(3, &cp, &ri, &[0, 1, 2], 2, &mut mark).is_some());
        // Triangle 0 - 1 - 2 plus 3 attached to all: 0, 1, 2, 3 all indistinguishable.
        let (cp, ri) = (vec![0, 1, 3, 6, 10], vec![0, 0, 1, 0, 1, 2, 0, 1, 2, 3]);
        let mut mark = vec![0; 4];
        let (g, dof_ptr, dofs) = quotient(4, &cp, &ri, &[0, 0, 0, 0], 6, &mut mark).unwrap();
        assert_eq!(
            (g.n(), g.adj.len(), dof_ptr, dofs),
            (1, 0, vec![0, 4], vec![0, 1, 2, 3])
        );
        // The hash grouping finds it.
        let (g, _, _) = compress(4, &cp, &ri);
        assert_eq!(g.vw, vec![4]);
    }
}
