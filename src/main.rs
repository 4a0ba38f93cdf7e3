//! `stickslip` command line.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Exit statuses, as `src/error.rs` maps them (`RunError::exit_code`, `SweepError::exit_code`).
const EXIT_ALL: &str = "\
Exit status (every command):
  0    success
  2    bad input: a case, sweep or mesh file, an option or a value; nothing is written
  3    solver failure, or an error-level self-check failed (run: the steps before it are kept;
       sweep-merge: rows are missing)
  4    output error (a file, or standard output, could not be written)
  5    run: equilibrium lost under a force-controlled tangential load (Q_max reported)
  101  a bug (a panic): please report it with the case

Cases, outputs and every option: README.md. The closed forms: docs/analytic.md.";

const EXIT_RUN: &str = "\
Exit status:
  0  the run completed (failed warning-level self-checks are printed; the run completes)
  2  bad input (the case, its mesh, an option, a --resume state); nothing is written
  3  solver failure, or an error-level self-check failed; the steps before it are kept and
     summary.json's `status` says where it stopped
  4  output error; the steps before it are kept
  5  equilibrium lost under a force-controlled tangential load: Q_max is bracketed and
     reported (summary.json `friction.q_max`), the state just before it kept; with --quiet
     nothing is printed for it";

const EXIT_SWEEP: &str = "\
Exit status:
  0  every row ran (each row's status and failed self-checks are in sweep.csv and sweep.json)
  2  bad input (the case, the sweep file, --shard, a part of another sweep); nothing is written
  3  the model could not be factorised
  4  output error";

const SWEEP_FILE: &str = "\
The sweep file lists laws and/or loads; each row is one law under one load:
  {\"friction\": [law, ...]}                 laws as in a case's contact.friction
  {\"grid\": {\"shape\": [\"ramp\", \"step\"], \"fs\": [0.15, 0.2], \"fd\": [0.1],
            \"delta\": [2e-4, 5e-4]}}          laws: the Cartesian product (shape default
                                            [\"ramp\"]; \"lambda\": [...] with \"radius\" and
                                            \"load\" instead of \"delta\"; \"history\": [...])
  {\"grid\": {\"pilot_x\": [{\"force\": 0.5}, {\"slip\": 0.01}]}}
                                            loads: targets of the case's last stage along x
  {\"stages\": [[stage, ...], ...]}           loads: whole replacements of the case's stages
Row r = load_index * laws + law_index, loads outermost, then shape, fs, fd, delta/lambda.
`f_s`/`f_d`, the old spelling of `fs`/`fd`, are read with a note.";

#[derive(Parser)]
#[command(
    name = "stickslip",
    version,
    about = "Plane-strain FE for frictional contact of two half-cylinders with slip-weakening friction",
    after_help = EXIT_ALL
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run a case file and write VTK, CSV and JSON output.
    #[command(after_help = EXIT_RUN)]
    Run {
        /// The case file (JSON).
        case: PathBuf,
        /// Output directory (default: the case's `output.dir`, else `out/<case name>`).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Number of threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Print nothing but errors: no progress, no warnings, no end summary (the output files
        /// are the same).
        #[arg(long)]
        quiet: bool,
        /// How much to print: error, warn, info (progress and end summary), debug (every
        /// Newton iteration).
        #[arg(long, value_enum, default_value = "info")]
        log: stickslip::run::LogLevel,
        /// Go on from a saved state: a `state_NNNN.json` written with every written step, or
        /// a directory (its latest state). The case file must be the one that wrote it.
        #[arg(long)]
        resume: Option<PathBuf>,
        /// Keep the model's linear algebra (ordering, factor, Delassus operator) in this
        /// directory and reuse it when the same mesh, bodies, supports, pilot and contact pair
        /// come again (default: $STICKSLIP_CACHE_DIR, else $XDG_CACHE_HOME/stickslip, else
        /// ~/.cache/stickslip; size cap $STICKSLIP_CACHE_MAX, default 4G).
        #[arg(long, value_name = "DIR", conflicts_with = "no_cache")]
        cache: Option<PathBuf>,
        /// Neither read nor write the model cache (also STICKSLIP_NO_CACHE=1).
        #[arg(long)]
        no_cache: bool,
    },
    /// Run one case against many friction laws and/or loads on one shared model, in parallel,
    /// and write one table (CSV and JSON).
    #[command(after_help = format!("{SWEEP_FILE}\n\n{EXIT_SWEEP}"))]
    Sweep {
        /// The case file (JSON); its friction law and its stages are replaced by each law and
        /// each load of the sweep.
        case: PathBuf,
        /// The sweep file (JSON): laws as a list (`friction`) or a grid (`grid`: shape, fs, fd,
        /// delta or lambda), loads as stage lists (`stages`) or targets (`grid.pilot_x`); see
        /// below.
        sweep: PathBuf,
        /// Output directory (default: out/<case name>_sweep).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Number of threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Print nothing but errors: no summary line, no resume, cache or spelling notes (the
        /// table is the same).
        #[arg(long)]
        quiet: bool,
        /// Run shard K of N only (rows r with r mod N = K, K from 0), appending them to
        /// OUT/part_K_of_N.jsonl; `slurm/N` takes K from SLURM_ARRAY_TASK_ID. A shard started
        /// again skips the rows its part already holds. Merge with `stickslip sweep-merge`.
        #[arg(long)]
        shard: Option<String>,
        /// Discard this shard's existing part instead of resuming it.
        #[arg(long)]
        fresh: bool,
        /// Keep the model's linear algebra (ordering, factor, Delassus operator) in this
        /// directory and reuse it when the same mesh, bodies, supports, pilot and contact pair
        /// come again (default: $STICKSLIP_CACHE_DIR, else $XDG_CACHE_HOME/stickslip, else
        /// ~/.cache/stickslip; size cap $STICKSLIP_CACHE_MAX, default 4G).
        #[arg(long, value_name = "DIR", conflicts_with = "no_cache")]
        cache: Option<PathBuf>,
        /// Neither read nor write the model cache (also STICKSLIP_NO_CACHE=1).
        #[arg(long)]
        no_cache: bool,
    },
    /// Merge the parts of a sharded sweep (part_K_of_N.jsonl in each DIR) into sweep.csv and
    /// sweep.json; refuses parts of different sweeps and reports rows no part holds.
    #[command(
        after_help = "Exit status:\n  0  merged\n  2  not a sweep part, or parts of \
        different sweeps; nothing is written\n  3  rows are missing (listed); nothing is written\n  \
        4  output error"
    )]
    SweepMerge {
        /// Directories holding parts (or part files).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Where to write the table (default: the first directory).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The paper's closed forms: scalars as JSON, curves as CSV (`--case CASE` takes the
    /// geometry, load and law from a case file).
    #[command(
        after_help = "Exit status:\n  0  success\n  2  bad arguments or values (the \
        message names them)\n  4  standard output could not be written\n\nEvery subcommand \
        with an example and its output: docs/analytic.md."
    )]
    Analytic(stickslip::analytic::cli::AnalyticArgs),
    /// Print the JSON Schema of the case file.
    #[command(after_help = "Exit status:\n  0  success\n  4  standard output could not be written")]
    Schema,
    /// Print counts, groups, element sizes and quality figures of a gmsh mesh (JSON).
    #[command(
        after_help = "Exit status:\n  0  success\n  2  the mesh cannot be read or \
        parsed\n  4  standard output could not be written"
    )]
    MeshInfo {
        /// The mesh file (gmsh MSH 4.1).
        mesh: PathBuf,
    },
}

/// The model cache asked for on the command line.
fn cache_choice(dir: Option<PathBuf>, off: bool) -> stickslip::cache::Choice {
    match (dir, off) {
        (_, true) => stickslip::cache::Choice::Off,
        (Some(d), false) => stickslip::cache::Choice::Dir(d),
        (None, false) => stickslip::cache::Choice::Default,
    }
}

/// Sets up the thread pools of rayon and faer (`None`: all cores); refuses `Some(0)`.
fn set_threads(n: Option<usize>) -> Result<(), String> {
    if n == Some(0) {
        return Err("--threads must be at least 1".into());
    }
    let n = n.unwrap_or(0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build_global()
        .map_err(|e| format!("cannot set up {n} threads: {e}"))?;
    // faer's own parallelism is set where models are built (`Model::build_on`).
    Ok(())
}

fn main() -> ExitCode {
    stickslip::trace::start();
    let cli = Cli::parse();
    match cli.cmd {
        Cmd::Run {
            case,
            out,
            threads,
            quiet,
            log,
            resume,
            cache,
            no_cache,
        } => {
            if let Err(e) = set_threads(threads) {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
            if !quiet {
                print_notes(&case, stickslip::case::deprecated_keys);
            }
            let opts = stickslip::run::RunOptions {
                out,
                quiet,
                log,
                resume,
                cache: cache_choice(cache, no_cache),
            };
            let ran = stickslip::run::run(&case, &opts);
            stickslip::trace::mark("run returned");
            match ran {
                Ok(_) => ExitCode::SUCCESS,
                Err(e) => {
                    // Exit 5 (equilibrium lost past Q_max) is the answer of a force-controlled
                    // run, in summary.json's status: `--quiet` keeps it off the terminal.
                    if !(quiet && e.exit_code() == 5) {
                        eprintln!("error: {e}");
                    }
                    ExitCode::from(e.exit_code() as u8)
                }
            }
        }
        Cmd::Sweep {
            case,
            sweep,
            out,
            threads,
            quiet,
            shard,
            fresh,
            cache,
            no_cache,
        } => {
            if let Err(e) = set_threads(threads) {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
            if !quiet {
                print_notes(&case, stickslip::case::deprecated_keys);
                print_notes(&sweep, stickslip::sweep::grid::deprecated_keys);
            }
            let res = shard
                .as_deref()
                .map(stickslip::sweep::parse_shard)
                .transpose()
                .and_then(|shard| {
                    let opts = stickslip::sweep::SweepOptions {
                        out,
                        quiet,
                        shard,
                        fresh,
                        cache: cache_choice(cache, no_cache),
                    };
                    stickslip::sweep::run(&case, &sweep, &opts)
                });
            match res {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(e.exit_code() as u8)
                }
            }
        }
        Cmd::SweepMerge { dirs, out } => {
            match stickslip::sweep::parts::merge(&dirs, out.as_deref()) {
                Ok(dir) => {
                    eprintln!("table in {}", dir.join("sweep.csv").display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(e.exit_code() as u8)
                }
            }
        }
        Cmd::Analytic(args) => {
            let mut out = std::io::stdout().lock();
            match stickslip::analytic::cli::run(&args, &mut out) {
                Ok(()) => ExitCode::SUCCESS,
                // A closed pipe (`… | head`): quiet success, as for `mesh-info`.
                Err(stickslip::analytic::cli::CliError::Io(e))
                    if e.kind() == std::io::ErrorKind::BrokenPipe =>
                {
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    // As for `mesh-info` and `schema`: standard output that cannot be written is
                    // an output error; everything else is a bad argument or value.
                    let io = matches!(e, stickslip::analytic::cli::CliError::Io(_));
                    ExitCode::from(if io { 4 } else { 2 })
                }
            }
        }
        Cmd::Schema => print_stdout(
            &serde_json::to_string_pretty(&stickslip::case::schema()).expect("serialisable"),
        ),
        Cmd::MeshInfo { mesh } => match stickslip::mesh::gmsh::read(&mesh) {
            Ok(m) => {
                let info = stickslip::mesh::info::info(&m);
                print_stdout(&serde_json::to_string_pretty(&info).expect("serialisable"))
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        },
    }
}

/// Prints `note: FILE: …` for each note `notes` finds in the JSON file `path` (old spellings of
/// keys). A file that cannot be read or parsed has none here: the command reports it.
fn print_notes(path: &std::path::Path, notes: fn(&serde_json::Value) -> Vec<String>) {
    let Some(v) = std::fs::read(path)
        .ok()
        .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
    else {
        return;
    };
    for n in notes(&v) {
        eprintln!("note: {}: {n}", path.display());
    }
}

/// Prints `text` and a newline to standard output. A closed pipe (`stickslip mesh-info … | head`)
/// ends the program quietly with success, as command-line tools do; other write errors are
/// reported.
fn print_stdout(text: &str) -> ExitCode {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match writeln!(out, "{text}").and_then(|()| out.flush()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: cannot write to standard output: {e}");
            ExitCode::from(4)
        }
    }
}
