//! One time step of the generalised-α scheme ([`super`]) on the model of `K + c M`.

use super::{Masses, Scheme};
use crate::case::{Case, Control};
use crate::contact::solver::{self, PilotDrive, State};
use crate::error::{ModelError, StepError};
use crate::friction::FrictionLaw;
use crate::model::Model;
use crate::model::step::PilotState;

/// The state of the bodies at a time: the free DOFs' displacement, velocity and
/// acceleration, the traction scale, the physical forces on the retained DOFs (pilot and
/// contact, without the grounding springs' share) and the kinetic energy.
#[derive(Clone, Debug)]
pub struct TimeState {
    pub time: f64,
    /// The size of the step that reached this state (0 at rest): a contact state's slip
    /// increments are over it.
    pub dt: f64,
    pub scale: f64,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub r: Vec<f64>,
    pub kinetic: f64,
    pub pilot: Option<PilotState>,
}

/// A time step's size, its scheme and the factorised `K + c M`.
pub struct Integrator {
    /// The model of `K + c M` (the same DOFs, contact pair and loads as the quasi-static one).
    pub model: Model,
    pub masses: Masses,
    pub scheme: Scheme,
    pub dt: f64,
    /// The contact Newton's factorised blocks of this model's Delassus operator.
    pub lu: solver::LuCache,
}

/// What a time step gives: the new state, the contact state (with contact) and the contact
/// Newton's iterations.
pub struct Stepped {
    pub time: TimeState,
    pub contact: Option<State>,
    pub iterations: usize,
}

impl Integrator {
    /// Builds and factorises `K + c M` for the time step `dt` of `scheme`, with the densities
    /// `density[b]` of the case's bodies, on a copy of `base`'s mesh.
    pub fn new(
        case: &Case,
        base: &Model,
        density: &[f64],
        scheme: Scheme,
        dt: f64,
    ) -> Result<Integrator, ModelError> {
        let c = scheme.mass_shift(dt);
        let shift: Vec<f64> = density.iter().map(|r| c * r).collect();
        let mut timings = crate::model::Timings::default();
        // The quasi-static model's grounding springs: a contact state means the same in both.
        let springs: Vec<f64> = base.condensed.grounding.iter().map(|g| g.1).collect();
        let mut model = Model::shifted(case, base.mesh.clone(), &shift, &springs, &mut timings)?;
        if let (Some(cm), Some(b)) = (model.contact.as_mut(), base.contact.as_ref()) {
            cm.system.floating_pilot = b.system.floating_pilot;
        }
        // The elastic forces `k(u_n)` of every step read each element's geometry from memory.
        model.keep_force_geometry();
        let masses = Masses::new(&model, density);
        Ok(Integrator {
            model,
            masses,
            scheme,
            dt,
            lu: solver::LuCache::default(),
        })
    }

    /// The state at rest at time `time` in the equilibrium `u` of the quasi-static `base`
    /// model at traction scale `scale` (contact state `st`, pilot state `pilot`): zero velocity
    /// and acceleration.
    pub fn at_rest(
        base: &Model,
        time: f64,
        scale: f64,
        u: Vec<f64>,
        st: Option<&State>,
        pilot: Option<PilotState>,
    ) -> TimeState {
        let n = u.len();
        let r = match st {
            Some(st) => physical_retained(base, st, &u),
            None => {
                let mut r = vec![0.0; base.dofs.n_retained];
                if let (Some(p), Some(_)) = (pilot, base.dofs.pilot) {
                    r[0] = p.fx;
                    r[1] = p.fy;
                }
                r
            }
        };
        TimeState {
            time,
            dt: 0.0,
            scale,
            u,
            v: vec![0.0; n],
            a: vec![0.0; n],
            r,
            kinetic: 0.0,
            pilot,
        }
    }

    /// One step from `now` (contact state `st`) to `now.time + dt`, with the tractions at
    /// `scale` and the pilot driven by `control` at the step's end.
    ///
    /// The load of the step's contact problem `(K + c M) u_{n+1} = f + r_{n+1}`:
    /// ```text
    ///   f = T_{n+1} + f_P + αf/(1−αf) (T_n + r_n − k(u_n)) + 1/(1−αf) M h_n,
    ///   h_n = (1−αm)/(βΔt²) (u_n + Δt v_n) + ((1−αm)(1/(2β) − 1) − αm) a_n,
    /// ```
    /// where `f_P` are the forces of the prescribed values through `K + c M` (the prescribed
    /// DOFs' share of `M h_n` cancels their `c M` part: they do not move).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        now: &TimeState,
        st: Option<&State>,
        scale: f64,
        control: [Control; 2],
        law: Option<&FrictionLaw>,
        opt: Option<&solver::Options>,
    ) -> Result<Stepped, StepError> {
        let Scheme {
            alpha_m: am,
            alpha_f: af,
            beta: b,
            gamma: g,
            ..
        } = self.scheme;
        let dt = self.dt;
        let m = &self.model;
        let n = now.u.len();
        let n_i = m.dofs.n_interior;
        // αf/(1−αf) (T_n + r_n − k(u_n)) + 1/(1−αf) M h_n, element by element.
        let ch = (1.0 - am) / (b * dt * dt);
        let ca = (1.0 - am) * (0.5 / b - 1.0) - am;
        let mut f = vec![0.0; n];
        {
            let (u, v, a) = (&now.u, &now.v, &now.a);
            let table = m.element_dof_table();
            let n_free = n;
            self.masses.apply_with(
                m,
                |i| {
                    let ue = m.element_u(i, u);
                    std::array::from_fn(|k| {
                        let d = table[i][k] as usize;
                        let (vk, ak) = if d < n_free { (v[d], a[d]) } else { (0.0, 0.0) };
                        ch * (ue[k] + dt * vk) + ca * ak
                    })
                },
                &mut f,
            );
        }
        f.iter_mut().for_each(|x| *x /= 1.0 - af);
        if af != 0.0 {
            let w = af / (1.0 - af);
            let mut k_u = vec![0.0; n];
            let table = m.element_dof_table();
            for (row, fe) in table.iter().zip(m.map_element_forces(&now.u, |f| f.fe)) {
                for k in 0..12 {
                    let d = row[k] as usize;
                    if d < n {
                        k_u[d] += fe[k];
                    }
                }
            }
            for d in 0..n {
                f[d] += w * (now.scale * m.f_traction[d] - k_u[d]);
            }
            for (k, r) in now.r.iter().enumerate() {
                f[n_i + k] += w * r;
            }
        }
        for d in 0..n {
            f[d] += scale * m.f_traction[d] + m.f_prescribed[d];
        }
        // The contact (or the pilot) at t_{n+1}.
        let (u1, contact, pilot, r1, iterations) = match (&m.contact, st) {
            (Some(cm), Some(st)) => {
                let opt = opt.expect("a contact model has solver options");
                let w0 = cm.w0(&m.condensed, &f);
                let drive = control.map(|c| match c {
                    Control::Force(f) => PilotDrive::Force(f),
                    Control::Displacement(d) => PilotDrive::Displacement(d),
                    Control::Slip(s) => PilotDrive::Slip(s),
                });
                let out = cm
                    .system
                    .solve_step(&w0, drive, law, st, None, opt, Some(&mut self.lu))
                    .map_err(StepError::Contact)?;
                let rf = cm.retained_forces(&out.state, m.dofs.n_retained);
                let mut u1 = m
                    .condensed
                    .recover_total_many(&[(f, rf)], true)
                    .pop()
                    .expect("one field");
                u1.truncate(n);
                let r1 = physical_retained(m, &out.state, &u1);
                let pilot = m.dofs.pilot.map(|_| PilotState {
                    ux: out.state.pilot_u[0],
                    uy: out.state.pilot_u[1],
                    fx: out.state.pilot_f[0],
                    fy: out.state.pilot_f[1],
                });
                (u1, Some(out.state), pilot, r1, out.iterations)
            }
            _ => {
                let cond = &m.condensed;
                if m.dofs.pilot.is_none() {
                    let u1 = cond.recover(&f, &[], &[]);
                    let r1 = vec![0.0; m.dofs.n_retained];
                    (u1, None, None, r1, 1)
                } else {
                    let gr = cond.reduce(&f);
                    let (up, rp) = crate::model::step::solve_pilot(
                        &cond.s_dense(),
                        &gr,
                        control,
                        cond.krr_scale,
                    )?;
                    let u1 = cond.recover(&f, &rp, &up);
                    let pilot = PilotState {
                        ux: up[0],
                        uy: up[1],
                        fx: rp[0],
                        fy: rp[1],
                    };
                    (u1, None, Some(pilot), rp.to_vec(), 1)
                }
            }
        };
        // Newmark's updates.
        let mut a1 = vec![0.0; n];
        let mut v1 = vec![0.0; n];
        for d in 0..n {
            a1[d] = (u1[d] - now.u[d] - dt * now.v[d]) / (b * dt * dt) - (0.5 / b - 1.0) * now.a[d];
            v1[d] = now.v[d] + dt * ((1.0 - g) * now.a[d] + g * a1[d]);
        }
        let kinetic = self.masses.kinetic(m, &v1);
        Ok(Stepped {
            time: TimeState {
                time: now.time + dt,
                dt,
                scale,
                u: u1,
                v: v1,
                a: a1,
                r: r1,
                kinetic,
                pilot,
            },
            contact,
            iterations,
        })
    }
}

/// The physical forces on the retained DOFs of contact state `st` of `model` with free
/// displacements `u`: `Yᵀ μ` less the grounding springs' forces `k_g u` that the anchor
/// unknowns include.
pub fn physical_retained(model: &Model, st: &State, u: &[f64]) -> Vec<f64> {
    let cm = model.contact.as_ref().expect("a contact model");
    let mut r = cm.retained_forces(st, model.dofs.n_retained);
    let n_i = model.condensed.n_i;
    for &(k, kg) in &model.condensed.grounding {
        r[k] -= kg * u[n_i + k];
    }
    r
}
