//! Writing an entry: its sections, the draft file a factorisation computes its values in, and
//! the atomic rename into place.

use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::format::{CHUNK, FORMAT, HEADER_AREA, MAGIC, MAX_SECTIONS, SectionInfo};
use super::hash::{Xxh64, xxh64};
use super::key::Key;
use super::reader::{MappedWords, Pages};
use super::words::Words;

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
        // A run-time check: the crate builds on big-endian machines, whose cache is unusable.
        #[allow(clippy::assertions_on_constants)]
        {
            assert!(
                cfg!(target_endian = "little"),
                "mapped floats are little-endian words"
            );
        }
        let bytes = &mut self.map[self.offset..self.offset + 8 * self.len];
        // Every section starts at a multiple of 8 bytes from the page-aligned start of the file
        // (checked by the cast).
        bytemuck::try_cast_slice_mut(bytes).expect("mapped floats are aligned")
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
pub(super) fn in_place_allowed() -> bool {
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
    /// In the directory `dir`, for the entry at `path` (`max_bytes`: the cache's size cap).
    pub(super) fn create(dir: &Path, path: &Path, max_bytes: u64, len: usize) -> Option<Draft> {
        let bytes = HEADER_AREA.checked_add(8 * len as u64)?;
        if !cfg!(all(target_os = "linux", target_endian = "little"))
            || !in_place_allowed()
            || bytes > max_bytes
        {
            return None;
        }
        std::fs::create_dir_all(dir).ok()?;
        let tmp = temporary_path(path);
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
pub(super) fn reserves_blocks(file: &std::fs::File) -> bool {
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        const EXT: i64 = 0xEF53;
        const XFS: i64 = 0x5846_5342;
        const TMPFS: i64 = 0x0102_1994;
        // SAFETY: `statfs` is plain data (all zeros is a value of it), filled in by the call
        // on a valid descriptor that `file` keeps open.
        let (rc, st) = unsafe {
            let mut st: libc::statfs = std::mem::zeroed();
            (libc::fstatfs(file.as_raw_fd(), &mut st), st)
        };
        if rc != 0 {
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

pub(super) fn header_bytes(key: Key, table: &[SectionInfo]) -> Vec<u8> {
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
pub(super) fn reserve(file: &std::fs::File, len: u64) -> bool {
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
pub(super) fn temporary_path(path: &Path) -> PathBuf {
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
pub(super) fn write_entry(path: &Path, key: Key, mut entry: Entry) -> std::io::Result<u64> {
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
