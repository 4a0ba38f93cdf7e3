//! Tests of the closed forms (`stickslip::analytic`) and friction laws (`stickslip::friction`)
//! against independent references: numerical quadrature of the defining integrals written out
//! here, limits stated in the paper, and the numbers of `docs/reference.md`.

use clap::Parser;
use std::f64::consts::PI;
use stickslip::analytic::cli::{AnalyticArgs, run};
use stickslip::analytic::dcm::{DoubleCm, Weakening, implied_law_normalized};
use stickslip::analytic::elliptic::{ellipe, ellipk, j_integral};
use stickslip::analytic::jkr::{Jkr, JkrCurve, k_ii};
use stickslip::analytic::{AnalyticError, CattaneoMindlin, Geometry, Hertz};
use stickslip::friction::{FrictionError, FrictionLaw};

/// Composite Simpson rule on `[0, π]` after `x = lo + (hi − lo)(1 − cos φ)/2`, which removes
/// square-root end singularities. Independent of the crate's own code.
fn quad_cos(f: impl Fn(f64) -> f64, lo: f64, hi: f64, m: usize) -> f64 {
    let h = PI / m as f64;
    let mut s = 0.0;
    for i in 0..=m {
        let phi = h * i as f64;
        let x = lo + 0.5 * (hi - lo) * (1.0 - phi.cos());
        let jac = 0.5 * (hi - lo) * phi.sin();
        let w = if i == 0 || i == m {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        s += w * f(x) * jac;
    }
    s * h / 3.0
}

fn vm272() -> Hertz {
    Hertz::new(Geometry::vm272(), 10.0).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

// Reference: definitions of K(m), E(m) (paper, after eq. W1) integrated numerically.
// Tolerance: relative 1e-10.
#[test]
fn elliptic_integrals_match_their_definitions() {
    for &m in &[0.0, 0.3, 0.5, 0.9, 0.999] {
        let k = quad_cos(
            |t: f64| 1.0 / (1.0 - m * t.sin().powi(2)).sqrt(),
            0.0,
            PI / 2.0,
            20000,
        );
        let e = quad_cos(
            |t: f64| (1.0 - m * t.sin().powi(2)).sqrt(),
            0.0,
            PI / 2.0,
            20000,
        );
        assert!(rel(ellipk(m), k) < 1e-10, "K({m}) = {} vs {k}", ellipk(m));
        assert!(rel(ellipe(m), e) < 1e-10, "E({m}) = {} vs {e}", ellipe(m));
    }
}

// Reference: eq. (Maugis1), W = ∫_c^b [q_x − f_d p] |du_x/dx| dx, integrated numerically with
// q_x − f_d p = C sqrt(b² − x²) (eqs. qx, C) and |du_x/dx| from eq. (CM-v2) as printed after
// (Maugis1). Compared with the closed form eq. (W1) (`DoubleCm::energy`), over c/a from 0.001
// to 0.99 and b from c(1 + 1e-4) to a. Tolerance: relative 1e-8.
#[test]
fn w1_matches_quadrature_of_maugis1() {
    let h = vm272();
    let (fs, fd) = (0.15, 0.1);
    let m = DoubleCm::new(h, fs, fd).unwrap();
    let (a, r, es) = (h.a, h.geom.r, h.geom.e_star);
    for &ct in &[0.001, 0.05, 0.3, 0.6, 0.9, 0.99] {
        let c = ct * a;
        for &t in &[1e-4, 1e-2, 0.2, 0.5, 0.9, 1.0] {
            let b = c + t * (a - c);
            let s = ((a * a - c * c) / (b * b - c * c)).sqrt();
            let cc = es * (fs - fd) / (2.0 * r) * s;
            let dudx = |x: f64| (fd + (fs - fd) * s) * (x * x - c * c).max(0.0).sqrt() / r;
            let w_quad = quad_cos(
                |x| cc * (b * b - x * x).max(0.0).sqrt() * dudx(x),
                c,
                b,
                4000,
            );
            let w = m.energy(c, b);
            assert!(
                rel(w, w_quad) < 1e-8,
                "c/a={ct}, t={t}: W1 {w} vs quadrature {w_quad}"
            );
        }
    }
    // J(b, c) by quadrature, both branches (series m ≤ 1/2, elliptic m > 1/2)
    for &(b, c) in &[
        (1.0, 0.999),
        (1.0, 0.8),
        (1.0, std::f64::consts::FRAC_1_SQRT_2),
        (1.0, 0.5),
        (2.0, 0.01),
    ] {
        let jq = quad_cos(
            |x: f64| ((b * b - x * x) * (x * x - c * c)).max(0.0).sqrt(),
            c,
            b,
            4000,
        );
        assert!(rel(j_integral(b, c), jq) < 1e-9, "J({b},{c})");
    }
}

// Reference: eq. (Qx) must equal the integral of eq. (qx2CM) over the contact; the solver's
// state must satisfy (Qx) and the energy condition. Tolerance: relative 1e-8 (quadrature),
// 1e-10 (residuals).
#[test]
fn dcm_traction_integrates_to_force_and_solution_satisfies_both_equations() {
    let h = vm272();
    let m = DoubleCm::new(h, 0.15, 0.1).unwrap();
    let delta = 2.897e-4;
    let q = 0.8;
    let st = m.solve_delta(q, delta).unwrap();
    assert!(rel(m.tangential_force(st.c, st.b), q) < 1e-10);
    let wt = (0.15 - 0.1) * h.pressure(st.c) * delta;
    assert!(rel(m.energy(st.c, st.b), wt) < 1e-10);
    // integrate piecewise (kinks at ±c, ±b)
    let a = h.a;
    let pts = [-a, -st.b, -st.c, st.c, st.b, a];
    let total: f64 = pts
        .windows(2)
        .map(|w| quad_cos(|x| m.traction(x, st.c, st.b), w[0], w[1], 2000))
        .sum();
    assert!(rel(total, q) < 1e-8, "∫q_x = {total}");
    // f = f_s at the stick boundary, f_d beyond b
    assert!(rel(m.local_friction(st.c, st.c, st.b), 0.15) < 1e-12);
    assert!(rel(m.local_friction(0.5 * (st.b + a), st.c, st.b), 0.1) < 1e-12);
    // W(c, b) increases with b (assumed by the bisection in b)
    for &ct in &[0.01, 0.3, 0.7, 0.95] {
        let c = ct * a;
        let mut prev = 0.0;
        for i in 1..=200 {
            let b = c + (a - c) * i as f64 / 200.0;
            let w = m.energy(c, b);
            assert!(w > prev, "W not increasing in b at c/a={ct}");
            prev = w;
        }
    }
}

// Reference: the JKR limit eq. (QJKR)/(qxJKRDelta) is the Λ → 0 limit of the double C–M
// solution (§4.2). Sequence Λ = 0.1 … 1e-4 at f_s = 0.15, f_d = 0.1, Q = 0.8 f_d P: the
// difference in c/a must shrink monotonically and fall below 2e-4 at Λ = 1e-4.
#[test]
fn dcm_tends_to_jkr_as_lambda_vanishes() {
    let h = vm272();
    let (fs, fd) = (0.15, 0.1);
    let m = DoubleCm::new(h, fs, fd).unwrap();
    let mut prev = f64::INFINITY;
    let mut last = 0.0;
    for &lam in &[0.1, 0.05, 0.02, 0.01, 0.005, 0.002, 0.001, 1e-4] {
        let delta = lam * (fs - fd) * h.a * h.a / h.geom.r;
        let st = m.solve_delta(0.8 * fd * h.p_load, delta).unwrap();
        let jkr = Jkr::new(h, fs, fd, delta).unwrap();
        let cj = jkr.curve().stick_half_width(0.8).unwrap();
        let diff = (st.c / h.a - cj).abs();
        assert!(
            diff < prev,
            "Λ={lam}: |Δc/a| = {diff} did not shrink (previous {prev})"
        );
        prev = diff;
        last = diff;
        assert!(st.b >= st.c && st.b <= h.a);
    }
    assert!(last < 2e-4, "{last}");
}

// Reference: paper §4.1 — when b = a the double C–M traction is C–M with f = f_s (eq. C-M);
// when f_s = f_d (or Δ = 0, §3) it is C–M with f = f_d. Tolerance: 1e-12 relative for the
// identities, 1e-6 for the near-limit f_s = f_d(1 + 1e-8).
#[test]
fn cattaneo_mindlin_is_recovered() {
    let h = vm272();
    let (fs, fd) = (0.15, 0.1);
    let m = DoubleCm::new(h, fs, fd).unwrap();
    let cm_fs = CattaneoMindlin::new(h, fs).unwrap();
    let cm_fd = CattaneoMindlin::new(h, fd).unwrap();
    let c = 0.55 * h.a;
    for i in 0..=50 {
        let x = -h.a + 2.0 * h.a * i as f64 / 50.0;
        let q1 = m.traction(x, c, h.a);
        let q2 = cm_fs.traction(x, c);
        assert!((q1 - q2).abs() <= 1e-12 * h.p0, "x={x}: {q1} vs {q2}");
    }
    // solving with exactly the energy that makes b = a at the C–M(f_s) stick radius
    let q = 0.9 * fd * h.p_load;
    let c_fs = cm_fs.stick_half_width(q).unwrap();
    let w = m.energy(c_fs, h.a);
    let st = m.solve_energy(q, w).unwrap();
    assert!(rel(st.c, c_fs) < 1e-9 && rel(st.b, h.a) < 1e-9, "{st:?}");
    // slightly more energy: b would exceed a → typed error naming the C–M(f_s) radius
    match m.solve_energy(q, 1.01 * w) {
        Err(AnalyticError::BExceedsA { c_cm_fs, .. }) => assert!(rel(c_fs, c_cm_fs) < 1e-12),
        other => panic!("expected BExceedsA, got {other:?}"),
    }
    // Δ = 0: abrupt transition, §3
    let c0 = m.solve_delta(q, 0.0).unwrap().c;
    assert!(rel(c0, cm_fd.stick_half_width(q).unwrap()) < 1e-12);
    // f_s = f_d exactly, and nearly
    let eq = DoubleCm::new(h, fd, fd).unwrap();
    assert!(
        rel(
            eq.solve_delta(q, 1e-3).unwrap().c,
            cm_fd.stick_half_width(q).unwrap()
        ) < 1e-12
    );
    let near = DoubleCm::new(h, fd * (1.0 + 1e-8), fd).unwrap();
    let cn = near.solve_delta(q, 1e-3).unwrap().c;
    assert!(rel(cn, cm_fd.stick_half_width(q).unwrap()) < 1e-6, "{cn}");
    assert!(matches!(
        eq.solve_energy(q, 1e-4),
        Err(AnalyticError::NoWeakening { .. })
    ));
}

// Reference: eq. (QJKR) with Ψ = 0 is 1 − c²/a², maximum f_d P at c = 0 (Discussion: "all the
// curves except the limiting case Ψ = 0 exhibit a maximum at non-zero c"). For Ψ > 0 the
// maximum is compared with a brute-force scan of eq. (QJKR) written out here.
// Tolerances: exact for Ψ = 0; 1e-9 on Q_max and 1e-4 on c/a for the scan (10⁶ samples).
#[test]
fn jkr_maximum() {
    let m0 = JkrCurve::new(0.0).unwrap().maximum();
    assert_eq!((m0.c_over_a, m0.q_ratio), (0.0, 1.0));
    for &psi in &[1e-6, 0.01, 0.1, 0.5, 2.0] {
        let g = |c: f64| 1.0 - c * c + 4.0 * (psi * c * (1.0 - c * c).sqrt() / PI).sqrt();
        let (mut cb, mut gb) = (0.0, g(0.0));
        for i in 1..1_000_000 {
            let c = i as f64 / 1e6;
            if g(c) > gb {
                cb = c;
                gb = g(c);
            }
        }
        let m = JkrCurve::new(psi).unwrap().maximum();
        assert!(
            (m.q_ratio - gb).abs() < 1e-9,
            "Ψ={psi}: {} vs {gb}",
            m.q_ratio
        );
        assert!(
            (m.c_over_a - cb).abs() < 1e-4,
            "Ψ={psi}: {} vs {cb}",
            m.c_over_a
        );
        assert!(m.c_over_a > 0.0);
    }
    // small Ψ: Q_max → f_d P
    assert!((JkrCurve::new(1e-12).unwrap().maximum().q_ratio - 1.0).abs() < 1e-5);
    assert!(matches!(
        JkrCurve::new(-0.1),
        Err(AnalyticError::NegativePsi { .. })
    ));
}

// Reference: eq. (KII), K_II = lim_{x→c⁻} q_x(x) sqrt(2π(c − x)) = sqrt(2 W E*), evaluated
// numerically from the traction eq. (qxJKRDelta) at c − x = 1e-6 c … 1e-12 c, and eq. (KIIa).
// Tolerance: relative 1e-4 at c − x = 1e-12 c, with monotonically decreasing error.
#[test]
fn k_ii_is_the_limit_of_the_singular_traction() {
    let h = vm272();
    let (fs, fd, delta) = (0.15, 0.1, 2.897e-4);
    let jkr = Jkr::new(h, fs, fd, delta).unwrap();
    let c = 0.6 * h.a;
    let w = (fs - fd) * h.pressure(c) * delta;
    let k_ref = (2.0 * w * h.geom.e_star).sqrt();
    assert!(rel(k_ii(w, h.geom.e_star), k_ref) < 1e-14);
    assert!(rel(jkr.k_ii(c), k_ref) < 1e-14);
    let mut prev = f64::INFINITY;
    for &eps in &[1e-6, 1e-8, 1e-10, 1e-12] {
        let x = c * (1.0 - eps);
        let k = jkr.traction(x, c) * (2.0 * PI * (c - x)).sqrt();
        let e = rel(k, k_ref);
        assert!(e < prev, "error did not decrease at eps={eps}");
        prev = e;
    }
    assert!(prev < 1e-4, "{prev}");
}

// Reference: docs/reference.md — a = 0.6808 mm, p0 = 9.351 N/mm², E* = 109.89 N/mm²,
// c = 0.4965 mm, c/a = 0.729 at Q = 0.936 N/mm, μ = 0.2. Tolerances: half a unit of the last
// quoted digit.
#[test]
fn hertz_and_cattaneo_numbers_of_vm272() {
    let h = vm272();
    assert!((h.geom.r - 4.0).abs() < 1e-12);
    assert!((h.geom.e_star - 109.89).abs() < 5e-3);
    assert!((h.a - 0.6808).abs() < 5e-5, "a = {}", h.a);
    assert!((h.p0 - 9.351).abs() < 5e-4, "p0 = {}", h.p0);
    let cm = CattaneoMindlin::new(h, 0.2).unwrap();
    let c = cm.stick_half_width(0.936).unwrap();
    assert!((c - 0.4965).abs() < 5e-5, "c = {c}");
    assert!((c / h.a - 0.729).abs() < 5e-4);
    assert!((cm.stick_half_width(0.93622).unwrap() / h.a - 0.729).abs() < 5e-4);
    // p(x) integrates to P (quadrature), tolerance 1e-10
    let p_int = quad_cos(|x| h.pressure(x), -h.a, h.a, 2000);
    assert!(rel(p_int, 10.0) < 1e-10);
    assert!(matches!(
        cm.stick_half_width(2.5),
        Err(AnalyticError::QAboveLimit { .. })
    ));
}

// Reference: eq. (Maugis) W/p = ∫(f − f_d)du by trapezoid quadrature of `mu(u)` on a fine
// grid (independent of the closed forms in `w_over_p`), and W/p = (f_s − f_d)Δ for every
// parametric shape. Tolerance: relative 2e-5 (trapezoid with 2·10⁶ intervals over 40Δ; the
// step's jump costs half an interval, 1e-5 relative).
#[test]
fn friction_law_integrals() {
    let (fs, fd, d) = (0.15, 0.1, 2.9e-4);
    let laws = [
        FrictionLaw::ramp(fs, fd, d).unwrap(),
        FrictionLaw::step(fs, fd, d).unwrap(),
        FrictionLaw::exponential(fs, fd, d).unwrap(),
        FrictionLaw::table(&[
            [0.0, 0.2],
            [1e-4, 0.18],
            [3e-4, 0.18],
            [5e-4, 0.12],
            [6e-4, 0.12],
        ])
        .unwrap(),
    ];
    for law in &laws {
        let fdl = law.f_dynamic().unwrap();
        let u_end = 40.0 * d;
        let n = 2_000_000;
        let h = u_end / n as f64;
        let mut w = 0.0;
        for i in 0..n {
            let (u0, u1) = (h * i as f64, h * (i + 1) as f64);
            w += 0.5 * h * (law.mu(u0) + law.mu(u1) - 2.0 * fdl);
        }
        let wp = law.w_over_p().unwrap();
        assert!(rel(wp, w) < 2e-5, "{law:?}: {wp} vs {w}");
        let delta = law.delta().unwrap();
        assert!(rel(wp, (law.f_static() - fdl) * delta) < 1e-12);
    }
    for law in &laws[..3] {
        assert!(rel(law.w_over_p().unwrap(), (fs - fd) * d) < 1e-14);
        assert_eq!(law.f_static(), fs);
    }
    // shapes
    let ramp = &laws[0];
    assert!(rel(ramp.mu(d), 0.5 * (fs + fd)) < 1e-14);
    assert_eq!(ramp.mu(2.0 * d), fd);
    assert_eq!(ramp.dmu_du(0.5 * d), Some(-(fs - fd) / (2.0 * d)));
    let step = &laws[1];
    assert_eq!((step.mu(d), step.mu(d * (1.0 + 1e-12))), (fs, fd));
    assert_eq!(step.dmu_du(d), None, "a step has no derivative at the jump");
    assert_eq!(step.dmu_du(0.5 * d), Some(0.0));
    // a table reproducing the step
    let t = FrictionLaw::table(&[[0.0, fs], [d, fs], [d, fd]]).unwrap();
    for &u in &[0.0, 0.5 * d, d, 1.5 * d] {
        assert_eq!(t.mu(u), step.mu(u));
    }
    assert_eq!(t.dmu_du(d), None);
    // presets: Table 1
    let p = FrictionLaw::preset("lead-mild-steel").unwrap();
    assert_eq!(
        p,
        FrictionLaw::Ramp {
            fs: 0.72,
            fd: 0.47,
            delta: 3e-3
        }
    );
    assert_eq!(FrictionLaw::preset_names().len(), 5);
    assert!(matches!(
        FrictionLaw::preset("gold"),
        Err(FrictionError::UnknownPreset { .. })
    ));
}

// Reference: the validation rules documented on `friction::Table`. Errors must name the row.
#[test]
fn table_validation_errors() {
    let e = FrictionLaw::table(&[[0.0, 0.2]]).unwrap_err();
    assert_eq!(e, FrictionError::TooFewRows { rows: 1 });
    let e = FrictionLaw::table(&[[0.0, 0.2], [1.0, 0.1], [0.5, 0.1]]).unwrap_err();
    assert!(matches!(e, FrictionError::RowSlipDecreasing { row: 2, .. }));
    assert!(e.to_string().contains("row 2"), "{e}");
    let e = FrictionLaw::table(&[[0.0, 0.2], [1.0, -0.1]]).unwrap_err();
    assert!(matches!(e, FrictionError::RowNegativeMu { row: 1, .. }));
    let e = FrictionLaw::table(&[[0.0, 0.2], [f64::NAN, 0.1]]).unwrap_err();
    assert!(matches!(e, FrictionError::RowNotFinite { row: 1, .. }));
    let e = FrictionLaw::table(&[[-1.0, 0.2], [1.0, 0.1]]).unwrap_err();
    assert!(matches!(e, FrictionError::RowNegativeSlip { row: 0, .. }));
    let e = FrictionLaw::table(&[[0.0, 0.2], [1.0, 0.15], [1.0, 0.12], [1.0, 0.1]]).unwrap_err();
    assert!(matches!(e, FrictionError::RowTripleSlip { row: 3, .. }));
    // a table ending on a slope does not settle
    let t = FrictionLaw::table(&[[0.0, 0.2], [1.0, 0.1]]).unwrap();
    assert!(matches!(
        t.f_dynamic(),
        Err(FrictionError::TableNotSettled { .. })
    ));
    assert!(t.delta().is_err() && t.w_over_p().is_err());
    // parametric checks
    assert!(matches!(
        FrictionLaw::ramp(0.1, 0.15, 1e-3),
        Err(FrictionError::FdExceedsFs { .. })
    ));
    assert!(matches!(
        FrictionLaw::step(0.15, 0.1, -1e-3),
        Err(FrictionError::NegativeDelta { .. })
    ));
    // JSON: unknown fields and bad rows rejected
    assert!(
        serde_json::from_str::<FrictionLaw>(
            r#"{"shape":"step","fs":0.15,"fd":0.1,"delta":1e-3,"extra":1}"#
        )
        .is_err()
    );
    let err = serde_json::from_str::<FrictionLaw>(
        r#"{"shape":"table","rows":[[0,0.2],[1,0.1],[0.5,0.1]]}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("row 2"), "{err}");
}

// Reference: Fig. 1 construction — the implied law starts at f_s (normalized 1) at u = 0 and,
// by definition of Δ* (eq. Maugis10), ∫ f_norm d(u/Δ*) = 1. Trapezoid over the samples,
// tolerance 2e-3 (2001 samples).
#[test]
fn implied_law_is_normalized() {
    for &(ac, bc) in &[(1.6, 1.5), (8.0, 4.5), (8.0, 1.2)] {
        let pts = implied_law_normalized(ac, bc, 2001).unwrap();
        assert!((pts[0][1] - 1.0).abs() < 1e-12 && pts[0][0] == 0.0);
        let integral: f64 = pts
            .windows(2)
            .map(|w| 0.5 * (w[1][0] - w[0][0]) * (w[0][1] + w[1][1]))
            .sum();
        assert!(
            (integral - 1.0).abs() < 2e-3,
            "a/c={ac}, b/c={bc}: {integral}"
        );
        // monotonically decreasing f
        assert!(pts.windows(2).all(|w| w[1][1] <= w[0][1] + 1e-12));
    }
    assert!(implied_law_normalized(1.6, 1.7, 10).is_err());
}

// Reference: the paper's Fig. 5 statement that Q_max is "very well predicted by the JKR
// theory even for Λ = 0.4" (Ψ = 0.1), and that the double C–M maximum tends to the JKR one as
// Λ → 0. Tolerances on Q_max: 1 % at Λ = 0.4, 0.2 % at Λ = 0.025, 0.01 % at Λ = 0.001.
#[test]
fn dcm_maximum_close_to_jkr_maximum() {
    let jkr = JkrCurve::new(0.1).unwrap().maximum();
    for &(lam, tol) in &[(0.4, 1e-2), (0.025, 2e-3), (0.001, 1e-4)] {
        let r = 1.0 + (0.1_f64 / lam).sqrt();
        let (m, weak) = DoubleCm::normalized(r, lam).unwrap();
        let (_, st) = m.max_force(weak).unwrap();
        let q = st.q / (PI / 4.0);
        assert!(rel(q, jkr.q_ratio) < tol, "Λ={lam}: {q} vs {}", jkr.q_ratio);
        assert!(st.c < jkr.c_over_a, "maximum shifted left (paper)");
    }
    // a force above the maximum: typed error
    let (m, weak) = DoubleCm::normalized(1.5, 0.1).unwrap();
    let err = m.solve(1.3 * PI / 4.0, weak).unwrap_err();
    assert!(matches!(err, AnalyticError::QAboveLimit { .. }), "{err:?}");
    // Weakening::Energy and SlipLength agree at the solution
    let st = m.solve(0.9 * PI / 4.0, weak).unwrap();
    let st2 = m.solve(0.9 * PI / 4.0, Weakening::Energy(st.w)).unwrap();
    assert!(rel(st2.c, st.c) < 1e-9);
}

#[derive(Parser)]
struct TestCli {
    #[command(flatten)]
    a: AnalyticArgs,
}

/// Runs `stickslip analytic` in-process on `args`, a command line split at whitespace.
fn cli(args: &str) -> Result<String, String> {
    let mut v = vec!["stickslip"];
    v.extend(args.split_whitespace());
    let parsed = TestCli::try_parse_from(v).map_err(|e| e.to_string())?;
    let mut buf = Vec::new();
    run(&parsed.a, &mut buf).map_err(|e| e.to_string())?;
    Ok(String::from_utf8(buf).unwrap())
}

// Reference: the required CLI examples of the brief; numbers re-checked against the library
// and the JKR maximum of eq. (QJKR). Tolerance 1e-12.
#[test]
fn cli_examples() {
    let out = cli("jkr --psi 0.1").unwrap();
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let m = JkrCurve::new(0.1).unwrap().maximum();
    assert!((v["q_max_ratio"].as_f64().unwrap() - m.q_ratio).abs() < 1e-12);
    assert!((v["c_max_over_a"].as_f64().unwrap() - m.c_over_a).abs() < 1e-12);
    let out = cli("dcm --fs 0.15 --fd 0.1 --lambda 0.05 --q-ratio 0.8").unwrap();
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let (c, b) = (
        v["c_over_a"].as_f64().unwrap(),
        v["b_over_a"].as_f64().unwrap(),
    );
    assert!(0.0 < c && c < b && b < 1.0);
    let out = cli("jkr-curve --psi 0.1 --n 11").unwrap();
    assert_eq!(out.lines().next().unwrap(), "c_over_a,q_ratio,stable");
    assert_eq!(out.lines().count(), 12);
    let out = cli("cm --mu 0.2 --q 0.936").unwrap();
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!((v["c_over_a"].as_f64().unwrap() - 0.729).abs() < 5e-4);
}

// Reference: bad parameters must give an error whose message names the problem.
#[test]
fn cli_bad_parameters() {
    let cases: &[(&str, &str)] = &[
        (
            "dcm --fs 0.1 --fd 0.15 --lambda 0.05 --q-ratio 0.8",
            "exceeds f_s",
        ),
        ("jkr --psi=-0.1", "Psi must be non-negative"),
        ("jkr --psi 0.1 --q-ratio 1.5", "exceeds Q_max/(f_d P)"),
        (
            "dcm --fs 0.15 --fd 0.1 --lambda 0.05 --q-ratio 1.6",
            "exceeds f_s P",
        ),
        (
            "dcm --fs 0.15 --fd 0.1 --lambda 5 --q-ratio 0.5",
            "b would exceed a",
        ),
        (
            "dcm --fs 0.15 --fd 0.1 --delta=-1e-3 --q-ratio 0.5",
            "must be non-negative",
        ),
        ("cm --mu 0.2 --q 3", "exceeds f P"),
        ("hertz --nu1 0.7", "Poisson"),
        ("hertz --load=-1", "must be positive"),
        (
            r#"law --json {"shape":"table","rows":[[0,0.2]]}"#,
            "at least 2 rows",
        ),
        ("law --preset gold", "unknown friction preset"),
        ("law --shape ramp --fs 0.15 --fd 0.1", "--delta is required"),
        ("implied-law --a-over-c 1.6 --b-over-c 2", "outside"),
        ("apparent --chi 0.05 --fs-over-fd 0.9", "exceeds f_s"),
        ("dcm --fs 0.15 --fd 0.1 --q-ratio 0.8", "required"),
    ];
    for (args, needle) in cases {
        let e = cli(args).expect_err(&format!("{args:?} should fail"));
        assert!(
            e.contains(needle),
            "{args:?}: message `{e}` lacks `{needle}`"
        );
    }
    // an unsettled table is reported, not an error
    let out = cli(r#"law --json {"shape":"table","rows":[[0,0.2],[1,0.1]]}"#).unwrap();
    assert!(out.contains("does not settle"), "{out}");
    // The history a case may give the law: named, and explained where it matters.
    let out =
        cli("law --shape ramp --fs 0.2 --fd 0.15 --delta 2e-4 --history since_stick").unwrap();
    assert!(
        out.contains(r#""history": "since_stick""#) && out.contains("regains f_s = 0.2"),
        "{out}"
    );
    let out = cli("law --shape constant --fs 0.2 --history since_stick").unwrap();
    assert!(out.contains("makes no difference"), "{out}");
}
