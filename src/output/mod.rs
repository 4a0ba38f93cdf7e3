//! Output files: `.vtu` per step and a `.pvd` series for ParaView, CSV and JSON for plotting.
//! Every file is written to a temporary name in the same directory and renamed into place, so
//! a run that stops leaves either a whole file or none.
//!
//! | module | content |
//! |---|---|
//! | [`atomic`] | files written whole or not at all (temporary name, rename), large ones past the page cache |
//! | [`series`] | the files of the steps of a run: the bodies' and contact `.vtu`, the `.pvd`, the contact CSV |
//! | [`background`] | the thread that writes the steps while the next ones are solved |
//! | [`fields`], [`vtu`] | the datasets of a step and their encoding |
//! | this file | names of the files, `.pvd` and CSV text, content hashes |

pub mod atomic;
pub mod background;
mod direct;
pub mod fields;
pub mod series;
pub mod vtu;

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

/// The file name of the restart state of `step` ([`series::StateFile`]).
pub fn state_file_name(step: usize) -> String {
    format!("state_{step:04}.json")
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
