//! The time series of a run on disk: one `.vtu` of the bodies (and of the contact face) per
//! written step, the contact CSV, and the `.pvd` collection rewritten after each step so that
//! a run stopped at any point leaves a series ParaView opens; then the step's restart state.
//! A step's bodies dataset is prepared (its field recovered, its stresses computed, its file
//! written to a temporary name) apart from being put in place, so that the writer thread
//! ([`super::background`]) and the driver's thread can both prepare steps.

use super::fields::{
    BodiesMesh, bodies_after_point_data, bodies_fields, bodies_fields_many, bodies_vtu,
    contact_csv, contact_vtu,
};
use super::vtu::Field;
use super::{PvdEntry, bodies_file_name, contact_file_name, pvd, state_file_name};
use crate::contact::solver::State;
use crate::error::RunError;
use crate::model::Model;
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::sync::{Arc, OnceLock};
use std::time::Instant;

/// Writes `bytes` to `path` atomically, the error naming the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    write_parts(path, &[bytes])
}

/// Writes the byte strings `parts` to `path` atomically, the error naming the file.
fn write_parts(path: &Path, parts: &[&[u8]]) -> Result<(), RunError> {
    super::atomic::write_atomic_parts(path, parts).map_err(|source| write_error(path, source))
}

/// The error of a file that could not be written.
fn write_error(path: &Path, source: std::io::Error) -> RunError {
    RunError::Write {
        path: path.display().to_string(),
        source,
    }
}

/// The name of the contact table of `step`.
fn contact_csv_name(step: usize) -> String {
    format!("contact_{step:04}.csv")
}

/// Writes the contact table of `step` alone (a run that writes no `.vtu` files), atomically.
pub fn write_contact_csv(
    model: &Model,
    dir: &Path,
    step: usize,
    st: &State,
    dt: Option<f64>,
) -> Result<(), RunError> {
    write_file(
        &dir.join(contact_csv_name(step)),
        contact_csv(model, st, dt).as_bytes(),
    )
}

/// A step's restart state as the series writes it, after the step's files
/// ([`super::state_file_name`]): its bytes are made when the step is written, on the thread
/// that writes it.
pub trait StateFile: Send + Sync {
    fn bytes(&self) -> Vec<u8>;
}

/// One converged step to write, with its own copy of what it needs.
pub struct StepOutput {
    pub step: usize,
    pub time: f64,
    pub scale: f64,
    /// The free solution (runs without contact).
    pub u: Option<Vec<f64>>,
    /// The contact state (runs with contact: the bodies' field is recovered from it).
    pub contact: Option<State>,
    /// The restart state to write after the step's files.
    pub state: Option<Box<dyn StateFile>>,
    /// Where to send the step's displacement field once recovered (the driver's checks of the
    /// last step use it rather than solving again).
    pub reply: Option<SyncSender<Vec<f64>>>,
    /// A step integrated in time: its physical time and time step (the `.pvd` of physical
    /// time lists it, and its contact fields carry the slip rate).
    pub physical: Option<(f64, f64)>,
}

/// What writing a step's bodies dataset needs, shared by the writer thread and the driver's
/// thread (which prepares the last steps itself once it has no more to solve).
#[derive(Clone)]
pub(super) struct Bodies<'a> {
    model: &'a Model,
    dir: &'a Path,
    stem: &'a str,
    /// zlib-compressed `.vtu` arrays (`output.compress`).
    compress: bool,
    /// The points and cells of the bodies dataset (built at the first write).
    mesh: Arc<OnceLock<BodiesMesh>>,
}

/// Steps whose bodies datasets are written to their temporary names (or failed), to be put in
/// place in order with the steps' other files ([`Series::commit`]).
pub struct Prepared {
    steps: Vec<StepOutput>,
    bodies: Vec<Result<(PathBuf, String), RunError>>,
    /// Seconds the preparation took.
    seconds: f64,
}

impl Prepared {
    /// Removes the temporary files (the steps will not be written).
    pub(super) fn discard(self) {
        for (tmp, _) in self.bodies.into_iter().flatten() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

impl Bodies<'_> {
    /// The fields of `steps` (recovered from their contact states in one sweep of the factor
    /// on this thread, their columns interleaved), sent to the steps that asked for them, and
    /// their bodies datasets written side by side to their temporary names: with `spread`
    /// their stresses and files on all threads, else on this one.
    ///
    /// The bytes of the datasets that do not depend on the step (after the point fields) are
    /// written meanwhile on a thread of its own ([`super::atomic::Ahead`]), where the file system
    /// allows it; the rest of each file follows once its fields are known. The same bytes.
    pub(super) fn prepare(&self, steps: Vec<StepOutput>, spread: bool) -> Prepared {
        std::thread::scope(|scope| {
            let ahead = (!self.compress).then(|| {
                let names: Vec<PathBuf> = steps
                    .iter()
                    .map(|s| self.dir.join(self.bodies_name(s)))
                    .collect();
                std::thread::Builder::new()
                    .name("stickslip-ahead".into())
                    .spawn_scoped(scope, move || self.write_ahead(&names))
                    .ok()
            });
            self.prepare_with(steps, spread, move || {
                ahead
                    .flatten()
                    .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
                    .unwrap_or_default()
            })
        })
    }

    /// The file name of a step's bodies dataset.
    fn bodies_name(&self, s: &StepOutput) -> String {
        bodies_file_name(self.stem, s.step)
    }

    /// The step-independent bytes of the bodies datasets `paths`, written ahead to their
    /// temporary names: per file, `None` where not (the file is then written whole).
    fn write_ahead(&self, paths: &[PathBuf]) -> Vec<Option<super::atomic::Ahead>> {
        let mesh = self.mesh.get_or_init(|| BodiesMesh::new(self.model));
        let after = bodies_after_point_data(mesh);
        let parts = after.parts();
        paths
            .iter()
            .map(|path| {
                // A failure here only loses the head start: the whole file is written later,
                // and that write reports any error.
                super::atomic::write_ahead(path, after.len, after.offset, &parts)
                    .ok()
                    .flatten()
            })
            .collect()
    }

    /// [`Self::prepare`] with the files begun ahead that `ahead` waits for (per step, none
    /// where not begun; none at all without a thread writing ahead).
    fn prepare_with(
        &self,
        steps: Vec<StepOutput>,
        spread: bool,
        ahead: impl FnOnce() -> Vec<Option<super::atomic::Ahead>>,
    ) -> Prepared {
        use rayon::prelude::*;
        let t = Instant::now();
        crate::trace::mark(format_args!(
            "prepare {} from step {}",
            steps.len(),
            steps.first().map_or(0, |s| s.step)
        ));
        let model = self.model;
        let states: Vec<(f64, &State)> = steps
            .iter()
            .filter(|s| s.u.is_none())
            .map(|s| {
                let st = s.contact.as_ref();
                (
                    s.scale,
                    st.expect("a step has a solution or a contact state"),
                )
            })
            .collect();
        // A batch (at most `BATCH` steps) is one group of interleaved columns, which
        // `contact_displacements` solves on this thread with or without `spread`.
        let mut recovered = model.contact_displacements(&states, false).into_iter();
        let fields: Vec<std::borrow::Cow<[f64]>> = steps
            .iter()
            .map(|s| match &s.u {
                Some(u) => std::borrow::Cow::Borrowed(u.as_slice()),
                None => std::borrow::Cow::Owned(recovered.next().expect("one field per state")),
            })
            .collect();
        for (s, u) in steps.iter().zip(&fields) {
            if let Some(tx) = &s.reply {
                // The driver may have stopped waiting (it failed): nothing to do then.
                let _ = tx.send(u.to_vec());
            }
        }
        crate::trace::mark("fields recovered");
        // Without `spread` on this thread alone: the contact solve (or the other thread's
        // preparation) has the other core.
        // Two or more steps: their stresses in one pass over the elements per group of up to
        // four (each element's gradients mapped once for the group: two steps in 8–12 ms on
        // L5 where one by one took 13–19, on one thread or on two, `examples/stress_timing`),
        // the groups on all threads with `spread`.
        let us: Vec<&[f64]> = fields.iter().map(|u| &u[..]).collect();
        let point_data: Vec<Vec<Field>> = match (us.len(), spread) {
            (1, spread) => vec![bodies_fields(model, us[0], spread)],
            (n, true) => {
                let groups = n.div_ceil(rayon::current_num_threads().max(1)).clamp(2, 4);
                us.par_chunks(groups)
                    .flat_map_iter(|g| bodies_fields_many(model, g))
                    .collect()
            }
            (_, false) => bodies_fields_many(model, &us),
        };
        crate::trace::mark("point fields");
        let mesh = self.mesh.get_or_init(|| BodiesMesh::new(model));
        let compress = self.compress;
        let mut ahead = ahead();
        ahead.resize_with(steps.len(), || None);
        let write =
            |((s, data), ahead): ((&StepOutput, &Vec<Field>), Option<super::atomic::Ahead>)| {
                let name = self.bodies_name(s);
                let path = self.dir.join(&name);
                let parts = bodies_vtu(mesh, data, compress);
                // A file begun ahead that cannot be finished (its temporary removed) is written
                // whole: any error of that write is the file's.
                let tmp = ahead
                    .and_then(|a| super::atomic::finish_ahead(a, &parts.parts()).ok())
                    .map_or_else(|| super::atomic::write_temporary(&path, &parts.parts()), Ok)
                    .map_err(|source| write_error(&path, source))?;
                Ok((tmp, name))
            };
        let bodies = if spread {
            steps
                .par_iter()
                .zip(&point_data)
                .zip(ahead)
                .map(write)
                .collect()
        } else {
            steps
                .iter()
                .zip(&point_data)
                .zip(ahead)
                .map(write)
                .collect()
        };
        crate::trace::mark("bodies files prepared");
        Prepared {
            steps,
            bodies,
            seconds: t.elapsed().as_secs_f64(),
        }
    }
}

/// The writer of a run's series of steps.
pub struct Series<'a> {
    pub(super) bodies: Bodies<'a>,
    entries: Vec<PvdEntry>,
    /// The steps integrated in time at their physical time (`<stem>_time.pvd`, written once a
    /// run has such steps: ParaView animates the event in physical time from it).
    time_entries: Vec<PvdEntry>,
    /// The files of an earlier run that this one replaces are closed here.
    reaper: super::atomic::Reaper,
    /// Seconds spent writing so far.
    pub seconds: f64,
    /// Write the contact table with each step (`output.contact_csv`).
    pub contact_csv: bool,
}

impl<'a> Series<'a> {
    pub fn new(model: &'a Model, dir: &'a Path, stem: &'a str, compress: bool) -> Self {
        Series {
            bodies: Bodies {
                model,
                dir,
                stem,
                compress,
                mesh: Arc::default(),
            },
            entries: Vec::new(),
            time_entries: Vec::new(),
            reaper: super::atomic::Reaper::new(),
            seconds: 0.0,
            contact_csv: true,
        }
    }

    /// Goes on with the `.pvd` entries of an earlier run (a restart).
    pub fn with_entries(mut self, entries: Vec<PvdEntry>) -> Self {
        self.entries = entries;
        self
    }

    /// Goes on with the `<stem>_time.pvd` entries of an earlier run (a restart).
    pub fn with_time_entries(mut self, entries: Vec<PvdEntry>) -> Self {
        self.time_entries = entries;
        self
    }

    /// The `.pvd` entries written so far.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    /// Writes the files of converged steps, in order: per step its bodies dataset (the
    /// fields from the free solution or, with contact, recovered from the contact state), its
    /// contact dataset and CSV, the rewritten `.pvd`, then its restart state if it has one.
    /// A batch with a step whose field is asked for (the last, which the driver waits for)
    /// has its stresses and files prepared on all threads, else on this one (the other core
    /// is the contact solve's).
    pub fn write(&mut self, steps: Vec<StepOutput>) -> Result<(), RunError> {
        let spread = steps.iter().any(|s| s.reply.is_some());
        let prepared = self.bodies.prepare(steps, spread);
        self.commit(prepared)
    }

    /// Puts prepared steps in place, in order: each bodies file renamed from its temporary
    /// name, followed by the step's other files, the `.pvd` and the restart state. A step
    /// that fails stops there, as if the steps were written one by one: the later steps'
    /// temporary files are removed, and no file of theirs is touched.
    pub(super) fn commit(&mut self, prepared: Prepared) -> Result<(), RunError> {
        let t = Instant::now();
        let Prepared {
            steps,
            bodies,
            seconds,
        } = prepared;
        let dir = self.bodies.dir;
        let mut bodies = bodies.into_iter();
        for s in steps {
            let written =
                bodies
                    .next()
                    .expect("one bodies file per step")
                    .and_then(|(tmp, name)| {
                        let path = dir.join(&name);
                        self.reaper
                            .commit(&tmp, &path)
                            .map_err(|source| write_error(&path, source))?;
                        crate::trace::mark("bodies file written");
                        self.write_files(s, name)
                    });
            if let Err(e) = written {
                for (tmp, _) in bodies.flatten() {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(e);
            }
        }
        self.seconds += seconds + t.elapsed().as_secs_f64();
        crate::trace::mark("batch written");
        Ok(())
    }

    /// Writes one step's files after its bodies dataset (written as `name`): the contact
    /// dataset and table, the `.pvd` and the restart state, written and synced together, then
    /// each renamed into place in that order.
    fn write_files(&mut self, s: StepOutput, name: String) -> Result<(), RunError> {
        let (model, stem, step) = (self.bodies.model, self.bodies.stem, s.step);
        let dir = self.bodies.dir;
        let compress = self.bodies.compress;
        self.entries.push(PvdEntry {
            time: s.time,
            part: 0,
            file: name,
        });
        let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
        if let Some(st) = &s.contact {
            let cname = contact_file_name(stem, step);
            let dt = s.physical.map(|p| p.1);
            files.push((dir.join(&cname), contact_vtu(model, st, dt, compress)));
            self.entries.push(PvdEntry {
                time: s.time,
                part: 1,
                file: cname,
            });
            if self.contact_csv {
                files.push((
                    dir.join(contact_csv_name(step)),
                    contact_csv(model, st, dt).into_bytes(),
                ));
            }
        }
        files.push((
            dir.join(format!("{stem}.pvd")),
            pvd(&self.entries).into_bytes(),
        ));
        if let Some((t, _)) = s.physical {
            let n = self.entries.len() - if s.contact.is_some() { 2 } else { 1 };
            let this_step: Vec<PvdEntry> = self.entries[n..]
                .iter()
                .map(|e| PvdEntry {
                    time: t,
                    part: e.part,
                    file: e.file.clone(),
                })
                .collect();
            self.time_entries.extend(this_step);
        }
        if !self.time_entries.is_empty() {
            files.push((
                dir.join(format!("{stem}_time.pvd")),
                pvd(&self.time_entries).into_bytes(),
            ));
        }
        // The state to resume from, after the step's files.
        if let Some(saved) = s.state {
            files.push((dir.join(state_file_name(step)), saved.bytes()));
        }
        self.put_all(&files)
    }

    /// Writes each `(path, bytes)` of `files` atomically, renamed into place in their order
    /// once all are written and synced (the files they replace closed by the reaper); the
    /// error names the file.
    fn put_all(&self, files: &[(PathBuf, Vec<u8>)]) -> Result<(), RunError> {
        let parts: Vec<(&Path, &[u8])> = files
            .iter()
            .map(|(p, b)| (p.as_path(), b.as_slice()))
            .collect();
        let temps = super::atomic::write_temporaries(&parts)
            .map_err(|(i, source)| write_error(&files[i].0, source))?;
        let mut temps = temps.into_iter().zip(files);
        while let Some((tmp, (path, _))) = temps.next() {
            if let Err(source) = self.reaper.commit(&tmp, path) {
                for (tmp, _) in temps {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(write_error(path, source));
            }
        }
        Ok(())
    }
}
