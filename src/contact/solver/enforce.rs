//! Enforcement: the active sets of an iterate, and the linearised equations each method
//! imposes once the sets are fixed.
//!
//! Every equation is written once, in [`ContactSystem::equations`], as
//! `α μ_own + γ μ_other + Σ c (W μ)_i = rhs` over the forces μ; the dense Newton matrix
//! ([`ContactSystem::newton_system`]) and the structured rows of the cached solve
//! ([`ContactSystem::newton_rows`]) are both assembled from that list, and
//! [`ContactSystem::newton_residual`] is the unlinearised function whose Jacobian they are.

use super::system::{ContactSystem, Iterate, Method, PilotDrive, State, Status};
use crate::friction::FrictionLaw;
use faer::Mat;

/// One linearised equation, the row of unknown `own` (a μ index):
/// `alpha μ_own + gamma μ_other + Σ_(i, c) c (W μ)_i = rhs`.
#[derive(Clone, Debug, PartialEq)]
pub struct Equation {
    pub own: usize,
    pub alpha: f64,
    pub gamma: f64,
    pub other: usize,
    /// `(i, c)`: rows `i` of `W` (μ indices) and their coefficients.
    pub w: WTerms,
    pub rhs: f64,
}

/// The `(i, c)` terms of an [`Equation`]: one, in place (every row but the slip control's), or
/// many. One heap allocation per equation and iteration had been a twentieth of a sweep's
/// time.
#[derive(Clone, Debug)]
pub enum WTerms {
    One([(usize, f64); 1]),
    Many(Vec<(usize, f64)>),
}

impl std::ops::Deref for WTerms {
    type Target = [(usize, f64)];
    fn deref(&self) -> &[(usize, f64)] {
        match self {
            WTerms::One(t) => t,
            WTerms::Many(t) => t,
        }
    }
}

impl PartialEq for WTerms {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl Equation {
    /// `c (W μ)_i = rhs` on the unknown `i` itself.
    fn w_row(own: usize, c: f64, rhs: f64) -> Self {
        Equation {
            own,
            alpha: 0.0,
            gamma: 0.0,
            other: own,
            w: WTerms::One([(own, c)]),
            rhs,
        }
    }

    /// `μ_own + c (W μ)_own = rhs`.
    fn spring(own: usize, c: f64, rhs: f64) -> Self {
        Equation {
            alpha: 1.0,
            ..Self::w_row(own, c, rhs)
        }
    }

    /// Whether the row is row `own` of `W` unchanged (a row of the block `K`).
    fn is_plain(&self) -> bool {
        self.alpha == 0.0 && self.gamma == 0.0 && *self.w == [(self.own, 1.0)]
    }
}

/// The linearisation of `F_t = s μ(U + |Δv̂|) F_n` at the iterate of a slip node.
#[derive(Clone, Copy, Debug, Default)]
pub struct SlipLin {
    /// μ and μ′ at the iterate's slip `U + |Δv̂_k|`.
    pub mu: f64,
    pub dmu: f64,
    /// The iterate's slip increment `Δv̂_k` and the sign `σ` of its derivative.
    pub dv: f64,
    pub sigma: f64,
}

/// The equations of one iteration: one per unknown, ordered as the normal forces of the nodes
/// in contact, their tangential forces (with friction), then the anchors.
pub struct Linearisation {
    pub equations: Vec<Equation>,
    pub slip: Vec<SlipLin>,
}

/// The linear system of one Newton iteration.
pub struct NewtonSystem {
    pub a: Mat<f64>,
    pub b: Mat<f64>,
    /// μ index of each unknown.
    pub unk: Vec<usize>,
    /// Slip nodes whose tangential force is substituted (`s μ F_n`).
    pub substituted: Vec<bool>,
    /// Per node: the slip linearisation (zero for nodes that do not slip).
    pub slip_lin: Vec<SlipLin>,
}

/// The Newton system of one iteration in the structured form [`super::LuCache::solve_rows`]
/// solves without assembling it (see [`ContactSystem::newton_rows`]): row `r` of the matrix is
/// row `r` of `K = W[unk, unk]`, except for the rows in `special`.
pub struct NewtonRows {
    /// μ index of each unknown: every contact node's normal and (with friction) tangential
    /// force, then the anchors; none substituted, so this depends on the contact set only.
    pub unk: Vec<usize>,
    pub b: Vec<f64>,
    /// The rows that differ from `K` (slip nodes, force-driven anchors), in increasing order.
    pub special: Vec<SpecialRow>,
    /// Rows (positions in `unk`) likely to become special: the tangential rows of stick nodes,
    /// nearest their friction limit `|F_t| / (μ F_n)` first.
    pub likely: Vec<usize>,
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

/// What the set update of an iteration reads besides the iterate's `y = w0 + W μ`.
pub(super) struct Trial<'a> {
    pub method: Method,
    pub law: Option<&'a FrictionLaw>,
    pub prev: &'a State,
    pub mu: &'a [f64],
    pub eps: &'a [f64],
    pub fbar_n: &'a [f64],
    pub fbar_t: &'a [f64],
}

impl ContactSystem {
    /// Updates the sets (open / stick / slip) and the slip directions from the iterate's
    /// `y = w0 + W μ`; returns how many nodes changed state. The trial forces are the
    /// complementarity functions' arguments: `F − c·(gap or slip)` for the Newton method, the
    /// penalty spring's force for the penalty method, the multiplier estimate plus the spring
    /// for the augmented Lagrangian.
    pub(super) fn update_sets(
        &self,
        t: &Trial,
        y: &[f64],
        status: &mut [Status],
        sign: &mut [f64],
    ) -> usize {
        let (ns, c) = (self.ns, self.c);
        let mut changes = 0;
        for j in 0..ns {
            let gap = self.gap0[j] + y[j];
            let dv = y[ns + j] - t.prev.v[j];
            let xi_n = match t.method {
                Method::Newton => t.mu[j] - c * gap,
                Method::Penalty => -t.eps[j] * gap,
                Method::AugmentedLagrangian => t.fbar_n[j] - t.eps[j] * gap,
            };
            let new = if xi_n <= 0.0 {
                Status::Open
            } else if let Some(law) = t.law {
                let mu_j = law.mu(t.prev.slip_mu[j] + dv.abs());
                let xi_t = match t.method {
                    Method::Newton => t.mu[ns + j] - c * dv,
                    Method::Penalty => t.prev.f_t[j] - t.eps[j] * dv,
                    Method::AugmentedLagrangian => t.fbar_t[j] - t.eps[j] * dv,
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
        changes
    }

    /// The linearised equations of the iterate with its sets fixed (see [`Equation`]).
    ///
    /// * normal, Newton: `ĝ = 0`; penalty and augmented Lagrangian: `F_n + ε ĝ = F̄_n`
    ///   (`F̄_n = 0` for the penalty method);
    /// * stick, Newton: `Δv̂ = 0`; penalty and augmented Lagrangian: `F_t + ε Δv̂ = F̄_t`
    ///   (the committed force for the penalty method);
    /// * slip: `F_t = s μ(U + |Δv̂|) F_n` linearised at the iterate,
    ///   `F_t − s μ_k F_n − s F_n,k μ′_k σ (Δv̂ − Δv̂_k) = 0`;
    /// * anchors: force `z − k_g u = f`, displacement `u = d`, or the mean slip
    ///   `Σ ω_j (v̂_j − v̂_j,old) = target − mean slip`;
    ///
    /// with `ĝ = g0 + w0_n + (W μ)_n`, `Δv̂ = w0_t + (W μ)_t − v̂_old`, `u = w0_z + (W μ)_z`.
    pub fn equations(&self, it: &Iterate) -> Linearisation {
        let ns = self.ns;
        let (w0, prev, mu, eps) = (it.w0, it.prev, it.mu, it.eps);
        let mut slip = vec![SlipLin::default(); ns];
        if let Some(law) = it.law {
            let slipping: Vec<usize> = (0..ns).filter(|&j| it.status[j] == Status::Slip).collect();
            let y_slip = match it.y {
                Some(y) => slipping.iter().map(|&j| y[ns + j]).collect(),
                None => {
                    let rows: Vec<usize> = slipping.iter().map(|&j| ns + j).collect();
                    self.y_rows(w0, mu, &rows)
                }
            };
            for (&j, &y_j) in slipping.iter().zip(&y_slip) {
                let dv = y_j - prev.v[j];
                let u_k = prev.slip_mu[j] + dv.abs();
                slip[j] = SlipLin {
                    mu: law.mu(u_k),
                    dmu: law.dmu_du(u_k).unwrap_or(0.0),
                    dv,
                    sigma: if dv != 0.0 { dv.signum() } else { -it.sign[j] },
                };
            }
        }
        let active: Vec<usize> = (0..ns).filter(|&j| it.status[j] != Status::Open).collect();
        let mut equations = Vec::with_capacity(2 * active.len() + self.kg.len());
        for &j in &active {
            let rhs = -(self.gap0[j] + w0[j]);
            equations.push(match it.method {
                Method::Newton => Equation::w_row(j, 1.0, rhs),
                Method::Penalty => Equation::spring(j, eps[j], eps[j] * rhs),
                Method::AugmentedLagrangian => {
                    Equation::spring(j, eps[j], it.fbar_n[j] + eps[j] * rhs)
                }
            });
        }
        if it.law.is_some() {
            for &j in &active {
                let u = ns + j;
                equations.push(match (it.status[j], it.method) {
                    (Status::Stick, Method::Newton) => Equation::w_row(u, 1.0, prev.v[j] - w0[u]),
                    (Status::Stick, _) => {
                        let fb = if it.method == Method::Penalty {
                            prev.f_t[j]
                        } else {
                            it.fbar_t[j]
                        };
                        Equation::spring(u, eps[j], fb - eps[j] * (w0[u] - prev.v[j]))
                    }
                    (Status::Slip, _) => {
                        let l = slip[j];
                        let coef = it.sign[j] * mu[j] * l.dmu * l.sigma;
                        Equation {
                            gamma: -(it.sign[j] * l.mu),
                            other: j,
                            ..Equation::spring(u, -coef, coef * (w0[u] - prev.v[j] - l.dv))
                        }
                    }
                    (Status::Open, _) => unreachable!("open nodes have no unknowns"),
                });
            }
        }
        for k in 0..self.kg.len() {
            let u = 2 * ns + k;
            equations.push(match self.anchor_drive(it.drive, k) {
                PilotDrive::Force(f) => Equation::spring(u, -self.kg[k], f + self.kg[k] * w0[u]),
                PilotDrive::Displacement(d) => Equation::w_row(u, 1.0, d - w0[u]),
                PilotDrive::Slip(target) => {
                    let omega = self.slip_weights(prev);
                    let mut rhs = target - prev.mean_slip;
                    let mut w = Vec::new();
                    for (j, &o) in omega.iter().enumerate() {
                        if o != 0.0 {
                            w.push((ns + j, o));
                            rhs -= o * (w0[ns + j] - prev.v[j]);
                        }
                    }
                    Equation {
                        w: WTerms::Many(w),
                        ..Equation::w_row(u, 0.0, rhs)
                    }
                }
            });
        }
        Linearisation { equations, slip }
    }

    /// The Newton system of one iteration with the sets fixed, assembled densely from
    /// [`Self::equations`]: `A x = b` over the unknowns `unk` (μ indices). With
    /// `it.substitute`, the tangential force of a slip node whose μ does not change with slip
    /// at the iterate (a constant law, or past the weakening) is `s μ F_n` exactly: it is
    /// folded into the normal force's column rather than solved for.
    pub fn newton_system(&self, it: &Iterate) -> NewtonSystem {
        let ns = self.ns;
        let m = self.m();
        let Linearisation { equations, slip } = self.equations(it);
        let substituted: Vec<bool> = (0..ns)
            .map(|j| {
                it.substitute
                    && it.law.is_some()
                    && it.status[j] == Status::Slip
                    && (slip[j].dmu == 0.0 || it.mu[j] == 0.0)
            })
            .collect();
        // How each μ component maps onto the unknowns: (μ index, unknown position, factor).
        let eqs: Vec<&Equation> = equations
            .iter()
            .filter(|e| !(e.own >= ns && e.own < 2 * ns && substituted[e.own - ns]))
            .collect();
        let unk: Vec<usize> = eqs.iter().map(|e| e.own).collect();
        let mut pos = vec![usize::MAX; m];
        for (q, &u) in unk.iter().enumerate() {
            pos[u] = q;
        }
        let mut cols: Vec<(usize, usize, f64)> = Vec::with_capacity(equations.len());
        for e in &equations {
            let u = e.own;
            if u >= ns && u < 2 * ns && substituted[u - ns] {
                let j = u - ns;
                cols.push((u, pos[j], it.sign[j] * slip[j].mu));
            } else {
                cols.push((u, pos[u], 1.0));
            }
        }
        let nu = unk.len();
        let mut a = Mat::<f64>::zeros(nu, nu);
        let mut b = Mat::<f64>::zeros(nu, 1);
        for (r, e) in eqs.iter().enumerate() {
            if e.alpha != 0.0 {
                a[(r, r)] += e.alpha;
            }
            if e.gamma != 0.0 {
                a[(r, pos[e.other])] += e.gamma;
            }
            // Row i of W over the unknowns; W is symmetric, so read its column i (contiguous).
            for &(i, c) in e.w.iter() {
                let col = self.w.col(i);
                for &(mi, q, f) in &cols {
                    a[(r, q)] += c * f * col[mi];
                }
            }
            b[(r, 0)] = e.rhs;
        }
        NewtonSystem {
            a,
            b,
            unk,
            substituted,
            slip_lin: slip,
        }
    }

    /// The system of [`Self::newton_system`] for the Newton method, without substitution, in
    /// structured form: the rows that are rows of `K = W[unk, unk]` (normal, stick and
    /// displacement-driven anchor rows) are left implicit, the others (slip nodes, force- and
    /// slip-driven anchors) are [`SpecialRow`]s. `None` for the penalty and
    /// augmented-Lagrangian methods (every normal row would be special) and when a slip-control
    /// row reads a node that is no longer an unknown: the caller then assembles the dense
    /// system.
    pub fn newton_rows(&self, it: &Iterate) -> Option<NewtonRows> {
        // Slip control reads tangential unknowns, which only friction gives.
        let slip_driven = (0..self.kg.len())
            .any(|k| matches!(self.anchor_drive(it.drive, k), PilotDrive::Slip(_)));
        if it.method != Method::Newton || (slip_driven && it.law.is_none()) {
            return None;
        }
        let Linearisation { equations, .. } = self.equations(it);
        let unk: Vec<usize> = equations.iter().map(|e| e.own).collect();
        let mut pos = vec![usize::MAX; self.m()];
        for (q, &u) in unk.iter().enumerate() {
            pos[u] = q;
        }
        let mut special = Vec::new();
        for (r, e) in equations.iter().enumerate() {
            if e.is_plain() {
                continue;
            }
            let col = if e.gamma != 0.0 { pos[e.other] } else { r };
            special.push(match &*e.w {
                &[(i, beta)] if i == e.own => SpecialRow {
                    row: r,
                    alpha: e.alpha,
                    beta,
                    gamma: e.gamma,
                    col,
                    combo: Vec::new(),
                },
                terms => SpecialRow {
                    row: r,
                    alpha: e.alpha,
                    beta: 0.0,
                    gamma: e.gamma,
                    col,
                    combo: terms
                        .iter()
                        .map(|&(i, c)| (pos[i] != usize::MAX).then_some((pos[i], c)))
                        .collect::<Option<_>>()?,
                },
            });
        }
        let b = equations.iter().map(|e| e.rhs).collect();
        let mut near: Vec<(f64, usize)> = Vec::new();
        if let Some(law) = it.law {
            let ns = self.ns;
            for j in (0..ns).filter(|&j| it.status[j] == Status::Stick) {
                let limit = law.mu(it.prev.slip_mu[j]) * it.mu[j];
                if limit > 0.0 && pos[ns + j] != usize::MAX {
                    near.push((it.mu[ns + j].abs() / limit, pos[ns + j]));
                }
            }
        }
        near.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let likely = near.into_iter().map(|(_, r)| r).collect();
        Some(NewtonRows {
            unk,
            b,
            special,
            likely,
        })
    }

    /// The residual of the equations of every method for the fixed sets of `it` (unlinearised:
    /// the slip rows with μ at the slip the unknowns give), at the unknowns `x` ordered as
    /// `sys.unk` of [`Self::newton_system`]: its Jacobian is `A`.
    pub fn newton_residual(&self, it: &Iterate, sys: &NewtonSystem, x: &[f64]) -> Vec<f64> {
        let ns = self.ns;
        let mut mu = vec![0.0; self.m()];
        for (q, &u) in sys.unk.iter().enumerate() {
            mu[u] = x[q];
        }
        for j in 0..ns {
            if sys.substituted[j] && it.status[j] == Status::Slip {
                mu[ns + j] = it.sign[j] * sys.slip_lin[j].mu * mu[j];
            }
        }
        let y = self.y(it.w0, &mu);
        let spring = it.method != Method::Newton;
        sys.unk
            .iter()
            .map(|&u| {
                if u < ns {
                    let gap = self.gap0[u] + y[u];
                    match it.method {
                        Method::Newton => gap,
                        Method::Penalty => mu[u] + it.eps[u] * gap,
                        Method::AugmentedLagrangian => mu[u] + it.eps[u] * gap - it.fbar_n[u],
                    }
                } else if u < 2 * ns {
                    let j = u - ns;
                    let dv = y[u] - it.prev.v[j];
                    match it.status[j] {
                        Status::Stick if spring => {
                            let fb = if it.method == Method::Penalty {
                                it.prev.f_t[j]
                            } else {
                                it.fbar_t[j]
                            };
                            mu[u] + it.eps[j] * dv - fb
                        }
                        Status::Stick => dv,
                        _ => {
                            let l = it.law.expect("friction");
                            mu[u] - it.sign[j] * l.mu(it.prev.slip_mu[j] + dv.abs()) * mu[j]
                        }
                    }
                } else {
                    let k = u - 2 * ns;
                    match self.anchor_drive(it.drive, k) {
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
}
