//! The supernodal structure a factorisation runs on, and the matrix it reads.

/// A symmetric matrix's lower triangle in the factor's (permuted) numbering, as the
/// factorisation reads it: in parts, each in compressed columns of its own; a column's entries
/// are those of all the parts.
pub struct LowerCsc {
    pub(super) parts: Vec<LowerPart>,
}

/// One part of a [`LowerCsc`]: `col_ptr` has the matrix's order plus one pointers.
pub(super) struct LowerPart {
    pub(super) col_ptr: Vec<u32>,
    pub(super) row_idx: Vec<u32>,
    pub(super) values: Vec<f64>,
}

impl LowerCsc {
    /// The lower triangle of `P A Pᵀ` from the upper triangle of `A` in compressed columns
    /// (`col_ptr`, `row_idx`, the value of entry `p` given by `value(p)`; entries below the
    /// diagonal are ignored), where `fwd[new] = old`. One part per range of `A`'s columns
    /// (about equal numbers of entries), made on rayon's threads; the factorisation adds each
    /// entry to a value of its own, so their order does not matter.
    pub fn permuted(
        col_ptr: &[usize],
        row_idx: &[usize],
        value: impl Fn(usize) -> f64 + Sync,
        fwd: &[usize],
    ) -> Self {
        use rayon::prelude::*;
        const PARTS: usize = 4;
        let size = fwd.len();
        let mut inv = vec![0u32; size];
        for (new, &old) in fwd.iter().enumerate() {
            inv[old] = new as u32;
        }
        // (column, row) of the entry (r, c) of the upper triangle, r ≤ c.
        let place = |r: usize, c: usize| {
            let (pr, pc) = (inv[r], inv[c]);
            if pr >= pc { (pc, pr) } else { (pr, pc) }
        };
        // Source columns in parts of about equal numbers of entries.
        let nnz_in = col_ptr[size];
        let bounds: Vec<usize> = (0..=PARTS)
            .map(|t| {
                col_ptr[..=size]
                    .partition_point(|&p| p < t * nnz_in / PARTS)
                    .min(size)
            })
            .collect();
        let parts = bounds
            .par_windows(2)
            .map(|w| {
                // Entries per destination column, then their offsets: `ptr[col]` is where
                // the next entry of `col` goes, the end of the column once all are placed.
                let mut ptr = vec![0u32; size + 1];
                for c in w[0]..w[1] {
                    for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                        if r <= c {
                            ptr[place(r, c).0 as usize + 1] += 1;
                        }
                    }
                }
                for j in 0..size {
                    ptr[j + 1] = ptr[j]
                        .checked_add(ptr[j + 1])
                        .expect("fewer than 2³² entries in a part");
                }
                let nnz = ptr[size] as usize;
                let (mut rows, mut values) = (vec![0u32; nnz], vec![0.0; nnz]);
                for c in w[0]..w[1] {
                    for p in col_ptr[c]..col_ptr[c + 1] {
                        let r = row_idx[p];
                        if r <= c {
                            let (col, row) = place(r, c);
                            let q = &mut ptr[col as usize];
                            rows[*q as usize] = row;
                            values[*q as usize] = value(p);
                            *q += 1;
                        }
                    }
                }
                // Each pointer now holds its column's end: shifted back to the starts.
                ptr.copy_within(0..size, 1);
                ptr[0] = 0;
                LowerPart {
                    col_ptr: ptr,
                    row_idx: rows,
                    values,
                }
            })
            .collect();
        LowerCsc { parts }
    }
}

/// The supernodal structure the factorisation needs: supernode `s` has the columns
/// `begin[s]..begin[s + 1]`, the off-diagonal rows `rows[row_ptr[s]..row_ptr[s + 1]]`
/// (ascending) and its values at `val_ptr[s]..` (column-major, its own rows then the others).
pub struct Structure<'a> {
    pub begin: &'a [usize],
    pub row_ptr: &'a [usize],
    pub rows: &'a [usize],
    pub val_ptr: &'a [usize],
}

impl Structure<'_> {
    /// Panics unless the supernodes tile the columns in order, each pattern is ascending and
    /// below its supernode, and each supernode's values have its shape, one after the other.
    pub(super) fn check(&self) {
        let nsup = self.n_supernodes();
        assert!(self.row_ptr.len() == nsup + 1 && self.val_ptr.len() == nsup + 1);
        assert!(self.begin.first() == Some(&0) && self.val_ptr.first() == Some(&0));
        for s in 0..nsup {
            assert!(self.begin[s] < self.begin[s + 1], "supernode {s} is empty");
            let p = self.pattern(s);
            assert!(
                p.windows(2).all(|w| w[0] < w[1])
                    && p.first().is_none_or(|&r| r >= self.begin[s + 1]),
                "supernode {s}'s rows are not ascending below it"
            );
            assert!(
                p.last().is_none_or(|&r| r < *self.begin.last().unwrap()),
                "supernode {s} has a row outside the matrix"
            );
            let n = self.ncols(s);
            assert_eq!(
                self.val_ptr[s + 1] - self.val_ptr[s],
                n * (n + p.len()),
                "supernode {s}'s values"
            );
        }
    }

    pub(super) fn n_supernodes(&self) -> usize {
        self.begin.len() - 1
    }

    pub(super) fn pattern(&self, s: usize) -> &[usize] {
        &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]]
    }

    pub(super) fn ncols(&self, s: usize) -> usize {
        self.begin[s + 1] - self.begin[s]
    }
}
