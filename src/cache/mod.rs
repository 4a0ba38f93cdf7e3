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

mod entry;
mod format;
mod hash;
mod key;
mod reader;
mod store;
#[cfg(test)]
mod tests;
mod words;

pub use entry::{Draft, DraftFile, Entry, WritableSection};
pub use format::{DEFAULT_MAX_BYTES, FORMAT, HEADER_AREA};
pub use hash::{Xxh64, hash_f64s, xxh64};
pub use key::{Key, build_id, model_key};
pub use reader::{MappedWords, Open, Reader, Unchecked};
pub use store::{Choice, Job, Report, Status, Store, evict, parse_size};
pub use words::Words;
