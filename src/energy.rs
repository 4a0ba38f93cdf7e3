//! The energy of a run, step by step: the work done on the bodies by the pilot, the tractions
//! and the supports; the elastic energy `U = ½ Σ_e u_eᵀ K_e u_e` of the displacement field;
//! and the work the contact forces absorb — the frictional dissipation
//! `D = −Σ_j ½ (F_t,j^new + F_t,j^old) Δv̂_j` (∫ q · Δslip over the interface, with the
//! trapezoidal rule in each step) and the normal-contact term `−Σ_j ½ (F_n^new + F_n^old) Δĝ_j`,
//! which is zero where the contact set does not change and a small artefact of the step where
//! nodes close or open.
//!
//! For a linear elastic body `U_new − U_old = ½ (u_new + u_old)ᵀ K (u_new − u_old)` and `K u`
//! is the sum of the external and contact forces in each converged state, so
//! `W_ext = ΔU + D + N` holds exactly at equilibrium: the balance's residual measures how well
//! each step is in equilibrium (it closes to the contact solver's tolerance), and it checks
//! the displacement recovery, the forces and the slip kinematics against each other.
//!
//! Steps integrated in time ([`crate::dynamics`]) add the kinetic energy `K = ½ vᵀ M v`: their
//! balance `W_ext = ΔU + ΔK + D + N + D_num` leaves `D_num`, the energy the time-stepping
//! scheme itself dissipates, reported apart (`numerical`) from the quasi-static `residual`.

use crate::contact::solver::State;
use crate::dofs::Dof;
use crate::driver::StepEvent;
use crate::model::Model;
use serde::Serialize;

/// One step's cumulative energies (from the unloaded state).
#[derive(Clone, Debug, Default, Serialize, serde::Deserialize)]
pub struct EnergyRow {
    pub step: usize,
    pub cycle: usize,
    pub work_pilot: f64,
    pub work_tractions: f64,
    pub work_supports: f64,
    pub elastic: f64,
    pub dissipation: f64,
    pub normal_work: f64,
    /// `W_ext − U − D − N` accumulated over the quasi-static steps (less the kinetic energy
    /// they start from: a quasi-static step is at rest).
    pub residual: f64,
    /// Kinetic energy `K = ½ vᵀ M v` (zero in quasi-static steps).
    #[serde(default)]
    pub kinetic: f64,
    /// `W_ext − ΔU − ΔK − D − N` accumulated over the steps integrated in time: the energy the
    /// time-stepping scheme dissipates (zero to round-off with ρ∞ = 1 and no contact change).
    #[serde(default)]
    pub numerical: f64,
}

/// The energies of one cycle of a cycle group.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct CycleEnergy {
    pub cycle: usize,
    /// Work done by the pilot and frictional dissipation over the cycle.
    pub work_pilot: f64,
    pub dissipation: f64,
    /// Elastic energy at the end of the cycle.
    pub elastic_end: f64,
}

/// The energy summary of a run (`summary.json`'s `energy`).
#[derive(Clone, Debug, Serialize)]
pub struct EnergySummary {
    pub last: EnergyRow,
    /// Largest |residual| over the run, relative to the largest |work| or |energy| met.
    pub balance_relative: f64,
    pub per_cycle: Vec<CycleEnergy>,
}

/// The state of the previous step the next one's energies need.
struct Snapshot {
    u: Vec<f64>,
    scale: f64,
    pilot: [f64; 4],
    f_n: Vec<f64>,
    f_t: Vec<f64>,
    /// `(Y u)_n` and `(Y u)_t` of the contact nodes.
    y_n: Vec<f64>,
    y_t: Vec<f64>,
}

/// What a restart needs of an [`EnergyMeter`] (the previous step's snapshot is rebuilt from
/// the checkpoint).
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct EnergySaved {
    row: EnergyRow,
    /// The rows of the steps so far: in the journal, not in the state file.
    #[serde(skip)]
    rows: Vec<EnergyRow>,
    per_cycle: Vec<CycleEnergy>,
    worst: f64,
    size: f64,
}

impl EnergySaved {
    /// The rows of the steps so far (read back from the journal).
    pub fn set_rows(&mut self, rows: Vec<EnergyRow>) {
        self.rows = rows;
    }

    /// The rows of the steps so far.
    pub fn rows(&self) -> &[EnergyRow] {
        &self.rows
    }
}

/// Accumulates the energies of the converged steps of a run.
pub struct EnergyMeter {
    prev: Snapshot,
    row: EnergyRow,
    pub rows: Vec<EnergyRow>,
    per_cycle: Vec<CycleEnergy>,
    worst: f64,
    size: f64,
}

impl EnergyMeter {
    /// A meter starting from the unloaded state of `model`.
    pub fn new(model: &Model) -> Self {
        let ns = model.contact.as_ref().map_or(0, |c| c.system.ns);
        EnergyMeter {
            prev: Snapshot {
                u: vec![0.0; model.dofs.n_free()],
                scale: 0.0,
                pilot: [0.0; 4],
                f_n: vec![0.0; ns],
                f_t: vec![0.0; ns],
                y_n: vec![0.0; ns],
                y_t: vec![0.0; ns],
            },
            row: EnergyRow::default(),
            rows: Vec::new(),
            per_cycle: Vec::new(),
            worst: 0.0,
            size: 0.0,
        }
    }

    /// What a restart needs to go on.
    /// The last step's energy row (for the journal).
    pub fn last_row(&self) -> Option<&EnergyRow> {
        self.rows.last()
    }

    pub fn saved(&self) -> EnergySaved {
        EnergySaved {
            row: self.row.clone(),
            rows: self.rows.clone(),
            per_cycle: self.per_cycle.clone(),
            worst: self.worst,
            size: self.size,
        }
    }

    /// A meter going on from `saved` after the checkpoint's step: the snapshot of that step is
    /// recomputed from the checkpoint as the uninterrupted run computed it.
    pub fn resume(model: &Model, saved: EnergySaved, c: &crate::driver::Checkpoint) -> Self {
        let u = match (&c.last_u, &c.cstate) {
            (Some(u), _) => u.clone(),
            (None, Some(st)) => model.contact_displacement(c.scale, st),
            (None, None) => vec![0.0; model.dofs.n_free()],
        };
        let p = c.records.last().and_then(|r| r.pilot).unwrap_or_default();
        let (f_n, f_t, y_n, y_t) = contact_snapshot(model, c.cstate.as_ref());
        EnergyMeter {
            prev: Snapshot {
                u,
                scale: c.scale,
                pilot: [p.ux, p.uy, p.fx, p.fy],
                f_n,
                f_t,
                y_n,
                y_t,
            },
            row: saved.row,
            rows: saved.rows,
            per_cycle: saved.per_cycle,
            worst: saved.worst,
            size: saved.size,
        }
    }

    /// Adds a converged step.
    pub fn step(&mut self, model: &Model, ev: &StepEvent) {
        let u = match (ev.u, ev.contact) {
            (Some(u), _) => u.clone(),
            (None, Some(st)) => model.contact_displacement(ev.scale, st),
            (None, None) => unreachable!("a step has a solution or a contact state"),
        };
        let (elastic, reactions) = elastic_energy(model, &u);
        let p = ev.record.pilot.unwrap_or_default();
        let pilot = [p.ux, p.uy, p.fx, p.fy];
        let prev = &self.prev;
        let work_pilot: f64 = (0..2)
            .map(|c| 0.5 * (pilot[2 + c] + prev.pilot[2 + c]) * (pilot[c] - prev.pilot[c]))
            .sum();
        let work_tractions: f64 = 0.5
            * (ev.scale + prev.scale)
            * model
                .f_traction
                .iter()
                .zip(u.iter().zip(&prev.u))
                .map(|(f, (a, b))| f * (a - b))
                .sum::<f64>();
        // Prescribed displacements are applied from zero in the first step and then held.
        let first = self.rows.is_empty();
        let work_supports: f64 = if first {
            reactions
                .iter()
                .zip(&model.dofs.prescribed)
                .map(|(r, up)| 0.5 * r * up)
                .sum()
        } else {
            0.0
        };
        let (f_n, f_t, y_n, y_t) = contact_snapshot(model, ev.contact);
        let mut dissipation = 0.0;
        let mut normal_work = 0.0;
        for j in 0..f_n.len() {
            dissipation -= 0.5 * (f_t[j] + prev.f_t[j]) * (y_t[j] - prev.y_t[j]);
            normal_work -= 0.5 * (f_n[j] + prev.f_n[j]) * (y_n[j] - prev.y_n[j]);
        }
        let r = &mut self.row;
        let elastic_change = elastic - r.elastic;
        let kinetic = ev.record.kinetic.unwrap_or(0.0);
        let kinetic_change = kinetic - r.kinetic;
        r.kinetic = kinetic;
        r.step = ev.step;
        r.cycle = ev.record.cycle.unwrap_or(0);
        r.work_pilot += work_pilot;
        r.work_tractions += work_tractions;
        r.work_supports += work_supports;
        r.elastic = elastic;
        r.dissipation += dissipation;
        r.normal_work += normal_work;
        let unbalanced = work_pilot + work_tractions + work_supports
            - elastic_change
            - kinetic_change
            - dissipation
            - normal_work;
        if ev.record.kinetic.is_some() {
            r.numerical += unbalanced;
        } else {
            r.residual += unbalanced;
        }
        self.size = [
            r.work_pilot.abs(),
            r.work_tractions.abs(),
            r.work_supports.abs(),
            elastic,
            kinetic,
            r.dissipation.abs(),
        ]
        .into_iter()
        .fold(self.size, f64::max);
        if self.size > 0.0 {
            self.worst = self.worst.max(r.residual.abs() / self.size);
        }
        if let Some(k) = ev.record.cycle {
            if self.per_cycle.last().is_none_or(|c| c.cycle != k) {
                self.per_cycle.push(CycleEnergy {
                    cycle: k,
                    work_pilot: 0.0,
                    dissipation: 0.0,
                    elastic_end: 0.0,
                });
            }
            let c = self.per_cycle.last_mut().expect("pushed");
            c.work_pilot += work_pilot;
            c.dissipation += dissipation;
            c.elastic_end = elastic;
        }
        self.rows.push(self.row.clone());
        self.prev = Snapshot {
            u,
            scale: ev.scale,
            pilot,
            f_n,
            f_t,
            y_n,
            y_t,
        };
    }

    /// The summary, once the run is over (`None` before any step).
    pub fn summary(&self) -> Option<EnergySummary> {
        self.rows.last().map(|last| EnergySummary {
            last: last.clone(),
            balance_relative: self.worst,
            per_cycle: self.per_cycle.clone(),
        })
    }

    /// `energy.csv`: the cumulative energies of every step.
    pub fn csv(&self) -> String {
        let rows: Vec<Vec<f64>> = self
            .rows
            .iter()
            .map(|r| {
                vec![
                    r.step as f64,
                    r.cycle as f64,
                    r.work_pilot,
                    r.work_tractions,
                    r.work_supports,
                    r.elastic,
                    r.dissipation,
                    r.normal_work,
                    r.residual,
                    r.kinetic,
                    r.numerical,
                ]
            })
            .collect();
        crate::output::csv(
            &[
                "step",
                "cycle",
                "work_pilot",
                "work_tractions",
                "work_supports",
                "elastic",
                "dissipation",
                "normal_work",
                "residual",
                "kinetic",
                "numerical",
            ],
            &rows,
            &["step", "cycle"],
        )
    }
}

/// The contact forces and `Y u` of a state (empty without contact).
#[allow(clippy::type_complexity)]
fn contact_snapshot(model: &Model, st: Option<&State>) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    match (st, &model.contact) {
        (Some(st), Some(cm)) => {
            let g0 = &cm.system.gap0;
            let y_n = st.gap.iter().zip(g0).map(|(g, g0)| g - g0).collect();
            (st.f_n.clone(), st.f_t.clone(), y_n, st.v.clone())
        }
        _ => Default::default(),
    }
}

/// `½ Σ_e u_eᵀ K_e u_e` over the model's elements (prescribed values included), and the
/// reaction at each prescribed DOF (the element forces summed there).
fn elastic_energy(model: &Model, u: &[f64]) -> (f64, Vec<f64>) {
    let dofs = &model.dofs;
    let mut reactions = vec![0.0; dofs.prescribed.len()];
    let mut energy = 0.0;
    for ((e, _), f) in model.elems.iter().zip(model.element_forces(u)) {
        let fe = f.fe;
        energy += 0.5 * (0..12).map(|i| f.ue[i] * fe[i]).sum::<f64>();
        for (a, &n) in model.mesh.triangles[*e].nodes.iter().enumerate() {
            for c in 0..2 {
                if let Dof::Fixed(k) = dofs.node[n][c] {
                    reactions[k] += fe[2 * a + c];
                }
            }
        }
    }
    (energy, reactions)
}
