//! The contact problem on the contact unknowns alone.
//!
//! The elastic bodies are condensed onto the retained DOFs `R` (contact nodes and pilot):
//! `Ŝ u_R = g + r_R` (see [`crate::condense`]). The contact and pilot forces enter as
//! `r_R = Yᵀ μ` with `Y = [Ĝ; T̂; E_Pᵀ]` and unknowns `μ = (F_n, F_t, z)`: nodal normal forces,
//! nodal tangential forces on the master side, and the pilot's force plus its grounding spring
//! force `z = r_P + k_g u_P`. Then
//! ```text
//!   Y u_R = w0 + W μ,   W = Y Ŝ⁻¹ Yᵀ = Zᵀ Z,   Z = L_RR⁻¹ Yᵀ,   w0 = Zᵀ L_RR⁻¹ g,
//! ```
//! gives every nodal gap `ĝ = g0 + (Y u_R)_n`, relative tangential displacement
//! `v̂ = (Y u_R)_t` and the pilot displacement from `μ` alone. `W` (the Delassus operator) is
//! dense and small and is built once per model; each Newton iteration is a dense solve on the
//! active unknowns.
//!
//! Complementarity at each slave node j (forces, gaps and slips are nodal quantities):
//! * normal: `F_n ≥ 0, ĝ ≥ 0, F_n ĝ = 0`, written `F_n − max(0, F_n − c ĝ) = 0`;
//! * friction (Coulomb with `μ_j = f(U_j)` of the accumulated slip `U_j`): stick
//!   (`Δv̂ = 0`) while `|F_t − c Δv̂| < μ_j (F_n − c ĝ)`, else slip with
//!   `F_t = μ_j F_n sign(F_t − c Δv̂)` (the force on the master opposes its slip).
//!
//! `c = E*` (the composite plane-strain modulus) makes the complementarity functions
//! homogeneous in force per length, so iterates do not depend on the units. In 2-D the
//! semi-smooth Newton method on these functions is the primal–dual active-set method: each
//! iteration fixes the sets (inactive / stick / slip) from the current iterate and solves the
//! linear equations they imply; it has converged when the sets no longer change and the
//! update is small. The penalty and augmented-Lagrangian methods solve the same equations with
//! `F_n = ε max(0, −ĝ)` (and an elastic tangential spring), the latter with an outer update of
//! the multiplier estimate until the penetration is below tolerance.

use crate::friction::FrictionLaw;
use faer::Mat;
use faer::linalg::solvers::Solve;

/// How the contact conditions are enforced.
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Semi-smooth Newton (primal–dual active set) on the complementarity functions: exact.
    Newton,
    /// Penalty: `F_n = ε max(0, −ĝ)`, tangential spring `ε`; `ε = κ E* w_j / h_j`.
    Penalty,
    /// Augmented Lagrangian: penalty with an outer multiplier update (Uzawa) until the largest
    /// penetration is below `tolerance × h`.
    AugmentedLagrangian,
}

/// Contact state of a slave node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Open,
    Stick,
    Slip,
}

impl Status {
    pub fn code(self) -> f64 {
        match self {
            Status::Open => 0.0,
            Status::Stick => 1.0,
            Status::Slip => 2.0,
        }
    }
}

/// How a pilot component is driven in a solve.
#[derive(Clone, Copy, Debug)]
pub enum PilotDrive {
    Force(f64),
    Displacement(f64),
    /// The x component only: the pilot force is whatever makes the mean slip
    /// ([`State::mean_slip`]) reach this value. Slip grows monotonically towards gross
    /// sliding, also on the softening branch past the peak tangential force, where both the
    /// force and the pilot displacement turn back (indirect displacement control).
    Slip(f64),
}

/// The converged contact state after a step (and the committed history).
#[derive(Clone, Debug)]
pub struct State {
    pub f_n: Vec<f64>,
    pub f_t: Vec<f64>,
    /// Anchor unknowns: force on each grounded DOF plus its spring force (pilot first).
    pub z: Vec<f64>,
    /// Relative tangential displacement v̂ (master minus slave).
    pub v: Vec<f64>,
    /// Accumulated slip U.
    pub slip: Vec<f64>,
    /// Slip increment of the last step (signed).
    pub dv: Vec<f64>,
    pub gap: Vec<f64>,
    pub status: Vec<Status>,
    pub mu: Vec<f64>,
    /// Pilot displacement and force.
    pub pilot_u: [f64; 2],
    pub pilot_f: [f64; 2],
    /// Mean slip: the sum over steps of the weighted mean of the slip increments `Δv̂` of the
    /// nodes in contact at the start of each step (weights: mortar weights), signed so that it
    /// grows when the pilot is pushed in +x. The quantity driven by [`PilotDrive::Slip`].
    pub mean_slip: f64,
}

/// One iteration's data for [`ContactSystem::newton_system`].
#[derive(Clone, Copy)]
pub struct Iterate<'a> {
    /// Substitute the tangential force of slip nodes with μ′ = 0 (`F_t = ±μ F_n`).
    pub substitute: bool,
    pub w0: &'a [f64],
    pub drive: [PilotDrive; 2],
    pub law: Option<&'a FrictionLaw>,
    pub prev: &'a State,
    /// Current forces μ = (F_n, F_t, z).
    pub mu: &'a [f64],
    pub status: &'a [Status],
    /// Slip direction per node (sign of the master's tangential force).
    pub sign: &'a [f64],
    pub method: Method,
    pub eps: &'a [f64],
    pub fbar_n: &'a [f64],
    pub fbar_t: &'a [f64],
}

/// The linear system of one Newton iteration.
pub struct NewtonSystem {
    pub a: Mat<f64>,
    pub b: Mat<f64>,
    /// μ index of each unknown.
    pub unk: Vec<usize>,
    /// Slip nodes whose tangential force is substituted (`s μ F_n`).
    pub substituted: Vec<bool>,
    /// Per node: (μ_k, μ'_k, Δv_k, σ) of the slip linearisation.
    pub slip_lin: Vec<(f64, f64, f64, f64)>,
}

/// The Newton system of one iteration in the structured form [`LuCache::solve_rows`] solves
/// without assembling it (see [`ContactSystem::newton_rows`]): row `r` of the matrix is row `r`
/// of `K = W[unk, unk]`, except for the rows in `special`.
pub struct NewtonRows {
    /// μ index of each unknown: every contact node's normal and (with friction) tangential
    /// force, then the anchors; none substituted, so this depends on the contact set only.
    pub unk: Vec<usize>,
    pub b: Vec<f64>,
    /// The rows that differ from `K` (slip nodes, force-driven anchors), in increasing order.
    pub special: Vec<SpecialRow>,
}

/// Row `row` of a [`NewtonRows`] matrix: `α e_row + β K_row + γ e_col`, or, when `combo` is
/// not empty, `α e_row + Σ c K_t + γ e_col` over its `(t, c)` (β unused): the slip-control
/// row, a weighted sum of the tangential rows of the nodes in contact.
#[derive(Clone, Debug)]
pub struct SpecialRow {
    pub row: usize,
    pub alpha: f64,
    pub beta: f64,
    pub gamma: f64,
    pub col: usize,
    pub combo: Vec<(usize, f64)>,
}

/// The condensed contact operator.
pub struct ContactSystem {
    pub ns: usize,
    /// Whether the first two anchors are the pilot's (x, y) DOFs.
    pub has_pilot: bool,
    /// Delassus operator `W` (m × m), m = 2 ns (+ 2 with a pilot).
    pub w: Mat<f64>,
    /// `Z = L_RR⁻¹ Yᵀ` (n_R × m).
    pub z: Mat<f64>,
    /// Nodal initial gaps (including the effect of prescribed displacements).
    pub gap0: Vec<f64>,
    /// Constant tangential offsets from prescribed displacements.
    pub v0: Vec<f64>,
    /// Complementarity constant `c = E*`.
    pub c: f64,
    /// Per node penalty stiffness for κ = 1: `E* w_j / h_j`.
    pub eps_unit: Vec<f64>,
    /// Grounding springs of the anchors: the pilot's DOFs, then DOFs of bodies held by contact
    /// alone (driven at zero force).
    pub kg: Vec<f64>,
    /// Mortar weight of each slave node (its share of the slave face length).
    pub weight: Vec<f64>,
    /// +1 or −1: the sign of the slips' response to a pilot force in +x, so that
    /// [`State::mean_slip`] grows in the direction the pilot is pushed.
    pub slip_orient: f64,
    /// Whether the pilot drives a body that no support holds (only the contact can).
    pub floating_pilot: bool,
}

/// Puts the three nodes of smallest gap in contact (stick with friction, else slip): three
/// nodes span both sides of the closest point, which holds a body the pilot pushes and stops a
/// frictionless rigid sliding mode.
fn seed_closest(gaps: &[f64], friction: bool, status: &mut [Status]) {
    let mut order: Vec<usize> = (0..gaps.len()).collect();
    order.sort_by(|&a, &b| gaps[a].total_cmp(&gaps[b]));
    for &j in order.iter().take(3) {
        status[j] = if friction {
            Status::Stick
        } else {
            Status::Slip
        };
    }
}

/// Options of a contact solve.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    pub method: Method,
    /// Penalty factor κ (penalty and augmented Lagrangian).
    pub kappa: f64,
    pub max_iterations: usize,
    /// Relative tolerance on the update of the forces (Newton), and on the penetration
    /// relative to the element size (augmented Lagrangian).
    pub tolerance: f64,
    /// Print every iteration (sets and update) to standard error.
    pub verbose: bool,
}

/// Result of one step solve.
#[derive(Clone, Debug)]
pub struct StepOutcome {
    pub state: State,
    pub iterations: usize,
    /// Largest |update| / max |force| at the last iteration.
    pub last_update: f64,
}

/// Why a step did not converge.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ContactError {
    #[error(
        "the contact Newton iteration did not converge in {iterations} iterations (last relative update {update:.2e}, {changes} nodes still changing state)"
    )]
    NoConvergence {
        iterations: usize,
        update: f64,
        changes: usize,
    },
    #[error("the contact equations became singular: {0}")]
    Singular(String),
}

impl ContactSystem {
    /// `y = w0 + W μ`.
    fn y(&self, w0: &[f64], mu: &[f64]) -> Vec<f64> {
        let m = w0.len();
        let mut y = w0.to_vec();
        for (j, &mj) in mu.iter().enumerate() {
            if mj != 0.0 {
                let col = self.w.col(j);
                for i in 0..m {
                    y[i] += col[i] * mj;
                }
            }
        }
        y
    }

    fn m(&self) -> usize {
        2 * self.ns + self.kg.len()
    }

    /// An initial state before any load: no contact force, zero slip.
    pub fn initial_state(&self) -> State {
        let ns = self.ns;
        State {
            f_n: vec![0.0; ns],
            f_t: vec![0.0; ns],
            z: vec![0.0; self.kg.len()],
            v: self.v0.clone(),
            slip: vec![0.0; ns],
            dv: vec![0.0; ns],
            gap: self.gap0.clone(),
            status: vec![Status::Open; ns],
            mu: vec![0.0; ns],
            pilot_u: [0.0; 2],
            pilot_f: [0.0; 2],
            mean_slip: 0.0,
        }
    }

    /// The weights `ω_j` of the mean slip for a step from `prev`: normalised mortar weights of
    /// the nodes in contact, times [`Self::slip_orient`] (all zero with no node in contact).
    pub fn slip_weights(&self, prev: &State) -> Vec<f64> {
        let on = |j: usize| prev.status[j] != Status::Open;
        let total: f64 = (0..self.ns)
            .filter(|&j| on(j))
            .map(|j| self.weight[j])
            .sum();
        (0..self.ns)
            .map(|j| {
                if on(j) && total > 0.0 {
                    self.slip_orient * self.weight[j] / total
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Solves one load step from the committed state `prev`, with the condensed load `w0`
    /// (from the bodies' loads), the pilot drive, and friction law `law` (`None`: frictionless).
    ///
    /// `guess`: predicted forces for this step (e.g. extrapolated from the last two steps); the
    /// first active sets are taken from it instead of from the committed state.
    ///
    /// `cache`: factorisations kept from earlier iterations and steps. With the Newton method (and
    /// a force- or displacement-driven pilot) each Newton system is solved from a cached Cholesky
    /// factor of the Delassus block `K = W[unk, unk]`, which depends on the contact set only, plus
    /// a small capacitance system for the rows that differ from `K` (slip nodes, force-driven
    /// anchors): see [`LuCache::solve_rows`]. Through a tangential ramp the contact set hardly
    /// changes, so one factorisation serves many steps and no dense Newton matrix is assembled.
    /// Otherwise (penalty, augmented Lagrangian, other drives) the dense system is solved by GMRES
    /// preconditioned with the cached LU of an earlier dense system, refactorised when GMRES needs
    /// more than a handful of iterations. Either way the tangential forces of slip nodes are kept
    /// as unknowns (not substituted) so that the unknowns do not change with every stick/slip
    /// change.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_step(
        &self,
        w0: &[f64],
        drive: [PilotDrive; 2],
        law: Option<&FrictionLaw>,
        prev: &State,
        guess: Option<&State>,
        opt: &Options,
        mut cache: Option<&mut LuCache>,
    ) -> Result<StepOutcome, ContactError> {
        let ns = self.ns;
        let m = self.m();
        assert_eq!(w0.len(), m);
        let c = self.c;
        let eps: Vec<f64> = self.eps_unit.iter().map(|e| e * opt.kappa).collect();
        // Unknowns μ = (F_n, F_t, z); warm start from the committed state.
        let start = guess.unwrap_or(prev);
        let mut mu = vec![0.0; m];
        mu[..ns].copy_from_slice(&start.f_n);
        mu[ns..2 * ns].copy_from_slice(&start.f_t);
        mu[2 * ns..].copy_from_slice(&start.z);
        // Multiplier estimates of the augmented Lagrangian.
        let mut fbar_n = prev.f_n.clone();
        let mut fbar_t = prev.f_t.clone();
        let mut status: Vec<Status> = prev.status.clone();
        // With no node in contact yet, start from the closest nodes so that the first linear
        // system holds the body that the pilot pushes (three nodes span both sides of the
        // first touch, which also stops a frictionless rigid sliding mode).
        if status.iter().all(|s| *s == Status::Open) {
            seed_closest(&self.gap0, law.is_some(), &mut status);
        }
        // Slip directions of the warm start: the sign of the committed tangential force.
        let mut sign: Vec<f64> = start
            .f_t
            .iter()
            .map(|f| if *f < 0.0 { -1.0 } else { 1.0 })
            .collect();
        let mut last_update = f64::INFINITY;
        let mut solved = false;
        // `W μ` of the current iterate when the last solve gave it.
        let mut w_mu: Option<Vec<f64>> = None;
        // Iterations in a row with the sets settled and the update small but above the
        // tolerance, and whether the structured solve has been given up for this step: its
        // accuracy (a Woodbury update of a cached factor, `W μ` taken from the equations) can
        // floor the update near 1e-8 on ill-conditioned systems (a steep μ′ with many slip
        // nodes), where the dense LU still converges.
        let (mut stalled, mut dense_only) = (0usize, false);
        // Iterations in a row with the sets fixed and the update not contracting (Newton
        // cycling across a kink of μ(u), e.g. the end of a ramp, where μ′ jumps), and the
        // relaxation applied to the update once that is detected.
        let (mut cycling, mut relax, mut prev_update) = (0usize, 1.0f64, f64::INFINITY);
        for it in 1..=opt.max_iterations {
            let y = match w_mu.take() {
                Some(w_mu) => w0.iter().zip(&w_mu).map(|(a, b)| a + b).collect(),
                None => self.y(w0, &mu),
            };
            // Sets from the current iterate (without a guess, the first iteration keeps the
            // committed sets).
            let mut changes = 0;
            if solved || guess.is_some() {
                for j in 0..ns {
                    let gap = self.gap0[j] + y[j];
                    let dv = y[ns + j] - prev.v[j];
                    let xi_n = match opt.method {
                        Method::Newton => mu[j] - c * gap,
                        Method::Penalty => -eps[j] * gap,
                        Method::AugmentedLagrangian => fbar_n[j] - eps[j] * gap,
                    };
                    let new = if xi_n <= 0.0 {
                        Status::Open
                    } else if let Some(law) = law {
                        let mu_j = law.mu(prev.slip[j] + dv.abs());
                        let xi_t = match opt.method {
                            Method::Newton => mu[ns + j] - c * dv,
                            Method::Penalty => prev.f_t[j] - eps[j] * dv,
                            Method::AugmentedLagrangian => fbar_t[j] - eps[j] * dv,
                        };
                        if xi_t.abs() < mu_j * xi_n {
                            Status::Stick
                        } else {
                            sign[j] = xi_t.signum();
                            Status::Slip
                        }
                    } else {
                        Status::Slip
                    };
                    if new != status[j] {
                        changes += 1;
                        status[j] = new;
                    }
                }
                // A force-driven pilot body that only the contact holds has no equilibrium with
                // every node open (the system is singular): an iterate that opens them all
                // overshot, so the closest nodes close again, as at the start of a step.
                let forced = drive.iter().any(|d| matches!(d, PilotDrive::Force(_)));
                if self.floating_pilot && forced && status.iter().all(|s| *s == Status::Open) {
                    let gaps: Vec<f64> = (0..ns).map(|j| self.gap0[j] + y[j]).collect();
                    seed_closest(&gaps, law.is_some(), &mut status);
                    changes += 1;
                }
                if opt.verbose {
                    let count = |st: Status| status.iter().filter(|s| **s == st).count();
                    eprintln!(
                        "    Newton iteration {it}: {} in contact ({} stick, {} slip), {changes} changed state, relative update {last_update:.2e}",
                        ns - count(Status::Open),
                        count(Status::Stick),
                        count(Status::Slip)
                    );
                }
                // With the sets unchanged the last linear solve is the answer when the equations
                // are linear in the sets (constant μ); a slip-dependent μ also needs a small update.
                let linear = law.is_none_or(|l| matches!(l, FrictionLaw::Constant { .. }));
                let converged_inner =
                    solved && changes == 0 && (linear || last_update <= opt.tolerance);
                if converged_inner {
                    if opt.method == Method::AugmentedLagrangian {
                        // Outer update: stop when the penetration is small.
                        let pen = (0..ns)
                            .filter(|&j| status[j] != Status::Open)
                            .map(|j| (-(self.gap0[j] + y[j])).max(0.0) / self.eps_h(j))
                            .fold(0.0, f64::max);
                        if pen <= opt.tolerance {
                            return Ok(self.finish(w0, &mu, &status, law, prev, it, last_update));
                        }
                        fbar_n.copy_from_slice(&mu[..ns]);
                        fbar_t.copy_from_slice(&mu[ns..2 * ns]);
                    } else {
                        return Ok(self.finish(w0, &mu, &status, law, prev, it, last_update));
                    }
                }
                if changes == 0 && last_update > 1e-5 && last_update >= 0.5 * prev_update {
                    cycling += 1;
                    if cycling >= 3 && relax == 1.0 {
                        relax = 0.5;
                        if opt.verbose {
                            eprintln!(
                                "    the update does not contract ({last_update:.2e}): halving the steps from here on"
                            );
                        }
                    }
                } else {
                    cycling = 0;
                }
                prev_update = last_update;
                if changes == 0 && last_update < 1e-5 {
                    stalled += 1;
                    if stalled >= 2 && !dense_only {
                        dense_only = true;
                        if opt.verbose {
                            eprintln!(
                                "    the update stalls at {last_update:.2e}: solving the assembled system from here on"
                            );
                        }
                    }
                } else {
                    stalled = 0;
                }
                if it == opt.max_iterations {
                    return Err(ContactError::NoConvergence {
                        iterations: it,
                        update: last_update,
                        changes,
                    });
                }
            }
            self.seed_slip(drive, prev, &mut status, &mut sign);
            solved = true;
            let it_ctx = Iterate {
                substitute: cache.is_none(),
                w0,
                drive,
                law,
                prev,
                mu: &mu,
                status: &status,
                sign: &sign,
                method: opt.method,
                eps: &eps,
                fbar_n: &fbar_n,
                fbar_t: &fbar_t,
            };
            let new_mu = 'solve: {
                // The structured solve; on any trouble (a singular block, a non-finite answer)
                // the dense system below decides.
                if let Some(c) = cache
                    .as_deref_mut()
                    .filter(|_| m >= STRUCTURED_MIN && !dense_only)
                    && let Some(rows) = self.newton_rows(&it_ctx)
                    && let Some((x, w_mu_new)) = c.solve_rows(&self.w, &rows, it == 1)
                {
                    let mut new_mu = vec![0.0; m];
                    for (q, &u) in rows.unk.iter().enumerate() {
                        new_mu[u] = x[q];
                    }
                    w_mu = Some(w_mu_new);
                    break 'solve new_mu;
                }
                let NewtonSystem {
                    a,
                    b,
                    unk,
                    substituted,
                    slip_lin,
                } = self.newton_system(&it_ctx);
                let nu = unk.len();
                let x = match cache.as_deref_mut() {
                    Some(c) => c.solve(&unk, &a, &b),
                    None => {
                        let lu = a.partial_piv_lu();
                        let x = lu.solve(&b);
                        if singular_pivots(&lu) { None } else { Some(x) }
                    }
                };
                let bad = x
                    .as_ref()
                    .is_none_or(|x| (0..nu).any(|i| !x[(i, 0)].is_finite()));
                if bad {
                    if let Some(c) = cache.as_deref_mut() {
                        c.clear();
                    }
                    return Err(ContactError::Singular(format!(
                        "{} unknowns, {} in contact; a body may be free to move in a direction no contact or support holds",
                        nu,
                        status.iter().filter(|s| **s != Status::Open).count()
                    )));
                }
                let x = x.expect("checked above");
                let mut new_mu = vec![0.0; m];
                for (q, &u) in unk.iter().enumerate() {
                    new_mu[u] = x[(q, 0)];
                }
                for j in 0..ns {
                    if substituted[j] && status[j] == Status::Slip {
                        new_mu[ns + j] = sign[j] * slip_lin[j].0 * new_mu[j];
                    }
                }
                new_mu
            };
            let new_mu: Vec<f64> = if relax < 1.0 {
                // `W μ` from the solve belongs to the full step: recompute it.
                w_mu = None;
                mu.iter()
                    .zip(&new_mu)
                    .map(|(o, n)| o + relax * (n - o))
                    .collect()
            } else {
                new_mu
            };
            let scale = new_mu[..2 * ns]
                .iter()
                .fold(0.0f64, |a, v| a.max(v.abs()))
                .max(f64::MIN_POSITIVE);
            last_update = (0..2 * ns)
                .map(|i| (new_mu[i] - mu[i]).abs())
                .fold(0.0, f64::max)
                / scale;
            mu = new_mu;
        }
        unreachable!("the loop returns")
    }

    /// The Newton system of one iteration with the sets fixed: `A x = b` over the unknowns
    /// `unk` (μ indices), with the tangential force of `substituted` slip nodes folded into
    /// their normal force column.
    pub fn newton_system(&self, it: &Iterate) -> NewtonSystem {
        let Iterate {
            w0,
            drive,
            law,
            prev,
            mu,
            status,
            sign,
            method,
            eps,
            fbar_n,
            fbar_t,
            ..
        } = *it;
        let ns = self.ns;
        let m = self.m();
        let opt_method = method;
        // Slip nodes whose μ does not change with slip at the iterate (constant law, or past
        // the weakening): their tangential force is s μ F_n exactly, so it is substituted
        // rather than solved for.
        let mut slip_lin = vec![(0.0, 0.0, 0.0, 0.0); ns]; // (μ_k, μ'_k, Δv_k, σ)
        let mut substituted = vec![false; ns];
        if let Some(law) = law {
            for j in 0..ns {
                if status[j] == Status::Slip {
                    let dv_k = self.y_at(w0, mu, ns + j) - prev.v[j];
                    let u_k = prev.slip[j] + dv_k.abs();
                    let dmu = law.dmu_du(u_k).unwrap_or(0.0);
                    let sigma = if dv_k != 0.0 { dv_k.signum() } else { -sign[j] };
                    slip_lin[j] = (law.mu(u_k), dmu, dv_k, sigma);
                    substituted[j] = it.substitute && (dmu == 0.0 || mu[j] == 0.0);
                }
            }
        }
        // Unknowns of this iteration, and how each μ component maps onto them:
        // (μ index, unknown position, factor).
        let mut pos = vec![usize::MAX; m];
        let mut unk = Vec::new();
        let mut cols: Vec<(usize, usize, f64)> = Vec::new();
        for j in 0..ns {
            if status[j] != Status::Open {
                pos[j] = unk.len();
                cols.push((j, unk.len(), 1.0));
                unk.push(j);
            }
        }
        if law.is_some() {
            for j in 0..ns {
                if status[j] == Status::Open {
                    continue;
                }
                if substituted[j] {
                    cols.push((ns + j, pos[j], sign[j] * slip_lin[j].0));
                } else {
                    pos[ns + j] = unk.len();
                    cols.push((ns + j, unk.len(), 1.0));
                    unk.push(ns + j);
                }
            }
        }
        for k in 0..self.kg.len() {
            pos[2 * ns + k] = unk.len();
            cols.push((2 * ns + k, unk.len(), 1.0));
            unk.push(2 * ns + k);
        }
        let nu = unk.len();
        let mut a = Mat::<f64>::zeros(nu, nu);
        let mut b = Mat::<f64>::zeros(nu, 1);
        // Row i of W over the unknowns; W is symmetric, so read its column i (contiguous).
        let wrow = |a: &mut Mat<f64>, r: usize, i: usize, scale: f64| {
            let col = self.w.col(i);
            for &(mi, q, f) in &cols {
                a[(r, q)] += scale * f * col[mi];
            }
        };
        for (r, &u) in unk.iter().enumerate() {
            if u < ns {
                let j = u;
                let rhs = -(self.gap0[j] + w0[j]);
                match opt_method {
                    Method::Newton => {
                        wrow(&mut a, r, j, 1.0);
                        b[(r, 0)] = rhs;
                    }
                    Method::Penalty | Method::AugmentedLagrangian => {
                        // F_n + ε ĝ = F̄ (F̄ = 0 for the penalty method)
                        a[(r, r)] += 1.0;
                        wrow(&mut a, r, j, eps[j]);
                        let fb = if opt_method == Method::Penalty {
                            0.0
                        } else {
                            fbar_n[j]
                        };
                        b[(r, 0)] = fb + eps[j] * rhs;
                    }
                }
            } else if u < 2 * ns {
                let j = u - ns;
                let vrhs = prev.v[j] - w0[u]; // Δv̂ = 0 ⇔ (W μ)_t = v_old − w0_t
                match status[j] {
                    Status::Stick => match opt_method {
                        Method::Newton => {
                            wrow(&mut a, r, u, 1.0);
                            b[(r, 0)] = vrhs;
                        }
                        Method::Penalty | Method::AugmentedLagrangian => {
                            // F_t = F̄_t − ε Δv̂
                            a[(r, r)] += 1.0;
                            wrow(&mut a, r, u, eps[j]);
                            let fb = if opt_method == Method::Penalty {
                                prev.f_t[j]
                            } else {
                                fbar_t[j]
                            };
                            b[(r, 0)] = fb - eps[j] * (w0[u] - prev.v[j]);
                        }
                    },
                    Status::Slip => {
                        // F_t = s μ(U + |Δv̂|) F_n, linearised at the current iterate:
                        // F_t − s μ_k F_n − s F_n,k μ'_k σ (Δv̂ − Δv̂_k) = 0.
                        let (mu_k, dmu, dv_k, sigma) = slip_lin[j];
                        let s_j = sign[j];
                        a[(r, r)] += 1.0;
                        a[(r, pos[j])] -= s_j * mu_k;
                        let coef = s_j * mu[j] * dmu * sigma;
                        wrow(&mut a, r, u, -coef);
                        b[(r, 0)] = coef * (w0[u] - prev.v[j] - dv_k);
                    }
                    Status::Open => unreachable!(),
                }
            } else {
                let k = u - 2 * ns;
                let d = self.anchor_drive(drive, k);
                match d {
                    PilotDrive::Force(f) => {
                        a[(r, r)] += 1.0;
                        wrow(&mut a, r, u, -self.kg[k]);
                        b[(r, 0)] = f + self.kg[k] * w0[u];
                    }
                    PilotDrive::Displacement(d) => {
                        wrow(&mut a, r, u, 1.0);
                        b[(r, 0)] = d - w0[u];
                    }
                    PilotDrive::Slip(target) => {
                        // Σ ω_j (v̂_j − v̂_j,old) = target − mean slip, v̂ = w0_t + (W μ)_t.
                        let omega = self.slip_weights(prev);
                        let mut rhs = target - prev.mean_slip;
                        for (j, &o) in omega.iter().enumerate() {
                            if o != 0.0 {
                                wrow(&mut a, r, ns + j, o);
                                rhs -= o * (w0[ns + j] - prev.v[j]);
                            }
                        }
                        b[(r, 0)] = rhs;
                    }
                }
            }
        }
        NewtonSystem {
            a,
            b,
            unk,
            substituted,
            slip_lin,
        }
    }

    /// The residual of the Newton method's equations for the fixed sets of `it`, at the
    /// unknowns `x` (ordered as `unk` of [`Self::newton_system`]): its Jacobian is `A`.
    pub fn newton_residual(&self, it: &Iterate, sys: &NewtonSystem, x: &[f64]) -> Vec<f64> {
        let ns = self.ns;
        let mut mu = vec![0.0; self.m()];
        for (q, &u) in sys.unk.iter().enumerate() {
            mu[u] = x[q];
        }
        let law = it.law;
        for j in 0..ns {
            if sys.substituted[j] && it.status[j] == Status::Slip {
                mu[ns + j] = it.sign[j] * sys.slip_lin[j].0 * mu[j];
            }
        }
        let y = self.y(it.w0, &mu);
        sys.unk
            .iter()
            .map(|&u| {
                if u < ns {
                    self.gap0[u] + y[u]
                } else if u < 2 * ns {
                    let j = u - ns;
                    let dv = y[u] - it.prev.v[j];
                    match it.status[j] {
                        Status::Stick => dv,
                        _ => {
                            let l = law.expect("friction");
                            mu[u] - it.sign[j] * l.mu(it.prev.slip[j] + dv.abs()) * mu[j]
                        }
                    }
                } else {
                    let k = u - 2 * ns;
                    let d = self.anchor_drive(it.drive, k);
                    match d {
                        PilotDrive::Force(f) => mu[u] - self.kg[k] * y[u] - f,
                        PilotDrive::Displacement(d) => y[u] - d,
                        PilotDrive::Slip(target) => {
                            let omega = self.slip_weights(it.prev);
                            let dm: f64 =
                                (0..ns).map(|j| omega[j] * (y[ns + j] - it.prev.v[j])).sum();
                            it.prev.mean_slip + dm - target
                        }
                    }
                }
            })
            .collect()
    }

    /// Under slip control the slip constraint contradicts a contact that sticks everywhere
    /// (the system is singular): when no node in contact slips, the two outermost nodes in
    /// contact start slipping in the driven direction, and the iteration finds the slip zones
    /// from there.
    fn seed_slip(
        &self,
        drive: [PilotDrive; 2],
        prev: &State,
        status: &mut [Status],
        sign: &mut [f64],
    ) {
        let PilotDrive::Slip(target) = drive[0] else {
            return;
        };
        let dm = target - prev.mean_slip;
        if !self.has_pilot || dm == 0.0 || status.contains(&Status::Slip) {
            return;
        }
        let on: Vec<usize> = (0..self.ns)
            .filter(|&j| status[j] != Status::Open)
            .collect();
        if let (Some(&first), Some(&last)) = (on.first(), on.last()) {
            for j in [first, last] {
                status[j] = Status::Slip;
                // The master's tangential force opposes its slip.
                sign[j] = -self.slip_orient * dm.signum();
            }
        }
    }

    /// The system of [`Self::newton_system`] for the Newton method, without substitution, in
    /// structured form: normal, stick and displacement-driven anchor rows are rows of
    /// `K = W[unk, unk]`; a slip row is `F_t − s μ_k F_n − coef (W μ)_t` and a force-driven
    /// anchor row `z − k_g (W μ)_z`, i.e. `α e_r + β K_r + γ e_q`. `None` for the penalty and
    /// augmented-Lagrangian methods (every normal row would be special) and for any other
    /// pilot drive: the caller then assembles the dense system.
    pub fn newton_rows(&self, it: &Iterate) -> Option<NewtonRows> {
        if it.method != Method::Newton {
            return None;
        }
        let ns = self.ns;
        let (w0, prev, mu, status, sign) = (it.w0, it.prev, it.mu, it.status, it.sign);
        let active: Vec<usize> = (0..ns).filter(|&j| status[j] != Status::Open).collect();
        let mut unk = active.clone();
        if it.law.is_some() {
            unk.extend(active.iter().map(|&j| ns + j));
        }
        unk.extend((0..self.kg.len()).map(|k| 2 * ns + k));
        let mut b = vec![0.0; unk.len()];
        let mut special = Vec::new();
        for (r, &u) in unk.iter().enumerate() {
            if u < ns {
                b[r] = -(self.gap0[u] + w0[u]);
            } else if u < 2 * ns {
                let j = u - ns;
                match status[j] {
                    Status::Stick => b[r] = prev.v[j] - w0[u],
                    Status::Slip => {
                        // As in `newton_system`: F_t − s μ_k F_n − s F_n,k μ'_k σ (Δv̂ − Δv̂_k) = 0.
                        let law = it.law.expect("tangential unknowns only with friction");
                        let dv_k = self.y_at(w0, mu, u) - prev.v[j];
                        let u_k = prev.slip[j] + dv_k.abs();
                        let dmu = law.dmu_du(u_k).unwrap_or(0.0);
                        let sigma = if dv_k != 0.0 { dv_k.signum() } else { -sign[j] };
                        let coef = sign[j] * mu[j] * dmu * sigma;
                        special.push(SpecialRow {
                            row: r,
                            alpha: 1.0,
                            beta: -coef,
                            gamma: -sign[j] * law.mu(u_k),
                            // The node's normal force: active nodes come first, in order.
                            col: r - active.len(),
                            combo: Vec::new(),
                        });
                        b[r] = coef * (w0[u] - prev.v[j] - dv_k);
                    }
                    Status::Open => unreachable!("open nodes have no unknowns"),
                }
            } else {
                let k = u - 2 * ns;
                let d = self.anchor_drive(it.drive, k);
                #[allow(unreachable_patterns)]
                match d {
                    PilotDrive::Force(f) => {
                        special.push(SpecialRow {
                            row: r,
                            alpha: 1.0,
                            beta: -self.kg[k],
                            gamma: 0.0,
                            col: r,
                            combo: Vec::new(),
                        });
                        b[r] = f + self.kg[k] * w0[u];
                    }
                    PilotDrive::Displacement(d) => b[r] = d - w0[u],
                    PilotDrive::Slip(target) => {
                        // As in `newton_system`: Σ ω_j (W μ)_t,j = target − mean slip − Σ ω_j
                        // (w0_t,j − v̂_j,old), over the nodes in contact at the last step; each
                        // of their tangential forces must be an unknown here.
                        it.law?;
                        let omega = self.slip_weights(prev);
                        let mut combo = Vec::new();
                        let mut rhs = target - prev.mean_slip;
                        for (j, &o) in omega.iter().enumerate() {
                            if o != 0.0 {
                                let t = active.binary_search(&j).ok()? + active.len();
                                combo.push((t, o));
                                rhs -= o * (w0[ns + j] - prev.v[j]);
                            }
                        }
                        special.push(SpecialRow {
                            row: r,
                            alpha: 0.0,
                            beta: 0.0,
                            gamma: 0.0,
                            col: r,
                            combo,
                        });
                        b[r] = rhs;
                    }
                    // A drive added later without a structured row: the dense system.
                    _ => return None,
                }
            }
        }
        Some(NewtonRows { unk, b, special })
    }

    /// How anchor `k` is driven: the pilot's components by `drive`, every other anchor (DOFs of
    /// a body held by contact alone) at zero force.
    fn anchor_drive(&self, drive: [PilotDrive; 2], k: usize) -> PilotDrive {
        if self.has_pilot && k < 2 {
            drive[k]
        } else {
            PilotDrive::Force(0.0)
        }
    }

    fn eps_h(&self, j: usize) -> f64 {
        // Penetration tolerance scale: w_j ≈ h_j / 3 … 2h_j / 3; eps_unit = E* w/h.
        self.eps_unit[j] / self.c * 1.0
    }

    fn y_at(&self, w0: &[f64], mu: &[f64], i: usize) -> f64 {
        let col = self.w.col(i);
        w0[i] + (0..mu.len()).map(|j| col[j] * mu[j]).sum::<f64>()
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        w0: &[f64],
        mu: &[f64],
        status: &[Status],
        law: Option<&FrictionLaw>,
        prev: &State,
        iterations: usize,
        last_update: f64,
    ) -> StepOutcome {
        let ns = self.ns;
        let y = self.y(w0, mu);
        let mut st = prev.clone();
        let omega = self.slip_weights(prev);
        st.mean_slip = prev.mean_slip
            + (0..ns)
                .map(|j| omega[j] * (y[ns + j] - prev.v[j]))
                .sum::<f64>();
        for j in 0..ns {
            st.f_n[j] = mu[j];
            st.f_t[j] = mu[ns + j];
            st.gap[j] = self.gap0[j] + y[j];
            st.v[j] = y[ns + j];
            st.dv[j] = y[ns + j] - prev.v[j];
            st.slip[j] = prev.slip[j]
                + if status[j] == Status::Slip {
                    st.dv[j].abs()
                } else {
                    0.0
                };
            st.status[j] = status[j];
            st.mu[j] = law.map_or(0.0, |l| l.mu(st.slip[j]));
        }
        for k in 0..self.kg.len() {
            st.z[k] = mu[2 * ns + k];
        }
        if self.has_pilot {
            for k in 0..2 {
                st.pilot_u[k] = y[2 * ns + k];
                st.pilot_f[k] = st.z[k] - self.kg[k] * st.pilot_u[k];
            }
        }
        StepOutcome {
            state: st,
            iterations,
            last_update,
        }
    }
}

/// Whether an LU factorisation is numerically singular: its smallest pivot against the largest.
/// A singular system (a body free to slide once every node slips, or a direction nothing holds)
/// still gives a finite answer from a backward-stable LU.
fn singular_pivots(lu: &faer::linalg::solvers::PartialPivLu<f64>) -> bool {
    let u = lu.U();
    let n = u.nrows();
    if n == 0 {
        return false;
    }
    let d: Vec<f64> = (0..n).map(|i| u[(i, i)].abs()).collect();
    let lo = d.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = d.iter().cloned().fold(0.0, f64::max);
    lo <= 1e-12 * hi
}

/// Factorisations kept across Newton iterations and load steps (see
/// [`ContactSystem::solve_step`]).
///
/// The structured path ([`Self::solve_rows`]) keeps the Cholesky factor of a Delassus block
/// `K = W[k_unk, k_unk]` and solves each Newton system `A x = b` whose matrix differs from `K`
/// only in a few rows by the Sherman–Morrison–Woodbury identity; the dense path
/// (`LuCache::solve`) keeps the LU of an earlier Newton matrix as a GMRES preconditioner.
#[derive(Default)]
pub struct LuCache {
    /// Dense path: unknowns and LU of the last factorised Newton matrix.
    unk: Vec<usize>,
    lu: Option<faer::linalg::solvers::PartialPivLu<f64>>,
    /// Structured path: unknowns (μ indices) of the factorised block `K`, the position in it
    /// of each μ index (`usize::MAX`: not in it), its Cholesky factor (`K = Zᵀ Z` restricted to
    /// the unknowns is symmetric positive definite), and the columns `K⁻¹ e_q` computed so far
    /// by position `q` (empty: not yet).
    k_unk: Vec<usize>,
    k_pos: Vec<usize>,
    k_llt: Option<faer::linalg::solvers::Llt<f64>>,
    k_cols: Vec<Vec<f64>>,
    /// Factorisations done (of `K` or of a dense Newton matrix) and GMRES iterations spent (for
    /// the run summary).
    pub factorisations: usize,
    pub gmres_iterations: usize,
}

/// Contact systems with fewer candidate unknowns than this are solved through the dense Newton
/// matrix even with a cache. There it costs microseconds, and such small systems are where the
/// degenerate cases live (a few nodes touching at zero load, whose active sets are decided by
/// the round-off in forces that are zero in exact arithmetic): the dense path keeps the
/// rounding of the reference solve for them.
const STRUCTURED_MIN: usize = 64;

/// GMRES iterations before giving up on the cached factorisation and refactorising.
const GMRES_MAX: usize = 12;

impl LuCache {
    /// Forgets the factorisations.
    pub fn clear(&mut self) {
        self.lu = None;
        self.unk.clear();
        self.k_llt = None;
        self.k_unk.clear();
        self.k_pos.clear();
        self.k_cols.clear();
    }

    /// Solves the structured Newton system `rows` (see [`ContactSystem::newton_rows`]) with the
    /// cached Cholesky factor of a Delassus block `K` whose unknowns include those of `rows`;
    /// `w` is the whole Delassus operator. Returns the unknowns (ordered as `rows.unk`) and
    /// `W μ` at the new iterate (all rows of `W`; on the system's own rows it is taken from the
    /// equations, which saves most of a product with `W` per iteration). `None` if `K` or the
    /// system is numerically singular, or the answer is not finite (the caller then assembles
    /// the dense system, whose LU decides).
    ///
    /// Why: through a load history the contact set changes little, and the Newton matrix
    /// differs from `K = W[unk, unk]` only in the rows of slip nodes and force-driven anchors
    /// (`p` of them, `p ≪ n`). Unknowns of `K` that left the contact are more such rows
    /// (`x_q = 0`), so `K` is refactorised only when a node outside it comes into contact or
    /// too many of its unknowns have left. With `A = K + E_P B` (`E_P` the special rows'
    /// unit vectors, `B = A_P − K_P`):
    /// ```text
    ///   x0 = K⁻¹ b,   G = K⁻¹ E_P,   C = I + B G = A_P G,   C y = B x0,   x = x0 − G y,
    /// ```
    /// where `A_P G` has the entries `α G_rj + γ G_qj + β δ_rj` (because `K G = E_P`) and
    /// `B x0 = α x0_r + γ x0_q + (β − 1) b_r` (because `K x0 = b`). Each iteration costs one
    /// solve with the cached factor and a `p × p` factorisation; the columns of `G` are kept
    /// until `K` is refactorised, so a node that starts to slip costs one more solve, once.
    ///
    /// `new_step`: the first iteration of a load step. While the contact set settles within a
    /// step, `K` is kept until a quarter of its unknowns have left; at the start of a step it
    /// is refactorised for the current set once more than 1/64 have, since those rows would
    /// otherwise enlarge the capacitance system of every iteration of the steps to come.
    pub fn solve_rows(
        &mut self,
        w: &Mat<f64>,
        rows: &NewtonRows,
        new_step: bool,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let covered = self.k_llt.is_some()
            && rows
                .unk
                .iter()
                .all(|&u| self.k_pos.get(u).is_some_and(|&q| q != usize::MAX));
        // Unknowns of K not in this system: each costs a special row (and a column of G).
        let left = self.k_unk.len().saturating_sub(rows.unk.len());
        let limit = self.k_unk.len() / if new_step { 64 } else { 4 };
        if !covered || left > limit {
            self.factorise_block(w, &rows.unk)?;
        }
        let nk = self.k_unk.len();
        let mut b = vec![0.0; nk];
        let mut in_system = vec![false; nk];
        for (r, &u) in rows.unk.iter().enumerate() {
            b[self.k_pos[u]] = rows.b[r];
            in_system[self.k_pos[u]] = true;
        }
        let mut special: Vec<SpecialRow> = rows
            .special
            .iter()
            .map(|s| SpecialRow {
                row: self.k_pos[rows.unk[s.row]],
                col: self.k_pos[rows.unk[s.col]],
                combo: s
                    .combo
                    .iter()
                    .map(|&(t, c)| (self.k_pos[rows.unk[t]], c))
                    .collect(),
                ..*s
            })
            .collect();
        special.extend((0..nk).filter(|&q| !in_system[q]).map(|q| SpecialRow {
            row: q,
            alpha: 1.0,
            beta: 0.0,
            gamma: 0.0,
            col: q,
            combo: Vec::new(),
        }));
        let llt = self.k_llt.as_ref()?;
        // Columns of G not computed yet, in one solve with several right-hand sides.
        let missing: Vec<usize> = special
            .iter()
            .map(|s| s.row)
            .filter(|&q| self.k_cols[q].is_empty())
            .collect();
        if !missing.is_empty() {
            let mut e = Mat::<f64>::zeros(nk, missing.len());
            for (c, &q) in missing.iter().enumerate() {
                e[(q, c)] = 1.0;
            }
            llt.solve_in_place(&mut e);
            for (c, &q) in missing.iter().enumerate() {
                self.k_cols[q] = e.col(c).iter().copied().collect();
            }
        }
        let mut x0 = Mat::from_fn(nk, 1, |i, _| b[i]);
        llt.solve_in_place(&mut x0);
        let mut x: Vec<f64> = x0.col(0).iter().copied().collect();
        let p = special.len();
        let mut y_cap = Vec::new();
        if p > 0 {
            let mut cap = Mat::<f64>::zeros(p, p);
            // Index in `special` of each row of K that is special.
            let mut special_at = vec![None; nk];
            for (i, si) in special.iter().enumerate() {
                special_at[si.row] = Some(i);
            }
            let mut rhs = Mat::<f64>::zeros(p, 1);
            // Size of the terms of each row: C is singular when A is, often by cancellation
            // between large terms (a direction nothing holds), which its own pivots relative
            // to each other do not show; relative to the terms they do.
            let mut size = vec![0.0f64; p];
            for (j, sj) in special.iter().enumerate() {
                let g = &self.k_cols[sj.row];
                for (i, si) in special.iter().enumerate() {
                    let (t1, t2) = (si.alpha * g[si.row], si.gamma * g[si.col]);
                    cap[(i, j)] = t1 + t2;
                    size[i] = size[i].max(t1.abs() + t2.abs());
                }
                if sj.combo.is_empty() {
                    cap[(j, j)] += sj.beta;
                    rhs[(j, 0)] =
                        sj.alpha * x[sj.row] + sj.gamma * x[sj.col] + (sj.beta - 1.0) * b[sj.row];
                } else {
                    // Σ c K_t G = Σ c (E_P)_t: unit entries where t is a special row.
                    for &(t, c) in &sj.combo {
                        if let Some(i) = special_at[t] {
                            cap[(j, i)] += c;
                        }
                    }
                    rhs[(j, 0)] = sj.alpha * x[sj.row]
                        + sj.gamma * x[sj.col]
                        + sj.combo.iter().map(|&(t, c)| c * b[t]).sum::<f64>()
                        - b[sj.row];
                }
            }
            for (i, si) in special.iter().enumerate() {
                let k_part = if si.combo.is_empty() {
                    si.beta.abs()
                } else {
                    si.combo.iter().map(|(_, c)| c.abs()).sum()
                };
                let scale = 1.0 / (size[i] + k_part).max(f64::MIN_POSITIVE);
                for j in 0..p {
                    cap[(i, j)] *= scale;
                }
                rhs[(i, 0)] *= scale;
            }
            let clu = cap.partial_piv_lu();
            // Near-singular (gross sliding, a free direction): the dense system decides.
            if (0..p).any(|i| clu.U()[(i, i)].abs() <= 1e-10) {
                return None;
            }
            let y = clu.solve(&rhs);
            y_cap = (0..p).map(|j| y[(j, 0)]).collect();
            for (sj, yj) in special.iter().zip(&y_cap) {
                for (xi, gi) in x.iter_mut().zip(&self.k_cols[sj.row]) {
                    *xi -= gi * yj;
                }
            }
        }
        // W μ of the new iterate, for the next iteration's sets: on this system's rows it is
        // what the rows impose, `K x = b − E_P y`, the others are products with W.
        let mut w_mu = vec![0.0; w.nrows()];
        let xs: Vec<f64> = rows.unk.iter().map(|&u| x[self.k_pos[u]]).collect();
        let mut in_unk = vec![false; w.nrows()];
        for &u in &rows.unk {
            in_unk[u] = true;
            w_mu[u] = b[self.k_pos[u]];
        }
        for (sj, yj) in special.iter().zip(&y_cap) {
            let u = self.k_unk[sj.row];
            if in_unk[u] {
                w_mu[u] -= yj;
            }
        }
        for (i, wi) in w_mu.iter_mut().enumerate() {
            if !in_unk[i] {
                let col = w.col(i);
                *wi = rows.unk.iter().zip(&xs).map(|(&u, xu)| col[u] * xu).sum();
            }
        }
        xs.iter().all(|v| v.is_finite()).then_some((xs, w_mu))
    }

    /// Factorises `K = W[unk, unk]` for [`Self::solve_rows`]; `None` if it is singular or not
    /// numerically positive definite.
    fn factorise_block(&mut self, w: &Mat<f64>, unk: &[usize]) -> Option<()> {
        let k = Mat::from_fn(unk.len(), unk.len(), |i, j| w[(unk[i], unk[j])]);
        let llt = k.llt(faer::Side::Lower).ok();
        self.factorisations += 1;
        self.k_llt = None;
        self.k_unk.clear();
        self.k_pos.clear();
        self.k_cols.clear();
        let llt = llt?;
        // The pivots are L_ii²: as for an LU, singular when the smallest is below 1e-12 of the
        // largest; and pivots within 2^52 of the smallest normal number have lost digits to
        // underflow (absurd moduli make W that small).
        let pivots: Vec<f64> = (0..unk.len()).map(|i| llt.L()[(i, i)].powi(2)).collect();
        let lo = pivots.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = pivots.iter().copied().fold(0.0, f64::max);
        if lo <= 1e-12 * hi || lo < f64::MIN_POSITIVE / f64::EPSILON {
            return None;
        }
        self.k_pos = vec![usize::MAX; w.nrows()];
        for (q, &u) in unk.iter().enumerate() {
            self.k_pos[u] = q;
        }
        self.k_unk = unk.to_vec();
        self.k_cols = vec![Vec::new(); unk.len()];
        self.k_llt = Some(llt);
        Some(())
    }

    /// Solves `A x = b` for the unknowns `unk`: by GMRES preconditioned with the cached LU when
    /// it is for the same unknowns, else (or if GMRES stalls) with a new LU, which is kept.
    /// `None` when the system is singular.
    fn solve(&mut self, unk: &[usize], a: &Mat<f64>, b: &Mat<f64>) -> Option<Mat<f64>> {
        if self.unk == unk
            && let Some(lu) = &self.lu
            && let Some((x, its)) = gmres(a, b, lu, 1e-13, GMRES_MAX)
        {
            self.gmres_iterations += its;
            return Some(x);
        }
        let lu = a.partial_piv_lu();
        self.factorisations += 1;
        if singular_pivots(&lu) {
            self.clear();
            return None;
        }
        let x = lu.solve(b);
        self.unk = unk.to_vec();
        self.lu = Some(lu);
        Some(x)
    }
}

/// Right-preconditioned GMRES (no restart) for `A x = b` with preconditioner `M⁻¹` given by an
/// LU of a nearby matrix, from `x0 = M⁻¹ b`. Returns the solution and the iterations, or
/// `None` if the relative residual is not below `tol` within `max_it` iterations.
fn gmres(
    a: &Mat<f64>,
    b: &Mat<f64>,
    m: &faer::linalg::solvers::PartialPivLu<f64>,
    tol: f64,
    max_it: usize,
) -> Option<(Mat<f64>, usize)> {
    let n = a.nrows();
    let bn = b.norm_l2();
    if bn == 0.0 {
        return Some((Mat::zeros(n, 1), 0));
    }
    let x0 = m.solve(b);
    let r0 = b - a * &x0;
    let beta = r0.norm_l2();
    if beta <= tol * bn {
        return Some((x0, 0));
    }
    // Arnoldi on A M⁻¹ with modified Gram–Schmidt; Givens rotations for the least squares.
    let mut v: Vec<Mat<f64>> = vec![&r0 * faer::Scale(1.0 / beta)];
    let mut h = vec![vec![0.0; max_it]; max_it + 1];
    let (mut cs, mut sn) = (vec![0.0; max_it], vec![0.0; max_it]);
    let mut g = vec![0.0; max_it + 1];
    g[0] = beta;
    for k in 0..max_it {
        let z = m.solve(&v[k]);
        let mut w = a * &z;
        for i in 0..=k {
            let hik = (v[i].transpose() * &w)[(0, 0)];
            h[i][k] = hik;
            w -= &v[i] * faer::Scale(hik);
        }
        let hn = w.norm_l2();
        h[k + 1][k] = hn;
        for i in 0..k {
            let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
            h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
            h[i][k] = t;
        }
        let d = h[k][k].hypot(h[k + 1][k]);
        if d == 0.0 {
            return None;
        }
        cs[k] = h[k][k] / d;
        sn[k] = h[k + 1][k] / d;
        h[k][k] = d;
        h[k + 1][k] = 0.0;
        g[k + 1] = -sn[k] * g[k];
        g[k] *= cs[k];
        if g[k + 1].abs() <= tol * bn || hn == 0.0 {
            // y = H⁻¹ g, x = x0 + M⁻¹ V y
            let mut y = vec![0.0; k + 1];
            for i in (0..=k).rev() {
                let s: f64 = (i + 1..=k).map(|j| h[i][j] * y[j]).sum();
                y[i] = (g[i] - s) / h[i][i];
            }
            let mut vy = Mat::<f64>::zeros(n, 1);
            for (i, yi) in y.iter().enumerate() {
                vy += &v[i] * faer::Scale(*yi);
            }
            let x = x0 + m.solve(&vy);
            // Guard against loss of orthogonality: check the true residual.
            let r = (b - a * &x).norm_l2();
            return (r <= 10.0 * tol * bn).then_some((x, k + 1));
        }
        v.push(&w * faer::Scale(1.0 / hn));
    }
    None
}
