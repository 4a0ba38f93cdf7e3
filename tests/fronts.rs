//! The fronts of the stick zone at each end and the mode-II stress intensity measured there
//! (`stickslip::model::fronts`; the columns `c_left … k2_paper` of `history.csv`):
//!
//! * the estimator on synthetic fields: the paper's JKR field (eq. sing) and any field of its
//!   form are recovered to rounding at both ends, a field singular at one end only to 0.1 %
//!   there; the face read in either direction and with the shear of either sign;
//! * the small-scale-transition claim (eqs. KII, KIIa, Lambda): on the VM272 ladder with the
//!   ramp law of Fig. 2, K_II / sqrt(2 W E*) approaches 1 as Λ falls (L5 at Λ = 0.05, L6 at
//!   0.0125, L7 at 0.003), close to what the same estimator reads from the double
//!   Cattaneo–Mindlin field (eq. qx2CM, `stickslip::analytic`), and `k2_paper` against the
//!   closed form evaluated here;
//! * Cattaneo–Mindlin (constant μ, no weakening): no singularity, K_II ≈ 0 and no `k2_paper`;
//!   the ends consistent with `c`; a record without the columns (an older journal or state)
//!   still reads.
mod common;
use common::{Table, run_case, shipped_case, shipped_case_on, validation_row};
use serde_json::json;
use stickslip::analytic::dcm::DoubleCm;
use stickslip::analytic::hertz::{Geometry, Hertz};
use stickslip::contact::solver::Status;
use stickslip::model::fronts::{Face, MIN_POINTS, Zone, k2_ends, k2_fit};
use stickslip::model::step::ContactFigures;

use std::f64::consts::PI;

/// `n` evenly spaced positions strictly inside `(lo, hi)`.
fn grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (1..n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect()
}

/// The paper's JKR field (eq. sing) in excess of `f_d p`, with the Hertz constants `E*/2R = k`:
/// `e(x) = K sqrt(c / (π (c² − x²))) − f_d k sqrt(c² − x²)`, whose stress intensity at `x = ±c`
/// is `K` (eq. KII).
fn jkr_excess(x: f64, c: f64, k2: f64, fd: f64, k: f64) -> f64 {
    k2 * (c / (PI * (c * c - x * x))).sqrt() - fd * k * (c * c - x * x).sqrt()
}

#[test]
fn k2_fit_recovers_the_paper_field_to_rounding() {
    // Symmetric JKR field: c = 0.4, K = 0.15, f_d = 0.1, E*/2R = 13.7 (VM272-like).
    let (c, k2, fd, k) = (0.4, 0.15, 0.1, 13.7);
    let x = grid(-c, c, 400);
    let e: Vec<f64> = x.iter().map(|&x| jkr_excess(x, c, k2, fd, k)).collect();
    let h = 2.0 * c / 400.0;
    for end in 0..2 {
        let got = k2_fit(&x, &e, [-c, c], end, 3.0 * h).unwrap();
        println!("JKR field, end {end}: K = {got:.15} (exact {k2})");
        assert!((got / k2 - 1.0).abs() < 1e-10, "end {end}: {got}");
    }
    // Any field of the form w(x)/sqrt((t1 − x)(x − t0)) with w quadratic: unequal stress
    // intensities at tips not centred on 0.
    let (t0, t1) = (-0.3, 0.5);
    let w = |x: f64| 0.02 + 0.05 * x - 0.3 * x * x;
    let x = grid(t0, t1, 300);
    let e: Vec<f64> = x
        .iter()
        .map(|&x| w(x) / ((t1 - x) * (x - t0)).sqrt())
        .collect();
    for (end, t) in [(0, t0), (1, t1)] {
        let exact = w(t) * (2.0 * PI / (t1 - t0)).sqrt();
        let got = k2_fit(&x, &e, [t0, t1], end, 0.02).unwrap();
        println!("quadratic w, end {end}: K = {got:.15} (exact {exact:.15})");
        assert!(
            (got / exact - 1.0).abs() < 1e-10,
            "end {end}: {got} vs {exact}"
        );
    }
}

#[test]
fn k2_fit_recovers_a_one_ended_singular_field() {
    // e = K / sqrt(2π ρ), ρ = t1 − x: singular at the right end only, bounded at the left.
    let (t0, t1, k2) = (-0.5, 0.5, 0.2);
    let x = grid(t0, t1, 400);
    let e: Vec<f64> = x
        .iter()
        .map(|&x| k2 / (2.0 * PI * (t1 - x)).sqrt())
        .collect();
    let h = (t1 - t0) / 400.0;
    let right = k2_fit(&x, &e, [t0, t1], 1, 3.0 * h).unwrap();
    println!("one-ended field: K_right / K = {:.6}", right / k2);
    // Measured 8.9e-4 off: w = e sqrt((t1 − x)(x − t0)) = K sqrt((x − t0)/2π) is not a
    // quadratic, and its fit over the right half of the zone extrapolates to the tip. (At the
    // bounded left end the same fit reads 0.13 K from the sqrt(x − t0) of w there; a stick
    // front of the contact problem is never bounded and non-zero: its regular part vanishes as
    // sqrt(ρ), which w carries as a linear term.)
    assert!((right / k2 - 1.0).abs() < 1.5e-3, "{right}");
}

#[test]
fn k2_fit_needs_enough_nodes_in_the_band() {
    let (c, k2, fd, k) = (0.4, 0.15, 0.1, 13.7);
    let x = grid(-c, c, 40);
    let e: Vec<f64> = x.iter().map(|&x| jkr_excess(x, c, k2, fd, k)).collect();
    // The band [rho_min, c] of the right end holds the nodes with x ≤ c − rho_min.
    let in_band = |rho_min: f64| {
        x.iter()
            .filter(|&&x| c - x >= rho_min && c - x <= c)
            .count()
    };
    let rho_ok = (0..40)
        .map(|i| c * i as f64 / 40.0)
        .rfind(|&r| in_band(r) >= MIN_POINTS)
        .unwrap();
    assert!(k2_fit(&x, &e, [-c, c], 1, rho_ok).is_some());
    assert!(k2_fit(&x, &e, [-c, c], 1, rho_ok + 0.5 * c / 20.0).is_none());
    // No tips apart: no value.
    assert!(k2_fit(&x, &e, [c, c], 1, 0.0).is_none());
}

/// A face of nodes on `x` (in the order given) with the JKR traction of [`jkr_excess`] in the
/// stick zone |x| < c, `μ p` slip beyond; shear of sign `s`.
fn jkr_face(x: &[f64], c: f64, k2: f64, s: f64) -> (Vec<f64>, Vec<f64>, Vec<Status>) {
    let (fd, k, a) = (0.1, 13.7, 0.7);
    let p: Vec<f64> = x.iter().map(|&x| k * (a * a - x * x).sqrt()).collect();
    let status: Vec<Status> = x
        .iter()
        .map(|&x| {
            if x.abs() < c {
                Status::Stick
            } else {
                Status::Slip
            }
        })
        .collect();
    let tau: Vec<f64> = x
        .iter()
        .zip(&p)
        .map(|(&x, &p)| {
            let e = if x.abs() < c {
                jkr_excess(x, c, k2, fd, k)
            } else {
                0.0
            };
            s * (fd * p + e)
        })
        .collect();
    (p, tau, status)
}

#[test]
fn k2_ends_read_either_face_direction_and_shear_sign() {
    let (a, k2) = (0.7, 0.15);
    let n = 700;
    // Nodes between the node positions, so that the stick front c = 0.4 is midway between two.
    let x: Vec<f64> = (0..n)
        .map(|i| -a + 2.0 * a * (i as f64 + 0.5) / n as f64)
        .collect();
    let c_nodes = 0.4;
    let spacing = 2.0 * a / n as f64;
    let h = vec![2.0 * spacing; n];
    let mut seen = Vec::new();
    for reversed in [false, true] {
        for s in [1.0, -1.0] {
            let xs: Vec<f64> = if reversed {
                x.iter().rev().copied().collect()
            } else {
                x.clone()
            };
            let (p, tau, status) = jkr_face(&xs, c_nodes, k2, s);
            let stick = Zone::of(&xs, |j| status[j] == Status::Stick).unwrap();
            let [l, r] = stick.left_right();
            assert!((l + c_nodes).abs() < 1e-12 && (r - c_nodes).abs() < 1e-12);
            let face = Face {
                x: &xs,
                p: &p,
                tau: &tau,
                status: &status,
                h: &h,
            };
            let k = k2_ends(&face, &stick, None, 0.1);
            let (kl, kr) = if stick.ends[0] < stick.ends[1] {
                (k[0].unwrap(), k[1].unwrap())
            } else {
                (k[1].unwrap(), k[0].unwrap())
            };
            println!("reversed {reversed}, shear sign {s}: K = {kl:.12}, {kr:.12}");
            // The nodes resolve the field exactly: K to rounding, whatever the order or sign.
            assert!((kl / k2 - 1.0).abs() < 1e-9 && (kr / k2 - 1.0).abs() < 1e-9);
            seen.push((kl, kr));
            // Without a slipping node beyond the front, no value at that end.
            let mut closed = status.clone();
            let beyond = if stick.ends[0] < stick.ends[1] {
                stick.first - 1
            } else {
                stick.last + 1
            };
            closed[beyond] = Status::Open;
            let face = Face {
                status: &closed,
                ..face
            };
            let k = k2_ends(&face, &stick, None, 0.1);
            assert_eq!(k.iter().filter(|v| v.is_none()).count(), 1);
        }
    }
    assert!(seen.windows(2).all(|w| (w[0].0 - w[1].0).abs() < 1e-12));
}

/// The last step of a Fig. 2 run (ramp law, Q = 0.8 f_d P) on `vm272_L{level}` at `lambda`:
/// its `history.csv` and contact CSV.
fn fig2_run(level: usize, lambda: f64) -> (Table, Table) {
    let mut v = shipped_case_on("fig2.json", &format!("vm272_L{level}.msh"));
    v["contact"]["friction"]["lambda"] = json!(lambda);
    v["output"] = json!({"vtu": false, "every": 1000});
    let r = run_case(&format!("fronts-L{level}"), &v, &["--quiet"]);
    r.assert_ok(&format!("Fig. 2 on L{level}, Λ = {lambda}"));
    (r.history(), r.last_contact())
}

/// What the estimator reads from the double Cattaneo–Mindlin field (eq. qx2CM) at `Q = 0.8
/// f_d P` and `lambda`, sampled at the positions `x` with element length `h`, over
/// `sqrt(2 W E*)` with `W` at the Hertz pressure of its tip `(c + b)/2`.
fn dcm_ratio(lambda: f64, x: &[f64], h: f64) -> f64 {
    let hz = Hertz::new(Geometry::vm272(), 10.0).unwrap();
    let (fs, fd) = (0.15, 0.1);
    let delta = lambda * (fs - fd) * hz.a * hz.a / hz.geom.r;
    let dcm = DoubleCm::new(hz, fs, fd).unwrap();
    let st = dcm.solve_delta(0.8, delta).unwrap();
    let t = 0.5 * (st.c + st.b);
    let (xs, es): (Vec<f64>, Vec<f64>) = x
        .iter()
        .filter(|x| x.abs() < st.c)
        .map(|&x| (x, dcm.traction(x, st.c, st.b) - fd * hz.pressure(x)))
        .unzip();
    let k = k2_fit(&xs, &es, [-t, t], 1, (3.0 * h).max(4.0 * (st.b - st.c))).unwrap();
    let paper = (2.0 * hz.geom.e_star * (fs - fd) * delta * hz.pressure(t)).sqrt();
    k / paper
}

/// One Fig. 2 run of the ladder: its K_II / sqrt(2 W E*) (mean of the two ends) and what the
/// estimator reads from the double C–M field on its nodes; checks its fronts and `k2_paper`.
fn ladder_point(level: usize, lambda: f64) -> (f64, f64) {
    let hz = Hertz::new(Geometry::vm272(), 10.0).unwrap();
    let fs_fd = 0.15 - 0.1;
    let (hist, contact) = fig2_run(level, lambda);
    let get = |name: &str| hist.last(name);
    let (cl, cr, bl, br) = (get("c_left"), get("c_right"), get("b_left"), get("b_right"));
    let (kl, kr, kp) = (get("k2_left"), get("k2_right"), get("k2_paper"));
    // The ends carry the symmetric widths.
    assert!((0.5 * (cr - cl) - get("c")).abs() < 1e-9 * hz.a);
    assert!((0.5 * (br - bl) - get("b")).abs() < 1e-9 * hz.a);
    // k2_paper: sqrt(2 E* W) with W = (f_s − f_d) Δ p_H(t), t the mean tip (c + b)/2 (the
    // contact stays centred to 3e-5 a), evaluated here with the closed-form Hertz.
    let delta = lambda * fs_fd * hz.a * hz.a / hz.geom.r;
    let t = 0.25 * ((cr + br) - (cl + bl));
    let paper = (2.0 * hz.geom.e_star * fs_fd * delta * hz.pressure(t)).sqrt();
    let x: Vec<f64> = contact.rows.iter().map(|r| r[0]).collect();
    let h = 2.0 * (x[x.len() / 2 + 1] - x[x.len() / 2]).abs();
    let dcm = dcm_ratio(lambda, &x, h);
    println!(
        "L{level} Λ = {lambda}: c = [{cl:.5}, {cr:.5}], b = [{bl:.5}, {br:.5}], K_II = {kl:.5}, {kr:.5}; \
         sqrt(2WE*) = {kp:.5} (closed form here {paper:.5}); K/sqrt(2WE*) = {:.4}, {:.4}; double C–M field {dcm:.4}",
        kl / kp,
        kr / kp
    );
    // Measured 1.8e-4: the run's R is fitted to the initial gaps of its mesh (4.0011 on L5)
    // and its load is the contact force, where this takes R = 4 and P = 10.
    assert!((kp / paper - 1.0).abs() < 5e-4, "k2_paper {kp} vs {paper}");
    // Symmetric problem: measured 1.4e-3 apart on L5, 1e-5 on L6 and L7.
    assert!((kl / kr - 1.0).abs() < 3e-3, "ends {kl} {kr}");
    (0.5 * (kl + kr) / kp, dcm)
}

#[test]
fn fe_k2_approaches_the_paper_value_as_lambda_falls() {
    // (mesh level, Λ): the mesh refined with Λ as far as the shipped ladder goes
    // (h/s0 = 0.31, 0.61, 1.29), and the two larger Λ once more on the next level.
    let ladder = [(5, 0.05), (6, 0.0125), (7, 0.003)];
    let rows: Vec<(f64, f64)> = ladder
        .iter()
        .map(|&(l, lam)| ladder_point(l, lam))
        .collect();
    let finer: Vec<(f64, f64)> = [(6, 0.05), (7, 0.0125)]
        .iter()
        .map(|&(l, lam)| ladder_point(l, lam))
        .collect();
    let err: Vec<f64> = rows.iter().map(|r| (r.0 - 1.0).abs()).collect();
    println!("K/sqrt(2WE*) − 1 on the ladder: {err:?}");
    // Measured 1.1384, 1.0666, 1.0185; from one load step to the next they scatter by about
    // ±1 % (the stick zone loses a node at a time; the scatter scales as f_d h).
    let expected = [1.138, 1.067, 1.019];
    let tol = 0.01;
    for ((r, e), (level, lambda)) in rows.iter().zip(expected).zip(ladder) {
        assert!(
            (r.0 - e).abs() < tol,
            "L{level} Λ = {lambda}: {} vs {e}",
            r.0
        );
        // The paper's own approximate solution read the same way: measured 1.084, 1.026,
        // 1.008, the FE 0.054, 0.040 and 0.011 above it: the approach to the JKR limit is the
        // problem's, not the estimator's.
        assert!(
            r.0 >= r.1 && r.0 - r.1 < 0.06,
            "L{level} Λ = {lambda}: {} vs {}",
            r.0,
            r.1
        );
    }
    // The error falls by 2.1 and 3.5 times.
    assert!(err[0] > 1.5 * err[1] && err[1] > 1.5 * err[2], "{err:?}");
    // The next mesh level at the same Λ: measured 1.1392 (L6, Λ = 0.05) and 1.0524 (L7,
    // Λ = 0.0125), 0.1 % and 1.3 % from L5 and L6.
    let spread = [
        (finer[0].0 - rows[0].0).abs(),
        (finer[1].0 - rows[1].0).abs(),
    ];
    println!(
        "next level: {:.4}, {:.4}; spread {spread:?}",
        finer[0].0, finer[1].0
    );
    assert!(spread.iter().all(|s| *s < 0.02), "{spread:?}");
    validation_row(
        "225-k2-ladder",
        "K_II at the stick fronts (eqs. KII, KIIa, Lambda), ramp law, Q = 0.8 f_d P: L5 at Λ = 0.05, L6 at 0.0125, L7 at 0.003",
        "sqrt(2 W E*), W at the Hertz pressure of the front",
        &format!(
            "K_II / sqrt(2WE*) = {:.3}, {:.3}, {:.3} (asserted within {tol} of 1.138, 1.067, 1.019, the error falling by over 1.5 times a step); the double C–M field read the same way {:.3}, {:.3}, {:.3}; one level finer at Λ = 0.05 and 0.0125: {:.3}, {:.3} (asserted within 0.02); the two ends within 0.3 %",
            rows[0].0,
            rows[1].0,
            rows[2].0,
            rows[0].1,
            rows[1].1,
            rows[2].1,
            finer[0].0,
            finer[1].0
        ),
        "fronts",
    );
}

#[test]
fn cattaneo_mindlin_has_no_singularity() {
    let mut v = shipped_case("vm272_cm.json");
    // The last step's fields only (the journal is kept with the .vtu series).
    v["output"] = json!({"every": 1000});
    let r = run_case("fronts-cm", &v, &["--quiet"]);
    r.assert_ok("vm272_cm");
    let hist = r.history();
    let hz = Hertz::new(Geometry::vm272(), 10.0).unwrap();
    let mu = 0.2;
    // The stress intensity of the shear μ p0 over a length a, the scale of the problem's K.
    let scale = mu * hz.p0 * (PI * hz.a).sqrt();
    let col = |name: &str| hist.col(name);
    let mut worst: f64 = 0.0;
    for row in &hist.rows {
        let (cl, cr) = (row[col("c_left")], row[col("c_right")]);
        assert!((0.5 * (cr - cl) - row[col("c")]).abs() < 1e-9 * hz.a);
        // No weakening: no b ends, no paper value.
        assert!(row[col("b_left")].is_nan() && row[col("b_right")].is_nan());
        assert!(row[col("k2_paper")].is_nan());
        if row[col("stage")] == 0.0 {
            // The normal load alone: the whole contact sticks, no front faces a slip zone.
            assert!(row[col("k2_left")].is_nan() && row[col("k2_right")].is_nan());
        } else {
            for k in [row[col("k2_left")], row[col("k2_right")]] {
                assert!(k.is_finite());
                worst = worst.max(k.abs() / scale);
            }
        }
    }
    println!("C–M: largest |K_II| = {worst:.2e} μ p0 sqrt(π a)");
    // Measured 4.5e-3 (K_II = 0.012), at a step where the slip zones are a few elements wide;
    // the closed form has no singularity. The stick zone changes a node at a time, and with it
    // the origin of the regular part −μ p*_c of the traction, ∝ sqrt(2 c ρ) near the front:
    // K moves by about μ (E*/2R) sqrt(2π c) h/4 (0.01 here, on L4 with μ = 0.2). The
    // slip-weakening runs of the ladder measure K_II = 0.17 and 0.04 at Λ = 0.05 and 0.003.
    assert!(worst < 6e-3, "{worst}");
    // The journal writes the absent values as null.
    let journal = std::fs::read_to_string(r.out.join("steps.jsonl")).unwrap();
    let first: serde_json::Value = serde_json::from_str(journal.lines().next().unwrap()).unwrap();
    let c = &first["record"]["contact"];
    assert!(c["k2_paper"].is_null(), "{first}");
    assert!(c["c_left"].is_number(), "{first}");
}

#[test]
fn a_record_without_the_front_columns_still_reads() {
    let old = r#"{"n_contact": 3, "n_stick": 1, "n_slip": 2, "a": 0.5, "x_centre": 0.0,
                  "c": 0.1, "b": 0.2, "fx": 1.0, "fy": -10.0, "mean_slip": 0.0}"#;
    let f: ContactFigures = serde_json::from_str(old).unwrap();
    assert_eq!(f.c, 0.1);
    assert!(f.c_left.is_none() && f.b_right.is_none() && f.k2_left.is_none());
    assert!(f.k2_paper.is_none());
}
