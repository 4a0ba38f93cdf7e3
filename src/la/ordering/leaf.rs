//! The leaves of the dissection, ordered by faer's approximate minimum degree.

use super::graph::Graph;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// faer's AMD of the pattern `A + Aᵀ` (rows may be unsorted).
///
/// # Panics
/// If faer's AMD runs out of memory or overflows its indices ([`try_amd_order`] says which).
pub(super) fn amd_order(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Vec<usize> {
    try_amd_order(n, col_ptr, row_idx)
        .expect("AMD ordering failed (out of memory or index overflow)")
}

/// faer's AMD of the pattern `A + Aᵀ` (rows may be unsorted), `fwd[new] = old`; faer's error
/// where it runs out of memory or overflows its indices.
pub fn try_amd_order(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<Vec<usize>, faer::sparse::FaerError> {
    let mut fwd = vec![0usize; n];
    let mut inv = vec![0usize; n];
    if n == 0 {
        return Ok(fwd);
    }
    let a = SymbolicSparseColMatRef::new_unsorted_checked(
        n,
        n,
        &col_ptr[..=n],
        None,
        &row_idx[..col_ptr[n]],
    );
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(n, col_ptr[n]))
        .map_err(|_| faer::sparse::FaerError::OutOfMemory)?;
    amd::order_maybe_unsorted(
        &mut fwd,
        &mut inv,
        a,
        Default::default(),
        MemStack::new(&mut mem),
    )?;
    Ok(fwd)
}

/// Orders `g` (vertices `ids`, increasing, of the compressed graph `top`) by faer's AMD on
/// its pattern together with its halo: the vertices of earlier separators next to it, joined
/// into a clique (they are eliminated after it). Without them, the leaf's boundary vertices
/// would look cheap and be eliminated first, filling the leaf's interior with the separators.
/// Returns `ids` in elimination order.
pub(super) fn leaf(g: &Graph, ids: &[u32], top: &Graph) -> Vec<u32> {
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
