//! Output files: `.vtu` per step and a `.pvd` series for ParaView, CSV and JSON for plotting.
//! Every file is written to a temporary name in the same directory and renamed into place, so
//! a run that stops leaves either a whole file or none.

pub mod fields;
pub mod series;
pub mod vtu;

use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically (temporary file + rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all().ok();
    }
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
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
