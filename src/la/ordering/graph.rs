//! The weighted vertex graph that nested dissection cuts: built from a matrix pattern by
//! merging indistinguishable DOFs (compression), and the sides and score of a bisection.

/// A vertex- and edge-weighted graph: symmetric adjacency without self loops.
#[derive(Clone)]
pub(super) struct Graph {
    pub(super) xadj: Vec<usize>,
    pub(super) adj: Vec<u32>,
    /// Edge weights, parallel to `adj`; empty when they are all 1.
    pub(super) ew: Vec<u32>,
    /// Vertex weights (number of DOFs).
    pub(super) vw: Vec<u32>,
}

impl Graph {
    #[inline]
    pub(super) fn n(&self) -> usize {
        self.vw.len()
    }

    #[inline]
    pub(super) fn nbrs(&self, v: usize) -> &[u32] {
        &self.adj[self.xadj[v]..self.xadj[v + 1]]
    }

    pub(super) fn total(&self) -> u64 {
        self.vw.iter().map(|&w| w as u64).sum()
    }

    /// The subgraphs induced by the parts `part[v] < nparts` (other vertices are dropped),
    /// each with its vertices in increasing order, and their numbers in `self`.
    pub(super) fn split(&self, part: &[u32], nparts: usize) -> Vec<(Graph, Vec<u32>)> {
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
    pub(super) fn ew(&self, k: usize) -> u32 {
        if self.ew.is_empty() { 1 } else { self.ew[k] }
    }
}

#[inline]
pub(super) fn mix(x: u64) -> u64 {
    // splitmix64 finaliser
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

pub(super) type Compressed = (Graph, Vec<usize>, Vec<usize>);

/// Merges indistinguishable DOFs into vertices (see the module documentation).
/// The vertex graph, and the DOFs of each vertex (`dofs[dof_ptr[v]..dof_ptr[v + 1]]`).
pub(super) fn compress(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Compressed {
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
pub(super) fn quotient(
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

/// No vertex (an empty slot of a vertex map).
pub(super) const NONE: u32 = u32::MAX;

/// Side of a vertex in a bisection.
pub(super) const A: u8 = 0;
pub(super) const B: u8 = 1;
pub(super) const SEP: u8 = 2;

/// Smaller is better: (infeasible, separator weight, imbalance).
pub(super) type Score = (bool, i64, i64);

pub(super) fn score(pw: &[i64; 3], maxpw: i64) -> Score {
    (pw[0].max(pw[1]) > maxpw, pw[2], (pw[0] - pw[1]).abs())
}

pub(super) fn part_weights(g: &Graph, side: &[u8]) -> [i64; 3] {
    let mut pw = [0i64; 3];
    for v in 0..g.n() {
        pw[side[v] as usize] += g.vw[v] as i64;
    }
    pw
}
