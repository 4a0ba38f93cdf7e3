//! Exact restart: at every written step a run saves the whole state it needs to go on
//! (`state_NNNN.json`: the driver's [`Checkpoint`] with the contact state, slip history and
//! stage position; the `.pvd` entries so far; the energy balance so far) under an identity of
//! the case file, its mesh and the program version. `stickslip run CASE --resume PATH` goes on
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
pub const FORMAT: u32 = 2;

/// What `state_NNNN.json` holds.
#[derive(Serialize, Deserialize)]
pub struct SavedRun {
    pub format: u32,
    /// Identity of the case file, its mesh, the program version and build, and the contact
    /// solve's path (see [`run_id`]).
    pub id: String,
    /// The candidate gap the model was built with (the zone may have been widened).
    pub candidate_gap: Option<f64>,
    pub checkpoint: Checkpoint,
    pub pvd: Vec<PvdEntry>,
    pub energy: Option<EnergySaved>,
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

/// The file name of the state of `step`.
pub fn state_name(step: usize) -> String {
    format!("state_{step:04}.json")
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
