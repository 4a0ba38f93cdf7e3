//! The on-disk model cache: the linear algebra of a model (the ordering, the numeric factor,
//! the Delassus operator `W`, the condensed loads of the prescribed displacements, …) kept in
//! a file named by a hash of everything it depends on, so that a second run of the same mesh,
//! materials, supports, pilot and contact pair skips the analysis, the factorisation and the
//! condensation. What goes into the key is in [`model_key`]; what goes into an entry, and how
//! it is used, in [`crate::model`] (`cached.rs`).
//!
//! # File format (version [`FORMAT`])
//!
//! Little-endian throughout; every section is a sequence of 8-byte words.
//! ```text
//!   magic "stkslpMC" (8 bytes) | format u32 | sections u32 | key (2 × u64)
//!   per section: tag u32 | kind u32 (1 integer, 2 float) | words u64 | XXH64 of its bytes u64
//!   XXH64 of all the header bytes above (u64)
//!   zero bytes up to HEADER_AREA (4096)
//!   the sections' words, in the order of the table
//! ```
//! The header hash covers the section hashes, so it checks the whole file. A file that is
//! shorter or longer than its table says, whose magic, format, key or any hash does not match,
//! or whose padding is not zero, is reported, deleted and rebuilt, never used. Entries are
//! written to a temporary name and renamed into place (no `fsync`: after a crash a file may be
//! incomplete, which the checks catch).
//!
//! The first section starts at a fixed offset so that it can be written before the others
//! are known: a contact model's factor values are computed by the numeric factorisation in a
//! shared mapping of the new entry's file ([`Draft`]), and the entry's writer then only hashes
//! them, instead of copying hundreds of MB into the page cache. That is done on Linux, on file
//! systems whose `fallocate` reserves the blocks for good (ext2/3/4, XFS, tmpfs), once they
//! are reserved; elsewhere, or without room, the values are computed in memory and written as
//! before. The draft takes its room in the cache directory from the factorisation on (before
//! the cap is enforced for the whole entry); a run that is killed leaves it as a temporary
//! file, which a later run deletes once it is an hour old. The run's factor then lives in the
//! file's pages: should the device fail to write them back while the run goes on and the
//! system reclaim them, the run would read zeros, where in memory it would not (an I/O error
//! of the cache's device; not guarded against).
//!
//! # Place and size
//!
//! `--cache DIR`, else `$STICKSLIP_CACHE_DIR`, else `$XDG_CACHE_HOME/stickslip`, else
//! `$HOME/.cache/stickslip`; `--no-cache` (or `STICKSLIP_NO_CACHE=1`) bypasses it. The
//! directory is kept under `$STICKSLIP_CACHE_MAX` bytes (suffixes K, M, G, T, binary; default
//! 4 GiB) by deleting the least recently used entries (a hit touches its file's modification
//! time) before a new one is written; an entry larger than the cap is not written.

use crate::case::Case;
use crate::la::DenseColumns;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Version of the file format and of the meaning of the sections. Bump it when either changes.
pub const FORMAT: u32 = 4;
const MAGIC: [u8; 8] = *b"stkslpMC";
/// Default size cap of the cache directory.
pub const DEFAULT_MAX_BYTES: u64 = 4 << 30;
/// At most this many sections in a file (a larger count is a corrupt header).
const MAX_SECTIONS: usize = 64;
/// Bytes read or written per chunk.
const CHUNK: usize = 1 << 20;
/// Bytes before the first section: the header, then zeros.
pub const HEADER_AREA: u64 = 4096;
const _: () = assert!(32 + 24 * MAX_SECTIONS as u64 + 8 <= HEADER_AREA);

// ------------------------------------------------------------------------------------------
// XXH64
// ------------------------------------------------------------------------------------------

const P1: u64 = 0x9E37_79B1_85EB_CA87;
const P2: u64 = 0xC2B2_AE3D_27D4_EB4F;
const P3: u64 = 0x1656_67B1_9E37_79F9;
const P4: u64 = 0x85EB_CA77_C2B2_AE63;
const P5: u64 = 0x27D4_EB2F_1656_67C5;

#[inline]
fn round(acc: u64, input: u64) -> u64 {
    acc.wrapping_add(input.wrapping_mul(P2))
        .rotate_left(31)
        .wrapping_mul(P1)
}

#[inline]
fn merge(acc: u64, v: u64) -> u64 {
    (acc ^ round(0, v)).wrapping_mul(P1).wrapping_add(P4)
}

#[inline]
fn le64(b: &[u8]) -> u64 {
    u64::from_le_bytes(b[..8].try_into().expect("8 bytes"))
}

/// Streaming XXH64 (Yann Collet's xxHash, 64-bit variant): a fast non-cryptographic hash, the
/// checksum of cache files and the building block of cache keys.
#[derive(Clone)]
pub struct Xxh64 {
    v: [u64; 4],
    seed: u64,
    total: u64,
    buf: [u8; 32],
    buf_len: usize,
}

impl Xxh64 {
    pub fn new(seed: u64) -> Xxh64 {
        Xxh64 {
            v: [
                seed.wrapping_add(P1).wrapping_add(P2),
                seed.wrapping_add(P2),
                seed,
                seed.wrapping_sub(P1),
            ],
            seed,
            total: 0,
            buf: [0; 32],
            buf_len: 0,
        }
    }

    #[inline]
    fn stripe(v: &mut [u64; 4], s: &[u8]) {
        v[0] = round(v[0], le64(&s[0..]));
        v[1] = round(v[1], le64(&s[8..]));
        v[2] = round(v[2], le64(&s[16..]));
        v[3] = round(v[3], le64(&s[24..]));
    }

    pub fn update(&mut self, mut data: &[u8]) {
        self.total += data.len() as u64;
        if self.buf_len > 0 {
            let take = (32 - self.buf_len).min(data.len());
            self.buf[self.buf_len..self.buf_len + take].copy_from_slice(&data[..take]);
            self.buf_len += take;
            data = &data[take..];
            if self.buf_len < 32 {
                return;
            }
            let buf = self.buf;
            Self::stripe(&mut self.v, &buf);
            self.buf_len = 0;
        }
        let mut chunks = data.chunks_exact(32);
        for s in &mut chunks {
            Self::stripe(&mut self.v, s);
        }
        let rest = chunks.remainder();
        self.buf[..rest.len()].copy_from_slice(rest);
        self.buf_len = rest.len();
    }

    pub fn finish(&self) -> u64 {
        let v = self.v;
        let mut h = if self.total >= 32 {
            let h = v[0]
                .rotate_left(1)
                .wrapping_add(v[1].rotate_left(7))
                .wrapping_add(v[2].rotate_left(12))
                .wrapping_add(v[3].rotate_left(18));
            merge(merge(merge(merge(h, v[0]), v[1]), v[2]), v[3])
        } else {
            self.seed.wrapping_add(P5)
        };
        h = h.wrapping_add(self.total);
        let mut tail = &self.buf[..self.buf_len];
        while tail.len() >= 8 {
            h ^= round(0, le64(tail));
            h = h.rotate_left(27).wrapping_mul(P1).wrapping_add(P4);
            tail = &tail[8..];
        }
        if tail.len() >= 4 {
            let k = u32::from_le_bytes(tail[..4].try_into().expect("4 bytes")) as u64;
            h ^= k.wrapping_mul(P1);
            h = h.rotate_left(23).wrapping_mul(P2).wrapping_add(P3);
            tail = &tail[4..];
        }
        for &b in tail {
            h ^= (b as u64).wrapping_mul(P5);
            h = h.rotate_left(11).wrapping_mul(P1);
        }
        h ^= h >> 33;
        h = h.wrapping_mul(P2);
        h ^= h >> 29;
        h = h.wrapping_mul(P3);
        h ^ (h >> 32)
    }
}

/// XXH64 of `data` with `seed`.
pub fn xxh64(data: &[u8], seed: u64) -> u64 {
    let mut h = Xxh64::new(seed);
    h.update(data);
    h.finish()
}

/// XXH64 of the little-endian bytes of `v` (seed 0).
pub fn hash_f64s(v: &[f64]) -> u64 {
    let mut h = Xxh64::new(0);
    let mut buf = Vec::with_capacity(CHUNK.min(8 * v.len()));
    for c in v.chunks(CHUNK / 8) {
        buf.clear();
        for x in c {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        h.update(&buf);
    }
    h.finish()
}

// ------------------------------------------------------------------------------------------
// Key
// ------------------------------------------------------------------------------------------

/// The 128-bit key of a cache entry (two XXH64 of the key material with different seeds).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key(pub [u64; 2]);

impl Key {
    pub fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.0[0], self.0[1])
    }
}

/// The key material: length-prefixed fields, floats by their bits, hashed as it comes (two
/// seeds: 128 bits) rather than gathered first (the mesh file is most of it).
struct KeyBuilder([Xxh64; 2]);

impl KeyBuilder {
    fn new() -> KeyBuilder {
        KeyBuilder([Xxh64::new(0), Xxh64::new(0x005e_ed0f_ca11)])
    }
    fn raw(&mut self, b: &[u8]) {
        for h in &mut self.0 {
            h.update(b);
        }
    }
    fn bytes(&mut self, b: &[u8]) {
        self.raw(&(b.len() as u64).to_le_bytes());
        self.raw(b);
    }
    fn str(&mut self, s: &str) {
        self.bytes(s.as_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.raw(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn opt_f64(&mut self, v: Option<f64>) {
        match v {
            Some(x) => {
                self.u64(1);
                self.f64(x);
            }
            None => self.u64(0),
        }
    }
    fn finish(&self) -> Key {
        Key([self.0[0].finish(), self.0[1].finish()])
    }
}

/// The identity of the running program's code: XXH64 of its executable file, read once.
/// Any rebuild that changes the machine code (the source, a dependency such as faer, the
/// compiler or its flags) changes it, so an entry is never used by other code than wrote it.
pub fn build_id() -> Result<u64, String> {
    static ID: std::sync::OnceLock<Result<u64, String>> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe().map_err(|e| format!("cannot locate the program: {e}"))?;
        let bytes = std::fs::read(&exe)
            .map_err(|e| format!("cannot read the program {}: {e}", exe.display()))?;
        Ok(xxh64(&bytes, 0))
    })
    .clone()
}

/// The key of a model's linear algebra: the cache format, the program version and build
/// ([`build_id`]), the ordering policy, the bytes of the mesh file, the bodies (group, E, ν) in
/// order, the supports (group, ux, uy) in order, the pilot's group, and the contact pair
/// (slave, master, the candidate gap in use, the normal kind). Nothing else changes `K`, the
/// constraint rows or the loads of the prescribed displacements: not the friction law, the
/// contact method, the tractions, the stages or the output, nor the number of threads (the
/// factorisation is bit-identical with any). `gap` is the candidate gap the pair was built
/// with (`None` without contact).
pub fn model_key(case: &Case, mesh_bytes: &[u8], gap: Option<f64>) -> Result<Key, String> {
    let mut k = KeyBuilder::new();
    k.str("stickslip model cache");
    k.u64(FORMAT as u64);
    k.str(env!("CARGO_PKG_VERSION"));
    k.u64(build_id()?);
    k.str(crate::la::ordering::ordering_policy());
    k.bytes(mesh_bytes);
    k.u64(case.bodies.len() as u64);
    for b in &case.bodies {
        k.str(&b.group);
        k.f64(b.e);
        k.f64(b.nu);
    }
    k.u64(case.supports.len() as u64);
    for s in &case.supports {
        k.str(&s.group);
        k.opt_f64(s.ux);
        k.opt_f64(s.uy);
    }
    match &case.pilot {
        Some(p) => {
            k.u64(1);
            k.str(&p.group);
        }
        None => k.u64(0),
    }
    match &case.contact {
        Some(c) => {
            k.u64(1);
            k.str(&c.slave);
            k.str(&c.master);
            k.opt_f64(gap);
            k.str(match c.normal {
                crate::case::NormalKind::Common => "common",
                crate::case::NormalKind::Local => "local",
            });
        }
        None => k.u64(0),
    }
    Ok(k.finish())
}

// ------------------------------------------------------------------------------------------
// Entries
// ------------------------------------------------------------------------------------------

/// The words of one section.
pub enum Words {
    U64(Vec<u64>),
    Usize(Vec<usize>),
    F64(Vec<f64>),
    /// Floats shared with the model (the factor values: written while the run goes on, or,
    /// when the entry has a draft, already in its file and only hashed).
    Shared(crate::la::SharedValues),
    /// Columns `(j, from)` of a dense matrix shared with the model, each from row `from` on,
    /// one after the other (the Delassus operator and its Cholesky factor: 130 and 65 MB at
    /// L7, which a copy would add to the run's peak memory).
    Columns(std::sync::Arc<dyn DenseColumns>, Vec<(usize, usize)>),
}

/// Calls `f` with the little-endian bytes of `pieces` (each at most `longest` floats), one after
/// the other, gathered into chunks of about [`CHUNK`] bytes.
#[cfg(all(target_endian = "little", target_pointer_width = "64"))]
fn in_chunks<'a>(
    pieces: impl Iterator<Item = &'a [f64]>,
    longest: usize,
    mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(CHUNK + 8 * longest);
    for p in pieces {
        buf.extend_from_slice(bytemuck::cast_slice(p));
        if buf.len() >= CHUNK {
            f(&buf)?;
            buf.clear();
        }
    }
    if !buf.is_empty() {
        f(&buf)?;
    }
    Ok(())
}

impl Words {
    /// All the columns of `m`.
    pub fn all_columns(m: std::sync::Arc<dyn DenseColumns>, ncols: usize) -> Words {
        Words::Columns(m, (0..ncols).map(|j| (j, 0)).collect())
    }

    /// The lower triangle of `m` (order `n`), column by column.
    pub fn lower_columns(m: std::sync::Arc<dyn DenseColumns>, n: usize) -> Words {
        Words::Columns(m, (0..n).map(|j| (j, j)).collect())
    }
}

impl Words {
    pub fn len(&self) -> usize {
        match self {
            Words::U64(v) => v.len(),
            Words::Usize(v) => v.len(),
            Words::F64(v) => v.len(),
            Words::Shared(v) => v.len(),
            Words::Columns(m, c) => c.iter().map(|&(_, from)| m.rows() - from).sum(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn kind(&self) -> u32 {
        match self {
            Words::U64(_) | Words::Usize(_) => 1,
            Words::F64(_) | Words::Shared(_) | Words::Columns(..) => 2,
        }
    }

    /// Calls `f` with the little-endian bytes of the words, a chunk at a time.
    fn for_each_chunk(
        &self,
        mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        // The words' own memory is their little-endian bytes on a little-endian 64-bit
        // machine: no copy (the factor values are most of an entry, 165 MB on L5).
        #[cfg(all(target_endian = "little", target_pointer_width = "64"))]
        {
            let bytes: &[u8] = match self {
                Words::U64(v) => bytemuck::cast_slice(v),
                Words::Usize(v) => bytemuck::cast_slice(v),
                Words::F64(v) => bytemuck::cast_slice(v),
                Words::Shared(v) => bytemuck::cast_slice(&v[..]),
                Words::Columns(m, cols) => {
                    let pieces = cols.iter().map(|&(j, from)| m.column(j, from));
                    return in_chunks(pieces, m.rows(), f);
                }
            };
            for c in bytes.chunks(CHUNK) {
                f(c)?;
            }
            Ok(())
        }
        #[cfg(not(all(target_endian = "little", target_pointer_width = "64")))]
        self.for_each_converted_chunk(f)
    }

    /// [`Self::for_each_chunk`] by converting each word.
    #[cfg_attr(
        all(target_endian = "little", target_pointer_width = "64"),
        allow(dead_code)
    )]
    fn for_each_converted_chunk(
        &self,
        mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let mut buf = Vec::with_capacity(CHUNK);
        let per = CHUNK / 8;
        macro_rules! chunks {
            ($v:expr, $conv:expr) => {
                for c in $v.chunks(per) {
                    buf.clear();
                    for x in c {
                        buf.extend_from_slice(&$conv(*x).to_le_bytes());
                    }
                    f(&buf)?;
                }
            };
        }
        match self {
            Words::U64(v) => chunks!(v, |x: u64| x),
            Words::Usize(v) => chunks!(v, |x: usize| x as u64),
            Words::F64(v) => chunks!(v, |x: f64| x),
            Words::Shared(v) => chunks!(&v[..], |x: f64| x),
            Words::Columns(..) => {
                chunks!(self.gathered().expect("gathered words"), |x: f64| x)
            }
        }
        Ok(())
    }

    /// The words as unsigned integers (a section of kind 1).
    pub fn into_u64(self) -> Option<Vec<u64>> {
        match self {
            Words::U64(v) => Some(v),
            Words::Usize(v) => Some(v.into_iter().map(|x| x as u64).collect()),
            _ => None,
        }
    }

    /// The words as floats (a section of kind 2).
    pub fn into_f64(self) -> Option<Vec<f64>> {
        match self {
            Words::F64(v) => Some(v),
            Words::Shared(v) => Some(v.to_vec()),
            Words::Columns(..) => self.gathered(),
            _ => None,
        }
    }

    /// The floats of [`Words::Columns`], one column after the other.
    fn gathered(&self) -> Option<Vec<f64>> {
        match self {
            Words::Columns(m, cols) => Some(
                cols.iter()
                    .flat_map(|&(j, from)| m.column(j, from).iter().copied())
                    .collect(),
            ),
            _ => None,
        }
    }
}

/// A cache entry: tagged sections, written and read in this order.
pub struct Entry {
    pub sections: Vec<(u32, Words)>,
    /// The entry's temporary file when its first section is already in it (the factor values
    /// computed in place, [`Draft`]): the writer hashes that section and writes the others.
    pub draft: Option<DraftFile>,
}

impl Entry {
    /// Size of the entry's file in bytes.
    pub fn file_len(&self) -> u64 {
        HEADER_AREA
            + self
                .sections
                .iter()
                .map(|(_, w)| 8 * w.len() as u64)
                .sum::<u64>()
    }
}

/// The words of a file section mapped for writing: a new entry's factor values, which the
/// numeric factorisation computes in place.
pub struct WritableSection {
    map: memmap2::MmapMut,
    /// Byte offset of the section in the mapping (a multiple of 8).
    offset: usize,
    /// Number of floats.
    len: usize,
}

impl WritableSection {
    /// Number of floats.
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The floats, to be written.
    pub fn as_mut_f64(&mut self) -> &mut [f64] {
        assert!(
            self.offset + 8 * self.len <= self.map.len(),
            "a section within its mapping"
        );
        // SAFETY: in bounds (checked above).
        let p = unsafe { self.map.as_mut_ptr().add(self.offset) };
        assert!(
            cfg!(target_endian = "little") && (p as usize).is_multiple_of(8),
            "mapped floats must be aligned little-endian words"
        );
        // SAFETY: aligned, in bounds, little-endian f64 words (checked above); any bit pattern
        // is a valid f64; the mapping lives as long as `self`, borrowed mutably here.
        unsafe { std::slice::from_raw_parts_mut(p.cast::<f64>(), self.len) }
    }

    /// Faults the section's pages in for writing, in parts on rayon's threads
    /// (`MADV_POPULATE_WRITE`, Linux 5.14 on): the pages of a new file read as zeros, so this
    /// is the parallel first touch without writing the zeros again. `false` where the kernel
    /// refuses it (the caller then writes the zeros). Zeros only on a [`Draft`]'s new file
    /// (`create_new`, blocks reserved), which is the only section of this type.
    pub fn populate(&self) -> bool {
        #[cfg(target_os = "linux")]
        {
            use rayon::prelude::*;
            const PART: usize = 64 << 20;
            let page = 4096;
            let start = self.offset / page * page;
            let end = self.offset + 8 * self.len;
            let parts: Vec<usize> = (start..end).step_by(PART).collect();
            parts.par_iter().all(|&a| {
                self.map
                    .advise_range(memmap2::Advice::PopulateWrite, a, PART.min(end - a))
                    .is_ok()
            })
        }
        #[cfg(not(target_os = "linux"))]
        false
    }

    /// The address of the floats (to tell them from a copy).
    fn address(&self) -> usize {
        self.map.as_ptr() as usize + self.offset
    }

    /// The section, written, as words that stay mapped (and are only read from here on).
    pub fn into_mapped(self) -> MappedWords {
        MappedWords {
            map: Pages::Written(self.map),
            offset: self.offset,
            len: self.len,
        }
    }
}

/// The temporary file of a new entry, removed when dropped unless [`write_entry`] renamed it
/// into place.
pub struct DraftFile {
    file: std::fs::File,
    tmp: PathBuf,
    /// Floats in its first section, already written.
    first_len: usize,
    /// Where the run holds them (the draft's mapping), to check that the entry's first section
    /// is those very floats.
    first_at: usize,
}

impl Drop for DraftFile {
    fn drop(&mut self) {
        if !self.tmp.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// A new entry's temporary file, created before the numeric factorisation with room for
/// `len` floats of factor values as its first section, mapped for writing: the factorisation
/// computes the values in the file's own pages, and the entry's writer only hashes them.
pub struct Draft {
    pub file: DraftFile,
    pub values: WritableSection,
}

/// Whether new entries' factor values may be computed in their file ([`Draft`]); set
/// `STICKSLIP_CACHE_IN_PLACE=0` to compute them in memory and write them afterwards (the
/// same bytes; a diagnostic for file systems where shared mappings misbehave).
fn in_place_allowed() -> bool {
    std::env::var("STICKSLIP_CACHE_IN_PLACE").map_or(true, |v| v != "0")
}

impl Draft {
    /// The draft of the entry under `key`, or `None` (nothing left behind) where the values
    /// cannot be computed in place: not on Linux or not little-endian, the cache directory
    /// cannot be written, the values alone exceed the cache's cap, or the file system is not
    /// one whose `fallocate` reserves the blocks for good ([`reserves_blocks`]) or it could not
    /// reserve them. A write to a mapped page for which the file system then finds no room
    /// kills the process (`SIGBUS`): where space may still run out after `fallocate`
    /// (copy-on-write file systems such as btrfs and ZFS, network file systems), the values
    /// go to memory.
    pub fn create(store: &Store, key: Key, len: usize) -> Option<Draft> {
        let bytes = HEADER_AREA.checked_add(8 * len as u64)?;
        if !cfg!(all(target_os = "linux", target_endian = "little"))
            || !in_place_allowed()
            || bytes > store.max_bytes
        {
            return None;
        }
        std::fs::create_dir_all(&store.dir).ok()?;
        let tmp = temporary_path(&store.path(key));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&tmp)
            .ok()?;
        // Removes the file from here on if anything fails.
        let mut draft_file = DraftFile {
            file,
            tmp,
            first_len: len,
            first_at: 0,
        };
        if !reserves_blocks(&draft_file.file) || !reserve(&draft_file.file, bytes) {
            return None;
        }
        // SAFETY: a file this process just created (`create_new`) under a name of its own;
        // see `Reader::map_next` on files changed by other programs while mapped.
        let map = unsafe {
            memmap2::MmapOptions::new()
                .len(usize::try_from(bytes).ok()?)
                .map_mut(&draft_file.file)
        }
        .ok()?;
        let values = WritableSection {
            map,
            offset: HEADER_AREA as usize,
            len,
        };
        draft_file.first_at = values.address();
        Some(Draft {
            file: draft_file,
            values,
        })
    }
}

/// Whether `file` is on a file system whose `fallocate` reserves the blocks for good, so
/// that writes through a mapping of them cannot fail for want of space: ext2/3/4, XFS and
/// tmpfs (Linux `statfs` magic numbers). Not the copy-on-write ones (btrfs, ZFS, bcachefs:
/// a write to a reserved block may need a new one) nor network or FUSE file systems.
fn reserves_blocks(file: &std::fs::File) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        const EXT: i64 = 0xEF53;
        const XFS: i64 = 0x5846_5342;
        const TMPFS: i64 = 0x0102_1994;
        // SAFETY: `statfs` is plain data, filled in by the call on a valid descriptor.
        let mut st: libc::statfs = unsafe { std::mem::zeroed() };
        if unsafe { libc::fstatfs(file.as_raw_fd(), &mut st) } != 0 {
            return false;
        }
        // `f_type` is an `i64` on most targets, narrower on some.
        #[allow(clippy::unnecessary_cast)]
        let kind = st.f_type as i64;
        matches!(kind, EXT | XFS | TMPFS)
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = file;
        false
    }
}

struct SectionInfo {
    tag: u32,
    kind: u32,
    words: u64,
    hash: u64,
}

fn header_bytes(key: Key, table: &[SectionInfo]) -> Vec<u8> {
    let mut h = Vec::with_capacity(32 + 24 * table.len() + 8);
    h.extend_from_slice(&MAGIC);
    h.extend_from_slice(&FORMAT.to_le_bytes());
    h.extend_from_slice(&(table.len() as u32).to_le_bytes());
    h.extend_from_slice(&key.0[0].to_le_bytes());
    h.extend_from_slice(&key.0[1].to_le_bytes());
    for s in table {
        h.extend_from_slice(&s.tag.to_le_bytes());
        h.extend_from_slice(&s.kind.to_le_bytes());
        h.extend_from_slice(&s.words.to_le_bytes());
        h.extend_from_slice(&s.hash.to_le_bytes());
    }
    let sum = xxh64(&h, 0);
    h.extend_from_slice(&sum.to_le_bytes());
    h
}

/// Reserves the file's blocks before it is written (Linux: `fallocate`; a hint, whose failure
/// the writes then report if it matters). The file system then maps each page as it is
/// written instead of reserving its block one page at a time: the cache writer's CPU for a
/// 148 MB entry (L5) 42–43 → 32–33 ms, in `STICKSLIP_TRACE`'s `cache entry written` mark.
pub(crate) fn preallocate(file: &std::fs::File, len: u64) {
    let _ = reserve(file, len);
}

/// Reserves the first `len` bytes of `file`'s blocks and makes it that long (zeros):
/// `true` if the file system did both, so that writes there through a mapping cannot fail
/// for want of space.
fn reserve(file: &std::fs::File, len: u64) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        let Ok(len) = libc::off_t::try_from(len) else {
            return false;
        };
        // SAFETY: a valid open descriptor; the call only allocates the file's blocks (and,
        // with mode 0, extends the file to `len`).
        unsafe { libc::fallocate(file.as_raw_fd(), 0, 0, len) == 0 }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = (file, len);
        false
    }
}

/// A temporary name for the entry `path` in its directory, unique in this process.
fn temporary_path(path: &Path) -> PathBuf {
    static SERIAL: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    // The process id and a counter, and the clock's nanoseconds for processes that share a
    // directory across machines or process-id namespaces; files are created with
    // `create_new`, so a clash is an error, never a file taken over.
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    dir.join(format!(
        ".{name}.tmp{}-{}-{nanos:09}",
        std::process::id(),
        SERIAL.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ))
}

/// Writes `entry` under `key` to `path`, through a temporary file in the same directory (the
/// entry's draft, whose first section is already written, if it has one).
fn write_entry(path: &Path, key: Key, mut entry: Entry) -> std::io::Result<u64> {
    let len = entry.file_len();
    if entry.sections.len() > MAX_SECTIONS {
        return Err(std::io::Error::other("too many sections for the header"));
    }
    let mut draft = match entry.draft.take() {
        Some(d) => d,
        None => {
            let tmp = temporary_path(path);
            let file = std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&tmp)?;
            let d = DraftFile {
                file,
                tmp,
                first_len: 0,
                first_at: 0,
            };
            preallocate(&d.file, len);
            d
        }
    };
    let prewritten = draft.first_len;
    // A draft's first section must be the very floats in its file.
    if prewritten > 0 {
        let same = match entry.sections.first() {
            Some((_, Words::Shared(v))) => {
                v.len() == prewritten && v.as_ptr() as usize == draft.first_at
            }
            _ => false,
        };
        if !same {
            return Err(std::io::Error::other(
                "the entry's first section is not the values in its draft",
            ));
        }
    }
    let mut f = std::io::BufWriter::with_capacity(CHUNK, &draft.file);
    f.seek(SeekFrom::Start(HEADER_AREA + 8 * prewritten as u64))?;
    let mut table = Vec::with_capacity(entry.sections.len());
    for (i, (tag, words)) in entry.sections.iter().enumerate() {
        let mut h = Xxh64::new(0);
        if i == 0 && prewritten > 0 {
            words.for_each_chunk(|b| {
                h.update(b);
                Ok(())
            })?;
        } else {
            words.for_each_chunk(|b| {
                h.update(b);
                f.write_all(b)
            })?;
        }
        table.push(SectionInfo {
            tag: *tag,
            kind: words.kind(),
            words: words.len() as u64,
            hash: h.finish(),
        });
    }
    let mut f = f.into_inner().map_err(|e| e.into_error())?;
    f.seek(SeekFrom::Start(0))?;
    f.write_all(&header_bytes(key, &table))?;
    // A draft's reserved blocks cover its first section only; a file written here is as
    // long as its last write.
    draft.file.set_len(len)?;
    std::fs::rename(&draft.tmp, path)?;
    draft.tmp = PathBuf::new();
    Ok(len)
}

/// An entry opened for reading: its header checked, its sections read one after the other
/// (each checked against its hash).
pub struct Reader {
    file: std::fs::File,
    table: Vec<SectionInfo>,
    next: usize,
    /// Byte offset of the next section in the file.
    pos: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

/// What [`Store::open`] finds.
pub enum Open {
    /// No entry for the key.
    Missing,
    /// An entry that cannot be used, and why.
    Corrupt(String),
    Ready(Reader),
}

impl Reader {
    fn open(path: &Path, key: Key) -> Open {
        let mut file = match std::fs::File::open(path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Open::Missing,
            Err(e) => return Open::Corrupt(format!("cannot be read: {e}")),
        };
        match Self::header(&mut file, key) {
            Ok((table, bytes)) => Open::Ready(Reader {
                pos: HEADER_AREA,
                file,
                table,
                next: 0,
                bytes,
            }),
            Err(why) => Open::Corrupt(why),
        }
    }

    fn header(file: &mut std::fs::File, key: Key) -> Result<(Vec<SectionInfo>, u64), String> {
        let len = file
            .metadata()
            .map_err(|e| format!("cannot be read: {e}"))?
            .len();
        let short = |need: u64| format!("truncated: {len} bytes, its header alone needs {need}");
        let mut head = [0u8; 32];
        file.read_exact(&mut head).map_err(|_| short(32))?;
        if head[..8] != MAGIC {
            return Err("not a stickslip model cache file (bad magic number)".into());
        }
        let format = u32::from_le_bytes(head[8..12].try_into().expect("4 bytes"));
        if format != FORMAT {
            return Err(format!(
                "written in cache format {format}, this program uses format {FORMAT}"
            ));
        }
        let count = u32::from_le_bytes(head[12..16].try_into().expect("4 bytes")) as usize;
        if count > MAX_SECTIONS {
            return Err(format!("corrupt header ({count} sections)"));
        }
        let mut rest = vec![0u8; 24 * count + 8];
        let need = 32 + rest.len() as u64;
        file.read_exact(&mut rest).map_err(|_| short(need))?;
        let mut all = head.to_vec();
        all.extend_from_slice(&rest[..24 * count]);
        let sum = le64(&rest[24 * count..]);
        if xxh64(&all, 0) != sum {
            return Err("corrupt header (checksum mismatch)".into());
        }
        let mut padding = vec![0u8; (HEADER_AREA - need) as usize];
        file.read_exact(&mut padding)
            .map_err(|_| short(HEADER_AREA))?;
        if padding.iter().any(|&b| b != 0) {
            return Err("corrupt header (bytes after it not zero)".into());
        }
        let file_key = Key([le64(&head[16..]), le64(&head[24..])]);
        if file_key != key {
            return Err(format!("holds another model (key {})", file_key.hex()));
        }
        let table: Vec<SectionInfo> = rest[..24 * count]
            .chunks_exact(24)
            .map(|c| SectionInfo {
                tag: u32::from_le_bytes(c[0..4].try_into().expect("4 bytes")),
                kind: u32::from_le_bytes(c[4..8].try_into().expect("4 bytes")),
                words: le64(&c[8..]),
                hash: le64(&c[16..]),
            })
            .collect();
        let expected = table
            .iter()
            .try_fold(HEADER_AREA, |acc, s| {
                s.words.checked_mul(8)?.checked_add(acc)
            })
            .ok_or_else(|| "corrupt header (section sizes overflow)".to_string())?;
        if len < expected {
            return Err(format!("truncated: {len} of {expected} bytes"));
        }
        if len > expected {
            return Err(format!(
                "{} bytes longer than its header says",
                len - expected
            ));
        }
        Ok((table, len))
    }

    /// Sections not yet read.
    pub fn remaining(&self) -> usize {
        self.table.len() - self.next
    }

    /// The tag of the next section, if any.
    pub fn next_tag(&self) -> Option<u32> {
        self.table.get(self.next).map(|s| s.tag)
    }

    /// Reads the next section and checks it against its hash: (tag, words).
    pub fn read_next(&mut self) -> Result<(u32, Words), String> {
        let s = self
            .table
            .get(self.next)
            .ok_or_else(|| "fewer sections than expected".to_string())?;
        self.next += 1;
        self.pos += 8 * s.words;
        let n = usize::try_from(s.words).map_err(|_| "section too large".to_string())?;
        let mut h = Xxh64::new(0);
        let mut buf = vec![0u8; CHUNK.min(8 * n)];
        let mut done = 0usize;
        let words = match s.kind {
            1 => {
                let mut v: Vec<u64> = Vec::with_capacity(n);
                while done < n {
                    let k = (n - done).min(CHUNK / 8);
                    let b = &mut buf[..8 * k];
                    self.file
                        .read_exact(b)
                        .map_err(|e| format!("cannot be read: {e}"))?;
                    h.update(b);
                    v.extend(b.chunks_exact(8).map(le64));
                    done += k;
                }
                Words::U64(v)
            }
            2 => {
                let mut v: Vec<f64> = Vec::with_capacity(n);
                while done < n {
                    let k = (n - done).min(CHUNK / 8);
                    let b = &mut buf[..8 * k];
                    self.file
                        .read_exact(b)
                        .map_err(|e| format!("cannot be read: {e}"))?;
                    h.update(b);
                    v.extend(b.chunks_exact(8).map(|c| f64::from_bits(le64(c))));
                    done += k;
                }
                Words::F64(v)
            }
            k => return Err(format!("corrupt header (section kind {k})")),
        };
        if h.finish() != s.hash {
            return Err(format!(
                "corrupt data (checksum mismatch in section {} of {})",
                self.next,
                self.table.len()
            ));
        }
        Ok((s.tag, words))
    }
}

impl Reader {
    /// Maps the next section, of floats, into memory instead of reading it (the file's pages
    /// are used in place): (tag, words still to be checked against their hash, which
    /// [`Unchecked::check`] does, on another thread if the caller likes). Falls back to
    /// [`Self::read_next`] where the file's bytes cannot be viewed as floats in place (a
    /// big-endian machine) or the mapping fails.
    ///
    /// The mapping lasts as long as the words. Entries are replaced by renaming a new file over
    /// them and evicted by deleting them, neither of which changes a mapped file; a file cut
    /// short by another program while a run reads it would stop that run (`SIGBUS`).
    pub fn map_next(&mut self) -> Result<(u32, Unchecked), String> {
        use crate::la::FactorValues;
        let read = |r: &mut Reader| -> Result<(u32, Unchecked), String> {
            let (tag, words) = r.read_next()?;
            let v = words.into_f64().ok_or_else(|| {
                "inconsistent (a section of integers where floats belong)".to_string()
            })?;
            Ok((tag, Unchecked::Read(FactorValues::Owned(v))))
        };
        let Some(s) = self.table.get(self.next) else {
            return Err("fewer sections than expected".into());
        };
        if cfg!(target_endian = "big") || s.kind != 2 {
            return read(self);
        }
        let (tag, words, hash) = (s.tag, s.words, s.hash);
        let (Ok(offset), Ok(len)) = (usize::try_from(self.pos), usize::try_from(words)) else {
            return Err("section too large".into());
        };
        // SAFETY: the file is only read; see the note above on files changed while mapped.
        let Ok(map) = (unsafe { memmap2::MmapOptions::new().map(&self.file) }) else {
            return read(self);
        };
        if map.len() < offset + 8 * len {
            return Err(format!(
                "truncated: {} bytes, its sections need {}",
                map.len(),
                offset + 8 * len
            ));
        }
        self.next += 1;
        self.pos += 8 * words;
        self.file
            .seek(SeekFrom::Start(self.pos))
            .map_err(|e| format!("cannot be read: {e}"))?;
        Ok((
            tag,
            Unchecked::Mapped {
                words: MappedWords {
                    map: Pages::Read(map),
                    offset,
                    len,
                },
                hash,
                section: (self.next, self.table.len()),
            },
        ))
    }
}

/// Floats of a section from [`Reader::map_next`], to be checked against their hash.
pub enum Unchecked {
    /// Read (and checked) already.
    Read(crate::la::FactorValues),
    /// Mapped: the hash and the section's place (1-based number, of how many) for the report.
    Mapped {
        words: MappedWords,
        hash: u64,
        section: (usize, usize),
    },
}

impl Unchecked {
    /// The floats, once their bytes match the section's hash.
    pub fn check(self) -> Result<crate::la::FactorValues, String> {
        match self {
            Unchecked::Read(v) => Ok(v),
            Unchecked::Mapped {
                words,
                hash,
                section: (k, of),
            } => {
                // The pages are read once, in order, by the hash.
                #[cfg(unix)]
                let _ = words.map.advise(memmap2::Advice::Sequential);
                let mut h = Xxh64::new(0);
                h.update(words.bytes());
                if h.finish() != hash {
                    return Err(format!(
                        "corrupt data (checksum mismatch in section {k} of {of})"
                    ));
                }
                #[cfg(unix)]
                let _ = words.map.advise(memmap2::Advice::Normal);
                Ok(crate::la::FactorValues::Stored(Box::new(words)))
            }
        }
    }
}

/// The pages of a mapped file.
enum Pages {
    Read(memmap2::Mmap),
    /// Mapped for writing, and written ([`WritableSection`]).
    Written(memmap2::MmapMut),
}

impl Pages {
    #[cfg(unix)]
    fn advise(&self, advice: memmap2::Advice) -> std::io::Result<()> {
        match self {
            Pages::Read(m) => m.advise(advice),
            Pages::Written(m) => m.advise(advice),
        }
    }

    /// The start of the mapping and its length in bytes (no reference to the whole mapping is
    /// formed: for a draft, the entry's writer writes the header page while the run reads the
    /// values).
    fn raw(&self) -> (*const u8, usize) {
        match self {
            Pages::Read(m) => (m.as_ptr(), m.len()),
            Pages::Written(m) => (m.as_ptr(), m.len()),
        }
    }
}

/// A section of floats mapped from a cache file (see [`Reader::map_next`]).
pub struct MappedWords {
    map: Pages,
    /// Byte offset of the section in the file (a multiple of 8).
    offset: usize,
    /// Number of floats.
    len: usize,
}

impl MappedWords {
    fn bytes(&self) -> &[u8] {
        let (p, len) = self.map.raw();
        assert!(
            self.offset + 8 * self.len <= len,
            "a section within its mapping"
        );
        // SAFETY: in bounds (checked above) of a mapping that lives as long as `self`; these
        // bytes are not written while the words exist (a draft's values are complete before
        // they become words, and nothing writes them after).
        unsafe { std::slice::from_raw_parts(p.add(self.offset), 8 * self.len) }
    }

    /// The floats, in place.
    pub fn as_f64(&self) -> &[f64] {
        let b = self.bytes();
        // Every section starts at a multiple of 8 bytes from the start of the file, and a
        // mapping starts on a page boundary, so the floats are aligned.
        assert!(
            cfg!(target_endian = "little") && (b.as_ptr() as usize).is_multiple_of(8),
            "mapped floats must be aligned little-endian words"
        );
        // SAFETY: aligned, in bounds, little-endian f64 words (checked above); any bit pattern
        // is a valid f64; the mapping lives as long as `self`.
        unsafe { std::slice::from_raw_parts(b.as_ptr().cast::<f64>(), self.len) }
    }
}

impl crate::la::StoredValues for MappedWords {
    fn as_f64(&self) -> &[f64] {
        MappedWords::as_f64(self)
    }
}

impl crate::la::ValuesDestination for WritableSection {
    fn as_mut_f64(&mut self) -> &mut [f64] {
        WritableSection::as_mut_f64(self)
    }
    fn populate(&self) -> bool {
        WritableSection::populate(self)
    }
    fn into_stored(self: Box<Self>) -> Box<dyn crate::la::StoredValues> {
        Box::new(self.into_mapped())
    }
}

// ------------------------------------------------------------------------------------------
// Store
// ------------------------------------------------------------------------------------------

/// Where the cache is, from the command line.
#[derive(Clone, Debug, Default)]
pub enum Choice {
    /// The default place (environment, then the per-user cache directory).
    #[default]
    Default,
    /// `--cache DIR`.
    Dir(PathBuf),
    /// `--no-cache`.
    Off,
}

/// How the cache served a model, for `summary.json`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Loaded from the cache.
    Hit,
    /// Not in the cache: built, and written to it.
    Miss,
    /// An entry was there but unusable (truncated, corrupt, foreign): built and written again.
    Rebuilt,
    /// No cache (`--no-cache`, or no place for it).
    Off,
}

/// The cache's part in a model, as `summary.json` reports it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    pub status: Status,
    /// The entry's file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    /// Its size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes: Option<u64>,
    /// Why an entry was rebuilt, not written, or why there is no cache.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// A new entry: whether the factorisation computed its factor values in the entry's file
    /// ([`Draft`]) rather than in memory, copied to the file afterwards.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor_in_place: Option<bool>,
}

impl Report {
    /// The report of a new entry that was not written, and `why`: no file to name.
    pub fn not_written(&mut self, why: &str) {
        let why = format!("not written: {why}");
        self.note = Some(match self.note.take() {
            Some(n) => format!("{n}; {why}"),
            None => why,
        });
        self.path = None;
        self.factor_in_place = None;
    }

    pub fn off(note: Option<String>) -> Report {
        Report {
            status: Status::Off,
            path: None,
            bytes: None,
            note,
            factor_in_place: None,
        }
    }
}

/// A cache directory and its size cap.
#[derive(Clone, Debug)]
pub struct Store {
    pub dir: PathBuf,
    pub max_bytes: u64,
    /// Print warnings (an unusable entry, a failed write) on standard error.
    pub warn: bool,
}

fn env_set(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.is_empty())
}

/// Parses a size: bytes, or a number with a binary suffix K, M, G, T (optionally `iB` or `B`).
pub fn parse_size(s: &str) -> Option<u64> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let x: f64 = num.parse().ok()?;
    let mult: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        _ => return None,
    };
    (x.is_finite() && x >= 0.0).then_some((x * mult as f64) as u64)
}

impl Store {
    /// The cache a run uses (see the module documentation), or the report of why it has none.
    pub fn resolve(choice: &Choice, warn: bool) -> Result<Store, Report> {
        let no_cache = env_set("STICKSLIP_NO_CACHE").is_some_and(|v| v != "0");
        let dir = match choice {
            Choice::Off => return Err(Report::off(None)),
            Choice::Dir(d) => d.clone(),
            Choice::Default if no_cache => {
                return Err(Report::off(Some("STICKSLIP_NO_CACHE is set".into())));
            }
            Choice::Default => {
                let xdg = env_set("XDG_CACHE_HOME")
                    .map(PathBuf::from)
                    .filter(|p| p.is_absolute());
                match env_set("STICKSLIP_CACHE_DIR")
                    .map(PathBuf::from)
                    .or_else(|| xdg.map(|x| x.join("stickslip")))
                    .or_else(|| env_set("HOME").map(|h| PathBuf::from(h).join(".cache/stickslip")))
                {
                    Some(d) => d,
                    None => {
                        return Err(Report::off(Some(
                            "no cache directory: set STICKSLIP_CACHE_DIR or HOME, or pass --cache DIR"
                                .into(),
                        )));
                    }
                }
            }
        };
        let max_bytes = match env_set("STICKSLIP_CACHE_MAX") {
            None => DEFAULT_MAX_BYTES,
            Some(v) => match parse_size(&v) {
                Some(b) => b,
                None => {
                    if warn {
                        eprintln!(
                            "warning: STICKSLIP_CACHE_MAX = `{v}` is not a size (e.g. 4G, 500M, 1073741824); using 4 GiB"
                        );
                    }
                    DEFAULT_MAX_BYTES
                }
            },
        };
        Ok(Store {
            dir,
            max_bytes,
            warn,
        })
    }

    /// The file of the entry with `key`.
    pub fn path(&self, key: Key) -> PathBuf {
        self.dir.join(format!("model-{}.bin", key.hex()))
    }

    /// Opens the entry with `key`; a hit marks it as recently used.
    pub fn open(&self, key: Key) -> Open {
        let path = self.path(key);
        let open = Reader::open(&path, key);
        if let Open::Ready(r) = &open {
            let _ = r.file.set_modified(std::time::SystemTime::now());
        }
        open
    }

    /// Deletes an unusable entry (reported with `why`).
    pub fn discard(&self, key: Key, why: &str) {
        let path = self.path(key);
        if self.warn {
            eprintln!(
                "warning: model cache: {} {why}; ignoring it and building the model again",
                path.display()
            );
        }
        let _ = std::fs::remove_file(&path);
    }

    /// Writes `entry` under `key` in a background thread (after making room for it under the
    /// cap). Returns the report of the entry (`status` is the caller's) and the job, which
    /// waits for the write when dropped.
    pub fn write_in_background(
        &self,
        key: Key,
        entry: Entry,
        status: Status,
        note: Option<String>,
    ) -> (Report, Option<Job>) {
        let path = self.path(key);
        let bytes = entry.file_len();
        let mut report = Report {
            status,
            path: Some(path.display().to_string()),
            bytes: Some(bytes),
            note,
            factor_in_place: Some(entry.draft.is_some()),
        };
        if bytes > self.max_bytes {
            report.not_written(&format!(
                "{bytes} bytes exceed the cache cap of {} bytes (STICKSLIP_CACHE_MAX)",
                self.max_bytes
            ));
            return (report, None);
        }
        let store = self.clone();
        let p = path.clone();
        // Counted from before the thread starts, so that no solve in between sees it idle.
        let busy = Writing::start();
        let handle = std::thread::Builder::new()
            .name("model-cache-writer".into())
            .spawn(move || {
                let _busy = busy;
                std::fs::create_dir_all(&store.dir)
                    .map_err(|e| format!("cannot create {}: {e}", store.dir.display()))?;
                evict(&store.dir, store.max_bytes.saturating_sub(bytes), &p);
                write_entry(&p, key, entry).map_err(|e| e.to_string())?;
                crate::trace::mark("cache entry written");
                Ok(())
            });
        match handle {
            Ok(h) => (
                report,
                Some(Job {
                    handle: Some(h),
                    path,
                    warn: self.warn,
                }),
            ),
            Err(e) => {
                report.note = Some(format!("not written: cannot start the writer: {e}"));
                (report, None)
            }
        }
    }
}

/// Entries being written in the background now.
static WRITING: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Whether an entry is being written in the background: that thread takes a core of its own
/// (copying hundreds of MB into the page cache), and a dense kernel split over all of rayon's
/// threads would then wait for its slowest part. The contact Newton's block factorisations
/// run on one thread meanwhile (the same bits either way): the first load step on L7 took
/// 252–266 ms with them on two threads, 224–229 ms on one, beside the writer (Fig. 2 with a
/// fresh cache directory, 3 runs of each, twice).
pub fn writing() -> bool {
    WRITING.load(std::sync::atomic::Ordering::Relaxed) > 0
}

/// One entry being written, from its start to its drop.
struct Writing;

impl Writing {
    fn start() -> Writing {
        WRITING.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Writing
    }
}

impl Drop for Writing {
    fn drop(&mut self) {
        WRITING.fetch_sub(1, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Deletes the least recently used entries of `dir` (files `model-*.bin`, by modification
/// time) until they take at most `budget` bytes, never `keep`; and temporary files left by
/// writers that were killed (older than an hour).
pub fn evict(dir: &Path, budget: u64, keep: &Path) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let now = std::time::SystemTime::now();
    let mut entries: Vec<(std::time::SystemTime, u64, PathBuf)> = Vec::new();
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Ok(md) = e.metadata() else { continue };
        let mtime = md.modified().unwrap_or(std::time::UNIX_EPOCH);
        if name.starts_with(".model-") && name.contains(".tmp") {
            if now.duration_since(mtime).is_ok_and(|d| d.as_secs() > 3600) {
                let _ = std::fs::remove_file(e.path());
            }
            continue;
        }
        if name.starts_with("model-") && name.ends_with(".bin") && md.is_file() {
            entries.push((mtime, md.len(), e.path()));
        }
    }
    let mut total: u64 = entries.iter().map(|e| e.1).sum();
    entries.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.2.cmp(&b.2)));
    for (_, len, path) in entries {
        if total <= budget {
            break;
        }
        if path == keep {
            continue;
        }
        if std::fs::remove_file(&path).is_ok() {
            total -= len;
        }
    }
}

/// A cache entry being written in the background; dropping it waits for the write (and
/// reports a failure on standard error).
pub struct Job {
    handle: Option<std::thread::JoinHandle<Result<(), String>>>,
    path: PathBuf,
    warn: bool,
}

impl Job {
    /// Waits for the write: `Err` with the reason if it failed.
    pub fn wait(mut self) -> Result<(), String> {
        self.join()
    }

    /// Waits for the write, and reports a failure on standard error as dropping the job would:
    /// the reason, if it failed.
    pub fn settle(mut self) -> Option<String> {
        let e = self.join().err()?;
        if self.warn {
            eprintln!(
                "warning: model cache: could not write {}: {e}",
                self.path.display()
            );
        }
        Some(e)
    }

    fn join(&mut self) -> Result<(), String> {
        match self.handle.take().map(|h| h.join()) {
            None | Some(Ok(Ok(()))) => Ok(()),
            Some(Ok(Err(e))) => Err(e),
            Some(Err(_)) => Err("the writer panicked".into()),
        }
    }
}

impl Drop for Job {
    fn drop(&mut self) {
        if let Err(e) = self.join()
            && self.warn
        {
            eprintln!(
                "warning: model cache: could not write {}: {e}",
                self.path.display()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bytes of `w` as written (its own memory where it can) and converted word by word.
    fn both_ways(w: &Words) -> (Vec<u8>, Vec<u8>) {
        let (mut direct, mut converted) = (Vec::new(), Vec::new());
        w.for_each_chunk(|b| {
            direct.extend_from_slice(b);
            Ok(())
        })
        .unwrap();
        w.for_each_converted_chunk(|b| {
            converted.extend_from_slice(b);
            Ok(())
        })
        .unwrap();
        (direct, converted)
    }

    #[test]
    fn the_bytes_of_words_are_their_little_endian_bytes() {
        let n = CHUNK / 8 + 5; // more than a chunk
        let f: Vec<f64> = (0..n).map(|i| (i as f64).sqrt() - 3.5).collect();
        let u: Vec<usize> = (0..n).map(|i| i * 2_654_435_761).collect();
        let shared = std::sync::Arc::new(crate::la::FactorValues::Owned(f.clone()));
        for w in [
            Words::F64(f.clone()),
            Words::U64(u.iter().map(|&x| x as u64).collect()),
            Words::Usize(u.clone()),
            Words::Shared(shared.clone()),
        ] {
            assert_eq!(w.len(), n);
            let (direct, converted) = both_ways(&w);
            assert_eq!(direct.len(), 8 * n);
            assert!(direct == converted);
        }
        // A dense matrix's columns, all of them and the lower triangle (more than a chunk).
        let m = 1100;
        let a = std::sync::Arc::new(faer::Mat::from_fn(m, m, |i, j| i as f64 - 0.5 * j as f64));
        for (w, lower) in [
            (Words::all_columns(a.clone(), m), false),
            (Words::lower_columns(a.clone(), m), true),
        ] {
            let expected: Vec<u8> = (0..m)
                .flat_map(|j| (if lower { j } else { 0 }..m).map(move |i| (i, j)))
                .flat_map(|(i, j)| a[(i, j)].to_le_bytes())
                .collect();
            let (direct, converted) = both_ways(&w);
            assert_eq!(8 * w.len(), expected.len());
            assert!(direct == expected && converted == expected);
        }
    }

    #[test]
    fn xxh64_reference_values() {
        assert_eq!(xxh64(b"", 0), 0xEF46_DB37_51D8_E999);
        assert_eq!(xxh64(b"a", 0), 0xD24E_C4F1_A98C_6E5B);
        assert_eq!(xxh64(b"abc", 0), 0x44BC_2CF5_AD77_0999);
        // Longer inputs (the 32-byte stripes), values from the `xxhash` Python package.
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
        assert_eq!(xxh64(&data, 42), 0xe7ca_5372_fc8e_a0a7);
        assert_eq!(xxh64(&data[..100], 0), 0xdad7_6c5e_3ed4_0107);
    }

    #[test]
    fn xxh64_streaming_matches_one_shot() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 + i / 13) as u8).collect();
        for split in [0, 1, 7, 31, 32, 33, 100, 999, 1000] {
            let mut h = Xxh64::new(42);
            h.update(&data[..split]);
            h.update(&data[split..]);
            assert_eq!(h.finish(), xxh64(&data, 42), "split {split}");
        }
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("4G"), Some(4 << 30));
        assert_eq!(parse_size("500MiB"), Some(500 << 20));
        assert_eq!(parse_size("1024"), Some(1024));
        assert_eq!(parse_size("1.5k"), Some(1536));
        assert_eq!(parse_size("lots"), None);
    }
}
