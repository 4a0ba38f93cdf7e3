//! The time series of a run on disk: one `.vtu` of the bodies (and of the contact face) per
//! written step, the contact CSV, and the `.pvd` collection rewritten after each step so that
//! a run stopped at any point leaves a series ParaView opens; then the step's restart state.
//!
//! The steps are written by a background thread ([`Background`]) while the driver solves the
//! next ones: it takes the steps in order from a queue of [`QUEUE`] steps and writes exactly
//! the files, in exactly the order, that writing in the loop would, so a run's files do not
//! depend on it. When it falls behind it takes the queued steps together (up to [`BATCH`]):
//! their displacement fields come from one block solve (which reads the factor once for all,
//! and gives each field bit for bit). When the queue is full (a run that writes more than it
//! solves) and once the driver has solved its last step, the driver prepares the last steps
//! still waiting on its own thread ([`Background::help`]; at the end on all threads when the
//! writer has caught up) and hands them back, and the writer puts them in place in their
//! turn. Each array goes to the file
//! from its own memory. Its first error stops it; the driver sees that error at its next step,
//! and stops.

use super::fields::{
    BodiesMesh, bodies_after_point_data, bodies_fields, bodies_fields_many, bodies_vtu,
    contact_csv, contact_vtu,
};
use super::vtu::Field;
use super::{PvdEntry, bodies_file_name, contact_file_name, pvd};
use crate::contact::solver::State;
use crate::error::RunError;
use crate::model::Model;
use crate::restart::{self, SavedRun};
use std::collections::{HashMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::mpsc::SyncSender;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock};
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
) -> Result<(), RunError> {
    write_file(
        &dir.join(contact_csv_name(step)),
        contact_csv(model, st).as_bytes(),
    )
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

/// Steps the writer (or the driver's thread) prepares at once at most: their fields in one
/// sweep of the factor. Four rather than two: Fig. 2 on L5 writing every step, whose queue
/// stays full, 1.370 → 1.310 s (`benches/ab.sh 6`, B/A 0.956); the shipped Fig. 2 (five written
/// steps) does not change (wall − floor 0.214 → 0.213 s, 10 pairs).
pub const BATCH: usize = 4;

/// Steps that may wait in the writer's queue before the driver prepares the last of them
/// itself ([`Background::send`]).
pub const QUEUE: usize = 8;

/// What writing a step's bodies dataset needs, shared by the writer thread and the driver's
/// thread (which prepares the last steps itself once it has no more to solve).
#[derive(Clone)]
struct Bodies<'a> {
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
    fn discard(self) {
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
    /// written meanwhile on a thread of its own ([`super::Ahead`]), where the file system
    /// allows it; the rest of each file follows once its fields are known. The same bytes.
    fn prepare(&self, steps: Vec<StepOutput>, spread: bool) -> Prepared {
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
    fn write_ahead(&self, paths: &[PathBuf]) -> Vec<Option<super::Ahead>> {
        let mesh = self.mesh.get_or_init(|| BodiesMesh::new(self.model));
        let after = bodies_after_point_data(mesh);
        let parts = after.parts();
        paths
            .iter()
            .map(|path| {
                // A failure here only loses the head start: the whole file is written later,
                // and that write reports any error.
                super::write_ahead(path, after.len, after.offset, &parts)
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
        ahead: impl FnOnce() -> Vec<Option<super::Ahead>>,
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
        let write = |((s, data), ahead): ((&StepOutput, &Vec<Field>), Option<super::Ahead>)| {
            let name = self.bodies_name(s);
            let path = self.dir.join(&name);
            let parts = bodies_vtu(mesh, data, compress);
            // A file begun ahead that cannot be finished (its temporary removed) is written
            // whole: any error of that write is the file's.
            let tmp = ahead
                .and_then(|a| super::finish_ahead(a, &parts.parts()).ok())
                .map_or_else(|| super::write_temporary(&path, &parts.parts()), Ok)
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
    bodies: Bodies<'a>,
    entries: Vec<PvdEntry>,
    /// The files of an earlier run that this one replaces are closed here.
    reaper: super::Reaper,
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
            reaper: super::Reaper::new(),
            seconds: 0.0,
            contact_csv: true,
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
    fn commit(&mut self, prepared: Prepared) -> Result<(), RunError> {
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
            files.push((dir.join(&cname), contact_vtu(model, st, compress)));
            self.entries.push(PvdEntry {
                time: s.time,
                part: 1,
                file: cname,
            });
            if self.contact_csv {
                files.push((
                    dir.join(contact_csv_name(step)),
                    contact_csv(model, st).into_bytes(),
                ));
            }
        }
        files.push((
            dir.join(format!("{stem}.pvd")),
            pvd(&self.entries).into_bytes(),
        ));
        // The state to resume from, after the step's files.
        if let Some(saved) = s.state {
            files.push((
                dir.join(restart::state_name(step)),
                serde_json::to_string(&saved)
                    .expect("serialisable")
                    .into_bytes(),
            ));
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
        let temps = super::write_temporaries(&parts)
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

/// An entry of the writer's queue: a step to write, or steps that the driver's thread took
/// from the queue to prepare (the writer puts them in place in their turn).
enum Item {
    Step(Box<StepOutput>),
    Taken(u64),
}

/// The queue between the driver and the writer thread.
#[derive(Default)]
struct Queue {
    items: VecDeque<Item>,
    /// Steps prepared by the driver's thread, by the number of their [`Item::Taken`].
    done: HashMap<u64, Prepared>,
    next_id: u64,
    /// No more steps will come.
    closed: bool,
    /// The writer is preparing steps (recovering their fields, computing their stresses).
    preparing: bool,
    /// The writer stopped on an error: nothing more is written.
    stopped: bool,
}

impl Queue {
    fn waiting_steps(&self) -> usize {
        self.items
            .iter()
            .filter(|i| matches!(i, Item::Step(_)))
            .count()
    }
}

/// The queue and its signal (any change to it).
#[derive(Default)]
struct Shared {
    queue: Mutex<Queue>,
    changed: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Queue> {
        self.queue.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn wait<'g>(&self, g: MutexGuard<'g, Queue>) -> MutexGuard<'g, Queue> {
        self.changed.wait(g).unwrap_or_else(|e| e.into_inner())
    }
}

/// A [`Series`] written on a thread of its own, fed through a queue of [`QUEUE`] steps: the
/// driver hands it a step and goes on; when the queue is full it prepares the last steps
/// waiting itself and hands them back (as at the end of the run), rather than wait. The
/// writer takes the steps from the front of the queue, up to [`BATCH`] waiting together (one
/// block solve for their fields). When the driver has no more steps to solve it takes the last of the
/// steps still waiting and prepares them itself ([`Self::help`]), so that both cores
/// write the last steps; the writer puts them in place in their turn.
pub struct Background<'scope, 'env> {
    shared: Arc<Shared>,
    bodies: Bodies<'env>,
    /// The writer thread: its busy seconds, or its first error. `None` once joined.
    handle: Option<ScopedJoinHandle<'scope, Result<f64, RunError>>>,
    /// Seconds the caller spent waiting for the writer.
    wait: f64,
    /// Steps waiting in the queue at most ([`QUEUE`] unless set, [`Self::with_queue`]).
    queue: usize,
    /// Steps the caller's thread prepared (in [`Self::send`] and [`Self::help`]).
    prepared_here: usize,
}

impl<'scope, 'env> Background<'scope, 'env> {
    /// Starts the writer thread of `series` in `scope`.
    pub fn spawn(scope: &'scope Scope<'scope, 'env>, mut series: Series<'env>) -> Self {
        let shared = Arc::new(Shared::default());
        let bodies = series.bodies.clone();
        let queue = shared.clone();
        let handle = std::thread::Builder::new()
            .name("stickslip-writer".into())
            .spawn_scoped(scope, move || {
                let written = writer_loop(&queue, &mut series);
                if written.is_err() {
                    // Nothing more is written: the steps prepared by the driver's thread lose
                    // their temporary files (those it is still preparing, when it is done).
                    let mut q = queue.lock();
                    q.stopped = true;
                    for (_, p) in q.done.drain() {
                        p.discard();
                    }
                    q.items.clear();
                    queue.changed.notify_all();
                }
                written.map(|()| series.seconds)
            })
            .expect("the writer thread starts");
        Background {
            shared,
            bodies,
            handle: Some(handle),
            wait: 0.0,
            queue: QUEUE,
            prepared_here: 0,
        }
    }

    /// With at most `steps` (at least one) waiting in the queue instead of [`QUEUE`].
    pub fn with_queue(mut self, steps: usize) -> Self {
        self.queue = steps.max(1);
        self
    }

    /// Steps prepared on the caller's thread so far, while the queue was full
    /// ([`Self::send`]) or at the end ([`Self::help`]).
    pub fn prepared_here(&self) -> usize {
        self.prepared_here
    }

    /// The writer's error if it has stopped on one (it stops only on an error while steps
    /// can still come). Each error is returned once.
    pub fn check(&mut self) -> Result<(), RunError> {
        if self.handle.as_ref().is_some_and(|h| h.is_finished()) {
            return Err(self.stopped_error());
        }
        Ok(())
    }

    /// Hands a step to the writer; while the queue is full, this thread prepares the last
    /// steps waiting (or waits, should none be left to take). The writer's error if it has
    /// stopped on one (after which the run stops: nothing more is sent, and [`Self::finish`]
    /// joins nothing).
    pub fn send(&mut self, step: StepOutput) -> Result<(), RunError> {
        self.check()?;
        let t = Instant::now();
        let mut q = self.shared.lock();
        while !q.stopped && q.waiting_steps() >= self.queue {
            // The writer is behind (a run that writes more than it solves, such as every
            // step of Fig. 2): this thread prepares the last steps waiting rather than idle.
            drop(q);
            match self.prepare_last(false) {
                Some(n) => {
                    self.prepared_here += n;
                    q = self.shared.lock();
                }
                None => {
                    q = self.shared.lock();
                    if !q.stopped && q.waiting_steps() >= self.queue {
                        q = self.shared.wait(q);
                    }
                }
            }
        }
        let stopped = q.stopped;
        if !stopped {
            q.items.push_back(Item::Step(Box::new(step)));
            self.shared.changed.notify_all();
        }
        drop(q);
        self.wait += t.elapsed().as_secs_f64();
        if stopped {
            return Err(self.stopped_error());
        }
        Ok(())
    }

    /// No more steps will come: prepares the steps still waiting in the queue on this
    /// thread, from the last (the writer takes them from the first), and hands them back to
    /// the writer, which puts them in place in their turn. When the writer is not preparing
    /// steps of its own, they are prepared on all threads (on L7 the writer has caught up
    /// when the last step comes, and its core would idle). A step whose field it asked for
    /// (the last) has it once this returns, whichever thread prepared it. Returns the number
    /// of steps this thread prepared.
    pub fn help(&mut self) -> usize {
        let mut prepared_here = 0;
        if self.handle.is_none() {
            return prepared_here;
        }
        self.shared.lock().closed = true;
        self.shared.changed.notify_all();
        while let Some(n) = self.prepare_last(true) {
            prepared_here += n;
        }
        self.prepared_here += prepared_here;
        prepared_here
    }

    /// Takes the last run of steps waiting in the queue (those after it, if any, are taken
    /// already), up to a batch, puts a marker in their place, prepares them on this thread and
    /// hands them back to the writer: the number of steps, or `None` when none waits or the
    /// writer has stopped.
    ///
    /// While the writer prepares steps of its own, all of them up to a batch, in one block
    /// solve (at the end of Fig. 2 on L5 the writer prepares two steps and two wait: taken one
    /// by one, each cost a sweep of the factor, 15 and 17 ms, where the two together took
    /// 28 ms). At the end of the run (`end`) with the writer not preparing steps (it has
    /// caught up, as on L7, or only puts files in place), the later half of them, on all
    /// threads, and the writer takes the earlier.
    fn prepare_last(&self, end: bool) -> Option<usize> {
        let shared = &self.shared;
        let (id, steps, spread) = {
            let mut q = shared.lock();
            if q.stopped {
                return None;
            }
            let last = q
                .items
                .iter()
                .rposition(|i| matches!(i, Item::Step(_)))
                .map(|k| k + 1)?;
            let first = q
                .items
                .range(..last)
                .rposition(|i| !matches!(i, Item::Step(_)))
                .map_or(0, |k| k + 1);
            let spread = end && !q.preparing;
            let take = if spread {
                (last - first).div_ceil(2).min(BATCH)
            } else {
                (last - first).min(BATCH)
            };
            let id = q.next_id;
            q.next_id += 1;
            let steps: Vec<StepOutput> = q
                .items
                .drain(last - take..last)
                .map(|i| match i {
                    Item::Step(s) => *s,
                    Item::Taken(_) => unreachable!("a run of steps"),
                })
                .collect();
            q.items.insert(last - take, Item::Taken(id));
            shared.changed.notify_all();
            (id, steps, spread)
        };
        let n = steps.len();
        let bodies = &self.bodies;
        let prepared = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            bodies.prepare(steps, spread)
        })) {
            Ok(p) => p,
            Err(panic) => {
                // The writer would wait for these steps for ever: it stops first.
                shared.lock().stopped = true;
                shared.changed.notify_all();
                std::panic::resume_unwind(panic)
            }
        };
        let mut q = shared.lock();
        if q.stopped {
            prepared.discard();
            return None;
        }
        q.done.insert(id, prepared);
        shared.changed.notify_all();
        Some(n)
    }

    /// Waits for the writer to put every step in place (after [`Self::help`]): (its busy
    /// seconds with this thread's preparations, the seconds the caller spent waiting for it),
    /// or its error (`Ok` with no busy time if the error was already returned by
    /// [`Self::check`] or [`Self::send`]).
    pub fn finish(mut self) -> Result<(f64, f64), RunError> {
        let _ = self.help();
        let Some(h) = self.handle.take() else {
            return Ok((0.0, self.wait));
        };
        let t = Instant::now();
        let busy = join(h)?;
        Ok((busy, self.wait + t.elapsed().as_secs_f64()))
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

/// A writer given up without [`Background::finish`] (the driver returned early, or unwinds from
/// a panic): the queue is closed, so that the writer ends once it has written what it holds
/// instead of waiting for more steps while the thread scope waits for it.
impl Drop for Background<'_, '_> {
    fn drop(&mut self) {
        self.shared.lock().closed = true;
        self.shared.changed.notify_all();
    }
}

/// The writer thread's work: the queue's items in order until it is closed and empty.
fn writer_loop(shared: &Shared, series: &mut Series<'_>) -> Result<(), RunError> {
    loop {
        let mut q = shared.lock();
        let prepared = loop {
            match q.items.front() {
                None if q.closed => return Ok(()),
                None => q = shared.wait(q),
                Some(Item::Taken(id)) => {
                    let id = *id;
                    match q.done.remove(&id) {
                        Some(p) => {
                            q.items.pop_front();
                            break Some(p);
                        }
                        // The driver's thread gave up on them (it panicked): nothing more.
                        None if q.stopped => return Ok(()),
                        None => q = shared.wait(q),
                    }
                }
                Some(Item::Step(_)) => break None,
            }
        };
        let prepared = match prepared {
            Some(p) => {
                drop(q);
                p
            }
            None => {
                // The steps waiting at the front, together.
                let mut batch = Vec::new();
                while batch.len() < BATCH && matches!(q.items.front(), Some(Item::Step(_))) {
                    if let Some(Item::Step(s)) = q.items.pop_front() {
                        batch.push(*s);
                    }
                }
                q.preparing = true;
                shared.changed.notify_all();
                drop(q);
                let spread = batch.iter().any(|s| s.reply.is_some());
                let prepared = series.bodies.prepare(batch, spread);
                shared.lock().preparing = false;
                prepared
            }
        };
        series.commit(prepared)?;
    }
}

/// Joins a writer thread, passing a panic of it on.
fn join(h: ScopedJoinHandle<'_, Result<f64, RunError>>) -> Result<f64, RunError> {
    h.join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}
