//! The condensed contact problem: its unknowns, states and options, the operator `W` with
//! its products, and the Cholesky factor of `W` in the order of first contact.

pub use crate::case::Method;
use crate::friction::FrictionLaw;
use faer::Mat;

/// Contact state of a slave node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct State {
    pub f_n: Vec<f64>,
    pub f_t: Vec<f64>,
    /// Anchor unknowns: force on each grounded DOF plus its spring force (pilot first).
    pub z: Vec<f64>,
    /// Relative tangential displacement v̂ (master minus slave).
    pub v: Vec<f64>,
    /// Accumulated slip U: the total slip path.
    pub slip: Vec<f64>,
    /// The slip μ is evaluated at: `slip`, or with a healing law
    /// ([`crate::friction::History::SinceStick`]) the slip since the node last stuck or opened.
    pub slip_mu: Vec<f64>,
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

/// The forces of the next step's predicted start, in μ order (`F_n`, `F_t`, `z`): those of
/// `now` extrapolated from `before` by `t` (the ratio of the next load increment to the last),
/// `now + t (now − before)` entry by entry, the normal forces clipped at zero. The driver's
/// predictor, and the start whose `y` the solver computes ahead ([`LuCache::take_next_y`]).
pub fn predicted_forces(now: [&[f64]; 3], before: [&[f64]; 3], t: f64) -> [Vec<f64>; 3] {
    let ext = |c: &[f64], o: &[f64]| -> Vec<f64> {
        c.iter().zip(o).map(|(c, o)| c + t * (c - o)).collect()
    };
    let f_n = ext(now[0], before[0])
        .into_iter()
        .map(|v| v.max(0.0))
        .collect();
    [f_n, ext(now[1], before[1]), ext(now[2], before[2])]
}

/// The statuses of the next step's predicted start: those of `prev`, with the stick nodes that
/// the slip fronts will pass if they move on as they did from `old` to `prev` (by `t` times as
/// far) predicted to slip. A stick node `d` nodes along the face from the nearest slip node of
/// `prev` (the slave nodes are numbered along the face), and `d + k` from that of `old`, is
/// reached when `d ≤ t k`. The Newton iteration's active sets move a front by about one node
/// per iteration: Fig. 2 on L7 advances each front by about nine nodes per step.
pub fn predict_slip(prev: &State, old: &State, t: f64) -> Vec<Status> {
    let d_prev = slip_distance(&prev.status);
    let d_old = slip_distance(&old.status);
    (0..prev.status.len())
        .map(|j| match (prev.status[j], d_prev[j], d_old[j]) {
            (Status::Stick, Some(d), Some(e)) if e > d && d as f64 <= t * (e - d) as f64 => {
                Status::Slip
            }
            (s, ..) => s,
        })
        .collect()
}

/// For each node, how many nodes along the face the nearest slip node is (`None`: none slips).
pub(super) fn slip_distance(status: &[Status]) -> Vec<Option<usize>> {
    let n = status.len();
    let mut d = vec![None; n];
    let mut last = None;
    for j in 0..n {
        if status[j] == Status::Slip {
            last = Some(j);
        }
        d[j] = last.map(|i| j - i);
    }
    let mut next = None;
    for j in (0..n).rev() {
        if status[j] == Status::Slip {
            next = Some(j);
        }
        if let Some(i) = next {
            d[j] = Some(d[j].map_or(i - j, |v: usize| v.min(i - j)));
        }
    }
    d
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
    /// `y = w0 + W μ` at them if known (else computed where needed).
    pub y: Option<&'a [f64]>,
    pub status: &'a [Status],
    /// Slip direction per node (sign of the master's tangential force).
    pub sign: &'a [f64],
    pub method: Method,
    pub eps: &'a [f64],
    pub fbar_n: &'a [f64],
    pub fbar_t: &'a [f64],
}

/// The condensed contact operator.
pub struct ContactSystem {
    pub ns: usize,
    /// Whether the first two anchors are the pilot's (x, y) DOFs.
    pub has_pilot: bool,
    /// Delassus operator `W` (m × m), m = 2 ns (+ 2 with a pilot).
    pub w: std::sync::Arc<Mat<f64>>,
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
    /// The Cholesky factor of `W` in an order where contact sets are leading sets, when the
    /// saddle-point factorisation gave it (see [`PrefixFactor`]).
    pub prefix: Option<std::sync::Arc<PrefixFactor>>,
}

/// A lower Cholesky factor `C` of the Delassus operator in an order of the contact unknowns
/// (`W[order, order] = C Cᵀ`): the anchors, then the slave nodes by increasing initial gap,
/// each node's normal then tangential unknown. The saddle-point factorisation gives it with
/// no extra work when its constraint rows are in this order
/// ([`crate::la::SaddleFactor::delassus`]), and the leading `p × p` block of `C` is the
/// Cholesky factor of `W` restricted to the first `p` unknowns of the order. A contact zone
/// that grows from the first point of contact is such a leading set (up to a few nodes), so
/// the structured solve takes its Delassus block from `C` instead of factorising it.
pub struct PrefixFactor {
    /// `C`, `m × m`, lower triangular (strictly upper part zero).
    pub c: Mat<f64>,
    /// `order[k]`: the μ index at position `k`.
    pub order: Vec<usize>,
    /// `pos[i]`: the position of μ index `i` (the inverse of `order`).
    pub pos: Vec<usize>,
}

impl crate::la::DenseColumns for PrefixFactor {
    fn rows(&self) -> usize {
        self.c.nrows()
    }
    fn column(&self, j: usize, from: usize) -> &[f64] {
        self.c.column(j, from)
    }
}

impl PrefixFactor {
    pub fn new(c: Mat<f64>, order: Vec<usize>) -> PrefixFactor {
        let mut pos = vec![0; order.len()];
        for (k, &i) in order.iter().enumerate() {
            pos[i] = k;
        }
        PrefixFactor { c, order, pos }
    }
}

/// Contact unknowns (rows of `W`) from which the constraint rows are factorised in the order of
/// [`PrefixFactor`] and its factor kept (L6 up on the VM272 ladder; below, the rows stay in the
/// order of μ and every result is what it was before the prefix factor existed). It was the
/// threshold of the structured solve's shortcuts until those came down to L5
/// ([`newton::SHORTCUTS_FROM`]); the model's factorisation and its cache entries did not change
/// with them.
pub const PREFIX_FROM: usize = 1536;

/// The order of [`PrefixFactor`] for a system of `ns` slave nodes with initial nodal gaps
/// `gap0` (mortar gaps, already per unit weight) and `m − 2 ns` anchors (a model takes it
/// from [`PREFIX_FROM`] unknowns).
pub fn prefix_order(gap0: &[f64], m: usize) -> Vec<usize> {
    let ns = gap0.len();
    assert!(m >= 2 * ns, "two unknowns per slave node and the anchors");
    let mut nodes: Vec<usize> = (0..ns).collect();
    nodes.sort_by(|&a, &b| gap0[a].total_cmp(&gap0[b]).then(a.cmp(&b)));
    let mut order: Vec<usize> = (2 * ns..m).collect();
    for j in nodes {
        order.push(j);
        order.push(ns + j);
    }
    order
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
    /// Which slip μ is a function of.
    pub history: crate::friction::History,
    /// Start a frictional first contact from the frictionless contact set (see
    /// [`ContactSystem::solve_step`]); off, it starts from the closest nodes stuck, as before
    /// (kept for the comparison in `tests/friction_contact.rs`).
    pub normal_first: bool,
    /// Start that frictionless problem from the contact set of a Hertzian line contact under
    /// the pilot's normal force (see `newton::hertz_set`); off, from the closest nodes, as
    /// before (kept for the comparison in `tests/friction_contact.rs`).
    pub hertz_start: bool,
    /// Accept an iterate whose force update is at round-off ([`SETTLED_UPDATE`]) while at most
    /// two nodes still flip their set: such a node sits on the friction limit, where either set
    /// gives the same forces to round-off. Off, such a step fails and the driver cuts it back.
    pub settle_round_off: bool,
}

/// The relative force update below which [`Options::settle_round_off`] accepts an iterate
/// whose sets still flip.
pub const SETTLED_UPDATE: f64 = 1e-12;

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
    #[error(
        "the contact equations became singular: {unknowns} unknowns, {in_contact} in contact; a body may be free to move in a direction no contact or support holds"
    )]
    Singular { unknowns: usize, in_contact: usize },
}

impl ContactSystem {
    /// `y = w0 + W μ`.
    pub(super) fn y(&self, w0: &[f64], mu: &[f64]) -> Vec<f64> {
        let mut y = w0.to_vec();
        let terms = mu.iter().enumerate().filter(|&(_, &mj)| mj != 0.0);
        crate::la::dense::add_columns(&mut y, &self.w, terms.map(|(j, &mj)| (j, mj)));
        y
    }

    /// `y = w0 + W μ` and `w0 + W ν` in one pass over `W`, each bit for bit [`Self::y`].
    pub(super) fn y_pair(&self, w0: &[f64], mu: &[f64], nu: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (mut y1, mut y2) = (w0.to_vec(), w0.to_vec());
        crate::la::dense::add_columns_pair(&mut y1, &mut y2, &self.w, mu, nu);
        (y1, y2)
    }

    pub(super) fn m(&self) -> usize {
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
            slip_mu: vec![0.0; ns],
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

    /// How anchor `k` is driven: the pilot's components by `drive`, every other anchor (DOFs of
    /// a body held by contact alone) at zero force.
    pub(super) fn anchor_drive(&self, drive: [PilotDrive; 2], k: usize) -> PilotDrive {
        if self.has_pilot && k < 2 {
            drive[k]
        } else {
            PilotDrive::Force(0.0)
        }
    }

    pub(super) fn eps_h(&self, j: usize) -> f64 {
        // Penetration tolerance scale: w_j ≈ h_j / 3 … 2h_j / 3; eps_unit = E* w/h.
        self.eps_unit[j] / self.c * 1.0
    }

    /// `y_i = w0_i + (W μ)_i` for each `i` of `rows` ([`w_rows_times`]).
    pub(super) fn y_rows(&self, w0: &[f64], mu: &[f64], rows: &[usize]) -> Vec<f64> {
        let wmu = w_rows_times(&self.w, mu, rows);
        rows.iter().zip(wmu).map(|(&i, p)| w0[i] + p).collect()
    }
}

/// `(W x)_i` for each `i` of `rows` (`W` symmetric: row `i` is column `i`): row by row the
/// arithmetic of `(0..m).map(|j| W[i, j] x_j).sum()` (a sum from −0.0 in the order of `j`, as
/// `Iterator::sum` adds), the same bits, [`LANES`] rows per pass over `x` with their sums side
/// by side. A sum alone waits on each addition to finish; eight keep the adder busy (the slip
/// rows of [`ContactSystem::equations`] had taken a twentieth of a sweep's time one by one).
pub(super) fn w_rows_times(w: &Mat<f64>, x: &[f64], rows: &[usize]) -> Vec<f64> {
    let m = x.len();
    let col = |i: usize| {
        &w.col(i)
            .try_as_col_major()
            .expect("contiguous columns")
            .as_slice()[..m]
    };
    let mut out = Vec::with_capacity(rows.len());
    for group in rows.chunks(LANES) {
        // A group of fewer rows repeats its last one in the spare lanes.
        let c: [&[f64]; LANES] = std::array::from_fn(|k| col(group[k.min(group.len() - 1)]));
        let acc = dot_lanes(&c, x);
        out.extend_from_slice(&acc[..group.len()]);
    }
    out
}

/// Rows per pass of [`w_rows_times`].
const LANES: usize = 8;

/// `Σ_j c[k][j] x[j]` for each lane `k`, each a sum from −0.0 in the order of `j`.
#[inline(always)]
fn dot_lanes(c: &[&[f64]; LANES], x: &[f64]) -> [f64; LANES] {
    let mut acc = [-0.0f64; LANES];
    // Every lane as long as `x`: no bounds check in the loop.
    let c: [&[f64]; LANES] = std::array::from_fn(|k| &c[k][..x.len()]);
    for (j, &xj) in x.iter().enumerate() {
        for k in 0..LANES {
            acc[k] += c[k][j] * xj;
        }
    }
    acc
}

/// The predicted forces of the next step: the last two states extrapolated by `t` (the ratio
/// of the next increment to the last), normal forces kept non-negative.
pub fn predicted_state(prev: &State, old: &State, t: f64) -> State {
    let mut g = prev.clone();
    g.status = predict_slip(prev, old, t);
    [g.f_n, g.f_t, g.z] = predicted_forces(
        [&prev.f_n, &prev.f_t, &prev.z],
        [&old.f_n, &old.f_t, &old.z],
        t,
    );
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The prefix order: the anchors, then the nodes by initial gap (ties by index), each
    /// node's normal then tangential unknown.
    #[test]
    fn the_prefix_order_puts_the_anchors_then_the_closest_nodes_first() {
        let gap0 = [0.3, 0.0, 0.1, 0.0, 0.2];
        // ns = 5: normals 0..5, tangentials 5..10, anchors 10, 11.
        assert_eq!(
            prefix_order(&gap0, 12),
            vec![10, 11, 1, 6, 3, 8, 2, 7, 4, 9, 0, 5]
        );
    }

    /// Rows of `W x` eight at a time: each the bits of its own sum in the order of `j`, for
    /// 0–17 rows (spare lanes, a repeated row), with zeros of both signs among the products.
    #[test]
    fn rows_of_w_times_x_together_give_the_bits_of_one_at_a_time() {
        let m = 37;
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut w = Mat::<f64>::zeros(m, m);
        for j in 0..m {
            for i in 0..=j {
                let v = rnd() * 10f64.powi((i % 7) as i32 - 3);
                w[(i, j)] = v;
                w[(j, i)] = v;
            }
        }
        let mut x: Vec<f64> = (0..m).map(|_| rnd()).collect();
        x[3] = 0.0;
        x[5] = -0.0;
        for count in 0..=17 {
            let rows: Vec<usize> = (0..count).map(|k| (7 * k + 2) % m).collect();
            let together = w_rows_times(&w, &x, &rows);
            for (&i, t) in rows.iter().zip(&together) {
                let alone: f64 = (0..m).map(|j| w[(i, j)] * x[j]).sum();
                assert_eq!(t.to_bits(), alone.to_bits(), "row {i} of {count}");
            }
        }
        // A row of zeros against negative zeros: the sum of −0.0 products is −0.0.
        let z = Mat::<f64>::zeros(m, m);
        let neg = vec![-1.0; m];
        let s = w_rows_times(&z, &neg, &[0]);
        let alone: f64 = (0..m).map(|j| z[(0, j)] * neg[j]).sum();
        assert_eq!(s[0].to_bits(), alone.to_bits());
    }

    /// A state with the statuses given by a string: `o` open, `t` stick, `s` slip.
    fn state(s: &str) -> State {
        let status: Vec<Status> = s
            .chars()
            .map(|c| match c {
                'o' => Status::Open,
                't' => Status::Stick,
                _ => Status::Slip,
            })
            .collect();
        let n = status.len();
        State {
            f_n: vec![0.0; n],
            f_t: vec![0.0; n],
            z: Vec::new(),
            v: vec![0.0; n],
            slip: vec![0.0; n],
            slip_mu: vec![0.0; n],
            dv: vec![0.0; n],
            gap: vec![0.0; n],
            status,
            mu: vec![0.0; n],
            pilot_u: [0.0; 2],
            pilot_f: [0.0; 2],
            mean_slip: 0.0,
        }
    }

    fn as_text(st: &[Status]) -> String {
        st.iter()
            .map(|s| match s {
                Status::Open => 'o',
                Status::Stick => 't',
                Status::Slip => 's',
            })
            .collect()
    }

    #[test]
    fn slip_fronts_are_predicted_to_move_on_as_they_moved() {
        // Both fronts moved two nodes inwards: predicted two further (t = 1), one (t = 0.5).
        let old = state("ossttttttttttttsso");
        let prev = state("ossssttttttttsssso");
        assert_eq!(
            as_text(&predict_slip(&prev, &old, 1.0)),
            "ossssssttttsssssso"
        );
        assert_eq!(
            as_text(&predict_slip(&prev, &old, 0.5)),
            "osssssttttttssssso"
        );
        // A front that stood still, or none before: no prediction.
        assert_eq!(
            as_text(&predict_slip(&prev, &prev, 1.0)),
            "ossssttttttttsssso"
        );
        let none = state("otttttttttttttttto");
        assert_eq!(
            as_text(&predict_slip(&prev, &none, 1.0)),
            "ossssttttttttsssso"
        );
        // Nodes that re-stick are left to the iteration.
        let old = state("osssstttsssso");
        let prev = state("otttttttttsso");
        assert_eq!(as_text(&predict_slip(&prev, &old, 1.0)), "otttttttttsso");
    }
}
