//! The time series of a run on disk: one `.vtu` of the bodies (and of the contact face) per
//! written step, the contact CSV, and the `.pvd` collection rewritten after each step so that
//! a run stopped at any point leaves a series ParaView opens.

use super::fields::{bodies_vtu, contact_csv, contact_vtu};
use super::{PvdEntry, pvd};
use crate::case::Case;
use crate::contact::solver::State;
use crate::error::RunError;
use crate::model::Model;
use std::path::Path;
use std::time::Instant;

/// Writes `bytes` to `path` atomically, the error naming the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    super::write_atomic(path, bytes).map_err(|source| RunError::Write {
        path: path.display().to_string(),
        source,
    })
}

/// The writer of a run's series of steps.
pub struct Series<'a> {
    model: &'a Model,
    case: &'a Case,
    dir: &'a Path,
    stem: &'a str,
    entries: Vec<PvdEntry>,
    /// Seconds spent writing so far.
    pub seconds: f64,
}

impl<'a> Series<'a> {
    pub fn new(model: &'a Model, case: &'a Case, dir: &'a Path, stem: &'a str) -> Self {
        Series {
            model,
            case,
            dir,
            stem,
            entries: Vec::new(),
            seconds: 0.0,
        }
    }

    /// Goes on with the `.pvd` entries of an earlier run (a restart).
    pub fn with_entries(mut self, entries: Vec<PvdEntry>) -> Self {
        self.entries = entries;
        self
    }

    /// The `.pvd` entries written so far.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    /// Writes the files of one converged step and rewrites the `.pvd`: the bodies' fields from
    /// the free solution `u` or, with contact, recovered from the contact state.
    pub fn write_step(
        &mut self,
        step: usize,
        time: f64,
        scale: f64,
        u: Option<&Vec<f64>>,
        contact: Option<&State>,
    ) -> Result<(), RunError> {
        let t = Instant::now();
        let (model, stem) = (self.model, self.stem);
        let vtk_error = |name: &str, e: vtkio::Error| RunError::Write {
            path: name.to_string(),
            source: std::io::Error::other(e.to_string()),
        };
        let name = format!("{stem}_{step:04}.vtu");
        let u = match (u, contact) {
            (Some(u), _) => u.clone(),
            (None, Some(st)) => model.contact_displacement(scale, st),
            (None, None) => unreachable!("a step has a solution or a contact state"),
        };
        let bytes = bodies_vtu(model, &u, self.case).map_err(|e| vtk_error(&name, e))?;
        write_file(&self.dir.join(&name), &bytes)?;
        self.entries.push(PvdEntry {
            time,
            part: 0,
            file: name,
        });
        if let Some(st) = contact {
            let cname = format!("{stem}_contact_{step:04}.vtu");
            let bytes = contact_vtu(model, st).map_err(|e| vtk_error(&cname, e))?;
            write_file(&self.dir.join(&cname), &bytes)?;
            self.entries.push(PvdEntry {
                time,
                part: 1,
                file: cname,
            });
            write_file(
                &self.dir.join(format!("contact_{step:04}.csv")),
                contact_csv(model, st).as_bytes(),
            )?;
        }
        write_file(
            &self.dir.join(format!("{stem}.pvd")),
            pvd(&self.entries).as_bytes(),
        )?;
        self.seconds += t.elapsed().as_secs_f64();
        Ok(())
    }
}
