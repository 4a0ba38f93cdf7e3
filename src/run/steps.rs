//! What each converged step of a run goes through on the driver's thread ([`StepSink`]): its
//! progress, energy row and journal line, and its output handed to the writer thread; and
//! the summary's equilibrium check of the last step beside the writer ([`check_last_step`]).

use super::progress::Progress;
use crate::case::Case;
use crate::driver::{Simulation, StepEvent};
use crate::energy::EnergyMeter;
use crate::error::RunError;
use crate::model::Model;
use crate::output::background::Background;
use crate::output::series::{StateFile, StepOutput};
use crate::restart::{self, SavedRun};
use std::path::Path;
use std::sync::mpsc::{Receiver, sync_channel};

/// What each converged step goes through on the driver's thread: the progress, the energy
/// balance, the journal line, and the writer (or the contact CSV alone when no `.vtu` is
/// written).
pub(super) struct StepSink<'a> {
    pub(super) case: &'a Case,
    pub(super) model: &'a Model,
    pub(super) out_dir: &'a Path,
    /// The run's identity, and the contact's candidate gap, which its restart states carry.
    pub(super) id: &'a str,
    pub(super) candidate_gap: Option<f64>,
    pub(super) progress: &'a Progress<'a>,
    pub(super) energy: &'a mut Option<EnergyMeter>,
    pub(super) journal: Option<std::fs::File>,
    pub(super) journal_path: &'a Path,
    /// The last converged step not yet written (`output.every` > 1).
    pub(super) unwritten: Option<StepOutput>,
    /// The last step and where its recovered displacements come from (runs with contact: the
    /// writer recovers them with the steps it writes and sends them back).
    pub(super) last_u: Option<(usize, Receiver<Vec<f64>>)>,
}

impl StepSink<'_> {
    /// Takes the converged step `ev`: its progress, energy and journal line, and its output,
    /// handed to `writer` when it is written.
    pub(super) fn step(
        &mut self,
        ev: &StepEvent,
        writer: &mut Background<'_, '_>,
    ) -> Result<(), RunError> {
        let case = self.case;
        self.progress.step(ev);
        if let Some(m) = self.energy.as_mut() {
            m.step(self.model, ev);
        }
        // Written: the nominal steps `output.every` picks and the last one, and with
        // `output.substeps` the sub-steps of cutbacks between them too. A step that covers
        // several nominal steps (an adaptive dynamic stage's) is written when it covers one
        // that is picked.
        let picked = ev.last
            || match ev.nominal {
                Some(k) => {
                    let e = case.output.every;
                    k / e != k.saturating_sub(ev.spans) / e
                }
                None => case.output.substeps,
            };
        self.journal_line(ev, picked)?;
        if !case.output.vtu {
            if picked
                && case.output.contact_csv
                && let Some(st) = ev.contact
            {
                crate::output::series::write_contact_csv(
                    self.model,
                    self.out_dir,
                    ev.step,
                    st,
                    ev.dt,
                )?;
            }
            return Ok(());
        }
        // A write that failed stops the run at its next step.
        writer.check()?;
        // The last step's displacements are recovered once, by the writer (with the steps
        // queued before it), for its output and for the checks of the summary.
        let reply = match (ev.u, ev.contact) {
            (None, Some(_)) if ev.last => {
                let (tx, rx) = sync_channel(1);
                self.last_u = Some((ev.step, rx));
                Some(tx)
            }
            _ => None,
        };
        let out = StepOutput {
            reply,
            step: ev.step,
            time: ev.time,
            scale: ev.scale,
            u: ev.u.cloned(),
            contact: ev.contact.cloned(),
            physical: ev.record.physical_time.zip(ev.dt),
            // The state to resume from, written after the step's files.
            state: ev.checkpoint.map(|c| -> Box<dyn StateFile> {
                Box::new(SavedRun {
                    format: restart::FORMAT,
                    id: self.id.to_string(),
                    candidate_gap: self.candidate_gap,
                    checkpoint: c.clone(),
                    steps: ev.step,
                    pvd: Vec::new(),
                    time_pvd: Vec::new(),
                    journal: String::new(),
                    energy: self.energy.as_ref().map(EnergyMeter::saved),
                })
            }),
        };
        if picked {
            self.unwritten = None;
            writer.send(out)
        } else {
            // Kept so that a run that stops early still writes its last converged state.
            self.unwritten = Some(out);
            Ok(())
        }
    }

    /// Appends the journal line of step `ev` (`written`: its files are written), on the device
    /// before the state that counts it.
    fn journal_line(&mut self, ev: &StepEvent, written: bool) -> Result<(), RunError> {
        let Some(f) = self.journal.as_mut() else {
            return Ok(());
        };
        let line = restart::JournalLine {
            record: ev.record.clone(),
            energy: self.energy.as_ref().and_then(|m| m.last_row().cloned()),
            written,
        };
        let text = restart::journal_text(std::slice::from_ref(&line));
        let journal_error = |source| RunError::Write {
            path: self.journal_path.display().to_string(),
            source,
        };
        std::io::Write::write_all(f, text.as_bytes()).map_err(journal_error)?;
        // On the device before the state that counts this line.
        if ev.checkpoint.is_some() {
            f.sync_data().map_err(journal_error)?;
        }
        Ok(())
    }
}

/// The summary's equilibrium check of the last step, when its field comes from the writer
/// (`last_u`: the step and where its field comes from; `sim.last_u` takes the field). The check
/// starts as soon as the field is recovered, on a thread of its own, while this thread helps
/// the writer with the steps still waiting: it fills the time the two output threads wait for
/// the device's writes and for each other at the end, instead of following them.
pub(super) fn check_last_step(
    model: &Model,
    sim: &mut Simulation,
    last_u: Option<(usize, Receiver<Vec<f64>>)>,
    writer: &mut Background<'_, '_>,
) -> Option<crate::checks::Check> {
    match last_u {
        Some((step, rx)) if sim.last_u.is_none() && sim.records.len() == step => {
            let sim_ref: &Simulation = sim;
            let (u, checked) = std::thread::scope(|s| {
                let checking = std::thread::Builder::new()
                    .name("stickslip-check".into())
                    .spawn_scoped(s, move || {
                        // None when the writer stopped on an error first (reported by
                        // `finish`).
                        let u = rx.recv().ok()?;
                        let e = crate::checks::equilibrium(&crate::checks::Input {
                            model,
                            u: &u,
                            scale: sim_ref.last_scale,
                            state: sim_ref.last_state.as_ref(),
                            records: &sim_ref.records,
                            friction: None,
                            equilibrium: None,
                        });
                        Some((u, e))
                    })
                    .expect("the check thread starts");
                let _ = writer.help();
                checking
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
                    .unzip()
            });
            sim.last_u = u;
            checked
        }
        _ => {
            let _ = writer.help();
            None
        }
    }
}
