//! The time series of a run on disk: one `.vtu` of the bodies (and of the contact face) per
//! written step, the contact CSV, and the `.pvd` collection rewritten after each step so that
//! a run stopped at any point leaves a series ParaView opens; then the step's restart state.
//!
//! The steps are written by a background thread ([`Background`]) while the driver solves the
//! next ones: it takes the steps in order from a channel of depth [`BATCH`] and writes exactly
//! the files, in exactly the order, that writing in the loop would, so a run's files do not
//! depend on it. When it falls behind it takes the queued steps together: their displacement
//! fields come from one block solve (which reads the factor once for all, and gives each field
//! bit for bit), and their point fields (stresses) are computed in parallel; each array goes to
//! the file from its own memory. Its first error stops it;
//! the driver sees that error at its next step, and stops.

use super::fields::{BodiesMesh, bodies_fields, bodies_vtu, contact_csv, contact_vtu};
use super::vtu::Field;
use super::{PvdEntry, pvd};
use crate::contact::solver::State;
use crate::error::RunError;
use crate::model::Model;
use crate::restart::{self, SavedRun};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::Instant;

/// Writes `bytes` to `path` atomically, the error naming the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), RunError> {
    write_parts(path, &[bytes])
}

/// Writes the byte strings `parts` to `path` atomically, the error naming the file.
fn write_parts(path: &Path, parts: &[&[u8]]) -> Result<(), RunError> {
    super::write_atomic_parts(path, parts).map_err(|source| write_error(path, source))
}

/// The error of a file that could not be written.
fn write_error(path: &Path, source: std::io::Error) -> RunError {
    RunError::Write {
        path: path.display().to_string(),
        source,
    }
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
    /// The restart state to write after the step's files; its `.pvd` entries are filled in
    /// with those written so far.
    pub state: Option<SavedRun>,
    /// Where to send the step's displacement field once recovered (the driver's checks of the
    /// last step use it rather than solving again).
    pub reply: Option<SyncSender<Vec<f64>>>,
}

/// Steps the writer takes at once at most, and the depth of its channel.
pub const BATCH: usize = 2;

/// The writer of a run's series of steps.
pub struct Series<'a> {
    model: &'a Model,
    dir: &'a Path,
    stem: &'a str,
    /// zlib-compressed `.vtu` arrays (`output.compress`).
    compress: bool,
    /// The points and cells of the bodies dataset (built at the first write).
    mesh: Option<BodiesMesh>,
    entries: Vec<PvdEntry>,
    /// Seconds spent writing so far.
    pub seconds: f64,
}

impl<'a> Series<'a> {
    pub fn new(model: &'a Model, dir: &'a Path, stem: &'a str, compress: bool) -> Self {
        Series {
            model,
            dir,
            stem,
            compress,
            mesh: None,
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

    /// Writes the files of converged steps, in order: per step its bodies dataset (the
    /// fields from the free solution or, with contact, recovered from the contact state), its
    /// contact dataset and CSV, the rewritten `.pvd`, then its restart state if it has one.
    pub fn write(&mut self, steps: Vec<StepOutput>) -> Result<(), RunError> {
        use rayon::prelude::*;
        let t = Instant::now();
        crate::trace::mark(format_args!(
            "write batch of {} from step {}",
            steps.len(),
            steps.first().map_or(0, |s| s.step)
        ));
        let model = self.model;
        // The fields recovered from contact states: one block solve for the batch.
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
        // While the driver solves the next steps, the batch is recovered in one sweep on this
        // thread (the factor read once, the other core left to the contact solve); a batch
        // with the last step, which the driver waits for, on all threads.
        let spread = steps.iter().any(|s| s.reply.is_some());
        let mut recovered = model.contact_displacements(&states, spread).into_iter();
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
        let point_data: Vec<Vec<Field>> =
            fields.par_iter().map(|u| bodies_fields(model, u)).collect();
        crate::trace::mark("point fields");
        // Taken out while the files are written, which borrows `self`.
        let mesh = self.mesh.take().unwrap_or_else(|| BodiesMesh::new(model));
        // The bodies files (the bulk of the bytes) of the batch are written in parallel, each
        // to its temporary name; then, step by step in order, each is renamed into place and
        // followed by the step's other files, the `.pvd` and the restart state. A step that
        // fails stops the batch there, as if its steps were written one by one: the later
        // steps' temporary files are removed, and no file of theirs is touched.
        let (dir, stem, compress) = (self.dir, self.stem, self.compress);
        let bodies: Vec<Result<(PathBuf, String), RunError>> = steps
            .par_iter()
            .zip(&point_data)
            .map(|(s, data)| {
                let name = format!("{stem}_{:04}.vtu", s.step);
                let path = dir.join(&name);
                let tmp = super::write_temporary(&path, &bodies_vtu(&mesh, data, compress).parts())
                    .map_err(|source| write_error(&path, source))?;
                Ok((tmp, name))
            })
            .collect();
        self.mesh = Some(mesh);
        let mut bodies = bodies.into_iter();
        for s in steps {
            let written =
                bodies
                    .next()
                    .expect("one bodies file per step")
                    .and_then(|(tmp, name)| {
                        let path = dir.join(&name);
                        super::commit(&tmp, &path).map_err(|source| write_error(&path, source))?;
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
        self.seconds += t.elapsed().as_secs_f64();
        crate::trace::mark("batch written");
        Ok(())
    }

    /// Writes one step's files after its bodies dataset (written as `name`).
    fn write_files(&mut self, s: StepOutput, name: String) -> Result<(), RunError> {
        let (model, stem, step) = (self.model, self.stem, s.step);
        self.entries.push(PvdEntry {
            time: s.time,
            part: 0,
            file: name,
        });
        if let Some(st) = &s.contact {
            let cname = format!("{stem}_contact_{step:04}.vtu");
            write_file(
                &self.dir.join(&cname),
                &contact_vtu(model, st, self.compress),
            )?;
            self.entries.push(PvdEntry {
                time: s.time,
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
        // The state to resume from, after the step's files.
        if let Some(mut saved) = s.state {
            saved.pvd = self.entries.clone();
            write_file(
                &self.dir.join(restart::state_name(step)),
                serde_json::to_string(&saved)
                    .expect("serialisable")
                    .as_bytes(),
            )?;
        }
        Ok(())
    }
}

/// A [`Series`] written on a thread of its own, fed through a channel of depth [`BATCH`]: the
/// driver hands it a step and goes on, and waits only when the channel is full.
pub struct Background<'scope> {
    tx: SyncSender<StepOutput>,
    /// The writer thread: its busy seconds, or its first error. `None` once joined.
    handle: Option<ScopedJoinHandle<'scope, Result<f64, RunError>>>,
    /// Seconds the caller spent waiting for the writer.
    wait: f64,
}

impl<'scope> Background<'scope> {
    /// Starts the writer thread of `series` in `scope`.
    pub fn spawn<'env>(scope: &'scope Scope<'scope, 'env>, mut series: Series<'env>) -> Self {
        let (tx, rx): (_, Receiver<StepOutput>) = sync_channel(BATCH);
        let handle = std::thread::Builder::new()
            .name("stickslip-writer".into())
            .spawn_scoped(scope, move || {
                while let Ok(first) = rx.recv() {
                    // The steps queued behind it go in the same batch.
                    let mut batch = vec![first];
                    while batch.len() < BATCH {
                        match rx.try_recv() {
                            Ok(s) => batch.push(s),
                            Err(_) => break,
                        }
                    }
                    // The first error ends the thread (and drops the receiver).
                    series.write(batch)?;
                }
                Ok(series.seconds)
            })
            .expect("the writer thread starts");
        Background {
            tx,
            handle: Some(handle),
            wait: 0.0,
        }
    }

    /// The writer's error if it has stopped on one (it stops only on an error while steps
    /// can still come). Each error is returned once.
    pub fn check(&mut self) -> Result<(), RunError> {
        if self.handle.as_ref().is_some_and(|h| h.is_finished()) {
            return Err(self.stopped_error());
        }
        Ok(())
    }

    /// Hands a step to the writer, waiting while the previous one is still queued; the
    /// writer's error if it has stopped on one (after which the run stops: nothing more is
    /// sent, and [`Self::finish`] joins nothing).
    pub fn send(&mut self, step: StepOutput) -> Result<(), RunError> {
        self.check()?;
        let t = Instant::now();
        let sent = self.tx.send(step);
        self.wait += t.elapsed().as_secs_f64();
        match sent {
            Ok(()) => Ok(()),
            // The receiver is gone: the writer stopped on an error.
            Err(_) => Err(self.stopped_error()),
        }
    }

    /// Waits for the writer to write every step handed to it: (its busy seconds, the seconds
    /// the caller spent waiting for it), or its error (`Ok` with no busy time if the error was
    /// already returned by [`Self::check`] or [`Self::send`]).
    pub fn finish(self) -> Result<(f64, f64), RunError> {
        let Background { tx, handle, wait } = self;
        // No more steps: the writer ends once it has written those queued.
        drop(tx);
        let Some(h) = handle else {
            return Ok((0.0, wait));
        };
        let t = Instant::now();
        let busy = join(h)?;
        Ok((busy, wait + t.elapsed().as_secs_f64()))
    }

    /// Joins the writer thread, which has stopped early: its error.
    fn stopped_error(&mut self) -> RunError {
        let h = self
            .handle
            .take()
            .expect("the writer thread is joined once");
        match join(h) {
            Err(e) => e,
            Ok(_) => unreachable!("the writer stops before it is finished only on an error"),
        }
    }
}

/// Joins a writer thread, passing a panic of it on.
fn join(h: ScopedJoinHandle<'_, Result<f64, RunError>>) -> Result<f64, RunError> {
    h.join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}
