//! Multilevel bisection: coarsening by heavy-edge matching, initial level-structure
//! separators on the coarsest graph, projection and refinement back up, and the recursion
//! of [`dissect`] over the parts.

use super::graph::{A, B, Graph, NONE, SEP, Score, part_weights, score};
use super::leaf::leaf;
use super::options::NdOptions;
use super::refine::{Workspace, refine};

/// How a graph is cut.
pub(super) enum Cut {
    /// It is disconnected: the component of each vertex, and their number.
    Components(Vec<u32>, usize),
    /// A vertex separator: the side of each vertex (`A`, `B` or `SEP`).
    Separator(Vec<u8>),
}

/// Subgraphs of at least this many vertices have their parts ordered in parallel (the
/// result does not depend on it).
pub(super) const PARALLEL_MIN: usize = 4096;

/// The nested-dissection order of the graph `g`, whose vertices are the vertices `ids`
/// (increasing) of the whole compressed graph `top`: those ids in elimination order.
pub(super) fn dissect(g: Graph, ids: Vec<u32>, opts: &NdOptions, top: &Graph) -> Vec<u32> {
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
pub(super) fn components(g: &Graph) -> (Vec<u32>, usize) {
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
pub(super) fn bisect(g: &Graph, opts: &NdOptions) -> Cut {
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
pub(super) fn next_random(s: &mut u64) -> u64 {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    s.wrapping_mul(0x2545_F491_4F6C_DD1D)
}

/// One level of coarsening: heavy-edge matching (vertices visited in a pseudo-random order
/// from `seed`, coarse vertices no heavier than `maxvw`), and the coarse graph with summed
/// vertex and edge weights; `cmap[v]` is the coarse vertex of `v`.
pub(super) fn coarsen(g: &Graph, maxvw: u64, seed: &mut u64) -> (Graph, Vec<u32>) {
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
pub(super) fn bfs(
    g: &Graph,
    root: usize,
    order: &mut Vec<u32>,
    level_ptr: &mut Vec<usize>,
    dist: &mut [u32],
) {
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

/// Level-structure separators of the (small, connected) graph `g` from
/// `opts.initial_tries` roots (a pseudo-peripheral vertex, then vertices spread over the
/// numbering), distinct, best first.
pub(super) fn initial_separators(g: &Graph, maxpw: i64, opts: &NdOptions) -> Vec<Vec<u8>> {
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
pub(super) fn level_separator(
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
