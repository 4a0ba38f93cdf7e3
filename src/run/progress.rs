//! The progress shown while a run steps: a bar on a terminal, a line per step otherwise, in
//! nominal steps of the case's load path.

use crate::case::Case;
use crate::driver::{LogLevel, StepEvent};

/// How many of the case's nominal load steps the load path has covered at `time` (stage index
/// plus the fraction of that stage).
fn nominal_steps_done(case: &Case, time: f64) -> f64 {
    let mut done = 0.0;
    for (i, st) in case.stages.iter().enumerate() {
        let frac = (time - i as f64).clamp(0.0, 1.0);
        done += frac * st.steps as f64;
    }
    done
}

/// The progress shown while a run steps: a bar on a terminal, a line per step otherwise.
pub(super) struct Progress<'a> {
    case: &'a Case,
    level: LogLevel,
    total: usize,
    bar: Option<indicatif::ProgressBar>,
}

impl<'a> Progress<'a> {
    pub(super) fn new(case: &'a Case, level: LogLevel) -> Self {
        let total = case.total_steps();
        let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
        let bar = (level >= LogLevel::Info && tty).then(|| {
            let b = indicatif::ProgressBar::new(total as u64);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} steps {elapsed} {msg}",
                )
                .expect("valid template"),
            );
            b
        });
        Progress {
            case,
            level,
            total,
            bar,
        }
    }

    pub(super) fn step(&self, ev: &StepEvent) {
        crate::trace::mark(format_args!("step {}", ev.step));
        let r = ev.record;
        let msg = match (r.pilot, r.contact) {
            (Some(p), Some(c)) => format!(
                "Q = {:.5}, P = {:.5}, a = {:.5}, c = {:.5}, {} its",
                p.fx, -p.fy, c.a, c.c, r.iterations
            ),
            (Some(p), None) => format!(
                "pilot u = ({:.4e}, {:.4e}), F = ({:.5}, {:.5})",
                p.ux, p.uy, p.fx, p.fy
            ),
            _ => format!("traction scale {:.4}", r.traction_scale),
        };
        // Progress in nominal steps: cutbacks add steps, so the count is not the position.
        let done = nominal_steps_done(self.case, ev.time);
        match &self.bar {
            Some(b) => {
                b.set_position(done.round() as u64);
                b.set_message(msg);
            }
            None if self.level >= LogLevel::Info => eprintln!(
                "step {} (stage {}, {:.0} % of the load path): {msg}",
                ev.step,
                r.stage,
                100.0 * done / self.total as f64
            ),
            None => {}
        }
    }

    pub(super) fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
