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
    if reader.next_tag() != Some(tag::VALUES) {
        return Err(bad("no factor values"));
    }
    // Mapped now, checked against its hash on a second thread below.
    let (_, values) = reader.map_next()?;
    let mut sec = Sections::read(&mut reader)?;
    let frame = Frame::take(&mut sec, sizes, grounded)?;
    let (n, n_r, m) = (sizes.n_free, sizes.n_retained, sizes.m);
    let grounding: Vec<(usize, f64)> = grounded.iter().copied().zip(frame.kg).collect();
    let (w, w0) = delassus(&mut sec, sizes)?;
    let prefix = prefix_factor(&mut sec, sizes, frame.stored_row_order)?;
    let ordering = frame.ordering;
    let order_len = if sizes.contact { n } else { sizes.n_interior };
    if !is_permutation(&ordering, order_len) {
        return Err(bad("ordering"));
    }
    // A contact model's factor is read with its stored layout (no analysis); a partial
    // factorisation's analysis is redone from the stored ordering, while a second thread reads
    // the factor values.
    let layout = frame.layout.map(|mut l| {
        l.fwd = ordering.iter().copied().chain(n..n + m).collect();
        l
    });
    let pattern = frame.pattern;
    let (analysis, analyse_s, values) = std::thread::scope(|s| {
        let values = s.spawn(move || values.check());
        let t = Instant::now();
        let analysis = match layout {
            Some(l) => l
                .check(n, m)
                .map(|()| Analysis::Layout(Arc::new(l)))
                .map_err(|e| bad(&e)),
            None => {
                let (col_ptr, row_idx) = pattern.as_ref().expect("taken without contact");
                PartialSymbolic::with_ordering(n, n_r, col_ptr, row_idx, &ordering)
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
    Ok(Restored {
        condensed: Condensed {
            n_i: sizes.n_interior,
            n_r,
            chol,
            grounding,
            krr_scale: frame.krr_scale,
        },
        w,
        prefix,
        f_prescribed: frame.f_prescribed,
        stiffness_nonzeros: frame.stiffness_nonzeros,
        w0,
        analyse_s,
        report: Report::off(None),
    })
}

/// Why an entry cannot be used: `what` of it does not fit the model.
fn bad(what: &str) -> String {
    format!("inconsistent ({what})")
}

/// The sections of an entry after its factor values, by tag; each taken once.
struct Sections(HashMap<u32, Words>);

impl Sections {
    /// Reads the sections left in `reader`.
    fn read(reader: &mut cache::Reader) -> Result<Self, String> {
        let mut sec: HashMap<u32, Words> = HashMap::new();
        while reader.remaining() > 0 {
            let (t, w) = reader.read_next()?;
            sec.insert(t, w);
        }
        Ok(Sections(sec))
    }

    /// Section `t` as indices (`what` names it in the error).
    fn usizes(&mut self, t: u32, what: &str) -> Result<Vec<usize>, String> {
        self.0
            .remove(&t)
            .and_then(Words::into_u64)
            .map(|v| v.into_iter().map(|x| x as usize).collect())
            .ok_or_else(|| bad(what))
    }

    /// Section `t` as `len` floats (`what` names it in the error).
    fn floats(&mut self, t: u32, len: usize, what: &str) -> Result<Vec<f64>, String> {
        self.0
            .remove(&t)
            .and_then(Words::into_f64)
            .filter(|v| v.len() == len)
            .ok_or_else(|| bad(what))
    }
}

/// What every entry holds besides its factor values and a contact model's `W`, checked against
/// the model's sizes and grounded DOFs.
struct Frame {
    ordering: Vec<usize>,
    /// The stiffness's upper pattern (a model without contact).
    pattern: Option<(Vec<usize>, Vec<usize>)>,
    /// The order of the constraint rows (a contact model that has one).
    stored_row_order: Option<Vec<usize>>,
    /// The supernodal layout of a contact model's factor, its `fwd` not yet filled in.
    layout: Option<crate::la::Supernodes>,
    /// The grounding springs, in the order of the grounded DOFs.
    kg: Vec<f64>,
    f_prescribed: Vec<f64>,
    stiffness_nonzeros: usize,
    krr_scale: f64,
}

impl Frame {
    fn take(sec: &mut Sections, sizes: &Sizes, grounded: &[usize]) -> Result<Frame, String> {
        let meta = sec.usizes(tag::META, "sizes")?;
        let ordering = sec.usizes(tag::ORDERING, "ordering")?;
        let pattern = if sizes.contact {
            None
        } else {
            Some((
                sec.usizes(tag::COL_PTR, "pattern")?,
                sec.usizes(tag::ROW_IDX, "pattern")?,
            ))
        };
        let stored_grounded = sec.usizes(tag::GROUNDED, "grounded DOFs")?;
        let stored_row_order = match &sizes.row_order {
            Some(_) if sizes.contact => {
                Some(sec.usizes(tag::PREFIX_ORDER, "order of the constraint rows")?)
            }
            _ => None,
        };
        // A contact model's supernodal layout (its ordering is the stored one, then the rows).
        let layout = if sizes.contact {
            Some(crate::la::Supernodes {
                begin: sec.usizes(tag::SN_BEGIN, "supernodes")?,
                row_ptr: sec.usizes(tag::SN_ROW_PTR, "supernodes")?,
                rows: sec.usizes(tag::SN_ROWS, "supernodes")?,
                val_ptr: sec.usizes(tag::SN_VAL_PTR, "supernodes")?,
                fwd: Vec::new(),
            })
        } else {
            None
        };
        let kg = sec.floats(tag::GROUND_KG, grounded.len(), "grounding springs")?;
        let f_prescribed = sec.floats(tag::F_PRESCRIBED, sizes.n_free, "prescribed forces")?;
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
        Ok(Frame {
            ordering,
            pattern,
            stored_row_order,
            layout,
            kg,
            f_prescribed,
            stiffness_nonzeros: meta[5],
            krr_scale: f64::from_bits(meta[6] as u64),
        })
    }
}

/// A contact model's Delassus operator `W` and its condensed loads `w0` (traction forces,
/// their `w0`, `w0` of the prescribed displacements); none without contact.
type Delassus = (
    Option<faer::Mat<f64>>,
    Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
);

/// [`Delassus`] from the entry's sections.
fn delassus(sec: &mut Sections, sizes: &Sizes) -> Result<Delassus, String> {
    if !sizes.contact {
        return Ok((None, None));
    }
    let (n, m) = (sizes.n_free, sizes.m);
    let wv = sec.floats(tag::DELASSUS, m * m, "Delassus operator")?;
    let ft = sec.floats(tag::F_TRACTION, n, "traction forces")?;
    let w0t = sec.floats(tag::W0_TRACTION, m, "condensed traction loads")?;
    let w0p = sec.floats(tag::W0_PRESCRIBED, m, "condensed prescribed loads")?;
    let w = faer::Mat::from_fn(m, m, |i, j| wv[j * m + i]);
    Ok((Some(w), Some((ft, w0t, w0p))))
}

/// The Cholesky factor of `W` in the order of the constraint rows, for a contact model that
/// has one (its stored order `stored_row_order` must be the model's); an entry of any other
/// model must hold none.
fn prefix_factor(
    sec: &mut Sections,
    sizes: &Sizes,
    stored_row_order: Option<Vec<usize>>,
) -> Result<Option<crate::contact::solver::PrefixFactor>, String> {
    let m = sizes.m;
    match &sizes.row_order {
        Some(order) if sizes.contact => {
            if stored_row_order.as_ref() != Some(order) {
                return Err(bad("order of the constraint rows"));
            }
            let packed = sec.floats(tag::PREFIX_C, m * (m + 1) / 2, "factor of W")?;
            let mut c = faer::Mat::<f64>::zeros(m, m);
            let mut at = 0;
            for j in 0..m {
                for i in j..m {
                    c[(i, j)] = packed[at];
                    at += 1;
                }
            }
            Ok(Some(crate::contact::solver::PrefixFactor::new(
                c,
                order.clone(),
            )))
        }
        _ => {
            if sec.0.contains_key(&tag::PREFIX_C) || sec.0.contains_key(&tag::PREFIX_ORDER) {
                return Err(bad("factor of W for a model without one"));
            }
            Ok(None)
        }
    }
}

enum Analysis {
    /// The checked layout of a contact model's factor.
    Layout(Arc<crate::la::Supernodes>),
    Partial(PartialSymbolic),
}
