//! The start of a step's iteration (the predicted forces, the first sets) and the safeguards
//! of the iteration against cycling and stalling.

use super::system::{State, Status};

/// The forces the driver predicts ([`super::system::predicted_forces`]) for the start of the step after
/// one that converged at `mu` from `prev`, in μ order, taking the next ratio of the increments
/// to be this step's, or 1 (equal increments).
pub(super) fn predicted_start(mu: &[f64], prev: &State, ns: usize, t: Option<f64>) -> Vec<f64> {
    let (f_n, rest) = mu.split_at(ns);
    let (f_t, z) = rest.split_at(ns);
    super::system::predicted_forces(
        [f_n, f_t, z],
        [&prev.f_n, &prev.f_t, &prev.z],
        t.unwrap_or(1.0),
    )
    .concat()
}

/// Contact unknowns (`2 ns` plus anchors) from which the structured solve takes its shortcuts
/// (see [`ContactSystem::solve_step`]): L5 up on the VM272 ladder (1 018 unknowns), not L4
/// (514). The coarse meshes are where the shortcuts' lost digit was seen to move a
/// force-controlled peak: on L3 and L4 the bracketing of Q_max ended up to 0.3 % early with
/// them (`tests/sweep.rs`, `tests/onset.rs`). At L5 and L7 they moved Q_max by at most 2.5e-4
/// of it (Fig. 2's case loaded past its peak, ramp laws f_s = 0.15 and 0.2, Λ = 0.025), and
/// by 8e-12 to 3.5e-5 in five such runs on L5 (`tests/shortcuts.rs`; the bracket of a peak
/// also moves with the load steps a run takes near it). At L5 they take 40 % off the 50-law
/// sweep's rows (`STICKSLIP_CONTACT_SHORTCUTS=off` against on, docs/benchmarks.md).
pub(super) const SHORTCUTS_FROM: usize = 768;

/// Whether the structured solve may take its shortcuts at all: `STICKSLIP_CONTACT_SHORTCUTS=off`
/// solves every iteration directly at every size (read once), for a peak to be bracketed
/// without the shortcuts' lost digit and for comparing the two paths (`tests/shortcuts.rs`).
pub(super) fn shortcuts_allowed() -> bool {
    static ALLOWED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ALLOWED.get_or_init(|| std::env::var("STICKSLIP_CONTACT_SHORTCUTS").as_deref() != Ok("off"))
}

/// Contact unknowns from which a first contact starts from the frictionless contact set
/// ([`ContactSystem::normal_first`]). Below (Fig. 2's zone on L3 has 208), a block
/// factorisation takes well under a millisecond and the iteration stays as it was: on L3 the
/// start moved the force-controlled Q_max of the f_s = 0.2 ramp law (`tests/sweep.rs`, a
/// peak on the jagged Q–slip curve of a mesh that does not resolve s0) from −0.47 % to
/// −0.77 % of JKR, the Newton iteration at the peak failing one bisection earlier from
/// states equal to 1e-12.
pub(super) const NORMAL_FIRST_FROM: usize = 512;

/// The contact set of a frictionless line contact between bodies whose initial gap is a
/// parabola, `g0 = g_min + t² / (2R)`, pressed together by the normal force `p` (per unit
/// length): Hertz's semi-width `a = (4 p R / (π E*))^½` puts its edge at the initial gap
/// `g_min + a² / (2R) = g_min + 2 p / (π E*)`, whatever the radius. The nodes within that gap
/// (in contact, frictionless: [`Status::Slip`]), or `None` when fewer than three are (a load
/// too small to tell, or none). Where the gap is not such a parabola this is only a start the
/// iteration corrects; where it is (the paper's cylinders on L5: 409 nodes from it against 409
/// at convergence) the frictionless solve takes two iterations instead of eleven (Fig. 2's
/// first step five instead of fourteen), each set a leading set of the prefix factor (the
/// nodes by increasing initial gap).
pub(super) fn hertz_set(gap0: &[f64], p: f64, e_star: f64) -> Option<Vec<Status>> {
    let g_min = gap0.iter().copied().fold(f64::INFINITY, f64::min);
    let edge = g_min + 2.0 * p / (std::f64::consts::PI * e_star);
    let status: Vec<Status> = gap0
        .iter()
        .map(|&g| {
            if g <= edge {
                Status::Slip
            } else {
                Status::Open
            }
        })
        .collect();
    let closed = status.iter().filter(|s| **s == Status::Slip).count();
    (p.is_finite() && e_star > 0.0 && closed >= 3).then_some(status)
}

/// Puts the three nodes of smallest gap in contact (stick with friction, else slip): three
/// nodes span both sides of the closest point, which holds a body the pilot pushes and stops a
/// frictionless rigid sliding mode.
pub(super) fn seed_closest(gaps: &[f64], friction: bool, status: &mut [Status]) {
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

/// The safeguards of the Newton iteration of one step.
pub(super) struct Guard {
    pub(super) verbose: bool,
    /// Iterations in a row with the sets settled and the update small but above the
    /// tolerance, and whether the structured solve has been given up for this step: its
    /// accuracy (a Woodbury update of a cached factor, `W μ` taken from the equations) can
    /// floor the update near 1e-8 on ill-conditioned systems (a steep μ′ with many slip
    /// nodes), where the dense LU still converges.
    pub(super) stalled: usize,
    pub(super) dense_only: bool,
    /// Iterations in a row with the sets fixed and the update not contracting (Newton
    /// cycling across a kink of μ(u), e.g. the end of a ramp, where μ′ jumps), and the
    /// relaxation applied to the update once that is detected.
    pub(super) cycling: usize,
    pub(super) relax: f64,
    pub(super) prev_update: f64,
}

impl Guard {
    pub(super) fn new(verbose: bool) -> Self {
        Guard {
            verbose,
            stalled: 0,
            dense_only: false,
            cycling: 0,
            relax: 1.0,
            prev_update: f64::INFINITY,
        }
    }

    /// Records an iteration that did not converge.
    pub(super) fn observe(&mut self, changes: usize, update: f64) {
        if changes == 0 && update > 1e-5 && update >= 0.5 * self.prev_update {
            self.cycling += 1;
            if self.cycling >= 3 && self.relax == 1.0 {
                self.relax = 0.5;
                if self.verbose {
                    eprintln!(
                        "    the update does not contract ({update:.2e}): halving the steps from here on"
                    );
                }
            }
        } else {
            self.cycling = 0;
        }
        self.prev_update = update;
        if changes == 0 && update < 1e-5 {
            self.stalled += 1;
            if self.stalled >= 2 && !self.dense_only {
                self.dense_only = true;
                if self.verbose {
                    eprintln!(
                        "    the update stalls at {update:.2e}: solving the assembled system from here on"
                    );
                }
            }
        } else {
            self.stalled = 0;
        }
    }
}
