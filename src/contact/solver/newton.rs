//! The Newton iteration of one load step: sets from the iterate, the linear solve of the
//! equations [`super::enforce`] writes, the augmented Lagrangian's outer update, and the
//! safeguards against cycling and stalling.

use super::enforce::NewtonSystem;
use super::enforce::Trial;
use super::factors::{LuCache, STRUCTURED_MIN};
use super::seeds::{
    Guard, NORMAL_FIRST_FROM, SHORTCUTS_FROM, hertz_set, predicted_start, seed_closest,
    shortcuts_allowed,
};
use super::system::{
    ContactError, ContactSystem, Iterate, Method, Options, PilotDrive, State, Status, StepOutcome,
};
use crate::friction::{FrictionLaw, History};
use crate::la::dense::solve_dense;

impl ContactSystem {
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
    ///
    /// With [`SHORTCUTS_FROM`] or more contact unknowns, the structured solve takes two
    /// shortcuts that cost about a digit of accuracy: each iteration's solve starts from the
    /// step's last direct solve (see [`LuCache::solve_rows`]), and the slip rows are
    /// linearised at `W μ` as the last solve gave it. Near a limit point (the peak of a
    /// force-controlled load, where the tangent is nearly singular) that digit can decide
    /// whether the iteration converges, so a step that fails with them is solved again without
    /// them before the failure is reported.
    ///
    /// A frictional step that makes the first contact starts from the contact set of the
    /// frictionless problem ([`Self::normal_first`]) when `opt.normal_first` allows it; the
    /// iterations of that solve are counted in the outcome's.
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
        // The shortcuts where they pay: a solve with the factor of a large block reads several
        // MB (L5) to tens of MB (L7).
        let fast = self.m() >= SHORTCUTS_FROM && shortcuts_allowed();
        if let Some(c) = cache.as_deref_mut() {
            c.exact = !fast;
        }
        let normal = match guess {
            None => self.normal_first(w0, drive, law, prev, opt, cache.as_deref_mut()),
            Some(_) => None,
        };
        if let Some(n) = &normal {
            let first = self.solve_step_with(
                w0,
                drive,
                law,
                prev,
                (None, Some(&n.state)),
                opt,
                cache.as_deref_mut(),
            );
            if let Ok(mut out) = first {
                out.iterations += n.iterations;
                return Ok(out);
            }
            // Not from this start: the step from the committed state, as without it.
            if opt.verbose {
                eprintln!("    not converged from the frictionless contact set: from the start");
            }
            if let Some(c) = cache.as_deref_mut() {
                c.exact = !fast;
                c.forget_direct();
            }
        }
        let first = self.solve_step_with(
            w0,
            drive,
            law,
            prev,
            (guess, None),
            opt,
            cache.as_deref_mut(),
        );
        // Predicted slip ([`super::predict_slip`]) that did not converge, or converged with
        // far more nodes slipping than predicted: with a softening law the start can lead the
        // iteration to another equilibrium (L6, force-controlled to Q = f_d P: every node
        // slipping at f_d instead of the stick zone that holds). The step again from the
        // forces alone, as without the prediction.
        let newly = |st: &[Status]| {
            (0..self.ns)
                .filter(|&j| st[j] == Status::Slip && prev.status[j] == Status::Stick)
                .count()
        };
        let predicted = guess.map_or(0, |g| newly(&g.status));
        let jumped = |out: &StepOutcome| newly(&out.state.status) > 2 * predicted + 4;
        let plain;
        let (first, guess) = if predicted > 0 && first.as_ref().map_or(true, jumped) {
            if opt.verbose {
                eprintln!(
                    "    not converged from the predicted slip of {predicted} nodes, or far past it: from the forces alone"
                );
            }
            plain = guess.map(|g| State {
                status: prev.status.clone(),
                ..g.clone()
            });
            if let Some(c) = cache.as_deref_mut() {
                c.forget_direct();
            }
            let again = self.solve_step_with(
                w0,
                drive,
                law,
                prev,
                (plain.as_ref(), None),
                opt,
                cache.as_deref_mut(),
            );
            (again, plain.as_ref())
        } else {
            (first, guess)
        };
        match (first, cache) {
            (Err(_), Some(c)) if fast => {
                c.exact = true;
                c.forget_direct();
                let again =
                    self.solve_step_with(w0, drive, law, prev, (guess, None), opt, Some(&mut *c));
                c.forget_direct();
                again
            }
            (first, _) => first,
        }
    }

    /// The start of a frictional step that makes the first contact (every node open before
    /// it): the frictionless problem of the same step, with a force-driven pilot held at its
    /// committed x displacement, gives the contact set and the normal forces; its nodes in
    /// contact then start stuck with no tangential force. Coming from all candidates stuck,
    /// the frictional iteration gave up the nodes outside the contact over a dozen
    /// iterations, each with twice the unknowns of the normal problem (Fig. 2 on L7: 14
    /// iterations, and a Delassus block of 4 032 unknowns factorised for a contact of 3 258).
    ///
    /// `None` (the step starts as before) when the step is not of that kind, when the
    /// frictionless problem could leave a body free to slide (anchors other than the pilot's,
    /// a slip-driven pilot), or when its solve fails. Only with the structured solve (the
    /// Newton method with a factor cache) and from [`NORMAL_FIRST_FROM`] contact unknowns,
    /// where the block sizes matter.
    fn normal_first(
        &self,
        w0: &[f64],
        drive: [PilotDrive; 2],
        law: Option<&FrictionLaw>,
        prev: &State,
        opt: &Options,
        cache: Option<&mut LuCache>,
    ) -> Option<StepOutcome> {
        law?;
        let cache = cache?;
        if !opt.normal_first {
            return None;
        }
        let pilot_anchors = if self.has_pilot { 2 } else { 0 };
        if opt.method != Method::Newton
            || self.m() < NORMAL_FIRST_FROM
            || self.kg.len() != pilot_anchors
            || prev.status.iter().any(|s| *s != Status::Open)
        {
            return None;
        }
        let mut held = drive;
        if self.has_pilot {
            held[0] = match drive[0] {
                PilotDrive::Force(_) => PilotDrive::Displacement(prev.pilot_u[0]),
                PilotDrive::Displacement(d) => PilotDrive::Displacement(d),
                PilotDrive::Slip(_) => return None,
            };
            if matches!(drive[1], PilotDrive::Slip(_)) {
                return None;
            }
        }
        if opt.verbose {
            eprintln!("    first contact: the frictionless problem for the contact set");
        }
        // From the contact set of a Hertzian line contact under the pilot's normal force where
        // it can be told (see [`hertz_set`]), else from the closest nodes; a seeded solve that
        // fails is done again from the closest nodes, as without the seed.
        let seeded = match held[1] {
            PilotDrive::Force(p) if self.has_pilot && opt.hertz_start => {
                hertz_set(&self.gap0, p.abs(), self.c)
            }
            _ => None,
        }
        .map(|status| State {
            status,
            ..prev.clone()
        });
        let from_seed = seeded.as_ref().and_then(|s| {
            let out = self.solve_step_with(w0, held, None, prev, (None, Some(s)), opt, Some(cache));
            if out.is_err() {
                cache.forget_direct();
                if opt.verbose {
                    eprintln!(
                        "    not converged from the Hertzian contact set: from the closest nodes"
                    );
                }
            }
            out.ok()
        });
        let mut out = match from_seed {
            Some(out) => out,
            None => self
                .solve_step_with(w0, held, None, prev, (None, None), opt, Some(cache))
                .ok()?,
        };
        let st = &mut out.state;
        for j in 0..self.ns {
            st.f_t[j] = 0.0;
            if st.status[j] != Status::Open {
                st.status[j] = Status::Stick;
            }
        }
        Some(out)
    }

    /// [`Self::solve_step`] once, with the shortcuts of the structured solve unless
    /// `cache.exact`. `(guess, sets)`: the guess of [`Self::solve_step`], or the forces and
    /// the sets of the first iteration (taken as they are, as the committed sets are
    /// without a guess).
    #[allow(clippy::too_many_arguments)]
    fn solve_step_with(
        &self,
        w0: &[f64],
        drive: [PilotDrive; 2],
        law: Option<&FrictionLaw>,
        prev: &State,
        (guess, sets): (Option<&State>, Option<&State>),
        opt: &Options,
        mut cache: Option<&mut LuCache>,
    ) -> Result<StepOutcome, ContactError> {
        let exact = cache.as_ref().is_none_or(|c| c.exact);
        let ns = self.ns;
        let m = self.m();
        assert_eq!(w0.len(), m);
        let eps: Vec<f64> = self.eps_unit.iter().map(|e| e * opt.kappa).collect();
        // Unknowns μ = (F_n, F_t, z); warm start from the committed state.
        let start = guess.or(sets).unwrap_or(prev);
        let mut mu = vec![0.0; m];
        mu[..ns].copy_from_slice(&start.f_n);
        mu[ns..2 * ns].copy_from_slice(&start.f_t);
        mu[2 * ns..].copy_from_slice(&start.z);
        // Multiplier estimates of the augmented Lagrangian.
        let mut fbar_n = prev.f_n.clone();
        let mut fbar_t = prev.f_t.clone();
        let mut status: Vec<Status> = sets.unwrap_or(prev).status.clone();
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
        let mut guard = Guard::new(opt.verbose);
        for it in 1..=opt.max_iterations {
            let (y, recalled) = self.iterate_y(w0, &mu, w_mu.take(), exact, cache.as_deref_mut());
            // Sets from the current iterate (without a guess, the first iteration keeps the
            // committed sets).
            if solved || guess.is_some() {
                let trial = Trial {
                    method: opt.method,
                    law,
                    prev,
                    mu: &mu,
                    eps: &eps,
                    fbar_n: &fbar_n,
                    fbar_t: &fbar_t,
                };
                let changes = self.next_sets(
                    &trial,
                    &y,
                    (&mut status, &mut sign),
                    (guess, solved),
                    drive,
                    (it, last_update, opt.verbose),
                );
                // With the sets unchanged the last linear solve is the answer when the equations
                // are linear in the sets (constant μ); a slip-dependent μ also needs a small update.
                let linear = law.is_none_or(|l| matches!(l, FrictionLaw::Constant { .. }));
                let settled = opt.settle_round_off
                    && solved
                    && changes <= 2
                    && last_update <= super::system::SETTLED_UPDATE;
                if solved && (changes == 0 || settled) && (linear || last_update <= opt.tolerance) {
                    if opt.method != Method::AugmentedLagrangian
                        || self.penetration(&y, &status) <= opt.tolerance
                    {
                        let y = self.converged_y(w0, &mu, prev, y, exact, cache.as_deref_mut());
                        if let (Some(c), Some(p)) = (cache.as_deref_mut(), recalled)
                            && !exact
                        {
                            c.remember_w_mu(mu.clone(), p);
                        }
                        return Ok(self.finish(
                            &y,
                            &mu,
                            &status,
                            law,
                            prev,
                            (it, last_update),
                            opt.history,
                        ));
                    }
                    // Outer update of the augmented Lagrangian: the multipliers move to the
                    // forces, and the penetration shrinks with each round.
                    fbar_n.copy_from_slice(&mu[..ns]);
                    fbar_t.copy_from_slice(&mu[ns..2 * ns]);
                }
                guard.observe(changes, last_update);
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
                y: (!exact).then_some(&y[..]),
                status: &status,
                sign: &sign,
                method: opt.method,
                eps: &eps,
                fbar_n: &fbar_n,
                fbar_t: &fbar_t,
            };
            let (new_mu, w_mu_new) =
                self.solve_iteration(&it_ctx, cache.as_deref_mut(), it == 1, guard.dense_only)?;
            w_mu = w_mu_new;
            let new_mu: Vec<f64> = if guard.relax < 1.0 {
                // `W μ` from the solve belongs to the full step: recompute it.
                w_mu = None;
                mu.iter()
                    .zip(&new_mu)
                    .map(|(o, n)| o + guard.relax * (n - o))
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

    /// `y = w0 + W μ` of an iterate, and `W μ` itself where it was known without a product:
    /// from the last solve (`w_mu`), recalled by the cache with the shortcuts (not `exact`), or
    /// the product the cache computed ahead for this start.
    fn iterate_y(
        &self,
        w0: &[f64],
        mu: &[f64],
        w_mu: Option<Vec<f64>>,
        exact: bool,
        mut cache: Option<&mut LuCache>,
    ) -> (Vec<f64>, Option<Vec<f64>>) {
        let recalled = match w_mu {
            Some(p) => Some(p),
            None if !exact => cache
                .as_deref_mut()
                .and_then(|c| c.recall_w_mu(mu, &self.w)),
            None => None,
        };
        let y: Vec<f64> = match &recalled {
            Some(p) => w0.iter().zip(p).map(|(a, b)| a + b).collect(),
            None => match cache.and_then(|c| c.take_next_y(w0, mu)) {
                Some(y) => y,
                None => self.y(w0, mu),
            },
        };
        (y, recalled)
    }

    /// The sets of the next iteration from the iterate `trial` with `y`: the update of
    /// [`Self::update_sets`]; on the first iteration from a `guess`, the stick nodes it predicts
    /// to slip slip; a force-driven pilot body that only the contact holds gets its closest
    /// nodes back when every node opened. Returns the number of nodes whose state changed.
    fn next_sets(
        &self,
        trial: &Trial<'_>,
        y: &[f64],
        (status, sign): (&mut [Status], &mut [f64]),
        (guess, solved): (Option<&State>, bool),
        drive: [PilotDrive; 2],
        (it, last_update, verbose): (usize, f64, bool),
    ) -> usize {
        let (ns, prev, law) = (self.ns, trial.prev, trial.law);
        let mut changes = self.update_sets(trial, y, status, sign);
        // The first iteration from a guess: the stick nodes it predicts to slip (the
        // slip fronts moving on) slip unless the update took them out of contact.
        if !solved && let Some(g) = guess {
            for j in 0..ns {
                if g.status[j] == Status::Slip
                    && prev.status[j] == Status::Stick
                    && status[j] == Status::Stick
                {
                    status[j] = Status::Slip;
                    changes += 1;
                }
            }
        }
        // A force-driven pilot body that only the contact holds has no equilibrium with
        // every node open (the system is singular): an iterate that opens them all
        // overshot, so the closest nodes close again, as at the start of a step.
        let forced = drive.iter().any(|d| matches!(d, PilotDrive::Force(_)));
        if self.floating_pilot && forced && status.iter().all(|s| *s == Status::Open) {
            let gaps: Vec<f64> = (0..ns).map(|j| self.gap0[j] + y[j]).collect();
            seed_closest(&gaps, law.is_some(), status);
            changes += 1;
        }
        if verbose {
            let count = |st: Status| status.iter().filter(|s| **s == st).count();
            eprintln!(
                "    Newton iteration {it}: {} in contact ({} stick, {} slip), {changes} changed state, relative update {last_update:.2e}",
                ns - count(Status::Open),
                count(Status::Stick),
                count(Status::Slip)
            );
        }
        changes
    }

    /// `y` of a converged iterate as the step reports it: with the shortcuts, `y` as the
    /// iteration tested it; else `W μ` again (on the rows of the system `y` is what they
    /// impose, off them the product differs by the solve's error, which near a
    /// force-controlled peak was enough to move the bracketed Q_max: L3, `tests/sweep.rs`).
    /// With a cache, the same pass over `W` also gives `y` at the start the driver will most
    /// likely predict for the next step (the increments are mostly equal), kept as that
    /// step's first product if it is that start bit for bit.
    fn converged_y(
        &self,
        w0: &[f64],
        mu: &[f64],
        prev: &State,
        y: Vec<f64>,
        exact: bool,
        cache: Option<&mut LuCache>,
    ) -> Vec<f64> {
        match (exact, cache) {
            (true, Some(c)) => {
                let next = predicted_start(mu, prev, self.ns, c.prediction());
                let (y, y_next) = self.y_pair(w0, mu, &next);
                c.keep_next_y(w0, next, y_next);
                y
            }
            (true, None) => self.y(w0, mu),
            (false, _) => y,
        }
    }

    /// Solves the linear system of one iteration: the structured solve from the cached factor
    /// when the system allows it, else (or on any trouble there: a singular block, a non-finite
    /// answer) the dense system, by the cached LU + GMRES or a fresh LU. Returns the new forces
    /// and, from the structured solve, `W μ` at them.
    fn solve_iteration(
        &self,
        it: &Iterate,
        mut cache: Option<&mut LuCache>,
        new_step: bool,
        dense_only: bool,
    ) -> Result<(Vec<f64>, Option<Vec<f64>>), ContactError> {
        let (ns, m) = (self.ns, self.m());
        if let Some(c) = cache
            .as_deref_mut()
            .filter(|_| m >= STRUCTURED_MIN && !dense_only)
            && let Some(rows) = self.newton_rows(it)
            && let Some((x, w_mu)) = c.solve_rows(&self.w, self.prefix.as_ref(), &rows, new_step)
        {
            let mut new_mu = vec![0.0; m];
            for (q, &u) in rows.unk.iter().enumerate() {
                new_mu[u] = x[q];
            }
            return Ok((new_mu, Some(w_mu)));
        }
        let NewtonSystem {
            a,
            b,
            unk,
            substituted,
            slip_lin,
        } = self.newton_system(it);
        let nu = unk.len();
        let x = match cache.as_deref_mut() {
            Some(c) => c.solve(&unk, &a, &b),
            None => solve_dense(&a, &b),
        };
        let Some(x) = x.filter(|x| (0..nu).all(|i| x[(i, 0)].is_finite())) else {
            if let Some(c) = cache {
                c.clear();
            }
            return Err(ContactError::Singular {
                unknowns: nu,
                in_contact: it.status.iter().filter(|s| **s != Status::Open).count(),
            });
        };
        let mut new_mu = vec![0.0; m];
        for (q, &u) in unk.iter().enumerate() {
            new_mu[u] = x[(q, 0)];
        }
        for j in 0..ns {
            if substituted[j] && it.status[j] == Status::Slip {
                new_mu[ns + j] = it.sign[j] * slip_lin[j].mu * new_mu[j];
            }
        }
        Ok((new_mu, None))
    }

    /// The largest penetration of the nodes in contact relative to their element size (the
    /// augmented Lagrangian's outer stopping test).
    fn penetration(&self, y: &[f64], status: &[Status]) -> f64 {
        (0..self.ns)
            .filter(|&j| status[j] != Status::Open)
            .map(|j| (-(self.gap0[j] + y[j])).max(0.0) / self.eps_h(j))
            .fold(0.0, f64::max)
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

    #[allow(clippy::too_many_arguments)]
    /// The converged state at the forces `mu`, with `y = w0 + W μ` at them.
    fn finish(
        &self,
        y: &[f64],
        mu: &[f64],
        status: &[Status],
        law: Option<&FrictionLaw>,
        prev: &State,
        (iterations, last_update): (usize, f64),
        history: History,
    ) -> StepOutcome {
        let ns = self.ns;
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
            let slipped = (status[j] == Status::Slip).then_some(st.dv[j]);
            st.slip_mu[j] = history.advance(prev.slip_mu[j], slipped);
            st.status[j] = status[j];
            st.mu[j] = law.map_or(0.0, |l| l.mu(st.slip_mu[j]));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// On a parabolic gap `g = g_min + t² / (2R)` the set is Hertz's `|t| ≤ a`,
    /// `a = (4 P R / (π E*))^½`, for any radius; a load that closes fewer than three nodes
    /// gives none.
    #[test]
    fn the_hertzian_set_of_a_parabolic_gap_is_the_nodes_within_the_semi_width() {
        let (p, e_star, g_min) = (10.0, 109.89, 1e-4);
        for radius in [0.5, 4.0, 40.0] {
            let a = (4.0 * p * radius / (std::f64::consts::PI * e_star)).sqrt();
            // Nodes at t = ±(k + 0.5) h, none on the edge itself.
            let h = a / 40.0;
            let t: Vec<f64> = (-200..200).map(|k| (k as f64 + 0.5) * h).collect();
            let gap: Vec<f64> = t.iter().map(|t| g_min + t * t / (2.0 * radius)).collect();
            let set = hertz_set(&gap, p, e_star).expect("a set");
            for (tk, s) in t.iter().zip(&set) {
                let inside = tk.abs() <= a;
                assert_eq!(
                    *s == Status::Slip,
                    inside,
                    "R = {radius}, t = {tk}, a = {a}"
                );
                assert!(*s == Status::Slip || *s == Status::Open);
            }
            assert_eq!(set.iter().filter(|s| **s == Status::Slip).count(), 80);
        }
        // A load whose semi-width is under one spacing: only the two nodes at ±h/2.
        let gap: Vec<f64> = (-5..5)
            .map(|k| ((k as f64 + 0.5) * 0.1f64).powi(2))
            .collect();
        assert!(hertz_set(&gap, 1e-9, e_star).is_none());
        assert!(hertz_set(&gap, f64::NAN, e_star).is_none());
    }
}
