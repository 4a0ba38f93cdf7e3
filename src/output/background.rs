//! The writer of a run's steps on a thread of its own ([`Background`]), while the driver
//! solves the next ones: it takes the steps in order from a queue of [`QUEUE`] steps and
//! writes exactly the files, in exactly the order, that writing in the loop would
//! ([`Series::write`]), so a run's files do not depend on it. When it falls behind it takes
//! the queued steps together (up to [`BATCH`]): their displacement fields come from one block
//! solve (which reads the factor once for all, and gives each field bit for bit). When the
//! queue is full (a run that writes more than it solves) and once the driver has solved its
//! last step, the driver prepares the last steps still waiting on its own thread
//! ([`Background::help`]; at the end on all threads when the writer has caught up) and hands
//! them back, and the writer puts them in place in their turn. Each array goes to the file
//! from its own memory. Its first error stops it; the driver sees that error at its next step,
//! and stops.

use super::series::{Bodies, Prepared, Series, StepOutput};
use crate::error::RunError;
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::{Scope, ScopedJoinHandle};
use std::time::Instant;

/// Steps the writer (or the driver's thread) prepares at once at most: their fields in one
/// sweep of the factor. Four rather than two: Fig. 2 on L5 writing every step, whose queue
/// stays full, 1.370 → 1.310 s (`benches/ab.sh 6`, B/A 0.956); the shipped Fig. 2 (five written
/// steps) does not change (wall − floor 0.214 → 0.213 s, 10 pairs).
pub const BATCH: usize = 4;

/// Steps that may wait in the writer's queue before the driver prepares the last of them
/// itself ([`Background::send`]).
pub const QUEUE: usize = 8;

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
