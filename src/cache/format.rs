//! The entry file's layout constants.

/// Version of the file format and of the meaning of the sections. Bump it when either changes.
pub const FORMAT: u32 = 4;
pub(super) const MAGIC: [u8; 8] = *b"stkslpMC";
/// Default size cap of the cache directory.
pub const DEFAULT_MAX_BYTES: u64 = 4 << 30;
/// At most this many sections in a file (a larger count is a corrupt header).
pub(super) const MAX_SECTIONS: usize = 64;
/// Bytes read or written per chunk.
pub(super) const CHUNK: usize = 1 << 20;
/// Bytes before the first section: the header, then zeros.
pub const HEADER_AREA: u64 = 4096;
const _: () = assert!(32 + 24 * MAX_SECTIONS as u64 + 8 <= HEADER_AREA);

/// One section of an entry's table: its tag, the kind of its words, their count and hash.
pub(super) struct SectionInfo {
    pub(super) tag: u32,
    pub(super) kind: u32,
    pub(super) words: u64,
    pub(super) hash: u64,
}
