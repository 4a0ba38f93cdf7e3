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
    pub const ALIGN: usize = 4096;
    /// The buffer the parts are copied through (aligned; one allocation per file).
    const CHUNK: usize = 4 << 20;

    /// Writes `parts` (`len` bytes in all) to a new file `path`. `Ok(false)` when the file
    /// system does not take `O_DIRECT` (nothing is left at `path`; the caller writes it the
    /// usual way), `Err` on any other failure.
    #[cfg(target_os = "linux")]
    pub fn write(path: &Path, parts: &[&[u8]], len: usize) -> std::io::Result<bool> {
        let Some(mut f) = open(path)? else {
            return Ok(false);
        };
        if !copy_out(&mut f, parts, 0, usize::MAX)? {
            drop(f);
            std::fs::remove_file(path)?;
            return Ok(false);
        }
        f.set_len(len as u64)?;
        f.sync_all().ok();
        Ok(true)
    }

    /// Creates (or truncates) `path` for writes past the page cache; `None` when the file
    /// system does not take `O_DIRECT` (nothing is left at `path`).
    #[cfg(target_os = "linux")]
    pub fn open(path: &Path) -> std::io::Result<Option<std::fs::File>> {
        use std::os::unix::fs::OpenOptionsExt;
        match std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .custom_flags(libc::O_DIRECT)
            .open(path)
        {
            Ok(f) => Ok(Some(f)),
            Err(e) if e.raw_os_error() == Some(libc::EINVAL) => {
                // Some kernels check the flag after `O_CREAT` has made the file.
                let _ = std::fs::remove_file(path);
                Ok(None)
            }
            Err(e) => Err(e),
        }
    }

    #[cfg(not(target_os = "linux"))]
    pub fn open(_: &Path) -> std::io::Result<Option<std::fs::File>> {
        Ok(None)
    }

    /// Writes bytes `skip..skip + limit` of `parts` (to their end if fewer) at the position of
    /// `f` (opened with `O_DIRECT`, the position aligned) through an aligned buffer, the last
    /// block padded to the alignment (the caller cuts the file back). `Ok(false)` when the first
    /// write is refused as unsupported (a file system can accept the flag and refuse that).
    #[cfg(target_os = "linux")]
    pub fn copy_out(
        f: &mut std::fs::File,
        parts: &[&[u8]],
        mut skip: usize,
        mut limit: usize,
    ) -> std::io::Result<bool> {
        use std::io::Write;
        let mut owner = Aligned::take();
        let buf = owner.bytes();
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
            let cut = skip.min(p.len());
            (p, skip) = (&p[cut..], skip - cut);
            p = &p[..limit.min(p.len())];
            limit -= p.len();
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

    #[cfg(not(target_os = "linux"))]
    pub fn copy_out(
        _: &mut std::fs::File,
        _: &[&[u8]],
        _: usize,
        _: usize,
    ) -> std::io::Result<bool> {
        Ok(false)
    }

    /// An aligned buffer of `CHUNK` bytes, handed back to [`POOL`] on drop.
    #[cfg(target_os = "linux")]
    struct Aligned(Option<Buffer>);

    /// An aligned allocation of `CHUNK` zeroed bytes, freed on drop.
    #[cfg(target_os = "linux")]
    struct Buffer(*mut u8);

    // SAFETY: the allocation is owned by the `Buffer` alone.
    #[cfg(target_os = "linux")]
    unsafe impl Send for Buffer {}

    /// Buffers kept for the next files (a fresh allocation of 4 MB faults in its 1024 pages
    /// at its first use: 20 ms of the CPU after the factorisation of Fig. 2 at L5 went to
    /// this copy, most of it in those faults).
    #[cfg(target_os = "linux")]
    static POOL: std::sync::Mutex<Vec<Buffer>> = std::sync::Mutex::new(Vec::new());

    /// Buffers the pool keeps at most (the writer's thread, the driver's and those that
    /// write ahead use one each at a time).
    #[cfg(target_os = "linux")]
    const POOL_MAX: usize = 4;

    #[cfg(target_os = "linux")]
    fn layout() -> std::alloc::Layout {
        std::alloc::Layout::from_size_align(CHUNK, ALIGN).expect("a valid layout")
    }

    #[cfg(target_os = "linux")]
    impl Aligned {
        /// A buffer from the pool, or a new one.
        fn take() -> Aligned {
            let kept = POOL.lock().unwrap_or_else(|e| e.into_inner()).pop();
            Aligned(Some(kept.unwrap_or_else(|| {
                // SAFETY: the layout has a nonzero size.
                let p = unsafe { std::alloc::alloc_zeroed(layout()) };
                if p.is_null() {
                    std::alloc::handle_alloc_error(layout());
                }
                Buffer(p)
            })))
        }

        fn bytes(&mut self) -> &mut [u8] {
            let p = self.0.as_ref().expect("a buffer").0;
            // SAFETY: `p` holds `CHUNK` initialised bytes (zeroed when allocated), borrowed
            // mutably with `self`.
            unsafe { std::slice::from_raw_parts_mut(p, CHUNK) }
        }
    }

    #[cfg(target_os = "linux")]
    impl Drop for Aligned {
        fn drop(&mut self) {
            let Some(b) = self.0.take() else { return };
            let mut pool = POOL.lock().unwrap_or_else(|e| e.into_inner());
            if pool.len() < POOL_MAX {
                pool.push(b);
            }
        }
    }

    #[cfg(target_os = "linux")]
    impl Drop for Buffer {
        fn drop(&mut self) {
            // SAFETY: allocated in `Aligned::take` with this layout.
            unsafe { std::alloc::dealloc(self.0, layout()) };
        }
    }
}

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

/// The name of the bodies dataset of `step` (case `stem`).
pub fn bodies_file_name(stem: &str, step: usize) -> String {
    format!("{stem}_{step:04}.vtu")
}

/// The name of the contact-face dataset of `step` (case `stem`).
pub fn contact_file_name(stem: &str, step: usize) -> String {
    format!("{stem}_contact_{step:04}.vtu")
}

/// The journal of step records a run writes beside its restart states (see
/// [`crate::restart`]).
pub const JOURNAL: &str = "steps.jsonl";

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
