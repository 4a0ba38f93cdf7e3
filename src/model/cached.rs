//! A model's linear algebra in the model cache ([`crate::cache`]): what an entry holds, and the
//! parts of the model rebuilt from it.
//!
//! An entry holds, in this order: the factor values, sizes and scalars (`META`), the fill-reducing ordering of
//! the free DOFs, the grounded DOFs and their springs, the forces of the prescribed
//! displacements; for a contact model the Delassus operator `W` (with, from
//! [`crate::contact::solver::PREFIX_FROM`] contact unknowns, the order of the constraint rows
//! and the packed Cholesky factor of `W` in it), the condensed loads `w0` (of
//! the tractions, with the traction forces they belong to, and of the prescribed
//! displacements) and the supernodal layout of the saddle factor (a hit needs no symbolic
//! analysis); without contact the upper pattern of `K`, from which the analysis is redone with
//! the stored ordering (faer has no way to store it). The values of the numeric factor come
//! first, at a fixed offset, so that a contact model's factorisation can compute them in the
//! new entry's file ([`cache::Draft`]); a hit maps them from the file and checks them against
//! their hash in a second thread while the layout is checked or the analysis redone
//! ([`cache::Reader::map_next`]). The whole saddle factor is kept (the solves with `K̂` read
//! its leading block only; the rest served to form `W`), so that its values are the very
//! array the factorisation wrote.

use crate::assembly::UpperCsc;
use crate::cache::{self, Entry, Key, Open, Report, Status, Store, Words};
use crate::condense::{Condensed, Factor};
use crate::la::{PartialSymbolic, SaddleFactor};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

/// Section tags.
mod tag {
    pub const META: u32 = 1;
    pub const ORDERING: u32 = 2;
    pub const COL_PTR: u32 = 3;
    pub const ROW_IDX: u32 = 4;
    pub const GROUNDED: u32 = 5;
    pub const GROUND_KG: u32 = 6;
    pub const F_PRESCRIBED: u32 = 7;
    pub const DELASSUS: u32 = 8;
    pub const F_TRACTION: u32 = 9;
    pub const W0_TRACTION: u32 = 10;
    pub const W0_PRESCRIBED: u32 = 11;
    /// Always the first section.
    pub const VALUES: u32 = 12;
    /// The supernodal layout of a contact model's factor ([`crate::la::Supernodes`]).
    pub const SN_BEGIN: u32 = 13;
    pub const SN_ROW_PTR: u32 = 14;
    pub const SN_ROWS: u32 = 15;
    pub const SN_VAL_PTR: u32 = 16;
    /// The order of the constraint rows and the packed lower triangle (column by column) of
    /// the Cholesky factor of `W` in it ([`crate::contact::solver::PrefixFactor`]), for the
    /// models that have one.
    pub const PREFIX_ORDER: u32 = 17;
    pub const PREFIX_C: u32 = 18;
}

/// `META`: kind, n_free, n_interior, n_retained, m, stiffness nonzeros, bits of `krr_scale`.
const META_LEN: usize = 7;

/// The sizes of a model, which an entry must match.
pub(super) struct Sizes {
    /// A contact model (saddle-point factorisation), else a partial Cholesky factorisation.
    pub contact: bool,
    pub n_free: usize,
    pub n_interior: usize,
    pub n_retained: usize,
    /// Constraint rows (0 without contact).
    pub m: usize,
    /// Their order in the saddle-point factorisation, when it is not that of μ
    /// ([`crate::contact::solver::prefix_order`]).
    pub row_order: Option<Vec<usize>>,
}

/// A cache miss: the entry to write.
pub(super) struct Pending {
    pub key: Key,
    pub status: Status,
    pub note: Option<String>,
}

/// The model parts restored from an entry.
pub(super) struct Restored {
    pub condensed: Condensed,
    pub w: Option<faer::Mat<f64>>,
    pub prefix: Option<crate::contact::solver::PrefixFactor>,
    pub f_prescribed: Vec<f64>,
    pub stiffness_nonzeros: usize,
    /// (traction forces, their `w0`, `w0` of the prescribed displacements).
    pub w0: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    /// Time to redo the analysis from the stored ordering.
    pub analyse_s: f64,
    report: Report,
}

/// What the cache has for a model.
pub(super) enum Lookup {
    /// No cache.
    None,
    /// The cache cannot be used (no key: the program cannot read itself).
    Off(Report),
    Hit(Box<Restored>),
    Miss(Pending),
}

impl Lookup {
    /// The report of a hit, or of a cache that cannot be used.
    pub fn report(&self) -> Option<Report> {
        match self {
            Lookup::Hit(r) => Some(r.report.clone()),
            Lookup::Off(r) => Some(r.clone()),
            Lookup::None | Lookup::Miss(_) => None,
        }
    }
}

/// Whether `a` and `b` hold the same floats, bit for bit.
pub(super) fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Looks the model up in `store`: a hit restores its linear algebra; an entry that cannot be
/// used is reported, deleted and becomes a miss (`rebuilt`).
pub(super) fn lookup(
    store: &Store,
    case: &crate::case::Case,
    mesh_bytes: &[u8],
    gap: Option<f64>,
    sizes: &Sizes,
    grounded: &[usize],
) -> Lookup {
    let key = match cache::model_key(case, mesh_bytes, gap) {
        Ok(k) => k,
        Err(why) => return Lookup::Off(Report::off(Some(why))),
    };
    let why = match store.open(key) {
        Open::Missing => {
            return Lookup::Miss(Pending {
                key,
                status: Status::Miss,
                note: None,
            });
        }
        Open::Corrupt(why) => why,
        Open::Ready(reader) => {
            let bytes = reader.bytes;
            match restore(reader, sizes, grounded) {
                Ok(mut r) => {
                    r.report = Report {
                        status: Status::Hit,
                        path: Some(store.path(key).display().to_string()),
                        bytes: Some(bytes),
                        note: None,
                        factor_in_place: None,
                    };
                    return Lookup::Hit(Box::new(r));
                }
                Err(why) => why,
            }
        }
    };
    store.discard(key, &why);
    Lookup::Miss(Pending {
        key,
        status: Status::Rebuilt,
        note: Some(format!("the entry was {why}")),
    })
}

/// The parts of a model just built, for its entry.
pub(super) struct Built<'a> {
    pub sizes: &'a Sizes,
    pub ordering: Vec<usize>,
    /// The assembled stiffness's pattern (stored for a model without contact; a contact
    /// model's is not needed and may have been freed).
    pub k: UpperCsc,
    /// Nonzeros of the assembled stiffness.
    pub nnz: usize,
    pub grounded: &'a [usize],
    pub condensed: &'a Condensed,
    pub w: Option<&'a Arc<faer::Mat<f64>>>,
    pub prefix: Option<&'a Arc<crate::contact::solver::PrefixFactor>>,
    pub f_prescribed: &'a [f64],
    pub f_traction: &'a [f64],
    pub contact_w0: &'a [Vec<f64>; 2],
    /// The entry's file, its factor values computed in place ([`cache::Draft`]).
    pub draft: Option<cache::DraftFile>,
}

/// The cache entry of a model just built.
pub(super) fn entry(b: Built) -> Entry {
    let s = b.sizes;
    let meta = vec![
        if s.contact { 1 } else { 2 },
        s.n_free as u64,
        s.n_interior as u64,
        s.n_retained as u64,
        s.m as u64,
        b.nnz as u64,
        b.condensed.krr_scale.to_bits(),
    ];
    // The whole factor, as the run computed it (for a contact model, in the entry's file when
    // it has a draft), and a contact model's layout of it.
    let (layout, values) = match &b.condensed.chol {
        Factor::Saddle(f) => (Some(f.layout()), Words::Shared(f.values())),
        Factor::Partial(f) => (None, Words::Shared(f.values())),
    };
    let mut sections = vec![
        (tag::VALUES, values),
        (tag::META, Words::U64(meta)),
        (tag::ORDERING, Words::Usize(b.ordering)),
        (tag::GROUNDED, Words::Usize(b.grounded.to_vec())),
        (
            tag::GROUND_KG,
            Words::F64(b.condensed.grounding.iter().map(|g| g.1).collect()),
        ),
        (tag::F_PRESCRIBED, Words::F64(b.f_prescribed.to_vec())),
    ];
    if let Some(w) = b.w {
        let m = w.nrows();
        sections.push((tag::DELASSUS, Words::all_columns(w.clone(), m)));
        sections.push((tag::F_TRACTION, Words::F64(b.f_traction.to_vec())));
        sections.push((tag::W0_TRACTION, Words::F64(b.contact_w0[0].clone())));
        sections.push((tag::W0_PRESCRIBED, Words::F64(b.contact_w0[1].clone())));
    }
    if let Some(pf) = b.prefix {
        let m = pf.c.nrows();
        sections.push((tag::PREFIX_ORDER, Words::Usize(pf.order.clone())));
        sections.push((tag::PREFIX_C, Words::lower_columns(pf.clone(), m)));
    }
    // The pattern of K for a partial factorisation's analysis (a contact model's factor keeps
    // its own layout instead).
    if !s.contact {
        sections.push((tag::COL_PTR, Words::Usize(b.k.col_ptr)));
        sections.push((tag::ROW_IDX, Words::Usize(b.k.row_idx)));
    }
    if let Some(layout) = layout {
        sections.push((tag::SN_BEGIN, Words::Usize(layout.begin.clone())));
        sections.push((tag::SN_ROW_PTR, Words::Usize(layout.row_ptr.clone())));
        sections.push((tag::SN_ROWS, Words::Usize(layout.rows.clone())));
        sections.push((tag::SN_VAL_PTR, Words::Usize(layout.val_ptr.clone())));
    }
    Entry {
        sections,
        draft: b.draft,
    }
}

fn is_permutation(p: &[usize], n: usize) -> bool {
    let mut seen = vec![false; n];
    p.len() == n
        && p.iter()
            .all(|&i| i < n && !std::mem::replace(&mut seen[i], true))
}

/// Whether `col_ptr`, `row_idx` are an upper-triangular CSC pattern of order `n` with sorted
/// rows (as the factorisation requires).
fn is_upper_pattern(col_ptr: &[usize], row_idx: &[usize], n: usize) -> bool {
    col_ptr.len() == n + 1
        && col_ptr[0] == 0
        && col_ptr[n] == row_idx.len()
        && col_ptr.windows(2).all(|w| w[0] <= w[1])
        && (0..n).all(|c| {
            let rows = &row_idx[col_ptr[c]..col_ptr[c + 1]];
            rows.windows(2).all(|w| w[0] < w[1]) && rows.last().is_none_or(|&r| r <= c)
        })
}

/// Restores the linear algebra of a model of `sizes` from an opened entry, checking every
/// section against the model (`Err`: why the entry cannot be used).
fn restore(
    mut reader: cache::Reader,
    sizes: &Sizes,
    grounded: &[usize],
) -> Result<Restored, String> {
    let bad = |what: &str| format!("inconsistent ({what})");
    if reader.next_tag() != Some(tag::VALUES) {
        return Err(bad("no factor values"));
    }
    // Mapped now, checked against its hash on a second thread below.
    let (_, values) = reader.map_next()?;
    let mut sec: HashMap<u32, Words> = HashMap::new();
    while reader.remaining() > 0 {
        let (t, w) = reader.read_next()?;
        sec.insert(t, w);
    }
    let mut take_u = |t: u32, what: &str| -> Result<Vec<usize>, String> {
        sec.remove(&t)
            .and_then(Words::into_u64)
            .map(|v| v.into_iter().map(|x| x as usize).collect())
            .ok_or_else(|| bad(what))
    };
    let meta = take_u(tag::META, "sizes")?;
    let ordering = take_u(tag::ORDERING, "ordering")?;
    let pattern = if sizes.contact {
        None
    } else {
        Some((
            take_u(tag::COL_PTR, "pattern")?,
            take_u(tag::ROW_IDX, "pattern")?,
        ))
    };
    let stored_grounded = take_u(tag::GROUNDED, "grounded DOFs")?;
    let stored_row_order = match &sizes.row_order {
        Some(_) if sizes.contact => {
            Some(take_u(tag::PREFIX_ORDER, "order of the constraint rows")?)
        }
        _ => None,
    };
    // A contact model's supernodal layout (its ordering is the stored one, then the rows).
    let layout = if sizes.contact {
        Some(crate::la::Supernodes {
            begin: take_u(tag::SN_BEGIN, "supernodes")?,
            row_ptr: take_u(tag::SN_ROW_PTR, "supernodes")?,
            rows: take_u(tag::SN_ROWS, "supernodes")?,
            val_ptr: take_u(tag::SN_VAL_PTR, "supernodes")?,
            fwd: Vec::new(),
        })
    } else {
        None
    };
    let mut take_f = |t: u32, len: usize, what: &str| -> Result<Vec<f64>, String> {
        sec.remove(&t)
            .and_then(Words::into_f64)
            .filter(|v| v.len() == len)
            .ok_or_else(|| bad(what))
    };
    let kg = take_f(tag::GROUND_KG, grounded.len(), "grounding springs")?;
    let f_prescribed = take_f(tag::F_PRESCRIBED, sizes.n_free, "prescribed forces")?;
    let (n, n_i, n_r, m) = (sizes.n_free, sizes.n_interior, sizes.n_retained, sizes.m);
    let kind = if sizes.contact { 1 } else { 2 };
    if meta.len() != META_LEN || meta[..5] != [kind, n, n_i, n_r, m] {
        return Err(bad("built for a model of other sizes"));
    }
    if stored_grounded != grounded {
        return Err(bad("other grounded DOFs"));
    }
    if let Some((col_ptr, row_idx)) = &pattern
        && (meta[5] != row_idx.len() || !is_upper_pattern(col_ptr, row_idx, n))
    {
        return Err(bad("stiffness pattern"));
    }
    let krr_scale = f64::from_bits(meta[6] as u64);
    let grounding: Vec<(usize, f64)> = grounded.iter().copied().zip(kg).collect();
    let (w, w0) = if sizes.contact {
        let wv = take_f(tag::DELASSUS, m * m, "Delassus operator")?;
        let ft = take_f(tag::F_TRACTION, n, "traction forces")?;
        let w0t = take_f(tag::W0_TRACTION, m, "condensed traction loads")?;
        let w0p = take_f(tag::W0_PRESCRIBED, m, "condensed prescribed loads")?;
        let w = faer::Mat::from_fn(m, m, |i, j| wv[j * m + i]);
        (Some(w), Some((ft, w0t, w0p)))
    } else {
        (None, None)
    };
    let prefix = match &sizes.row_order {
        Some(order) if sizes.contact => {
            if stored_row_order.as_ref() != Some(order) {
                return Err(bad("order of the constraint rows"));
            }
            let packed = take_f(tag::PREFIX_C, m * (m + 1) / 2, "factor of W")?;
            Some(crate::contact::solver::PrefixFactor::new(
                unpack_lower(&packed, m),
                order.clone(),
            ))
        }
        _ => {
            if sec.contains_key(&tag::PREFIX_C) || sec.contains_key(&tag::PREFIX_ORDER) {
                return Err(bad("factor of W for a model without one"));
            }
            None
        }
    };
    let order_len = if sizes.contact { n } else { n_i };
    if !is_permutation(&ordering, order_len) {
        return Err(bad("ordering"));
    }
    let layout = layout.map(|mut l| {
        l.fwd = ordering.iter().copied().chain(n..n + m).collect();
        l
    });
    let (chol, analyse_s) = factor_of(values, layout, pattern.as_ref(), &ordering, (n, n_r, m))?;
    Ok(Restored {
        condensed: Condensed {
            n_i,
            n_r,
            chol,
            grounding,
            krr_scale,
        },
        w,
        prefix,
        f_prescribed,
        stiffness_nonzeros: meta[5],
        w0,
        analyse_s,
        report: Report::off(None),
    })
}

/// The lower triangle of an `m × m` matrix from its columns below the diagonal packed one
/// after the other (the upper triangle zero).
fn unpack_lower(packed: &[f64], m: usize) -> faer::Mat<f64> {
    let mut c = faer::Mat::<f64>::zeros(m, m);
    let mut at = 0;
    for j in 0..m {
        for i in j..m {
            c[(i, j)] = packed[at];
            at += 1;
        }
    }
    c
}

/// The factor of a restored model and the seconds its analysis took: a contact model's
/// factor is read with its stored `layout` (no analysis); a partial factorisation's analysis
/// is redone from the stored `ordering` and stiffness `pattern`, while a second thread checks
/// the mapped factor `values` against their hash. `(n, n_r, m)`: free DOFs, retained DOFs,
/// constraint rows.
fn factor_of(
    values: cache::Unchecked,
    layout: Option<crate::la::Supernodes>,
    pattern: Option<&(Vec<usize>, Vec<usize>)>,
    ordering: &[usize],
    (n, n_r, m): (usize, usize, usize),
) -> Result<(Factor, f64), String> {
    let bad = |what: &str| format!("inconsistent ({what})");
    let (analysis, analyse_s, values) = std::thread::scope(|s| {
        let values = s.spawn(move || values.check());
        let t = Instant::now();
        let analysis = match layout {
            Some(l) => l
                .check(n, m)
                .map(|()| Analysis::Layout(Arc::new(l)))
                .map_err(|e| bad(&e)),
            None => {
                let (col_ptr, row_idx) = pattern.expect("taken without contact");
                PartialSymbolic::with_ordering(n, n_r, col_ptr, row_idx, ordering)
                    .map(Analysis::Partial)
                    .map_err(|e| format!("unusable: {e}"))
            }
        };
        let analyse_s = t.elapsed().as_secs_f64();
        let values = values
            .join()
            .unwrap_or_else(|_| Err("cannot be read (the reader panicked)".into()));
        (analysis, analyse_s, values)
    });
    let values = Arc::new(values?);
    let chol = match analysis? {
        Analysis::Layout(l) => SaddleFactor::from_layout(l, values, n, m).map(Factor::Saddle),
        Analysis::Partial(s) => s.from_values(values).map(Factor::Partial),
    }
    .map_err(|e| format!("unusable: {e}"))?;
    Ok((chol, analyse_s))
}

enum Analysis {
    /// The checked layout of a contact model's factor.
    Layout(Arc<crate::la::Supernodes>),
    Partial(PartialSymbolic),
}
