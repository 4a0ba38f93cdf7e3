//! The contact solver on systems small enough to solve by hand: one or two nodes, a given
//! Delassus operator W, no bodies. `y = w0 + W μ` holds the normal gap increments and the
//! tangential relative displacements; μ = (F_n, F_t). Each answer below follows from the
//! complementarity conditions written out (contact: gap 0 and F_n ≥ 0; stick: no relative
//! tangential displacement; slip: |F_t| = μ F_n against the motion).

mod common;
use common::{sci, validation_row};
use faer::Mat;
use stickslip::contact::solver::{
    ContactSystem, Method, Options, PilotDrive, State, Status, StepOutcome,
};
use stickslip::friction::FrictionLaw;

/// A system of `ns` nodes with Delassus operator `w` (2ns × 2ns, row-major) and initial gaps.
fn system(ns: usize, w: &[f64], gap0: &[f64]) -> ContactSystem {
    let m = 2 * ns;
    ContactSystem {
        ns,
        has_pilot: false,
        w: std::sync::Arc::new(Mat::from_fn(m, m, |i, j| w[i * m + j])),
        gap0: gap0.to_vec(),
        v0: vec![0.0; ns],
        c: 1.0,
        eps_unit: vec![1.0; ns],
        kg: vec![],
        weight: vec![1.0 / ns as f64; ns],
        slip_orient: 1.0,
        floating_pilot: false,
        prefix: None,
    }
}

/// Bound on the error of a force, slip or gap against its hand-solved value (all of order 0.1–1):
/// a few units in the last place (measured 0 or 5.6e-17, one unit at 0.4).
const TOL: f64 = 5e-16;

fn options(method: Method) -> Options {
    Options {
        method,
        kappa: 1e6,
        max_iterations: 60,
        tolerance: 1e-12,
        verbose: false,
        history: Default::default(),
        normal_first: true,
        hertz_start: true,
        settle_round_off: false,
    }
}

fn solve(
    sys: &ContactSystem,
    w0: &[f64],
    law: Option<&FrictionLaw>,
    prev: &State,
    method: Method,
) -> StepOutcome {
    sys.solve_step(
        w0,
        [PilotDrive::Force(0.0); 2],
        law,
        prev,
        None,
        &options(method),
        None,
    )
    .expect("the small system converges")
}

/// One node pressed by an imposed approach d through compliance w_n: contact when d > g0,
/// F_n = (d − g0)/w_n; open (F_n = 0) when d < g0. Newton exactly, penalty to 1/κ.
#[test]
fn one_node_normal_contact() {
    let (wn, wt, g0) = (0.5, 0.8, 0.1);
    let sys = system(1, &[wn, 0.0, 0.0, wt], &[g0]);
    let prev = sys.initial_state();
    let mut newton: f64 = 0.0;
    for d in [0.3, 0.05] {
        let out = solve(&sys, &[-d, 0.0], None, &prev, Method::Newton);
        let exact = ((d - g0) / wn).max(0.0);
        let e = (out.state.f_n[0] - exact).abs();
        newton = newton.max(e);
        assert!(e < TOL, "d = {d}: {out:?}");
        let status = if exact > 0.0 {
            Status::Slip
        } else {
            Status::Open
        };
        assert_eq!(
            out.state.status[0], status,
            "frictionless contact is `slip`"
        );
        assert_eq!(out.state.f_t[0], 0.0);
    }
    // Penalty: F_n = ε (penetration), with ε = κ · 1: F_n = (d − g0)/(w_n + 1/ε).
    let out = solve(&sys, &[-0.3, 0.0], None, &prev, Method::Penalty);
    let exact = 0.2 / (wn + 1e-6);
    let penalty = (out.state.f_n[0] - exact).abs();
    let penalty_tol = 3e-16;
    assert!(penalty < penalty_tol, "{out:?}");
    println!("normal contact: Newton error {newton:.2e}, penalty error {penalty:.2e}");
    validation_row(
        "120-small-normal",
        "contact solver on one node with a given Delassus operator: normal contact, closed and open (Newton), closed (penalty)",
        "hand-solved complementarity",
        &format!(
            "Newton to {} (asserted < {TOL:.0e}); penalty, with its 1/κ offset, to {} (asserted < {penalty_tol:.0e})",
            sci(newton),
            sci(penalty)
        ),
        "contact_small",
    );
}

/// One node in contact under Coulomb friction μ = 0.3, with an imposed tangential relative
/// displacement s: stick while |s|/w_t < μ F_n (F_t = −s/w_t), slip beyond (|F_t| = μ F_n,
/// opposing s, and the slip is s − w_t μ F_n).
#[test]
fn one_node_stick_and_slip() {
    let (wn, wt, g0, d) = (0.5, 0.8, 0.0, 0.2);
    let sys = system(1, &[wn, 0.0, 0.0, wt], &[g0]);
    let law = FrictionLaw::constant(0.3).unwrap();
    let prev = sys.initial_state();
    let fn_exact = d / wn; // 0.4: μ F_n = 0.12
    let (mut worst, mut sticks, mut slips): (f64, usize, usize) = (0.0, 0, 0);
    let mut err = |e: f64| {
        worst = worst.max(e);
        e
    };
    for s in [0.05, -0.05, 0.2, -0.2] {
        let out = solve(&sys, &[-d, s], Some(&law), &prev, Method::Newton);
        let st = &out.state;
        assert!(err((st.f_n[0] - fn_exact).abs()) < TOL, "{st:?}");
        let stick_force = -s / wt;
        if stick_force.abs() < 0.3 * fn_exact {
            assert_eq!(st.status[0], Status::Stick, "s = {s}");
            assert!(
                err((st.f_t[0] - stick_force).abs()) < TOL,
                "s = {s}: {st:?}"
            );
            assert!(err(st.slip[0].abs()) < TOL);
            sticks += 1;
        } else {
            assert_eq!(st.status[0], Status::Slip, "s = {s}");
            assert!(
                err((st.f_t[0] + s.signum() * 0.3 * fn_exact).abs()) < TOL,
                "s = {s}: {st:?}"
            );
            let slip = s.abs() - wt * 0.3 * fn_exact;
            assert!(err((st.slip[0] - slip).abs()) < TOL, "s = {s}: {st:?}");
            slips += 1;
        }
    }
    println!("stick and slip: largest error {worst:.2e}");
    validation_row(
        "121-small-coulomb",
        "contact solver on one node: Coulomb stick and slip both ways",
        "hand-solved complementarity",
        &format!(
            "{sticks} stick and {slips} slip states as predicted; F_n, F_t and slip to {} (asserted < {TOL:.0e})",
            sci(worst)
        ),
        "contact_small",
    );
}

/// Two nodes coupled through W: both in contact, F = W_nn⁻¹ (d − g0) solved by hand; when the
/// second node's gap is large enough it stays open and the first carries the load alone.
#[test]
fn two_coupled_nodes() {
    // Normal block [[2, 1], [1, 2]], tangential block identity, no normal–tangential coupling.
    #[rustfmt::skip]
    let w = [
        2.0, 1.0, 0.0, 0.0,
        1.0, 2.0, 0.0, 0.0,
        0.0, 0.0, 1.0, 0.0,
        0.0, 0.0, 0.0, 1.0,
    ];
    let d = 1.0;
    // Both closed: 2 F1 + F2 = d − g1, F1 + 2 F2 = d − g2.
    let sys = system(2, &w, &[0.0, 0.3]);
    let out = solve(
        &sys,
        &[-d, -d, 0.0, 0.0],
        None,
        &sys.initial_state(),
        Method::Newton,
    );
    let (r1, r2) = (d - 0.0, d - 0.3);
    let f1 = (2.0 * r1 - r2) / 3.0;
    let f2 = (2.0 * r2 - r1) / 3.0;
    let closed = (out.state.f_n[0] - f1)
        .abs()
        .max((out.state.f_n[1] - f2).abs());
    assert!(closed < TOL, "{:?}", out.state);
    // Second gap 0.8: with node 1 alone F1 = d/2 = 0.5 and the gap at node 2 is
    // g2 − d + 1·F1 = 0.3 > 0: node 2 stays open.
    let sys = system(2, &w, &[0.0, 0.8]);
    let out = solve(
        &sys,
        &[-d, -d, 0.0, 0.0],
        None,
        &sys.initial_state(),
        Method::Newton,
    );
    let open = (out.state.f_n[0] - 0.5)
        .abs()
        .max((out.state.gap[1] - 0.3).abs());
    assert!(open < TOL, "{:?}", out.state);
    assert_eq!(out.state.f_n[1], 0.0);
    assert_eq!(out.state.status[1], Status::Open);
    println!("two nodes: both closed {closed:.2e}, one open {open:.2e}");
    validation_row(
        "122-small-two-nodes",
        "contact solver on two coupled nodes: both closed; one open",
        "hand-solved complementarity",
        &format!(
            "both closed: forces to {}; one open: force and gap to {}, the open node's force exactly 0 (asserted < {TOL:.0e})",
            sci(closed),
            sci(open)
        ),
        "contact_small",
    );
}

/// Slip weakening on one node: with a ramp law f_s = 0.3 → f_d = 0.2 over 2Δ, Δ = 0.05, an
/// imposed tangential displacement s beyond the stick limit slips by u with
/// |F_t| = μ(u) F_n and u = |s| − w_t |F_t|, a linear equation solved by hand.
#[test]
fn one_node_slip_weakening() {
    let (wn, wt, d) = (0.5, 0.8, 0.2);
    let sys = system(1, &[wn, 0.0, 0.0, wt], &[0.0]);
    let law = FrictionLaw::ramp(0.3, 0.2, 0.05).unwrap();
    let fn_ = d / wn; // 0.4
    let s = 0.15;
    let out = solve(
        &sys,
        &[-d, s],
        Some(&law),
        &sys.initial_state(),
        Method::Newton,
    );
    // μ(u) = 0.3 − 0.1 u / 0.1 = 0.3 − u (u < 0.1); u = s − w_t μ(u) F_n
    // → u = s − 0.32 (0.3 − u) → u (1 − 0.32) = s − 0.096.
    let u = (s - wt * fn_ * 0.3) / (1.0 - wt * fn_);
    assert!(u > 0.0 && u < 0.1);
    let st = &out.state;
    assert_eq!(st.status[0], Status::Slip);
    let tol = TOL;
    let (e_slip, e_force) = ((st.slip[0] - u).abs(), (st.f_t[0] + (0.3 - u) * fn_).abs());
    println!("slip weakening: slip error {e_slip:.2e}, force error {e_force:.2e}");
    assert!(e_slip < tol, "slip {} vs {u}", st.slip[0]);
    assert!(e_force < tol, "{st:?}");
    validation_row(
        "123-small-weakening",
        "contact solver on one node: ramp slip weakening",
        "hand-solved complementarity",
        &format!(
            "slip to {}, |F_t| = μ(u) F_n to {} (asserted < {tol:.0e})",
            sci(e_slip),
            sci(e_force)
        ),
        "contact_small",
    );
}
