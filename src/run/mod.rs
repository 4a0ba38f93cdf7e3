//! The run driver: stages and load steps (with cutbacks and the bracketing of Q_max), one
//! solve per step on the condensed model ([`crate::model::step`]), the output of every step
//! ([`crate::output::fields`]) and the report at the end ([`crate::report`]).
//!
//! | module | content |
//! |---|---|
//! | this file | a run of a case file: the model (rebuilt with a wider contact zone when the contact reaches its rim), the output begun, the steps, the summary |
//! | `steps` | what each converged step goes through: progress, energy, journal, the writer; the last step's check |
//! | `progress` | the progress bar or lines |

mod progress;
mod steps;

use crate::case::Case;
pub use crate::driver::{
    LogLevel, MAX_CUTBACKS, Restart, Simulation, StepEvent, simulate, simulate_with,
};
use crate::energy::EnergyMeter;
pub use crate::error::RunError;
use crate::model::Model;
use crate::output::background::Background;
use crate::output::series::{Series, write_file};
use crate::report::{Summary, end_summary, history_csv, print_warnings, summarise};
use crate::restart::{self, SavedRun};
use progress::Progress;
use std::path::{Path, PathBuf};
use steps::{StepSink, check_last_step};

/// Options of a run from the command line.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Output directory (overrides the case's).
    pub out: Option<PathBuf>,
    /// Print nothing but errors (same as `log = Error`).
    pub quiet: bool,
    /// How much to print: errors; warnings; progress and the end summary (default); every
    /// Newton iteration.
    pub log: LogLevel,
    /// Resume from a saved state (a `state_NNNN.json`, or a directory: its latest state).
    pub resume: Option<PathBuf>,
    /// The model cache (`--cache DIR`, `--no-cache`; see [`crate::cache`]).
    pub cache: crate::cache::Choice,
}

impl RunOptions {
    fn level(&self) -> LogLevel {
        if self.quiet {
            LogLevel::Error
        } else {
            self.log
        }
    }
}

/// Runs a case file end to end and writes its output. Returns the summary.
/// If the contact grows to the edge of its candidate zone, the zone is doubled and the run
/// starts again.
pub fn run(case_path: &Path, opts: &RunOptions) -> Result<Summary, RunError> {
    let case = Case::load(case_path)?;
    crate::trace::mark("case loaded");
    let out_dir = opts
        .out
        .clone()
        .or(case.output.dir.clone())
        .unwrap_or_else(|| {
            PathBuf::from("out").join(
                case_path
                    .file_stem()
                    .map(|s| s.to_string_lossy().to_string())
                    .unwrap_or("case".into()),
            )
        });
    // A resumed run is checked before anything is built or written.
    let mut resume = opts
        .resume
        .as_ref()
        .map(|p| restart::load(p, &case, case_path))
        .transpose()?;
    let (mut gap, doublings) = (resume.as_ref().and_then(|s| s.candidate_gap), 8);
    let store = crate::cache::Store::resolve(&opts.cache, opts.level() >= LogLevel::Warn);
    // The run's identity (a hash of the case and mesh files and the program's build, which the
    // restart states carry: 25 ms at L7, the executable's 5 ms), on a thread of their own while
    // the model is built, whose first phases leave a core idle.
    let case = &case;
    std::thread::scope(|scope| {
        let cached = store.is_ok();
        let mut id_job = Some(scope.spawn(move || {
            // The program's identity (reading and hashing the executable, 5 ms) for the model
            // cache's key before the main thread asks for it; the run id reads it too.
            if cached {
                let _ = crate::cache::build_id();
            }
            restart::run_id(case, case_path)
        }));
        let mut id = String::new();
        for _ in 0..doublings {
            let mut model = Model::build_cached(case, case_path, gap, store.as_ref().ok())?;
            if let Err(off) = &store {
                model.cache = Some(off.clone());
            }
            model.refuse_empty_patches(case, &case_path.display().to_string())?;
            if let Some(job) = id_job.take() {
                id = job.join().expect("the run-id thread does not panic")?;
            }
            let resumed = resume.is_some();
            match run_model(
                case,
                case_path,
                model,
                &out_dir,
                opts,
                resume.take(),
                id.clone(),
            ) {
                Err(RunError::ZoneClipped { gap: g, step }) if resumed => {
                    return Err(RunError::Resume {
                        path: opts.resume.as_ref().expect("resumed").display().to_string(),
                        why: format!(
                            "the contact reached the edge of the candidate zone at step {step} \
                             (candidate gap {g:.3e}): run the case again from the start"
                        ),
                    });
                }
                Err(RunError::ZoneClipped { gap: g, step }) => {
                    if !opts.quiet {
                        eprintln!(
                            "note: the contact reached the edge of the candidate zone at step {step} (candidate gap {g:.3e}); doubling the zone and starting again"
                        );
                    }
                    gap = Some(2.0 * g);
                }
                other => return other,
            }
        }
        Err(RunError::ZoneKeptGrowing {
            gap: gap.unwrap_or(f64::NAN),
            doublings,
        })
    })
}

/// Projected output above which a run warns before it starts (10 GiB; `STICKSLIP_OUTPUT_WARN`
/// sets another number of bytes).
pub const OUTPUT_WARN_BYTES: u64 = 10 << 30;

/// The projected output above which a run warns: [`OUTPUT_WARN_BYTES`] unless
/// `STICKSLIP_OUTPUT_WARN` gives a number of bytes.
fn output_warn_bytes() -> u64 {
    std::env::var("STICKSLIP_OUTPUT_WARN")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(OUTPUT_WARN_BYTES)
}

/// Bytes of a written step's `.vtu` files per node of the model, raw binary (coordinates,
/// displacement, stresses, von Mises, body and node ids: 120 B per node measured on
/// `pad_flat.msh`), and of its contact files per contact node.
const VTU_BYTES_PER_NODE: u64 = 128;
const CONTACT_BYTES_PER_NODE: u64 = 512;

/// Bytes of one written step (see [`VTU_BYTES_PER_NODE`]).
fn step_bytes(model: &Model) -> u64 {
    let nodes = model.active.iter().filter(|a| **a).count() as u64;
    let contact = model.contact.as_ref().map_or(0, |c| c.system.ns) as u64;
    nodes * VTU_BYTES_PER_NODE + contact * CONTACT_BYTES_PER_NODE
}

/// Steps a run of `case` writes when no step is cut back (with `output.substeps`, cutbacks
/// add more).
fn written_steps(case: &Case) -> u64 {
    if !case.output.vtu {
        return 0;
    }
    // The multiples of `every` among the nominal steps, and the last one.
    case.total_steps().div_ceil(case.output.every) as u64
}

/// The output a run of `case` on `model` is projected to write, restart states aside.
fn projected_output_bytes(case: &Case, model: &Model) -> u64 {
    written_steps(case) * step_bytes(model)
}

/// Steps through the stages of a built model, writing output to `out_dir`; `id` is the run's
/// identity ([`restart::run_id`]), which its restart states carry.
pub fn run_model(
    case: &Case,
    case_path: &Path,
    mut model: Model,
    out_dir: &Path,
    opts: &RunOptions,
    resume: Option<SavedRun>,
    id: String,
) -> Result<Summary, RunError> {
    refuse_before_writing(case, &model, opts, resume.as_ref())?;
    std::fs::create_dir_all(out_dir).map_err(|source| RunError::Write {
        path: out_dir.display().to_string(),
        source,
    })?;
    let stem = case_path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or("case".into());
    let level = opts.level();
    warn_of_large_output(case, &model, out_dir, level);
    let progress = Progress::new(case, level);
    let law = model.friction.clone();
    let journal_path = out_dir.join(restart::JOURNAL);
    let (series, mut energy, journal, restart) =
        begin_output(case, &model, out_dir, &stem, &journal_path, resume)?;
    // The steps are written on a thread of their own while the next ones are solved.
    let (summarised, history, solve_s, t_write, t_wait, bracket_attempts) =
        std::thread::scope(|scope| {
            let mut writer = Background::spawn(scope, series);
            let mut sink = StepSink {
                case,
                model: &model,
                out_dir,
                id: &id,
                candidate_gap: model.contact.as_ref().map(|c| c.pair.candidate_gap),
                progress: &progress,
                energy: &mut energy,
                journal,
                journal_path: &journal_path,
                unwritten: None,
                last_u: None,
            };
            crate::trace::mark("simulate");
            let sim = simulate_with(
                &model,
                case,
                law.as_ref(),
                level,
                &mut |ev| sink.step(ev, &mut writer),
                restart,
            );
            let mut sim = match sim {
                Ok(sim) => sim,
                // The steps handed to the writer are written first; its error came first.
                Err(e) => return Err(writer.finish().err().unwrap_or(e)),
            };
            if let Some(w) = sink.unwritten.take()
                && sim.failure.is_some()
            {
                writer.send(w)?;
            }
            // The steps still waiting for the writer: this thread prepares them from the last
            // while the writer finishes those it has; then the summary and its checks.
            let equilibrium = check_last_step(&model, &mut sim, sink.last_u, &mut writer);
            crate::trace::mark("simulated");
            let solve_s = sim.solve_s;
            let bracket_attempts = sim.bracket_attempts;
            let history = history_csv(&sim.records);
            let summarised = summarise(&model, case, case_path, out_dir, sim, equilibrium);
            crate::trace::mark("summarised");
            let (t_write, t_wait) = writer.finish()?;
            crate::trace::mark("writer done");
            // Every field is recovered (the writer has finished: a solve it had still to begin
            // would find the values gone): the factor's values are freed on a thread of their
            // own while the history is written.
            if let Some(values) = model.condensed.chol.release() {
                scope.spawn(move || free_when_unshared(values));
            }
            Ok((
                summarised,
                history,
                solve_s,
                t_write,
                t_wait,
                bracket_attempts,
            ))
        })?;
    progress.finish();
    write_file(&out_dir.join("history.csv"), history.as_bytes())?;
    let (mut summary, failure, lost_equilibrium) = summarised;
    model.timings.solve = solve_s;
    model.timings.write = t_write;
    model.timings.write_wait = t_wait;
    summary.timings_s = model.timings.clone();
    if let Some(m) = &energy {
        write_file(&out_dir.join("energy.csv"), m.csv().as_bytes())?;
        summary.energy = m.summary();
        // Runs that integrate in time: the scheme's energy (a warning if it gained any).
        if let (Some(e), false) = (&summary.energy, summary.events.is_empty()) {
            summary.checks.push(crate::checks::scheme_energy(&e.last));
        }
    }
    // Runs whose time steps have fronts of weakening: the energy reaching them.
    let forced = |stage: usize, x: f64| {
        case.stages[stage]
            .weaken
            .iter()
            .any(|p| p.speed.is_some() && p.x[0] <= x && x <= p.x[1])
    };
    if let Some(c) = crate::checks::front_energy(&summary.steps, &forced) {
        summary.checks.push(c);
    }
    summary.output_bytes = crate::report::output_bytes(out_dir, &stem);
    write_file(
        &out_dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)
            .expect("serialisable")
            .as_bytes(),
    )?;
    crate::trace::mark("summary written");
    print_warnings(&summary, level >= LogLevel::Warn);
    if level >= LogLevel::Info {
        eprint!("{}", end_summary(case_path, &summary, out_dir, &stem));
    }
    if let Some((q_max, q_fail)) = lost_equilibrium {
        let local_peak = summary.friction.as_ref().and_then(|f| f.local_peak(q_max));
        let event = summary
            .events
            .iter()
            .rfind(|e| e.after_lost_equilibrium)
            .map(|e| e.describe());
        return Err(RunError::EquilibriumLost {
            q_max,
            q_fail,
            cutbacks: bracket_attempts,
            local_peak,
            event,
        });
    }
    if let Some(e) = failure {
        return Err(e);
    }
    Ok(summary)
}

/// Refuses, before anything is written, a resumed state whose contact does not fit the model
/// built from the case, and (a run from the start) the loads that no step can carry.
fn refuse_before_writing(
    case: &Case,
    model: &Model,
    opts: &RunOptions,
    resume: Option<&SavedRun>,
) -> Result<(), RunError> {
    if let (Some(s), Some(cm)) = (resume, &model.contact)
        && s.checkpoint
            .cstate
            .as_ref()
            .is_some_and(|st| st.f_n.len() != cm.system.ns)
    {
        return Err(RunError::Resume {
            path: opts
                .resume
                .clone()
                .unwrap_or_default()
                .display()
                .to_string(),
            why: "its contact state does not fit the model built from the case".into(),
        });
    }
    if resume.is_none() {
        crate::driver::refuse_unloadable(model, case, model.friction.as_ref())?;
    }
    Ok(())
}

/// Warns (at `level` warn and above) when the run is projected to write more than
/// [`output_warn_bytes`].
fn warn_of_large_output(case: &Case, model: &Model, out_dir: &Path, level: LogLevel) {
    let projected = projected_output_bytes(case, model);
    if level >= LogLevel::Warn && projected > output_warn_bytes() {
        eprintln!(
            "warning: this run will write about {} ({projected} bytes) to {} ({} written steps \
             of about {} each; `output.every` writes fewer, `\"vtu\": false` none)",
            crate::report::human_bytes(projected),
            out_dir.display(),
            written_steps(case),
            crate::report::human_bytes(step_bytes(model)),
        );
    }
}

/// The output a run begins with: the series of its steps (going on with a resumed run's `.pvd`
/// entries), its energy meter (resumed with the state), the journal of step records beside the
/// states (see `crate::restart`: begun afresh, or with the records of the state a resumed run
/// goes on from; none when no `.vtu` is written), and the driver's checkpoints (with the
/// written steps: none when nothing is written) and where it resumes.
fn begin_output<'a>(
    case: &Case,
    model: &'a Model,
    out_dir: &'a Path,
    stem: &'a str,
    journal_path: &Path,
    resume: Option<SavedRun>,
) -> Result<BegunOutput<'a>, RunError> {
    let mut series = Series::new(model, out_dir, stem, case.output.compress);
    series.contact_csv = case.output.contact_csv;
    let mut energy = case.tracks_energy().then(|| EnergyMeter::new(model));
    let mut from = None;
    let journal = if case.output.vtu {
        let start = resume.as_ref().map_or("", |s| s.journal.as_str());
        let journal_error = |source| RunError::Write {
            path: journal_path.display().to_string(),
            source,
        };
        let mut f = std::fs::File::create(journal_path).map_err(journal_error)?;
        std::io::Write::write_all(&mut f, start.as_bytes()).map_err(journal_error)?;
        Some(f)
    } else {
        None
    };
    if let Some(s) = resume {
        series = series.with_entries(s.pvd).with_time_entries(s.time_pvd);
        if let Some(saved) = s.energy {
            energy = Some(EnergyMeter::resume(model, saved, &s.checkpoint));
        }
        from = Some(s.checkpoint);
    }
    let restart = Restart {
        every: case.output.vtu.then_some(case.output.every),
        from,
    };
    Ok((series, energy, journal, restart))
}

/// What [`begin_output`] gives: the series, the energy meter, the journal and the driver's
/// checkpoints.
type BegunOutput<'a> = (
    Series<'a>,
    Option<EnergyMeter>,
    Option<std::fs::File>,
    Restart,
);

/// Returns the heap's free pages to the system (glibc keeps the memory of freed blocks
/// mapped, hundreds of MB after a run's build, which the process's exit would otherwise unmap
/// after the output: 6 ms on Fig. 2 at L5, measured from the `run returned` trace mark to the
/// process's end).
fn release_free_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: `malloc_trim` only gives back pages of free blocks; it may be called from
        // any thread at any time.
        unsafe { libc::malloc_trim(0) };
        crate::trace::mark("heap trimmed");
    }
}

/// Drops `v` once no solve holds it any more (polled every millisecond), then returns the
/// heap's free pages to the system.
fn free_when_unshared<T>(mut v: std::sync::Arc<T>) {
    loop {
        match std::sync::Arc::try_unwrap(v) {
            Ok(inner) => {
                drop(inner);
                crate::trace::mark("factor freed");
                release_free_heap();
                return;
            }
            Err(shared) => {
                v = shared;
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
        }
    }
}
