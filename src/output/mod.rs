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
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        for p in parts {
            f.write_all(p)?;
        }
        f.sync_all().ok();
        Ok(())
    })();
    match written {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
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
