//! Fiduccia–Mattheyses refinement of a vertex separator, with its indexed gain heaps.

use super::graph::{Graph, NONE, SEP, Score, score};
use super::options::NdOptions;

/// An indexed max-heap of vertices keyed by gain (ties: the smaller vertex first).
pub(super) struct Heap {
    heap: Vec<(i64, u32)>,
    /// Position of each vertex in `heap`, or `NONE`.
    loc: Vec<u32>,
}

impl Heap {
    pub(super) fn new(n: usize) -> Self {
        Heap {
            heap: Vec::new(),
            loc: vec![NONE; n],
        }
    }

    #[inline]
    pub(super) fn above(a: (i64, u32), b: (i64, u32)) -> bool {
        a.0 > b.0 || (a.0 == b.0 && a.1 < b.1)
    }

    pub(super) fn top(&self) -> Option<(i64, u32)> {
        self.heap.first().copied()
    }

    pub(super) fn set(&mut self, v: u32, key: i64) {
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

    pub(super) fn remove(&mut self, v: u32) {
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

    pub(super) fn clear(&mut self) {
        for &(_, v) in &self.heap {
            self.loc[v as usize] = NONE;
        }
        self.heap.clear();
    }

    pub(super) fn up(&mut self, mut i: usize) {
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

    pub(super) fn down(&mut self, mut i: usize) {
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
pub(super) struct Workspace {
    heaps: [Heap; 2],
    gain: Vec<[i64; 2]>,
    locked: Vec<bool>,
    mark: Vec<bool>,
}

impl Workspace {
    pub(super) fn new(n: usize) -> Self {
        Workspace {
            heaps: [Heap::new(n), Heap::new(n)],
            gain: vec![[0; 2]; n],
            locked: vec![false; n],
            mark: vec![false; n],
        }
    }
}

/// The gains of moving separator vertex `v` of `g` to side A and to side B: its weight less
/// the weight of its neighbours on the other side (which enter the separator).
fn separator_gains(g: &Graph, side: &[u8], v: u32) -> [i64; 2] {
    let w = |v: u32| g.vw[v as usize] as i64;
    let mut pull = [0i64; 2];
    for &u in g.nbrs(v as usize) {
        let s = side[u as usize];
        if s != SEP {
            pull[s as usize] += w(u);
        }
    }
    [w(v) - pull[1], w(v) - pull[0]]
}

/// Fiduccia–Mattheyses refinement of the vertex separator `side` of `g` (two-sided: a
/// separator vertex moves into either side, its neighbours on the other side enter the
/// separator), keeping the best state of each pass. `pw` are the weights of the sides and
/// the separator, `seps` the separator's vertices; both are kept up to date. Returns the
/// final score.
pub(super) fn refine(
    g: &Graph,
    side: &mut [u8],
    pw: &mut [i64; 3],
    seps: &mut Vec<u32>,
    maxpw: i64,
    opts: &NdOptions,
    ws: &mut Workspace,
) -> Score {
    let w = |v: u32| g.vw[v as usize] as i64;
    let gains = |side: &[u8], v: u32| separator_gains(g, side, v);
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
