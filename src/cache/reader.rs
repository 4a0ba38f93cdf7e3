//! Reading an entry: sections read and checked, or mapped in place.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use super::format::{CHUNK, FORMAT, HEADER_AREA, MAGIC, MAX_SECTIONS, SectionInfo};
use super::hash::{Xxh64, le64, xxh64};
use super::key::Key;
use super::words::Words;

/// An entry opened for reading: its header checked, its sections read one after the other
/// (each checked against its hash).
pub struct Reader {
    pub(super) file: std::fs::File,
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
    pub(super) fn open(path: &Path, key: Key) -> Open {
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
pub(super) enum Pages {
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
    pub(super) map: Pages,
    /// Byte offset of the section in the file (a multiple of 8).
    pub(super) offset: usize,
    /// Number of floats.
    pub(super) len: usize,
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
        // A run-time check: the crate builds on big-endian machines, whose cache is unusable.
        #[allow(clippy::assertions_on_constants)]
        {
            assert!(
                cfg!(target_endian = "little"),
                "mapped floats are little-endian words"
            );
        }
        // Every section starts at a multiple of 8 bytes from the page-aligned start of the
        // file (checked by the cast).
        bytemuck::try_cast_slice(self.bytes()).expect("mapped floats are aligned")
    }
}

impl crate::la::StoredValues for MappedWords {
    fn as_f64(&self) -> &[f64] {
        MappedWords::as_f64(self)
    }
}
