//! The cache directory: where it is, its size cap and eviction, and the background writer.

use std::path::{Path, PathBuf};

use super::entry::{Draft, Entry, write_entry};
use super::format::DEFAULT_MAX_BYTES;
use super::key::Key;
use super::reader::{Open, Reader};

/// Where the cache is, from the command line.
#[derive(Clone, Debug, Default)]
pub enum Choice {
    /// The default place (environment, then the per-user cache directory).
    #[default]
    Default,
    /// `--cache DIR`.
    Dir(PathBuf),
    /// `--no-cache`.
    Off,
}

/// How the cache served a model, for `summary.json`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Loaded from the cache.
    Hit,
    /// Not in the cache: built, and written to it.
    Miss,
    /// An entry was there but unusable (truncated, corrupt, foreign): built and written again.
    Rebuilt,
    /// No cache (`--no-cache`, or no place for it).
    Off,
}

/// The cache's part in a model, as `summary.json` reports it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    pub status: Status,
    /// The entry's file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    /// Its size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes: Option<u64>,
    /// Why an entry was rebuilt, not written, or why there is no cache.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// A new entry: whether the factorisation computed its factor values in the entry's file
    /// ([`Draft`]) rather than in memory, copied to the file afterwards.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor_in_place: Option<bool>,
}

impl Report {
    /// The report of a new entry that was not written, and `why`: no file to name.
    pub fn not_written(&mut self, why: &str) {
        let why = format!("not written: {why}");
        self.note = Some(match self.note.take() {
            Some(n) => format!("{n}; {why}"),
            None => why,
        });
        self.path = None;
        self.factor_in_place = None;
    }

    pub fn off(note: Option<String>) -> Report {
        Report {
            status: Status::Off,
            path: None,
            bytes: None,
            note,
            factor_in_place: None,
        }
    }
}

/// A cache directory and its size cap.
#[derive(Clone, Debug)]
pub struct Store {
    pub dir: PathBuf,
    pub max_bytes: u64,
    /// Print warnings (an unusable entry, a failed write) on standard error.
    pub warn: bool,
}

fn env_set(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.is_empty())
}

/// Parses a size: bytes, or a number with a binary suffix K, M, G, T (optionally `iB` or `B`).
pub fn parse_size(s: &str) -> Option<u64> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let x: f64 = num.parse().ok()?;
    let mult: u64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => 1 << 20,
        "g" | "gb" | "gib" => 1 << 30,
        "t" | "tb" | "tib" => 1 << 40,
        _ => return None,
    };
    (x.is_finite() && x >= 0.0).then_some((x * mult as f64) as u64)
}

impl Store {
    /// The cache a run uses (see the module documentation), or the report of why it has none.
    pub fn resolve(choice: &Choice, warn: bool) -> Result<Store, Report> {
        let no_cache = env_set("STICKSLIP_NO_CACHE").is_some_and(|v| v != "0");
        let dir = match choice {
            Choice::Off => return Err(Report::off(None)),
            Choice::Dir(d) => d.clone(),
            Choice::Default if no_cache => {
                return Err(Report::off(Some("STICKSLIP_NO_CACHE is set".into())));
            }
            Choice::Default => {
                let xdg = env_set("XDG_CACHE_HOME")
                    .map(PathBuf::from)
                    .filter(|p| p.is_absolute());
                match env_set("STICKSLIP_CACHE_DIR")
                    .map(PathBuf::from)
                    .or_else(|| xdg.map(|x| x.join("stickslip")))
                    .or_else(|| env_set("HOME").map(|h| PathBuf::from(h).join(".cache/stickslip")))
                {
                    Some(d) => d,
                    None => {
                        return Err(Report::off(Some(
                            "no cache directory: set STICKSLIP_CACHE_DIR or HOME, or pass --cache DIR"
                                .into(),
                        )));
                    }
                }
            }
        };
        let max_bytes = match env_set("STICKSLIP_CACHE_MAX") {
            None => DEFAULT_MAX_BYTES,
            Some(v) => match parse_size(&v) {
                Some(b) => b,
                None => {
                    if warn {
                        eprintln!(
                            "warning: STICKSLIP_CACHE_MAX = `{v}` is not a size (e.g. 4G, 500M, 1073741824); using 4 GiB"
                        );
                    }
                    DEFAULT_MAX_BYTES
                }
            },
        };
        Ok(Store {
            dir,
            max_bytes,
            warn,
        })
    }

    /// A new entry's draft file for `key` with room for `len` factor values, mapped for the
    /// factorisation to compute them in ([`Draft`]); `None` where that is not done.
    pub fn draft(&self, key: Key, len: usize) -> Option<Draft> {
        Draft::create(&self.dir, &self.path(key), self.max_bytes, len)
    }

    /// The file of the entry with `key`.
    pub fn path(&self, key: Key) -> PathBuf {
        self.dir.join(format!("model-{}.bin", key.hex()))
    }

    /// Opens the entry with `key`; a hit marks it as recently used.
    pub fn open(&self, key: Key) -> Open {
        let path = self.path(key);
        let open = Reader::open(&path, key);
        if let Open::Ready(r) = &open {
            let _ = r.file.set_modified(std::time::SystemTime::now());
        }
        open
    }

    /// Deletes an unusable entry (reported with `why`).
    pub fn discard(&self, key: Key, why: &str) {
        let path = self.path(key);
        if self.warn {
            eprintln!(
                "warning: model cache: {} {why}; ignoring it and building the model again",
                path.display()
            );
        }
        let _ = std::fs::remove_file(&path);
    }

    /// Writes `entry` under `key` in a background thread (after making room for it under the
    /// cap). Returns the report of the entry (`status` is the caller's) and the job, which
    /// waits for the write when dropped.
    pub fn write_in_background(
        &self,
        key: Key,
        entry: Entry,
        status: Status,
        note: Option<String>,
    ) -> (Report, Option<Job>) {
        let path = self.path(key);
        let bytes = entry.file_len();
        let mut report = Report {
            status,
            path: Some(path.display().to_string()),
            bytes: Some(bytes),
            note,
            factor_in_place: Some(entry.draft.is_some()),
        };
        if bytes > self.max_bytes {
            report.not_written(&format!(
                "{bytes} bytes exceed the cache cap of {} bytes (STICKSLIP_CACHE_MAX)",
                self.max_bytes
            ));
            return (report, None);
        }
        let store = self.clone();
        let p = path.clone();
        let handle = std::thread::Builder::new()
            .name("model-cache-writer".into())
            .spawn(move || {
                std::fs::create_dir_all(&store.dir)
                    .map_err(|e| format!("cannot create {}: {e}", store.dir.display()))?;
                evict(&store.dir, store.max_bytes.saturating_sub(bytes), &p);
                write_entry(&p, key, entry).map_err(|e| e.to_string())?;
                crate::trace::mark("cache entry written");
                Ok(())
            });
        match handle {
            Ok(h) => (
                report,
                Some(Job {
                    handle: Some(h),
                    path,
                    warn: self.warn,
                }),
            ),
            Err(e) => {
                report.note = Some(format!("not written: cannot start the writer: {e}"));
                (report, None)
            }
        }
    }
}

/// Deletes the least recently used entries of `dir` (files `model-*.bin`, by modification
/// time) until they take at most `budget` bytes, never `keep`; and temporary files left by
/// writers that were killed (older than an hour).
pub fn evict(dir: &Path, budget: u64, keep: &Path) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let now = std::time::SystemTime::now();
    let mut entries: Vec<(std::time::SystemTime, u64, PathBuf)> = Vec::new();
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Ok(md) = e.metadata() else { continue };
        let mtime = md.modified().unwrap_or(std::time::UNIX_EPOCH);
        if name.starts_with(".model-") && name.contains(".tmp") {
            if now.duration_since(mtime).is_ok_and(|d| d.as_secs() > 3600) {
                let _ = std::fs::remove_file(e.path());
            }
            continue;
        }
        if name.starts_with("model-") && name.ends_with(".bin") && md.is_file() {
            entries.push((mtime, md.len(), e.path()));
        }
    }
    let mut total: u64 = entries.iter().map(|e| e.1).sum();
    entries.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.2.cmp(&b.2)));
    for (_, len, path) in entries {
        if total <= budget {
            break;
        }
        if path == keep {
            continue;
        }
        if std::fs::remove_file(&path).is_ok() {
            total -= len;
        }
    }
}

/// A cache entry being written in the background; dropping it waits for the write (and
/// reports a failure on standard error).
pub struct Job {
    handle: Option<std::thread::JoinHandle<Result<(), String>>>,
    path: PathBuf,
    warn: bool,
}

impl Job {
    /// Waits for the write: `Err` with the reason if it failed.
    pub fn wait(mut self) -> Result<(), String> {
        self.join()
    }

    /// Waits for the write, and reports a failure on standard error as dropping the job would:
    /// the reason, if it failed.
    pub fn settle(mut self) -> Option<String> {
        let e = self.join().err()?;
        if self.warn {
            eprintln!(
                "warning: model cache: could not write {}: {e}",
                self.path.display()
            );
        }
        Some(e)
    }

    fn join(&mut self) -> Result<(), String> {
        match self.handle.take().map(|h| h.join()) {
            None | Some(Ok(Ok(()))) => Ok(()),
            Some(Ok(Err(e))) => Err(e),
            Some(Err(_)) => Err("the writer panicked".into()),
        }
    }
}

impl Drop for Job {
    fn drop(&mut self) {
        if let Err(e) = self.join()
            && self.warn
        {
            eprintln!(
                "warning: model cache: could not write {}: {e}",
                self.path.display()
            );
        }
    }
}
