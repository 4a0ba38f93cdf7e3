//! Output files: `.vtu` per step and a `.pvd` series for ParaView, CSV and JSON for plotting.
//! Every file is written to a temporary name in the same directory and renamed into place, so
//! a run that stops leaves either a whole file or none.

pub mod fields;
pub mod series;
pub mod vtu;

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

/// Writing a large file with `O_DIRECT`: its bytes go from the program's memory to the device
/// without a copy in the kernel's page cache. A run writes its `.vtu` files once and does not
/// read them again, and filling the page cache is most of what a buffered write of them costs:
/// 55–80 ms of CPU for 34 MB on the 2-core VM of `docs/benchmarks.md` (pages the kernel takes
/// fresh from the host), against under 2 ms this way (measured with a scratch program; the
/// device's own transfer takes ~20 ms, on the writing thread, not the CPU).
mod direct {
    use std::path::Path;

    /// The alignment of the buffer, of each write's length and of the file offsets.
    const ALIGN: usize = 4096;
    /// The buffer the parts are copied through (aligned; one allocation per file).
    const CHUNK: usize = 4 << 20;

    /// Writes `parts` (`len` bytes in all) to a new file `path`. `Ok(false)` when the file
    /// system does not take `O_DIRECT` (nothing is left at `path`; the caller writes it the
    /// usual way), `Err` on any other failure.
    #[cfg(target_os = "linux")]
    pub fn write(path: &Path, parts: &[&[u8]], len: usize) -> std::io::Result<bool> {
        use std::os::unix::fs::OpenOptionsExt;
        let mut f = match std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .custom_flags(libc::O_DIRECT)
            .open(path)
        {
            Ok(f) => f,
            Err(e) if e.raw_os_error() == Some(libc::EINVAL) => return Ok(false),
            Err(e) => return Err(e),
        };
        if !copy_out(&mut f, parts)? {
            drop(f);
            std::fs::remove_file(path)?;
            return Ok(false);
        }
        f.set_len(len as u64)?;
        f.sync_all().ok();
        Ok(true)
    }

    /// Writes `parts` to `f` (opened with `O_DIRECT`) through an aligned buffer, the last block
    /// padded to the alignment (the caller cuts the file back). `Ok(false)` when the first
    /// write is refused as unsupported (a file system can accept the flag and refuse that).
    #[cfg(target_os = "linux")]
    fn copy_out(f: &mut std::fs::File, parts: &[&[u8]]) -> std::io::Result<bool> {
        use std::io::Write;
        let layout = std::alloc::Layout::from_size_align(CHUNK, ALIGN).expect("a valid layout");
        let owner = Aligned::new(layout);
        // SAFETY: `owner` holds `CHUNK` zeroed bytes until the end of the function.
        let buf = unsafe { std::slice::from_raw_parts_mut(owner.0, CHUNK) };
        let (mut fill, mut first) = (0, true);
        let mut flush = |bytes: &[u8]| match f.write_all(bytes) {
            Ok(()) => {
                first = false;
                Ok(true)
            }
            Err(e) if first && e.raw_os_error() == Some(libc::EINVAL) => Ok(false),
            Err(e) => Err(e),
        };
        for p in parts {
            let mut p: &[u8] = p;
            while !p.is_empty() {
                let n = p.len().min(CHUNK - fill);
                buf[fill..fill + n].copy_from_slice(&p[..n]);
                fill += n;
                p = &p[n..];
                if fill == CHUNK {
                    if !flush(buf)? {
                        return Ok(false);
                    }
                    fill = 0;
                }
            }
        }
        if fill == 0 {
            return Ok(true);
        }
        let padded = fill.div_ceil(ALIGN) * ALIGN;
        buf[fill..padded].fill(0);
        flush(&buf[..padded])
    }

    #[cfg(not(target_os = "linux"))]
    pub fn write(_: &Path, _: &[&[u8]], _: usize) -> std::io::Result<bool> {
        Ok(false)
    }

    /// An aligned allocation of zeroed bytes, freed on drop.
    #[cfg(target_os = "linux")]
    struct Aligned(*mut u8, std::alloc::Layout);

    #[cfg(target_os = "linux")]
    impl Aligned {
        fn new(layout: std::alloc::Layout) -> Aligned {
            // SAFETY: the layout has a nonzero size.
            let p = unsafe { std::alloc::alloc_zeroed(layout) };
            if p.is_null() {
                std::alloc::handle_alloc_error(layout);
            }
            Aligned(p, layout)
        }
    }

    #[cfg(target_os = "linux")]
    impl Drop for Aligned {
        fn drop(&mut self) {
            // SAFETY: allocated in `new` with this layout.
            unsafe { std::alloc::dealloc(self.0, self.1) };
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

/// A stable 64-bit FNV-1a hash of byte strings (each prefixed by its length), as hex: the
/// identity of a run or a sweep (its case file, mesh file, sweep file, program version),
/// which restart states and sweep parts carry.
pub fn content_id(parts: &[&[u8]]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |b: u8| {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    };
    for p in parts {
        for b in (p.len() as u64).to_le_bytes() {
            eat(b);
        }
        for &b in *p {
            eat(b);
        }
    }
    format!("{h:016x}")
}

/// One dataset of a `.pvd` collection.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PvdEntry {
    pub time: f64,
    /// 0 for the bodies, 1 for the contact surface.
    pub part: usize,
    pub file: String,
}

/// The text of a `.pvd` collection file.
pub fn pvd(entries: &[PvdEntry]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for e in entries {
        s += &format!(
            "    <DataSet timestep=\"{:.9e}\" group=\"\" part=\"{}\" file=\"{}\"/>\n",
            e.time, e.part, e.file
        );
    }
    s += "  </Collection>\n</VTKFile>\n";
    s
}

/// A CSV table with a header row: columns named in `integer` (counts, indices, status codes)
/// are written as integers, the others as `{:.12e}`.
pub fn csv(header: &[&str], rows: &[Vec<f64>], integer: &[&str]) -> String {
    let int_col: Vec<bool> = header.iter().map(|h| integer.contains(h)).collect();
    let mut s = header.join(",");
    s.push('\n');
    for r in rows {
        let line: Vec<String> = r
            .iter()
            .zip(&int_col)
            .map(|(v, &int)| {
                if int {
                    format!("{}", v.round() as i64)
                } else {
                    format!("{v:.12e}")
                }
            })
            .collect();
        s += &line.join(",");
        s.push('\n');
    }
    s
}

/// Peak resident memory of this process in bytes (Linux `VmHWM`), if known.
pub fn peak_memory_bytes() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
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

    /// A file of several chunks and a ragged end, in parts that straddle the chunks, written
    /// through `O_DIRECT` (a disk-backed temporary directory) and through `/dev/shm` (tmpfs,
    /// which may refuse the flag: the buffered path), reads back byte for byte, and leaves no
    /// temporary file.
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
        let mut dirs =
            vec![std::env::temp_dir().join(format!("stickslip-direct-{}", std::process::id()))];
        if Path::new("/dev/shm").is_dir() {
            dirs.push(PathBuf::from(format!(
                "/dev/shm/stickslip-direct-{}",
                std::process::id()
            )));
        }
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
}
