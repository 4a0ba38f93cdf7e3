//! Files written whole or not at all: each file is written to a temporary name in its
//! directory and renamed into place ([`commit`]), several files together or none
//! ([`write_temporaries`]), large ones past the page cache where the file system allows it
//! (`super::direct`), the tail of a large one ahead of its head ([`write_ahead`]), and the
//! renames on a thread of their own ([`Reaper`]).

use super::direct;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_parts(path, &[bytes])
}

/// Writes the byte strings `parts`, one after the other, to `path` atomically (temporary
/// file + rename), without joining them in memory first.
pub fn write_atomic_parts(path: &Path, parts: &[&[u8]]) -> std::io::Result<()> {
    let tmp = write_temporary(path, parts)?;
    commit(&tmp, path)
}

/// The first half of [`write_atomic_parts`]: writes `parts` to the temporary name of `path`
/// (in the same directory) and returns it; nothing is left behind on an error.
pub fn write_temporary(path: &Path, parts: &[&[u8]]) -> std::io::Result<PathBuf> {
    let (tmp, file) = write_unsynced(path, parts)?;
    if let Some(f) = file {
        // A file system that cannot sync still gets the file.
        f.sync_all().ok();
    }
    Ok(tmp)
}

/// [`write_temporary`] for several files at once: each written to its temporary name, then all
/// synced, so that the file system commits them together (on ext4 the first sync writes the
/// others' data and metadata with its own: one journal commit instead of one per file, 0.2–5 ms
/// each on the machine of `docs/benchmarks.md`). Returns the temporary names in order, or the
/// index of the file that failed and its error, with nothing left behind.
pub fn write_temporaries(
    files: &[(&Path, &[u8])],
) -> Result<Vec<PathBuf>, (usize, std::io::Error)> {
    let mut written = Vec::with_capacity(files.len());
    for (i, (path, bytes)) in files.iter().enumerate() {
        match write_unsynced(path, &[bytes]) {
            Ok(w) => written.push(w),
            Err(e) => {
                for (tmp, _) in &written {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err((i, e));
            }
        }
    }
    for f in written.iter().filter_map(|(_, f)| f.as_ref()) {
        f.sync_all().ok();
    }
    Ok(written.into_iter().map(|(tmp, _)| tmp).collect())
}

/// Writes `parts` to the temporary name of `path`: large files past the page cache ([`direct`],
/// synced there), others through the page cache, whose file is returned still to be synced.
/// Nothing is left behind on an error.
fn write_unsynced(
    path: &Path,
    parts: &[&[u8]],
) -> std::io::Result<(PathBuf, Option<std::fs::File>)> {
    let tmp = temporary_name(path);
    let len: usize = parts.iter().map(|p| p.len()).sum();
    let written = (|| {
        if len >= DIRECT_FROM && direct::write(&tmp, parts, len)? {
            return Ok(None);
        }
        let mut f = std::fs::File::create(&tmp)?;
        for p in parts {
            f.write_all(p)?;
        }
        Ok(Some(f))
    })();
    match written {
        Ok(f) => Ok((tmp, f)),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// The temporary name of `path` in its directory (this process's).
fn temporary_name(path: &Path) -> PathBuf {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    dir.join(format!(".{name}.tmp{}", std::process::id()))
}

/// Files of at least this many bytes (a step's `.vtu` of the bodies: 11 MB at L5, 34 MB at
/// L7) are written past the page cache where the file system allows it ([`direct`]).
const DIRECT_FROM: usize = 1 << 20;

/// A large file's temporary whose bytes from an aligned offset on are written ahead of the
/// rest ([`write_ahead`]), past the page cache; removed when dropped unfinished.
///
/// A step's `.vtu` of the bodies ends with the same bytes at every step (the cells' data, the
/// points and the cells: half of its 11 MB at L5). Written as a step is taken for output, they
/// go to the device while the step's fields are recovered and its stresses computed, instead of
/// after them: at the end of a run the device's transfer of the last steps' files (about 1 ms
/// per MB on the machine of `docs/benchmarks.md`, with the processor idle) is on the critical
/// path.
pub struct Ahead {
    tmp: PathBuf,
    file: Option<std::fs::File>,
    /// The aligned offset from which the bytes are written.
    from: usize,
    /// The file's length.
    len: usize,
}

/// Writes the temporary file of `path`, of `len` bytes of which `parts` are those from byte
/// `offset` on, from the first aligned offset at or after `offset`. `Ok(None)` (nothing left
/// behind) for a file too small to be worth it or a file system that does not take
/// `O_DIRECT`; on an error nothing is left behind either.
pub fn write_ahead(
    path: &Path,
    len: usize,
    offset: usize,
    parts: &[&[u8]],
) -> std::io::Result<Option<Ahead>> {
    use std::io::{Seek, SeekFrom};
    let from = offset.next_multiple_of(direct::ALIGN);
    if len < DIRECT_FROM || from >= len {
        return Ok(None);
    }
    let tmp = temporary_name(path);
    let Some(file) = direct::open(&tmp)? else {
        return Ok(None);
    };
    let mut ahead = Ahead {
        tmp,
        file: Some(file),
        from,
        len,
    };
    let f = ahead.file.as_mut().expect("just opened");
    f.seek(SeekFrom::Start(from as u64))?;
    if !direct::copy_out(f, parts, from - offset, usize::MAX)? {
        // Dropped: the file is removed.
        return Ok(None);
    }
    Ok(Some(ahead))
}

/// Finishes a file begun by [`write_ahead`] with its whole contents `parts` (whose bytes from
/// the aligned offset on are not written again): cut to its length, synced. Returns its
/// temporary name; nothing is left behind on an error.
pub fn finish_ahead(mut ahead: Ahead, parts: &[&[u8]]) -> std::io::Result<PathBuf> {
    use std::io::{Seek, SeekFrom};
    let total: usize = parts.iter().map(|p| p.len()).sum();
    if total != ahead.len {
        return Err(std::io::Error::other(format!(
            "{} bytes to write where {} were planned",
            total, ahead.len
        )));
    }
    let f = ahead.file.as_mut().expect("an unfinished file");
    f.seek(SeekFrom::Start(0))?;
    if !direct::copy_out(f, parts, 0, ahead.from)? {
        return Err(std::io::Error::other("a write past the page cache refused"));
    }
    f.set_len(ahead.len as u64)?;
    f.sync_all().ok();
    ahead.file = None;
    Ok(std::mem::take(&mut ahead.tmp))
}

impl Drop for Ahead {
    fn drop(&mut self) {
        if self.file.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// The second half of [`write_atomic_parts`]: renames the temporary file `tmp` to `path`
/// (removing it if that fails).
pub fn commit(tmp: &Path, path: &Path) -> std::io::Result<()> {
    std::fs::rename(tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(tmp);
    })
}

/// The files a run's output replaces, closed on a thread of their own. Renaming a new file
/// over an old one deletes the old one there and then, and deleting an 11 MB `.vtu` costs
/// about 2 ms on the machine of `docs/benchmarks.md` (a run written into the directory of an
/// earlier one replaces every file): held open across the rename, the old file is deleted when
/// this thread closes it instead, off the writer's path. Dropping the reaper waits for it.
pub struct Reaper {
    tx: Option<std::sync::mpsc::Sender<std::fs::File>>,
    handle: Option<std::thread::JoinHandle<()>>,
}

impl Reaper {
    pub fn new() -> Reaper {
        let (tx, rx) = std::sync::mpsc::channel::<std::fs::File>();
        let handle = std::thread::Builder::new()
            .name("stickslip-reaper".into())
            .spawn(move || rx.into_iter().for_each(drop))
            .ok();
        Reaper {
            tx: handle.as_ref().map(|_| tx),
            handle,
        }
    }

    /// [`commit`], the file it replaces (if any) closed on the reaper's thread. (Only where a
    /// file held open can be renamed over: Unix.)
    pub fn commit(&self, tmp: &Path, path: &Path) -> std::io::Result<()> {
        let old = match &self.tx {
            Some(_) if cfg!(unix) => std::fs::File::open(path).ok(),
            _ => None,
        };
        commit(tmp, path)?;
        if let (Some(f), Some(tx)) = (old, &self.tx) {
            // A reaper that has gone (it cannot, short of a panic) leaves the closing here.
            let _ = tx.send(f);
        }
        Ok(())
    }
}

impl Default for Reaper {
    fn default() -> Self {
        Reaper::new()
    }
}

impl Drop for Reaper {
    fn drop(&mut self) {
        self.tx.take();
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names of the files in `dir`, sorted.
    fn names_in(dir: &Path) -> Vec<String> {
        let mut names: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().into_string().unwrap())
            .collect();
        names.sort();
        names
    }

    /// Directories for a test's files, named by `tag` and this process: in the temporary
    /// directory (disk-backed: `O_DIRECT`) and in `/dev/shm` where there is one (tmpfs, which
    /// may refuse the flag: the buffered path).
    fn scratch_dirs(tag: &str) -> Vec<PathBuf> {
        let name = format!("stickslip-{tag}-{}", std::process::id());
        let mut dirs = vec![std::env::temp_dir().join(&name)];
        if Path::new("/dev/shm").is_dir() {
            dirs.push(Path::new("/dev/shm").join(&name));
        }
        dirs
    }

    /// Files renamed over others through the reaper replace them, a missing temporary file is
    /// an error that keeps the file it would replace, and nothing else is left.
    #[test]
    fn the_reaper_replaces_files_and_leaves_nothing_else() {
        let dir = std::env::temp_dir().join(format!("stickslip-reaper-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (old, fresh) = (dir.join("a.vtu"), dir.join("b.vtu"));
        std::fs::write(&old, vec![1u8; 3 << 20]).unwrap();
        let reaper = Reaper::new();
        for (path, bytes) in [(&old, b"new a".as_slice()), (&fresh, b"new b".as_slice())] {
            let tmp = write_temporary(path, &[bytes]).unwrap();
            reaper.commit(&tmp, path).unwrap();
            assert_eq!(std::fs::read(path).unwrap(), bytes);
        }
        // A temporary file that is not there: an error, and the file it would replace kept.
        let missing = dir.join(".gone.tmp");
        assert!(reaper.commit(&missing, &old).is_err());
        assert_eq!(std::fs::read(&old).unwrap(), b"new a");
        drop(reaper);
        let names = names_in(&dir);
        assert_eq!(names, ["a.vtu", "b.vtu"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Files written together come back as given, large and small; a file that cannot be
    /// written is named by its index, and none of the others' temporary files is left.
    #[test]
    fn files_written_together_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("stickslip-together-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big = vec![7u8; DIRECT_FROM + 12_345];
        let (a, b) = (dir.join("a.csv"), dir.join("b.vtu"));
        let temps = write_temporaries(&[(&a, b"small"), (&b, &big)]).unwrap();
        assert_eq!(temps.len(), 2);
        assert_eq!(std::fs::read(&temps[0]).unwrap(), b"small");
        assert_eq!(std::fs::read(&temps[1]).unwrap(), big);
        for (tmp, path) in temps.iter().zip([&a, &b]) {
            commit(tmp, path).unwrap();
        }
        assert_eq!(std::fs::read(&a).unwrap(), b"small");
        // The third file's directory does not exist.
        let nowhere = dir.join("missing").join("c.pvd");
        let c = dir.join("c.csv");
        let err = write_temporaries(&[(&c, b"c"), (&a, b"again"), (&nowhere, b"x")]).unwrap_err();
        assert_eq!(err.0, 2);
        let names = names_in(&dir);
        assert_eq!(
            names,
            ["a.csv", "b.vtu"],
            "the files of before, and nothing else"
        );
        assert_eq!(std::fs::read(&a).unwrap(), b"small");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A file of several chunks and a ragged end, in parts that straddle the chunks, written
    /// through `O_DIRECT` (a disk-backed temporary directory) and through `/dev/shm` (tmpfs,
    /// which may refuse the flag: the buffered path), reads back byte for byte, and leaves no
    /// temporary file.
    #[test]
    fn large_files_read_back_as_written() {
        let bytes: Vec<u8> = (0..(9 << 20) + 4_321u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        let parts: Vec<&[u8]> = vec![
            &bytes[..17],
            &bytes[17..(5 << 20) + 3],
            &bytes[(5 << 20) + 3..],
        ];
        let dirs = scratch_dirs("direct");
        for dir in dirs {
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("big.vtu");
            write_atomic_parts(&path, &parts).unwrap();
            assert!(std::fs::read(&path).unwrap() == bytes, "{}", dir.display());
            let names: Vec<_> = std::fs::read_dir(&dir)
                .unwrap()
                .flatten()
                .map(|e| e.file_name())
                .collect();
            assert_eq!(
                names,
                vec![std::ffi::OsString::from("big.vtu")],
                "{}",
                dir.display()
            );
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }

    /// A file begun ahead from any offset (aligned, not, in its last block, past its end) and
    /// finished with its whole contents reads back as written whole; a file begun and not
    /// finished, or finished with contents of another length, leaves nothing.
    #[test]
    fn files_written_ahead_read_back_as_written_whole() {
        let bytes: Vec<u8> = (0..(9 << 20) + 4_321u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 11) as u8)
            .collect();
        let len = bytes.len();
        // Parts that straddle the offsets and the chunks.
        let cuts = [0, 17, 4_095, (4 << 20) + 1, (5 << 20) + 3, len - 100, len];
        let parts: Vec<&[u8]> = cuts.windows(2).map(|w| &bytes[w[0]..w[1]]).collect();
        let tail_of = |offset: usize| -> Vec<&[u8]> {
            let mut rest = Vec::new();
            let mut at = 0;
            for p in &parts {
                if at + p.len() > offset {
                    rest.push(&p[offset.saturating_sub(at)..]);
                }
                at += p.len();
            }
            rest
        };
        let dirs = scratch_dirs("ahead");
        for dir in dirs {
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("big.vtu");
            let mut begun = 0;
            for offset in [0, 4_096, 5_000, (4 << 20) + 7, len - 5_000, len - 10] {
                let ahead = write_ahead(&path, len, offset, &tail_of(offset)).unwrap();
                let Some(ahead) = ahead else {
                    // Only where the file system refuses O_DIRECT, or nothing is left to write
                    // ahead (the last block): nothing is left behind.
                    let names = names_in(&dir);
                    assert!(names.iter().all(|n| !n.contains(".tmp")), "{names:?}");
                    continue;
                };
                begun += 1;
                let tmp = finish_ahead(ahead, &parts).unwrap();
                assert!(std::fs::read(&tmp).unwrap() == bytes, "offset {offset}");
                commit(&tmp, &path).unwrap();
                assert_eq!(names_in(&dir), ["big.vtu"]);
            }
            let probe = dir.join("probe");
            if direct::open(&probe).unwrap().is_some() {
                // A file system that takes O_DIRECT: every offset but the last block's.
                assert_eq!(begun, 5, "{}", dir.display());
                std::fs::remove_file(&probe).unwrap();
            }
            if let Some(a) = write_ahead(&path, len, 5_000, &tail_of(5_000)).unwrap() {
                drop(a);
                assert_eq!(
                    names_in(&dir),
                    ["big.vtu"],
                    "a file dropped unfinished is removed"
                );
            }
            if let Some(a) = write_ahead(&path, len, 5_000, &tail_of(5_000)).unwrap() {
                let err = finish_ahead(a, &parts[1..]).unwrap_err();
                assert!(err.to_string().contains("were planned"), "{err}");
                assert_eq!(
                    names_in(&dir),
                    ["big.vtu"],
                    "a file not finished is removed"
                );
            }
            assert!(std::fs::read(&path).unwrap() == bytes);
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
