//! The elimination tree's schedule: independent subtrees, and the supernodes above them.

use super::structure::Structure;

/// The elimination tree's schedule: the descendants that update each supernode, the
/// independent subtrees and the supernodes above them.
pub(super) struct Schedule {
    /// Per supernode, the supernodes whose rows reach into its columns (ascending).
    pub(super) desc_ptr: Vec<usize>,
    pub(super) desc: Vec<u32>,
    /// Disjoint subtrees (their supernodes ascending), the largest first.
    pub(super) subtrees: Vec<Vec<usize>>,
    /// Per supernode in a subtree, its place in the subtree's list.
    pub(super) slot: Vec<u32>,
    /// The supernodes in no subtree, ascending.
    pub(super) top: Vec<usize>,
}

/// Subtrees are split until none has more than this share of the tree's work (a fixed share,
/// so that the schedule, like the values, does not depend on the number of threads).
pub(super) const SPLIT_SHARE: f64 = 1.0 / 16.0;

/// A top supernode's updates are split over its columns from this many columns.
pub const SPLIT_COLUMNS: usize = 32;

/// A split top supernode's updates are applied in this many ranges of its columns: a fixed
/// number, so that every update's shape, and with it the order of the sums in faer's product,
/// does not depend on the number of threads.
pub(super) const SPLIT_PARTS: usize = 8;

impl Schedule {
    pub(super) fn of(st: &Structure) -> Schedule {
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

    pub(super) fn descendants(&self, s: usize) -> &[u32] {
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
