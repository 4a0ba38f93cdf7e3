//! The parts of a sweep on disk: each shard `K` of `N` appends its rows, one JSON line each,
//! to `part_K_of_N.jsonl` under a header line that names the sweep. A shard started again
//! reads the rows already there (complete lines only: a line cut short by a kill is dropped)
//! and runs the rest; [`merge`] gathers the parts of one sweep into `sweep.csv` and
//! `sweep.json`, refusing parts of another sweep and reporting rows that no part holds.

use crate::error::SweepError;
use crate::output::atomic::write_atomic;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The file name of shard `k` of `n`.
pub fn part_name(k: usize, n: usize) -> String {
    format!("part_{k}_of_{n}.jsonl")
}

/// What a part file holds: its header, its complete rows by row number, the run records of
/// each time the shard ran, and the byte length of its complete lines.
pub struct Part {
    pub header: Value,
    pub rows: BTreeMap<usize, Value>,
    pub runs: Vec<Value>,
    pub complete_len: usize,
}

/// Reads a part file; lines after the last newline (a row cut short) are ignored.
pub fn read_part(path: &Path) -> Result<Part, SweepError> {
    let bytes = std::fs::read(path).map_err(|source| SweepError::Read {
        path: path.display().to_string(),
        source,
    })?;
    let bad = |why: String| SweepError::BadPart {
        path: path.display().to_string(),
        why,
    };
    let complete_len = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let text = std::str::from_utf8(&bytes[..complete_len]).map_err(|e| bad(e.to_string()))?;
    let mut lines = text.lines();
    let header: Value = lines
        .next()
        .and_then(|l| serde_json::from_str::<Value>(l).ok())
        .and_then(|v| v.get("part").cloned())
        .ok_or_else(|| bad("the first line is not a part header".into()))?;
    let (mut rows, mut runs) = (BTreeMap::new(), Vec::new());
    for (i, line) in lines.enumerate() {
        let v: Value =
            serde_json::from_str(line).map_err(|e| bad(format!("line {}: {e}", i + 2)))?;
        if let Some(run) = v.get("run") {
            runs.push(run.clone());
        } else {
            let r = v["row"]
                .as_u64()
                .ok_or_else(|| bad(format!("line {}: a row without `row`", i + 2)))?;
            rows.entry(r as usize).or_insert(v);
        }
    }
    Ok(Part {
        header,
        rows,
        runs,
        complete_len,
    })
}

/// The part of one shard, open for appending rows.
pub struct PartWriter {
    path: PathBuf,
    file: std::fs::File,
}

impl PartWriter {
    /// The part at `path` to resume, if there is one: `None` when it does not exist or
    /// `fresh` discards it; a part of another sweep (different `sweep_id`) is refused.
    pub fn existing(path: &Path, header: &Value, fresh: bool) -> Result<Option<Part>, SweepError> {
        if !path.exists() || fresh {
            return Ok(None);
        }
        let part = read_part(path)?;
        if part.header["sweep_id"] != header["sweep_id"] {
            return Err(SweepError::ForeignPart {
                path: path.display().to_string(),
                found: part.header["sweep_id"].as_str().unwrap_or("?").to_string(),
                expected: header["sweep_id"].as_str().unwrap_or("?").to_string(),
            });
        }
        Ok(Some(part))
    }

    /// Opens the part `path` of the sweep described by `header` for appending: goes on from
    /// `existing` ([`Self::existing`]) or creates it. Returns the writer, the rows already
    /// there and how many bytes of a row cut short were dropped.
    pub fn open(
        path: &Path,
        header: &Value,
        existing: Option<Part>,
    ) -> Result<(Self, BTreeMap<usize, Value>, usize), SweepError> {
        let write_err = |source| SweepError::Write {
            path: path.display().to_string(),
            source,
        };
        let (rows, dropped) = match existing {
            Some(part) => {
                let len = std::fs::metadata(path).map_err(write_err)?.len() as usize;
                if len > part.complete_len {
                    // Cut the half-written row off before appending.
                    let f = std::fs::OpenOptions::new()
                        .write(true)
                        .open(path)
                        .map_err(write_err)?;
                    f.set_len(part.complete_len as u64).map_err(write_err)?;
                }
                (part.rows, len - part.complete_len)
            }
            None => {
                let line = json!({ "part": header }).to_string() + "\n";
                write_atomic(path, line.as_bytes()).map_err(write_err)?;
                (BTreeMap::new(), 0)
            }
        };
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(write_err)?;
        Ok((
            PartWriter {
                path: path.to_path_buf(),
                file,
            },
            rows,
            dropped,
        ))
    }

    /// Appends one line (a row, or a run record) in a single write.
    pub fn append(&mut self, v: &Value) -> Result<(), SweepError> {
        let line = v.to_string() + "\n";
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|source| SweepError::Write {
                path: self.path.display().to_string(),
                source,
            })
    }
}

/// The part files in `dirs` (a directory: its `part_*_of_*.jsonl`; a file: itself).
fn part_files(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, SweepError> {
    let mut files = Vec::new();
    for d in dirs {
        if d.is_file() {
            files.push(d.clone());
            continue;
        }
        let entries = std::fs::read_dir(d).map_err(|source| SweepError::Read {
            path: d.display().to_string(),
            source,
        })?;
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                let n = p.file_name().map(|n| n.to_string_lossy().to_string());
                n.is_some_and(|n| n.starts_with("part_") && n.ends_with(".jsonl"))
            })
            .collect();
        found.sort();
        files.extend(found);
    }
    if files.is_empty() {
        return Err(SweepError::NoParts {
            dirs: dirs
                .iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    Ok(files)
}

/// The merged table of the parts in `dirs`: the header of the sweep, every row in order, and
/// the run records of all shards. Refuses parts of different sweeps and a table with rows
/// missing.
pub fn gather(dirs: &[PathBuf]) -> Result<(Value, Vec<Value>, Vec<Value>), SweepError> {
    let files = part_files(dirs)?;
    let mut header: Option<(PathBuf, Value)> = None;
    let (mut rows, mut runs) = (BTreeMap::new(), Vec::new());
    for f in &files {
        let part = read_part(f)?;
        match &header {
            None => header = Some((f.clone(), part.header.clone())),
            Some((first, h)) if h["sweep_id"] != part.header["sweep_id"] => {
                return Err(SweepError::Mismatch {
                    first: first.display().to_string(),
                    second: f.display().to_string(),
                    a: h["sweep_id"].as_str().unwrap_or("?").to_string(),
                    b: part.header["sweep_id"].as_str().unwrap_or("?").to_string(),
                });
            }
            Some(_) => {}
        }
        for (r, v) in part.rows {
            rows.entry(r).or_insert(v);
        }
        runs.extend(part.runs);
    }
    let (_, header) = header.expect("at least one part");
    let total = header["rows"].as_u64().unwrap_or(0) as usize;
    let missing: Vec<usize> = (0..total).filter(|r| !rows.contains_key(r)).collect();
    if !missing.is_empty() {
        return Err(SweepError::Missing { missing, total });
    }
    Ok((header, rows.into_values().collect(), runs))
}

/// Merges the parts in `dirs` into `sweep.csv` and `sweep.json` in `out` (default: the first
/// directory). Nothing is written when a part is foreign or rows are missing.
pub fn merge(dirs: &[PathBuf], out: Option<&Path>) -> Result<PathBuf, SweepError> {
    let (header, rows, runs) = gather(dirs)?;
    let out = match out {
        Some(o) => o.to_path_buf(),
        None if dirs[0].is_file() => dirs[0].parent().unwrap_or(Path::new(".")).to_path_buf(),
        None => dirs[0].clone(),
    };
    write_table(&out, &header, &rows, &runs)?;
    Ok(out)
}

/// Writes `sweep.csv` and `sweep.json` of a complete table.
pub fn write_table(
    out: &Path,
    header: &Value,
    rows: &[Value],
    runs: &[Value],
) -> Result<(), SweepError> {
    let w = |name: &str, bytes: &[u8]| {
        std::fs::create_dir_all(out)
            .and_then(|()| write_atomic(&out.join(name), bytes))
            .map_err(|source| SweepError::Write {
                path: out.join(name).display().to_string(),
                source,
            })
    };
    let sum = |k: &str| runs.iter().filter_map(|r| r[k].as_f64()).sum::<f64>();
    let threads = runs.iter().filter_map(|r| r["threads"].as_u64()).max();
    let json = json!({
        "case": header["case"],
        "sweep": header["sweep"],
        "sweep_id": header["sweep_id"],
        "contact_shortcuts_from": header["contact_shortcuts_from"],
        "build_s": sum("build_s"),
        "sweep_s": sum("sweep_s"),
        "threads": threads,
        "runs": runs,
        "rows": rows,
    });
    w("sweep.csv", super::table(rows).as_bytes())?;
    w(
        "sweep.json",
        serde_json::to_string_pretty(&json)
            .expect("serialisable")
            .as_bytes(),
    )
}
