//! Self-checks of a finished run: numbers that say whether the answer can be trusted, each
//! with the threshold it is held to. They go into `summary.json` (`checks`) and, when they
//! fail, onto the terminal; a failed check that makes the answer meaningless (equilibrium not
//! satisfied, a body that ran away) is an error, the others are warnings.
//!
//! * `equilibrium`: the nodal forces of the recovered displacement field, `f_int = Σ K_e u_e`,
//!   against the applied loads, the contact forces and the pilot force at every free DOF, and
//!   the global balance of the support reactions, the pilot force and the tractions; relative
//!   to the largest of those forces, and never to less than the force a strain of 1e-12 of
//!   the stiffest body produces over the model's size nor to less than the largest term
//!   `K_ij u_j` summed (round-off of a zero or vanishing load, or of a body moved rigidly).
//! * `max_displacement`: the largest nodal displacement over the model's size (the diagonal of
//!   its bounding box); small-strain theory needs it small, and a runaway means an unheld body.
//! * `zone_margin`: elements between the outermost contact node and the edge of the candidate
//!   zone (a run with contact on the zone's rim never completes: the zone is doubled);
//!   `face_end`: contact on the end of a face, where the face is too short for the contact.
//! * `elements_across_contact`: slave elements across the contact width 2a.
//! * `s0_resolution`: the contact element size over s0, the transition length of a
//!   slip-weakening law (resolved when h ≤ s0/2).
//! * `front_energy`: in runs whose time steps have fronts of weakening, the energy release
//!   rate reaching a moving front against the fracture energy of its process zone, averaged
//!   over windows of time steps (a front running on its own has `G = Γ`).
//! * `hertz_a`: at the end of the first stage, the contact semi-width against the Hertz value
//!   for the load, E* and the radius fitted to the initial gaps (only where the gap profile is
//!   a parabola and the contact has not reached a face end).

use crate::contact::solver::{State, Status};
pub use crate::driver::DISPLACEMENT_ERROR;
use crate::model::Model;
pub use crate::model::profile::{HERTZ_PROFILE_LIMIT, fit_radius, not_hertzian};
use crate::record::{FrictionSummary, StepRecord};
use serde::Serialize;

/// How much a check matters when it fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Level {
    /// Passed (or informative).
    Ok,
    /// Failed, but the answer may still be usable: read the note.
    Warning,
    /// Failed: the answer is meaningless; the run does not complete.
    Error,
    /// Not applied to this scene; the note says why (e.g. `hertz_a` on a profile that is not
    /// Hertzian).
    NotApplied,
}

/// One self-check: its value, the threshold it is held to, and the verdict.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    pub name: &'static str,
    pub value: f64,
    /// The threshold the value is compared with.
    pub limit: f64,
    /// `value >= limit` passes (else `value <= limit`).
    pub at_least: bool,
    pub level: Level,
    pub note: String,
}

impl Check {
    /// A check that passes when `value <= limit` (NaN fails).
    fn new(name: &'static str, value: f64, limit: f64, fail: Level, note: String) -> Check {
        let pass = value <= limit;
        Check {
            name,
            value,
            limit,
            at_least: false,
            level: if pass { Level::Ok } else { fail },
            note,
        }
    }

    /// A check that passes when `value >= limit` (NaN fails).
    fn at_least(name: &'static str, value: f64, limit: f64, fail: Level, note: String) -> Check {
        let pass = value >= limit;
        Check {
            name,
            value,
            limit,
            at_least: true,
            level: if pass { Level::Ok } else { fail },
            note,
        }
    }
}

/// Energy the time-stepping scheme may gain over a run, relative to the largest work or energy
/// of the run's energy balance, before a warning ([`scheme_energy`]).
pub const SCHEME_GAIN_LIMIT: f64 = 1e-3;

/// The energy of the time-stepping scheme over a run's steps integrated in time, from the last
/// row of its energy balance: the generalised-α scheme only dissipates (`numerical ≥ 0`), and
/// contact conditions at the step's end keep it so; an energy gain (`numerical < 0`) beyond
/// [`SCHEME_GAIN_LIMIT`] of the run's largest work or energy is warned of (a Δt too coarse for
/// the contact's changes is the usual cause). For runs with steps integrated in time only.
pub fn scheme_energy(last: &crate::energy::EnergyRow) -> Check {
    let scale = [
        last.work_pilot.abs(),
        last.work_tractions.abs(),
        last.work_supports.abs(),
        last.elastic.abs(),
        last.kinetic.abs(),
        last.dissipation.abs(),
    ]
    .into_iter()
    .fold(0.0, f64::max)
    .max(f64::MIN_POSITIVE);
    let gain = (-last.numerical).max(0.0) / scale;
    let note = if gain > SCHEME_GAIN_LIMIT {
        format!(
            "the time-stepping scheme gained {:.3e} of energy (numerical dissipation {:.3e}) against the run's largest work or energy {scale:.3e}: the steps integrated in time do not keep the energy balance; try a smaller dt",
            -last.numerical, last.numerical
        )
    } else {
        format!(
            "numerical dissipation {:.3e} over the steps integrated in time, against the run's largest work or energy {scale:.3e}",
            last.numerical
        )
    };
    Check::new(
        "scheme_energy",
        gain,
        SCHEME_GAIN_LIMIT,
        Level::Warning,
        note,
    )
}

/// Time steps over which a front's `G/Γ` is averaged by [`front_energy`].
pub const FRONT_WINDOW: usize = 31;
/// The window mean of `G/Γ` at a moving front below which [`front_energy`] warns.
pub const FRONT_ENERGY_LIMIT: f64 = 0.8;

/// The energy reaching the fronts of weakening of a run's time steps
/// ([`crate::record::FrontFigures`]). A front that runs on its own takes in the fracture energy
/// of its process zone, `G = Γ`, whatever its speed; where the elements along the process zone
/// or the time steps are too coarse for it, the measured `G` falls below `Γ`. Over every
/// window of [`FRONT_WINDOW`] consecutive time steps in which a front exists and moves, and
/// which no growing patch forces (`forced(stage, x)`: a front inside a patch that weakens
/// nodes at a prescribed speed takes what the patch gives it), the mean of `G/Γ` is held to at
/// least [`FRONT_ENERGY_LIMIT`]; the value is the smallest such mean. `None` where no window
/// qualifies (no time step has a front with its `G` and `Γ`).
pub fn front_energy(records: &[StepRecord], forced: &dyn Fn(usize, f64) -> bool) -> Option<Check> {
    // (value, side, t0, t1, x0, x1)
    let mut worst: Option<(f64, usize, f64, f64, f64, f64)> = None;
    let mut windows = 0usize;
    for side in 0..2 {
        let mut run: Vec<(f64, f64, f64)> = Vec::new();
        let mut close = |run: &mut Vec<(f64, f64, f64)>| {
            for w in run.windows(FRONT_WINDOW) {
                let (a, b) = (w[0], w[FRONT_WINDOW - 1]);
                if a.1 == b.1 {
                    continue;
                }
                windows += 1;
                let mean = w.iter().map(|r| r.2).sum::<f64>() / FRONT_WINDOW as f64;
                if worst.is_none_or(|v| mean < v.0) {
                    worst = Some((mean, side, a.0, b.0, a.1, b.1));
                }
            }
            run.clear();
        };
        for r in records {
            let sample = match (r.physical_time, &r.fronts) {
                (Some(t), Some(f)) => match (f.front[side], f.g[side], f.gamma[side]) {
                    (Some(x), Some(g), Some(gam)) if gam > 0.0 && !forced(r.stage, x) => {
                        Some((t, x, g / gam))
                    }
                    _ => None,
                },
                _ => None,
            };
            match sample {
                Some(s) => run.push(s),
                None => close(&mut run),
            }
        }
        close(&mut run);
    }
    let (value, side, t0, t1, x0, x1) = worst?;
    let name = ["left", "right"][side];
    let speed = (x1 - x0).abs() / (t1 - t0);
    let note = if value < FRONT_ENERGY_LIMIT {
        format!(
            "the energy release rate reaching the {name} front averaged {value:.3} of the fracture energy Γ over t = {t0:.4e}..{t1:.4e} while it ran from x = {x0:.4} to {x1:.4} ({speed:.4e} per unit time): a moving front takes in Γ, so its process zone is not resolved there; a finer mesh along the interface (or a smaller dt) resolves it"
        )
    } else {
        format!(
            "the energy release rate at the moving fronts averaged at least {value:.3} of the fracture energy Γ over each of {windows} windows of {FRONT_WINDOW} time steps"
        )
    };
    Some(Check::at_least(
        "front_energy",
        value,
        FRONT_ENERGY_LIMIT,
        Level::Warning,
        note,
    ))
}

/// Relative equilibrium residual above which the answer is rejected.
pub const EQUILIBRIUM_LIMIT: f64 = 1e-6;
/// The strain whose force is the smallest scale of the equilibrium check.
const ROUND_OFF_STRAIN: f64 = 1e-12;
/// Displacement over model size above which small-strain theory is doubtful (warning); above
/// [`DISPLACEMENT_ERROR`] a body ran away (error).
pub const DISPLACEMENT_WARN: f64 = 0.01;
/// Fewer elements across the contact width than this draws a warning.
pub const MIN_ELEMENTS_ACROSS: f64 = 10.0;
/// Relative deviation of a from Hertz that draws a warning.
pub const HERTZ_A_LIMIT: f64 = 0.03;
/// Hertz semi-width of a line contact: `a = sqrt(4 P R / (π E*))`.
pub fn hertz_a(load: f64, radius: f64, e_star: f64) -> f64 {
    (4.0 * load * radius / (std::f64::consts::PI * e_star)).sqrt()
}

/// What the checks read from a finished run.
pub struct Input<'a> {
    pub model: &'a Model,
    /// The free solution of the last converged step and its traction scale.
    pub u: &'a [f64],
    pub scale: f64,
    /// The contact state of the last converged step (runs with contact).
    pub state: Option<&'a State>,
    pub records: &'a [StepRecord],
    pub friction: Option<&'a FrictionSummary>,
    /// The equilibrium check of this field, computed already ([`equilibrium`]).
    pub equilibrium: Option<Check>,
}

/// All checks of a finished run.
pub fn run_checks(inp: &Input) -> Vec<Check> {
    crate::trace::mark("checks: start");
    let e = inp.equilibrium.clone().unwrap_or_else(|| equilibrium(inp));
    crate::trace::mark("checks: equilibrium");
    let mut out = vec![e, displacement(inp)];
    if let (Some(st), Some(_)) = (inp.state, &inp.model.contact) {
        out.extend(contact_checks(inp, st));
    }
    out
}

/// The force balance of the recovered field (see the module docs).
pub fn equilibrium(inp: &Input) -> Check {
    equilibrium_many(std::slice::from_ref(inp))
        .pop()
        .expect("one check per field")
}

/// [`equilibrium`] of several fields of one model (a sweep's rows): their element forces in
/// one pass over the elements, eight fields at a time (each element's geometry read once for
/// them), on the calling thread. The same numbers as one field at a time.
pub fn equilibrium_many(inps: &[Input]) -> Vec<Check> {
    inps.chunks(8)
        .flat_map(|c| match c.len() {
            1 => equilibrium_lanes::<1>(c),
            2 => equilibrium_lanes::<2>(c),
            3 | 4 => equilibrium_lanes::<4>(c),
            _ => equilibrium_lanes::<8>(c),
        })
        .collect()
}

/// [`equilibrium_many`] of at most `R` fields of one model (the lanes past them zero). The
/// fields and the residuals are interleaved (one cache line per DOF for all of them).
fn equilibrium_lanes<const R: usize>(inps: &[Input]) -> Vec<Check> {
    let model = inps[0].model;
    let n_free = model.dofs.n_free();
    let us: Vec<&[f64]> = inps.iter().map(|i| i.u).collect();
    let uu = model.interleave::<R>(&us);
    // Residual at free DOFs: f_int − loads − contact and pilot forces; each element's nodal
    // forces added in the order of the elements, with the size of the terms summed.
    let mut res: Vec<[f64; R]> = model
        .f_traction
        .iter()
        .map(|f| std::array::from_fn(|j| inps.get(j).map_or(0.0, |i| -i.scale * f)))
        .collect();
    let mut reaction = [[0.0; 2]; R];
    let mut term = [0.0f64; R];
    let table = model.element_dof_table();
    model.each_element_forces(&uu, |i, ue, fe, kmax| {
        for j in 0..R {
            let umax = ue.iter().fold(0.0f64, |m, v| m.max(v[j].abs()));
            term[j] = term[j].max(kmax * umax);
        }
        for (k, &d) in table[i].iter().enumerate() {
            let d = d as usize;
            if d < n_free {
                for j in 0..R {
                    res[d][j] += fe[k][j];
                }
            } else if d != u32::MAX as usize {
                for j in 0..R {
                    reaction[j][k % 2] += fe[k][j];
                }
            }
        }
    });
    inps.iter()
        .enumerate()
        .map(|(j, inp)| {
            balance(
                inp,
                res.iter().map(|r| r[j]).collect(),
                reaction[j],
                term[j],
            )
        })
        .collect()
}

/// The equilibrium check of a field from its residual `res` at the free DOFs (internal forces
/// less the loads), the supports' `reaction` and the largest term summed into them.
fn balance(inp: &Input, mut res: Vec<f64>, reaction: [f64; 2], term: f64) -> Check {
    use crate::dofs::Dof;
    let model = inp.model;
    let dofs = &model.dofs;
    let mut pilot = [0.0; 2];
    if let (Some(st), Some(cm)) = (inp.state, &model.contact) {
        let mut contact_only = st.clone();
        contact_only.z.iter_mut().for_each(|z| *z = 0.0);
        let r = cm.retained_forces(&contact_only, dofs.n_retained);
        for (k, v) in r.iter().enumerate() {
            res[dofs.n_interior + k] -= v;
        }
        pilot = st.pilot_f;
    } else if let Some(p) = inp.records.last().and_then(|r| r.pilot) {
        pilot = [p.fx, p.fy];
    }
    if let Some(p) = dofs.pilot {
        for c in 0..2 {
            res[p[c]] -= pilot[c];
        }
    }
    let traction: [f64; 2] = std::array::from_fn(|c| {
        (0..model.mesh.nodes.len())
            .filter_map(|n| match dofs.node[n][c] {
                Dof::Free(i) => Some(inp.scale * model.f_traction[i]),
                _ => None,
            })
            .sum()
    });
    // The supports' reactions are f_int at the fixed DOFs: they, the pilot and the tractions
    // balance (the contact forces are internal).
    let global = (0..2)
        .map(|c| (pilot[c] + traction[c] + reaction[c]).abs())
        .fold(0.0, f64::max);
    let local = res.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    // The force a strain of 1e-12 of the stiffest body over the model's size produces: below
    // it a residual is round-off (zero and vanishing loads, a body moved rigidly).
    let e_max = model.elems.iter().map(|(_, m)| m.e).fold(0.0, f64::max);
    let round_off = ROUND_OFF_STRAIN * e_max * model.scales().0;
    let scale = [pilot, traction, reaction]
        .iter()
        .map(|v| v[0].hypot(v[1]))
        .fold(round_off.max(term), f64::max);
    let value = if scale > 0.0 {
        local.max(global) / scale
    } else {
        0.0
    };
    if inp.records.last().is_some_and(|r| r.kinetic.is_some()) {
        // A step integrated in time balances inertia too (at the scheme's intermediate time):
        // the static balance measures the inertial forces, not an error.
        return Check {
            name: "equilibrium",
            value,
            limit: EQUILIBRIUM_LIMIT,
            at_least: false,
            level: Level::NotApplied,
            note: format!(
                "not applied: the last step is integrated in time (the static imbalance {value:.3e} is the inertial force; the energy balance checks it)"
            ),
        };
    }
    Check::new(
        "equilibrium",
        value,
        EQUILIBRIUM_LIMIT,
        Level::Error,
        format!(
            "largest nodal force residual {local:.3e}, global imbalance {global:.3e} (supports, pilot, tractions), relative to {scale:.3e}"
        ),
    )
}

/// The largest displacement against the model's size.
fn displacement(inp: &Input) -> Check {
    let dofs = &inp.model.dofs;
    let umax = (0..inp.model.mesh.nodes.len())
        .filter(|&n| inp.model.active[n])
        .map(|n| {
            let u = dofs.displacement(n, inp.u);
            u[0].hypot(u[1])
        })
        .fold(0.0, f64::max);
    let size = inp.model.scales().0;
    let value = umax / size;
    let mut c = Check::new(
        "max_displacement",
        value,
        DISPLACEMENT_WARN,
        Level::Warning,
        format!(
            "largest displacement {umax:.3e} over the model size {size:.3e}; small-strain theory needs it small (warning above {DISPLACEMENT_WARN}, error above {DISPLACEMENT_ERROR}: a body ran away)"
        ),
    );
    if value.is_nan() || value > DISPLACEMENT_ERROR {
        c.level = Level::Error;
    }
    c
}

/// Zone margin, face ends, elements across the contact, s0 resolution and Hertz a.
fn contact_checks(inp: &Input, st: &State) -> Vec<Check> {
    let model = inp.model;
    let cm = model.contact.as_ref().expect("checked by the caller");
    let m = &cm.pair.mortar;
    let mut out = Vec::new();
    let n0 = cm.pair.first_touch;
    let tau = [n0[1], -n0[0]];
    let t_of = |n: usize| {
        let x = model.mesh.nodes[n];
        x[0] * tau[0] + x[1] * tau[1]
    };
    let closed: Vec<usize> = (0..m.slave_nodes.len())
        .filter(|&j| st.status[j] != Status::Open)
        .collect();
    if closed.is_empty() {
        return out;
    }
    // Margin on each side, in elements: zone nodes beyond the outermost contact node, counted
    // as edges (two nodes per quadratic edge).
    let ts: Vec<f64> = closed.iter().map(|&j| t_of(m.slave_nodes[j])).collect();
    let (tlo, thi) = ts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    let zone_t: Vec<f64> = m.slave_nodes.iter().map(|&n| t_of(n)).collect();
    // A side whose outermost zone node ends a face cannot grow: the face_end check covers it.
    let end_of = |lo: bool| {
        let k = (0..zone_t.len())
            .min_by(|&i, &j| {
                let o = zone_t[i].total_cmp(&zone_t[j]);
                if lo { o } else { o.reverse() }
            })
            .expect("a zone with contact has nodes");
        cm.pair.face_ends.contains(&m.slave_nodes[k])
    };
    let beyond_lo = zone_t.iter().filter(|&&t| t < tlo).count();
    let beyond_hi = zone_t.iter().filter(|&&t| t > thi).count();
    let sides: Vec<usize> = [(beyond_lo, end_of(true)), (beyond_hi, end_of(false))]
        .iter()
        .filter(|(_, face_end)| !face_end)
        .map(|(n, _)| *n)
        .collect();
    if let Some(&beyond) = sides.iter().min() {
        let margin = beyond as f64 / 2.0;
        out.push(Check::at_least(
            "zone_margin",
            margin,
            1.0,
            Level::Error,
            format!(
                "{margin} slave elements between the contact and the nearer edge of the candidate zone (contact on the rim doubles the zone and restarts)"
            ),
        ));
    }
    let at_end = closed
        .iter()
        .filter(|&&j| cm.pair.face_ends.contains(&m.slave_nodes[j]))
        .count();
    out.push(Check::new(
        "face_end",
        at_end as f64,
        0.0,
        Level::Warning,
        format!(
            "{at_end} contact nodes on the end of the slave face or beyond the end of the master face: the faces are too short to hold the contact, unless the scene means it (a flat punch, a patch test)"
        ),
    ));
    // Elements across the contact width (the contact figures' a, the centre element size).
    let last = inp.records.last().and_then(|r| r.contact);
    let a = last.map_or(0.0, |c| c.a);
    let jc = closed[closed.len() / 2];
    let across = 2.0 * a / m.h[jc];
    out.push(Check::at_least(
        "elements_across_contact",
        across,
        MIN_ELEMENTS_ACROSS,
        Level::Warning,
        format!(
            "{across:.1} slave elements across the contact width 2a = {:.4e} (h = {:.3e}); fewer than {MIN_ELEMENTS_ACROSS} resolve the pressure poorly",
            2.0 * a,
            m.h[jc]
        ),
    ));
    if let Some(f) = inp.friction
        && let Some(s0) = f.s0_over_a.zip(f.a_hertz).map(|(s, a)| s * a)
    {
        out.push(Check::new(
            "s0_resolution",
            f.h_contact / s0,
            0.5,
            Level::Warning,
            format!(
                "contact element size {:.3e} over the slip-weakening transition length s0 = {s0:.3e}; above 0.5 the transition zone is not resolved and Q_max depends on the mesh",
                f.h_contact
            ),
        ));
    }
    out.extend(hertz_check(inp));
    out
}

/// `a` at the end of the first stage against Hertz (see the module docs).
fn hertz_check(inp: &Input) -> Option<Check> {
    let model = inp.model;
    let cm = model.contact.as_ref()?;
    let rec = inp
        .records
        .iter()
        .take_while(|r| r.stage == 0)
        .last()
        .or(inp.records.last())?;
    let fig = rec.contact?;
    let n0 = cm.pair.first_touch;
    let load = (fig.fx * n0[0] + fig.fy * n0[1]).abs();
    let tangential = (fig.fx * n0[1] - fig.fy * n0[0]).abs();
    let (radius, _, _, rms) = fit_radius(model, Some(1.5 * fig.a))?;
    // Not a Hertzian stage: no finite curvature, or a profile that is not a parabola (said in
    // the check's note), or a contact with a sizeable tangential load (which changes a only
    // through β, a small effect, but then the stage is not the normal one).
    if let Some(why) = not_hertzian(radius, rms) {
        return Some(Check {
            name: "hertz_a",
            value: rms,
            limit: HERTZ_PROFILE_LIMIT,
            at_least: false,
            level: Level::NotApplied,
            note: format!("not applied: {why}"),
        });
    }
    if tangential > 0.05 * load {
        return None;
    }
    let ah = hertz_a(load, radius, cm.e_star);
    let dev = fig.a / ah - 1.0;
    Some(Check::new(
        "hertz_a",
        dev.abs(),
        HERTZ_A_LIMIT,
        Level::Warning,
        format!(
            "a = {:.5e} at step {} against Hertz {ah:.5e} (P = {load:.4e}, fitted R = {radius:.4e}, E* = {:.4e}): {:+.2} %",
            fig.a,
            rec.step,
            cm.e_star,
            100.0 * dev
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scheme_energy_warns_of_a_gain_and_not_of_a_loss() {
        let row = |numerical: f64| crate::energy::EnergyRow {
            work_pilot: 2.0,
            elastic: 1.0,
            dissipation: 0.5,
            numerical,
            ..Default::default()
        };
        assert_eq!(scheme_energy(&row(0.1)).level, Level::Ok);
        assert_eq!(scheme_energy(&row(-1e-3)).level, Level::Ok);
        let gain = scheme_energy(&row(-0.01));
        assert_eq!(gain.level, Level::Warning);
        assert!((gain.value - 0.005).abs() < 1e-15, "{}", gain.value);
    }

    /// A front moving at one node per step with `G/Γ = ratio(x)`: records of stage 0.
    fn fronts(n: usize, ratio: &dyn Fn(f64) -> f64) -> Vec<StepRecord> {
        (0..n)
            .map(|k| {
                let x = k as f64;
                StepRecord {
                    step: k + 1,
                    stage: 0,
                    time: 0.0,
                    traction_scale: 1.0,
                    pilot: None,
                    iterations: 1,
                    cutbacks: 0,
                    contact: None,
                    wall_s: 0.0,
                    cycle: None,
                    physical_time: Some(1e-6 * (k + 1) as f64),
                    kinetic: Some(0.0),
                    fronts: Some(crate::record::FrontFigures {
                        front: [None, Some(x)],
                        g: [None, Some(2.0 * ratio(x))],
                        gamma: [None, Some(2.0)],
                    }),
                }
            })
            .collect()
    }

    #[test]
    fn a_moving_front_short_of_its_fracture_energy_is_warned_of_unless_a_patch_forces_it() {
        let free = |_: usize, _: f64| false;
        let c = front_energy(&fronts(100, &|_| 0.99), &free).expect("windows");
        assert_eq!(c.level, Level::Ok);
        assert!((c.value - 0.99).abs() < 1e-12);
        // G/Γ = 0.5 beyond x = 60: the windows that lie there average 0.5.
        let low = fronts(100, &|x| if x >= 60.0 { 0.5 } else { 1.0 });
        let c = front_energy(&low, &free).expect("windows");
        assert_eq!(c.level, Level::Warning);
        assert!((c.value - 0.5).abs() < 1e-12, "{}", c.value);
        assert!(c.note.contains("right front"), "{}", c.note);
        // A growing patch over x ≥ 50 forces the front there: those steps are not held to Γ.
        let patch = |_: usize, x: f64| x >= 50.0;
        let c = front_energy(&low, &patch).expect("windows");
        assert_eq!(c.level, Level::Ok, "{}", c.note);
        // A front that does not move, or runs shorter than a window, is not held to Γ.
        let mut still = fronts(100, &|_| 0.1);
        for r in &mut still {
            r.fronts.as_mut().unwrap().front[1] = Some(3.0);
        }
        assert!(front_energy(&still, &free).is_none());
        assert!(front_energy(&fronts(FRONT_WINDOW - 1, &|_| 0.1), &free).is_none());
    }
}
