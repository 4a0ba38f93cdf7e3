//! Exact restart: at every written step a run saves the state it needs to go on
//! (`state_NNNN.json`: the driver's [`Checkpoint`] with the contact state, slip history and
//! stage position; how many `.pvd` entries and step records it has; the energy balance's sums)
//! under an identity of the case file, its mesh and the program version. A state's size does
//! not grow with the steps: the step records (and their energy rows) go, one JSON line per
//! converged step, to the journal `steps.jsonl` beside the states, appended as the steps
//! converge, with whether each was written (the `.pvd` entries are made from those); a state
//! names how many of the journal's lines are its own. `stickslip run CASE --resume PATH` goes on
//! from such a state and writes what the uninterrupted run writes (timings apart): at every
//! checkpoint the contact solver keeps only the factorisations the state records how to rebuild
//! (the Delassus block and the batches of columns solved from it), and the resumed run rebuilds
//! them, so both runs compute the steps after it from the same state with the same arithmetic.

use crate::case::Case;
use crate::driver::Checkpoint;
use crate::energy::EnergySaved;
use crate::error::RunError;
use crate::output::PvdEntry;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Version of the state file layout.
pub const FORMAT: u32 = 3;

pub use crate::output::JOURNAL;

/// What `state_NNNN.json` holds. The step records of its checkpoint, the energy rows and the
/// `.pvd` entries are not in the file: [`load`] reads them from the journal and the `.pvd`.
#[derive(Serialize, Deserialize)]
pub struct SavedRun {
    pub format: u32,
    /// Identity of the case file, its mesh, the program version and build, and the contact
    /// solve's path (see [`run_id`]).
    pub id: String,
    /// The candidate gap the model was built with (the zone may have been widened).
    pub candidate_gap: Option<f64>,
    pub checkpoint: Checkpoint,
    /// Records in the journal up to this state (its converged steps).
    pub steps: usize,
    /// The `.pvd` entries up to this state, made from the journal's written steps.
    #[serde(skip)]
    pub pvd: Vec<PvdEntry>,
    /// The entries of `<stem>_time.pvd` up to this state (the written steps integrated in
    /// time), made from the journal.
    #[serde(skip)]
    pub time_pvd: Vec<PvdEntry>,
    /// The journal's lines up to this state, which a resumed run's journal begins with.
    #[serde(skip)]
    pub journal: String,
    pub energy: Option<EnergySaved>,
}

/// One line of the journal: a converged step's record and, when the run keeps it, its
/// energy row.
#[derive(Serialize, Deserialize)]
pub struct JournalLine {
    pub record: crate::record::StepRecord,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy: Option<crate::energy::EnergyRow>,
    /// Whether the step's files were written (its `.pvd` entries).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub written: bool,
}

/// The `.pvd` entries of the written steps among `lines`, as [`crate::output::series`] names
/// a step's files (case `stem`).
pub fn pvd_entries(lines: &[JournalLine], stem: &str) -> Vec<PvdEntry> {
    entries_at(lines, stem, |r| Some(r.time))
}

/// The entries of `<stem>_time.pvd` for the written steps integrated in time among `lines`, at
/// their physical time.
pub fn time_pvd_entries(lines: &[JournalLine], stem: &str) -> Vec<PvdEntry> {
    entries_at(lines, stem, |r| r.physical_time)
}

/// The `.pvd` entries of the written steps among `lines` that `time` gives a time.
fn entries_at(
    lines: &[JournalLine],
    stem: &str,
    time: impl Fn(&crate::record::StepRecord) -> Option<f64>,
) -> Vec<PvdEntry> {
    let mut entries = Vec::new();
    for l in lines.iter().filter(|l| l.written) {
        let Some(time) = time(&l.record) else {
            continue;
        };
        let step = l.record.step;
        entries.push(PvdEntry {
            time,
            part: 0,
            file: crate::output::bodies_file_name(stem, step),
        });
        if l.record.contact.is_some() {
            entries.push(PvdEntry {
                time,
                part: 1,
                file: crate::output::contact_file_name(stem, step),
            });
        }
    }
    entries
}

/// The journal's text for `lines`.
pub fn journal_text(lines: &[JournalLine]) -> String {
    lines
        .iter()
        .map(|l| serde_json::to_string(l).expect("serialisable") + "\n")
        .collect()
}

/// The first `n` lines of the journal in `dir`.
fn read_journal(dir: &Path, n: usize) -> Result<Vec<JournalLine>, String> {
    let path = dir.join(JOURNAL);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read its journal {}: {e}", path.display()))?;
    let lines: Vec<JournalLine> = text
        .lines()
        .take(n)
        .enumerate()
        .map(|(i, l)| {
            serde_json::from_str(l)
                .map_err(|e| format!("{} line {}: not a step record ({e})", path.display(), i + 1))
        })
        .collect::<Result<_, _>>()?;
    if lines.len() < n {
        return Err(format!(
            "its journal {} holds {} steps, fewer than the state's {n}",
            path.display(),
            lines.len()
        ));
    }
    Ok(lines)
}

/// The identity a state must carry to resume `case` (read from `case_path`): the bytes of the
/// case file and its mesh, the program version and build (the executable's hash, as the model
/// cache keys on: another build can take another floating-point path, and the resumed run
/// would then not be the uninterrupted one), and `STICKSLIP_CONTACT_SHORTCUTS=off` where set.
pub fn run_id(case: &Case, case_path: &Path) -> Result<String, RunError> {
    let read = |p: &Path| {
        std::fs::read(p).map_err(|e| RunError::Resume {
            path: p.display().to_string(),
            why: format!("cannot read it: {e}"),
        })
    };
    // States of every earlier build, those written before the build was part of the identity
    // included, are refused.
    let (case_bytes, mesh_bytes) = (read(case_path)?, read(&case.mesh_path(case_path))?);
    Ok(program_identity(&[&case_bytes, &mesh_bytes]))
}

/// The content id of `inputs` and of the program that computes from them: its version, its
/// build (the executable's hash, as the model cache keys on: another build can take another
/// floating-point path) and `STICKSLIP_CONTACT_SHORTCUTS=off` where set (another path in the
/// last digits). Restart states and sweep parts carry it. A program that cannot read its own
/// executable gives an id of its version alone (as before builds were part of it).
pub fn program_identity(inputs: &[&[u8]]) -> String {
    let build = crate::cache::build_id().ok().map(u64::to_le_bytes);
    let mut parts: Vec<&[u8]> = inputs.to_vec();
    parts.push(env!("CARGO_PKG_VERSION").as_bytes());
    parts.extend(build.as_ref().map(|b| b.as_slice()));
    parts.extend(crate::contact::solver::path_identity());
    crate::output::content_id(&parts)
}

impl crate::output::series::StateFile for SavedRun {
    /// `state_NNNN.json`: the state as JSON.
    fn bytes(&self) -> Vec<u8> {
        serde_json::to_string(self)
            .expect("serialisable")
            .into_bytes()
    }
}

/// Reads the state at `path` (a state file, or a directory: its latest state) and checks that
/// it belongs to `case`.
pub fn load(path: &Path, case: &Case, case_path: &Path) -> Result<SavedRun, RunError> {
    let bad = |p: &Path, why: String| RunError::Resume {
        path: p.display().to_string(),
        why,
    };
    let file = if path.is_dir() {
        latest(path).ok_or_else(|| {
            bad(
                path,
                "holds no state_NNNN.json: states are written with every written step".into(),
            )
        })?
    } else {
        path.to_path_buf()
    };
    let text =
        std::fs::read_to_string(&file).map_err(|e| bad(&file, format!("cannot read it: {e}")))?;
    let saved: SavedRun = serde_json::from_str(&text)
        .map_err(|e| bad(&file, format!("not a stickslip state file ({e})")))?;
    if saved.format != FORMAT {
        return Err(bad(
            &file,
            format!(
                "state format {} (this program reads {FORMAT})",
                saved.format
            ),
        ));
    }
    let id = run_id(case, case_path)?;
    if saved.id != id {
        return Err(bad(
            &file,
            format!(
                "is the state of another case, mesh or program build, or of a run with another \
                 STICKSLIP_CONTACT_SHORTCUTS (id {}, this case {id}): resume with the case file, \
                 the program and the setting that wrote it",
                saved.id
            ),
        ));
    }
    let mut saved = saved;
    let dir = file.parent().unwrap_or(Path::new("."));
    let lines = read_journal(dir, saved.steps).map_err(|why| bad(&file, why))?;
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or("case".into());
    saved.pvd = pvd_entries(&lines, &stem);
    saved.time_pvd = time_pvd_entries(&lines, &stem);
    saved.journal = journal_text(&lines);
    if let Some(e) = saved.energy.as_mut() {
        e.set_rows(lines.iter().filter_map(|l| l.energy.clone()).collect());
    }
    saved.checkpoint.records = lines.into_iter().map(|l| l.record).collect();
    Ok(saved)
}

/// The state file of the highest step in `dir`.
fn latest(dir: &Path) -> Option<PathBuf> {
    std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let n = p.file_name()?.to_str()?.to_string();
            let step: usize = n
                .strip_prefix("state_")?
                .strip_suffix(".json")?
                .parse()
                .ok()?;
            Some((step, p))
        })
        .max_by_key(|(s, _)| *s)
        .map(|(_, p)| p)
}
