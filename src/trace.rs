//! An opt-in timeline of a run: with `STICKSLIP_TRACE=1`, [`mark`] prints the milliseconds
//! since the process started (first call of [`start`]), the process's minor page faults so far
//! (each a page of memory touched for the first time, ≈ 1.2 µs here), the calling thread's CPU
//! time so far and a label to standard error. Used to
//! find where the wall time of a run goes outside the timed phases of `summary.json`.

use std::sync::OnceLock;
use std::time::Instant;

static START: OnceLock<Option<Instant>> = OnceLock::new();

fn origin() -> Option<Instant> {
    *START.get_or_init(|| {
        std::env::var_os("STICKSLIP_TRACE")
            .is_some_and(|v| v != "0" && !v.is_empty())
            .then(Instant::now)
    })
}

/// Starts the clock (call first thing in `main`).
pub fn start() {
    origin();
}

/// Prints `label` with the time since [`start`], if tracing is on (`label` may be
/// `format_args!(…)`, formatted only then).
pub fn mark(label: impl std::fmt::Display) {
    if let Some(t0) = origin() {
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let thread = std::thread::current();
        eprintln!(
            "trace {ms:9.1} ms {:7} faults {:7.1} ms CPU [{}] {label}",
            minor_faults(),
            thread_cpu_ms(),
            thread.name().unwrap_or("-")
        );
    }
}

/// The process's minor page faults so far (memory touched for the first time), or 0 where the
/// count is not available.
fn minor_faults() -> libc::c_long {
    #[cfg(unix)]
    {
        // SAFETY: `rusage` is plain data (all zeros is a value of it); getrusage writes the
        // struct it is given.
        let (rc, r) = unsafe {
            let mut r: libc::rusage = std::mem::zeroed();
            (libc::getrusage(libc::RUSAGE_SELF, &mut r), r)
        };
        if rc == 0 {
            return r.ru_minflt;
        }
    }
    0
}

/// The calling thread's CPU time so far (user and system), in ms, or NaN where not available.
fn thread_cpu_ms() -> f64 {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: as in `minor_faults`.
        let (rc, r) = unsafe {
            let mut r: libc::rusage = std::mem::zeroed();
            (libc::getrusage(libc::RUSAGE_THREAD, &mut r), r)
        };
        if rc == 0 {
            let ms = |t: libc::timeval| t.tv_sec as f64 * 1e3 + t.tv_usec as f64 * 1e-3;
            return ms(r.ru_utime) + ms(r.ru_stime);
        }
    }
    f64::NAN
}
