//! Writing a large file with `O_DIRECT`: its bytes go from the program's memory to the device
//! without a copy in the kernel's page cache. A run writes its `.vtu` files once and does not
//! read them again, and filling the page cache is most of what a buffered write of them costs:
//! 55–80 ms of CPU for 34 MB on the 2-core VM of `docs/benchmarks.md` (pages the kernel takes
//! fresh from the host), against under 2 ms this way (measured with a scratch program; the
//! device's own transfer takes ~20 ms, on the writing thread, not the CPU).

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
pub fn copy_out(_: &mut std::fs::File, _: &[&[u8]], _: usize, _: usize) -> std::io::Result<bool> {
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
