//! One load step on the condensed model: the solve without contact (the pilot's two
//! equations on the Schur complement), the contact solve from a committed state, the full
//! displacement field of a contact state, and the contact figures of a state (a, c, b, the
//! fronts at each end and K_II there, forces).

use crate::analytic::hertz::{Geometry, Hertz};
use crate::case::Control;
use crate::contact::solver::{self, ContactError, PilotDrive, State, Status};
use crate::error::StepError;
use crate::model::Model;
use crate::model::fronts::{self, Zone};
use serde::Serialize;

/// The state of the pilot after a step.
#[derive(Clone, Copy, Debug, Default, Serialize, serde::Deserialize)]
pub struct PilotState {
    pub ux: f64,
    pub uy: f64,
    pub fx: f64,
    pub fy: f64,
}

/// Figures of the contact after a step.
#[derive(Clone, Copy, Debug, Default, Serialize, serde::Deserialize)]
pub struct ContactFigures {
    /// Nodes in contact, in stick, in slip.
    pub n_contact: usize,
    pub n_stick: usize,
    pub n_slip: usize,
    /// Contact semi-width (edges extrapolated with p² linear in x between the two outermost
    /// contact nodes on each side).
    pub a: f64,
    /// Centre of the contact.
    pub x_centre: f64,
    /// Stick semi-width (each edge midway between the outermost stick node and the next node).
    pub c: f64,
    /// Semi-width of the zone where μ has not yet reached its dynamic value (midway rule).
    pub b: f64,
    /// Total contact force on the master side.
    pub fx: f64,
    pub fy: f64,
    /// Mean slip over the contact (the quantity of slip control; see `State::mean_slip`).
    pub mean_slip: f64,
    /// Ends of the stick zone, `c_left ≤ c_right` (x; each midway between the outermost stick
    /// node and the next node, so `c = (c_right − c_left)/2`). Absent without a stick node.
    #[serde(default)]
    pub c_left: Option<f64>,
    #[serde(default)]
    pub c_right: Option<f64>,
    /// Ends of the zone where μ has not yet weakened to f_d (same rule, `b = (b_right −
    /// b_left)/2`). Absent without a slip-weakening law or a node in contact.
    #[serde(default)]
    pub b_left: Option<f64>,
    #[serde(default)]
    pub b_right: Option<f64>,
    /// Mode-II stress intensity at the left and right ends of the stick zone, measured from
    /// the shear traction in excess of f_d p (see [`crate::model::fronts`]: the fit, its tips
    /// and band). Absent where the end does not face a slip zone or its band holds too few
    /// nodes.
    #[serde(default)]
    pub k2_left: Option<f64>,
    #[serde(default)]
    pub k2_right: Option<f64>,
    /// The paper's `K_II = sqrt(2 W E*)` (eqs. KII, KIIa) with `W = (W/p) p`, `p` the Hertz
    /// pressure `E* sqrt(a² − d²) / 2R` at the mean distance `d` of the two tips from the
    /// contact centre (`a` from the normal contact force, R fitted to the initial gaps).
    /// Present with a slip-weakening law (`f_s > f_d`), a Hertzian profile and a measured
    /// `k2_left` or `k2_right`.
    #[serde(default)]
    pub k2_paper: Option<f64>,
}

/// The load of one step: the traction scale and the pilot's two controls.
#[derive(Clone, Copy, Debug)]
pub struct StepLoad {
    pub scale: f64,
    pub control: [Control; 2],
}

/// One element's nodal displacements and internal forces `K_e u_e`, and the largest entry of
/// `K_e` (the size of the terms summed into the forces).
pub struct ElementForces {
    pub ue: [f64; 12],
    pub fe: [f64; 12],
    pub kmax: f64,
}

impl Model {
    /// Raises the slip μ sees of the slave nodes within each `(extent, slip)` of `patches`
    /// ([`crate::case::weaken`]); `Err(i)` when patch `i` holds no slave node (the others are
    /// applied). Without a contact nothing is held: `Err(0)` for a non-empty list.
    pub fn weaken(
        &self,
        patches: impl IntoIterator<Item = ([f64; 2], f64)>,
        slip_mu: &mut [f64],
    ) -> Result<(), usize> {
        let mut patches = patches.into_iter().peekable();
        if patches.peek().is_none() {
            return Ok(());
        }
        let cm = self.contact.as_ref().ok_or(0usize)?;
        let xs: Vec<f64> = cm
            .pair
            .mortar
            .slave_nodes
            .iter()
            .map(|&n| self.mesh.nodes[n][0])
            .collect();
        crate::case::weaken(&xs, patches, slip_mu)
    }

    /// Refuses a `stages[i].weaken` patch of `case` (read from `path`, as the error names it)
    /// that holds no node of the slave face, naming it; called wherever a case's model is built
    /// to be run.
    pub fn refuse_empty_patches(
        &self,
        case: &crate::case::Case,
        path: &str,
    ) -> Result<(), crate::case::CaseError> {
        let ns = self
            .contact
            .as_ref()
            .map_or(0, |c| c.pair.mortar.slave_nodes.len());
        for (i, stage) in case.stages.iter().enumerate() {
            let whole = stage.weaken.iter().map(|p| (p.x, p.slip));
            if let Err(k) = self.weaken(whole, &mut vec![0.0; ns]) {
                let [x0, x1] = stage.weaken[k].x;
                let slave = case.contact.as_ref().map_or("", |c| c.slave.as_str());
                return Err(crate::case::CaseError::Value {
                    path: path.to_string(),
                    key: format!("stages[{i}].weaken[{k}].x"),
                    value: format!("[{x0}, {x1}]"),
                    why: format!("holds no node of the slave group `{slave}`"),
                });
            }
        }
        Ok(())
    }

    /// From now on the simulations of this model share their factorised Delassus blocks (see
    /// [`crate::contact::solver::BlockStore`]): for a sweep, whose rows run side by side.
    pub fn share_contact_blocks(&self) {
        self.contact_blocks.get_or_init(Default::default);
    }

    /// Where the simulations of this model share their factorised Delassus blocks, if they do.
    pub fn contact_blocks(&self) -> Option<std::sync::Arc<crate::contact::solver::BlockStore>> {
        self.contact_blocks.get().cloned()
    }

    /// The nodal displacements and internal forces of every element for the free solution `u`
    /// (prescribed values included), in the order of `self.elems`.
    pub fn element_forces(&self, u: &[f64]) -> Vec<ElementForces> {
        self.map_element_forces(u, |f| f)
    }

    /// `keep` of each element's [`ElementForces`] (in parallel, in the order of `self.elems`),
    /// without storing the forces themselves (the summary's equilibrium check keeps 13 of
    /// their 25 numbers: 28 MB of forces at L7 it would otherwise write and read again).
    pub fn map_element_forces<T: Send>(
        &self,
        u: &[f64],
        keep: impl Fn(ElementForces) -> T + Sync,
    ) -> Vec<T> {
        use crate::elasticity::{element_forces, element_forces_with};
        use rayon::prelude::*;
        let kept = self.force_geometry.get();
        self.elems
            .par_iter()
            .enumerate()
            .map(|(i, (e, mat))| {
                let ue: [f64; 12] = self.element_u(i, u);
                let (fe, kmax) = match kept {
                    Some(g) => element_forces_with(&g[i], &ue, mat),
                    None => element_forces(&self.mesh.tri_coords(*e), &ue, mat),
                };
                keep(ElementForces { ue, fe, kmax })
            })
            .collect()
    }

    /// The element forces of `R` fields at once ([`crate::elasticity::element_forces_lanes`]:
    /// the same numbers as one field at a time), element by element in the order of
    /// `self.elems` on the calling thread, each handed to `each(i, ue, fe, kmax)` with the
    /// element's displacements and forces (`[k][j]`: DOF `k` of field `j`) and the largest
    /// entry of its stiffness. `uu`: the fields as [`Model::interleave`] gives them.
    pub fn each_element_forces<const R: usize>(
        &self,
        uu: &[[f64; R]],
        mut each: impl FnMut(usize, &[[f64; R]; 12], &[[f64; R]; 12], f64),
    ) {
        self.each_element_forces_body(uu, &mut each)
    }

    #[inline(always)]
    fn each_element_forces_body<const R: usize>(
        &self,
        uu: &[[f64; R]],
        each: &mut impl FnMut(usize, &[[f64; R]; 12], &[[f64; R]; 12], f64),
    ) {
        use crate::elasticity::{element_forces_lanes, force_geometry};
        let kept = self.force_geometry.get();
        let table = self.element_dof_table();
        for (i, (e, mat)) in self.elems.iter().enumerate() {
            let ue = Model::element_u_lanes(&table[i], uu);
            let computed;
            let geo = match kept {
                Some(g) => &g[i],
                None => {
                    computed = force_geometry(&self.mesh.tri_coords(*e), mat);
                    &computed
                }
            };
            let fe = element_forces_lanes(geo, &ue, mat);
            each(i, &ue, &fe, geo.kmax());
        }
    }

    /// From now on [`Model::element_forces`] and [`Model::each_element_forces`] read each
    /// element's geometry from memory instead of mapping its quadrature points again (the
    /// same numbers). About 640 bytes per element (29 MB on L5). A sweep no longer keeps it:
    /// checked eight rows at a time, mapping the geometry costs as much as reading it.
    pub fn keep_force_geometry(&self) {
        use rayon::prelude::*;
        self.force_geometry.get_or_init(|| {
            self.elems
                .par_iter()
                .map(|(e, mat)| crate::elasticity::force_geometry(&self.mesh.tri_coords(*e), mat))
                .collect()
        });
    }

    /// Solves one load step without contact: tractions at `scale`, the pilot driven by
    /// `control`. Returns the free solution vector and the pilot state (if there is a pilot).
    pub fn solve_step(
        &self,
        scale: f64,
        control: [Control; 2],
    ) -> Result<(Vec<f64>, Option<PilotState>), StepError> {
        let f = self.load(scale);
        let cond = &self.condensed;
        if self.dofs.pilot.is_none() {
            return Ok((cond.recover(&f, &[], &[]), None));
        }
        let g = cond.reduce(&f);
        let (u, r) = solve_pilot(&cond.s_dense(), &g, control, cond.krr_scale)?;
        Ok((
            cond.recover(&f, &r, &u),
            Some(PilotState {
                ux: u[0],
                uy: u[1],
                fx: r[0],
                fy: r[1],
            }),
        ))
    }

    /// The free load vector at traction scale `scale`.
    pub fn load(&self, scale: f64) -> Vec<f64> {
        self.f_traction
            .iter()
            .zip(&self.f_prescribed)
            .map(|(a, b)| scale * a + b)
            .collect()
    }

    /// Solves one load step with contact from the committed state `prev` (the contact unknowns
    /// only; [`Model::contact_displacement`] recovers the full field when it is wanted).
    pub fn solve_contact_step(
        &self,
        load: StepLoad,
        prev: &State,
        guess: Option<&State>,
        opt: &solver::Options,
        law: Option<&crate::friction::FrictionLaw>,
        cache: Option<&mut solver::LuCache>,
    ) -> Result<solver::StepOutcome, ContactError> {
        let StepLoad { scale, control } = load;
        let cm = self.contact.as_ref().expect("contact model");
        let w0: Vec<f64> = self.contact_w0[0]
            .iter()
            .zip(&self.contact_w0[1])
            .map(|(a, b)| scale * a + b)
            .collect();
        let drive = control.map(|c| match c {
            Control::Force(f) => PilotDrive::Force(f),
            Control::Displacement(d) => PilotDrive::Displacement(d),
            Control::Slip(s) => PilotDrive::Slip(s),
        });
        cm.system
            .solve_step(&w0, drive, law, prev, guess, opt, cache)
    }

    /// [`Model::contact_displacement`] of several states in one block solve, which reads the
    /// factor once for all of them (bit for bit the same fields).
    ///
    /// `spread`: the columns split over rayon's threads (else one sweep on the calling thread,
    /// as the output writer does while the contact solve has the other core).
    pub fn contact_displacements(&self, states: &[(f64, &State)], spread: bool) -> Vec<Vec<f64>> {
        if states.is_empty() {
            return Vec::new();
        }
        let cm = self.contact.as_ref().expect("contact model");
        let cases: Vec<_> = states
            .iter()
            .map(|(scale, st)| {
                (
                    self.load(*scale),
                    cm.retained_forces(st, self.dofs.n_retained),
                )
            })
            .collect();
        self.condensed.recover_total_many(&cases, spread)
    }

    /// The displacement of all free DOFs for a contact state at traction scale `scale`: one
    /// solve with the factorised stiffness.
    pub fn contact_displacement(&self, scale: f64, st: &State) -> Vec<f64> {
        let mut u = self.contact_displacements(&[(scale, st)], true);
        u.pop().expect("one field per state")
    }

    /// Contact figures of a state.
    pub fn contact_figures(
        &self,
        st: &State,
        law: Option<&crate::friction::FrictionLaw>,
    ) -> ContactFigures {
        let cm = self.contact.as_ref().expect("contact model");
        let m = &cm.pair.mortar;
        let xs: Vec<f64> = m
            .slave_nodes
            .iter()
            .map(|&n| self.mesh.nodes[n][0])
            .collect();
        let p: Vec<f64> = (0..xs.len()).map(|j| st.f_n[j] / m.weight[j]).collect();
        let on: Vec<usize> = (0..xs.len())
            .filter(|&j| st.status[j] != Status::Open)
            .collect();
        let mut fig = ContactFigures {
            n_contact: on.len(),
            n_stick: st.status.iter().filter(|s| **s == Status::Stick).count(),
            n_slip: st.status.iter().filter(|s| **s == Status::Slip).count(),
            ..Default::default()
        };
        let r = cm.retained_forces(st, self.dofs.n_retained);
        let (mut fx, mut fy) = (0.0, 0.0);
        for &node in &m.master_nodes {
            for c in 0..2 {
                if let crate::dofs::Dof::Free(i) = self.dofs.node[node][c] {
                    let k = i - self.dofs.n_interior;
                    if c == 0 { fx += r[k] } else { fy += r[k] }
                }
            }
        }
        fig.fx = fx;
        fig.fy = fy;
        fig.mean_slip = st.mean_slip;
        if on.is_empty() {
            return fig;
        }
        let (lo, hi) = (on[0], *on.last().expect("non-empty"));
        let edge = |j1: usize, j2: usize| -> f64 {
            // p² linear in x through the two outermost nodes, extrapolated to zero.
            let (a, b) = (p[j1].max(0.0).powi(2), p[j2].max(0.0).powi(2));
            let dx = xs[j1] - xs[j2];
            if b > a && dx != 0.0 {
                {
                    // at most one node spacing beyond the last contact node
                    let ext = a / (b - a) * dx;
                    xs[j1] + if dx > 0.0 { ext.min(dx) } else { ext.max(dx) }
                }
            } else {
                xs[j1]
            }
        };
        let left = if lo < hi { edge(lo, lo + 1) } else { xs[lo] };
        let right = if hi > lo { edge(hi, hi - 1) } else { xs[hi] };
        // The face may run in −x (a slave on the upper body): widths are absolute.
        fig.a = 0.5 * (right - left).abs();
        fig.x_centre = 0.5 * (right + left);
        let stick = Zone::of(&xs, |j| st.status[j] == Status::Stick);
        fig.c = stick.map_or(0.0, |z| z.half_width());
        if let Some(z) = stick {
            [fig.c_left, fig.c_right] = z.left_right().map(Some);
        }
        let Some(law) = law else {
            return fig;
        };
        let Ok(fd) = law.f_dynamic() else {
            return fig;
        };
        let fs = law.f_static();
        let tol = fronts::WEAKENED_TOL * (fs - fd);
        let weakening = (fs > fd)
            .then(|| {
                Zone::of(&xs, |j| {
                    st.status[j] != Status::Open && law.mu(st.slip_mu[j]) > fd + tol
                })
            })
            .flatten();
        fig.b = weakening.map_or(0.0, |z| z.half_width());
        if let Some(z) = weakening {
            [fig.b_left, fig.b_right] = z.left_right().map(Some);
        }
        // The process zone that places the tips of K_II: the weakening zone, cut where the
        // slip reaches fronts::process_slip (the whole of it for a ramp or a step).
        let process = match fronts::process_slip(law) {
            Some(u_end) if weakening.is_some() => Zone::of(&xs, |j| {
                st.status[j] != Status::Open
                    && law.mu(st.slip_mu[j]) > fd + tol
                    && st.slip_mu[j] < u_end
            }),
            _ => weakening,
        };
        let Some(stick) = stick else {
            return fig;
        };
        let tau: Vec<f64> = (0..xs.len()).map(|j| -st.f_t[j] / m.weight[j]).collect();
        let face = fronts::Face {
            x: &xs,
            p: &p,
            tau: &tau,
            status: &st.status,
            h: &m.h,
        };
        let k2 = fronts::k2_ends(&face, &stick, process.as_ref(), fd);
        // Left is the end of smaller x (the face may run in −x).
        let (left, right) = if stick.ends[0] <= stick.ends[1] {
            (0, 1)
        } else {
            (1, 0)
        };
        fig.k2_left = k2[left];
        fig.k2_right = k2[right];
        if fs > fd && (fig.k2_left.is_some() || fig.k2_right.is_some()) {
            fig.k2_paper = self.k2_paper(law, &fig, &stick, process.as_ref());
        }
        fig
    }

    /// The paper's `K_II = sqrt(2 W E*)` for the fronts of a state (see
    /// [`ContactFigures::k2_paper`]); `None` where the profile is not Hertzian or the law has no
    /// fracture energy.
    fn k2_paper(
        &self,
        law: &crate::friction::FrictionLaw,
        fig: &ContactFigures,
        stick: &Zone,
        process: Option<&Zone>,
    ) -> Option<f64> {
        let cm = self.contact.as_ref()?;
        let w_over_p = law.w_over_p().ok().filter(|w| *w > 0.0)?;
        let (radius, _, _, rms) = crate::model::profile::fit_radius(self, None)?;
        if crate::model::profile::not_hertzian(radius, rms).is_some() {
            return None;
        }
        let n0 = cm.pair.common_normal.unwrap_or([0.0, 1.0]);
        let load = (fig.fx * n0[0] + fig.fy * n0[1]).abs();
        let hertz = Hertz::new(Geometry::new(radius, cm.e_star).ok()?, load).ok()?;
        // The tips of the measured K_II: the midpoints of the process zones.
        let (tips, _) = fronts::tips(stick, process);
        let d = 0.5 * ((tips[0] - fig.x_centre).abs() + (tips[1] - fig.x_centre).abs());
        let p = hertz.pressure(d);
        Some((2.0 * cm.e_star * w_over_p * p).sqrt())
    }
}

/// Solves `S u = g + r` on the pilot DOFs with, per component, either the force `r` or the
/// displacement `u` given. Returns (u, r). `scale` is the stiffness scale of the pilot
/// before condensation: a pivot below 1e-10 of it means nothing holds the pilot.
pub fn solve_pilot(
    s: &[f64],
    g: &[f64],
    control: [Control; 2],
    scale: f64,
) -> Result<([f64; 2], [f64; 2]), StepError> {
    let mut u = [0.0; 2];
    let mut r = [0.0; 2];
    let mut free = Vec::new();
    for c in 0..2 {
        match control[c] {
            Control::Force(f) => {
                r[c] = f;
                free.push(c);
            }
            Control::Displacement(d) => u[c] = d,
            Control::Slip(_) => {
                return Err(StepError::SlipWithoutFriction);
            }
        }
    }
    // S_FF u_F = g_F + r_F − S_FD u_D
    let rhs: Vec<f64> = free
        .iter()
        .map(|&i| {
            g[i] + r[i]
                - (0..2)
                    .filter(|j| !free.contains(j))
                    .map(|j| s[i * 2 + j] * u[j])
                    .sum::<f64>()
        })
        .collect();
    match free.len() {
        1 => {
            let i = free[0];
            if s[i * 2 + i].abs() <= 1e-10 * scale {
                return Err(StepError::PilotUnheld);
            }
            u[i] = rhs[0] / s[i * 2 + i];
        }
        2 => {
            let det = s[0] * s[3] - s[1] * s[2];
            if s[0].abs().min(s[3].abs()) <= 1e-10 * scale || det.abs() <= 1e-10 * scale * scale {
                return Err(StepError::PilotUnheld);
            }
            u[0] = (s[3] * rhs[0] - s[1] * rhs[1]) / det;
            u[1] = (s[0] * rhs[1] - s[2] * rhs[0]) / det;
        }
        _ => {}
    }
    for i in 0..2 {
        r[i] = s[i * 2] * u[0] + s[i * 2 + 1] * u[1] - g[i];
    }
    Ok((u, r))
}
