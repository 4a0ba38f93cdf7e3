//! Frictional mortar contact on the VM272 half-cylinders against the paper's closed forms
//! (`stickslip::analytic`, an independent implementation of the paper's equations):
//! * Cattaneo–Mindlin (constant μ = 0.2, Q = 0.936 N/mm; vm272.md: c/a = 0.729);
//! * the abrupt static→dynamic transition of §3 (step law with Δ far below the mesh size:
//!   Cattaneo–Mindlin with f = f_d);
//! * the double Cattaneo–Mindlin solution of Figs. 2 and 3 (ramp and step laws);
//! * convergence in the load-step count;
//! * finite-difference checks of the Newton Jacobian for the ramp and exponential laws.
//!
//! The shipped cases are run as they are, or with the mesh or step count changed.

mod common;
use common::{
    mesh_path, repo, run_case_in, shipped_case, shipped_case_on, tempdir, validation_row,
};
use serde_json::{Value, json};
use stickslip::analytic::cattaneo::CattaneoMindlin;
use stickslip::analytic::dcm::DoubleCm;
use stickslip::analytic::hertz::{Geometry, Hertz};

/// Nodal results along the slave face at the last step: (x, p, q, status).
struct Face {
    x: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    c: f64,
    b: f64,
}

/// Runs a case (the shipped file with `edit` applied) and reads its last step.
fn run(case: &str, name: &str, edit: &dyn Fn(&mut Value)) -> Face {
    let mut v = shipped_case(case);
    v["output"] = json!({"vtu": true, "every": 100000});
    edit(&mut v);
    let text = serde_json::to_string(&v).unwrap();
    let r = run_case_in(&tempdir(name), case, &text, &["--quiet"]);
    r.assert_ok(case);
    let h = r.history();
    let csv = r.last_contact();
    Face {
        x: csv.rows.iter().map(|r| r[0]).collect(),
        p: csv.rows.iter().map(|r| r[2]).collect(),
        q: csv.rows.iter().map(|r| r[3]).collect(),
        c: h.last("c"),
        b: h.last("b"),
    }
}

fn hertz() -> Hertz {
    Hertz::new(Geometry::vm272(), 10.0).unwrap()
}

fn with_mesh(level: usize) -> impl Fn(&mut Value) {
    move |v: &mut Value| v["mesh"] = mesh_path(&format!("vm272_L{level}.msh"))
}

/// Largest |q − q_ref|/scale over |x| ≤ a, skipping |x| within `skip` of each listed boundary
/// and within two elements of the contact edge |x| = a, where the pressure itself carries the
/// edge error bounded by the Hertz test over |x| ≤ 0.95a (q = μ p there).
fn worst(f: &Face, q_ref: &dyn Fn(f64) -> f64, scale: f64, skip: &[(f64, f64)]) -> f64 {
    let a = hertz().a;
    let elem = a / 102.4;
    f.x.iter()
        .zip(&f.q)
        .filter(|(x, _)| {
            x.abs() <= a - 2.0 * elem && skip.iter().all(|(edge, w)| (x.abs() - edge).abs() > *w)
        })
        .map(|(x, q)| (q - q_ref(*x)).abs() / scale)
        .fold(0.0, f64::max)
}

/// Cattaneo–Mindlin on the finest mesh: c/a within 1 % of 0.729; q within 2 % of μ p0 except
/// within two elements of |x| = c; the pressure unchanged by the tangential load (β = 0).
#[test]
fn cattaneo_mindlin_on_the_finest_mesh() {
    let h = hertz();
    let mu = 0.2;
    let f = run("vm272_cm.json", "cm5", &with_mesh(5));
    let cm = CattaneoMindlin::new(h, mu).unwrap();
    let c = cm.stick_half_width(0.936).unwrap();
    let elem = h.a / 102.4;
    let e = worst(&f, &|x| cm.traction(x, c), mu * h.p0, &[(c, 2.0 * elem)]);
    let p_dev =
        f.x.iter()
            .zip(&f.p)
            .filter(|(x, _)| x.abs() <= 0.95 * h.a)
            .map(|(x, p)| (p - h.pressure(*x)).abs() / h.p0)
            .fold(0.0, f64::max);
    println!(
        "C–M L5: c/a = {:.4} (closed form {:.4}), max |q − q_CM|/(μ p0) = {e:.4}, max |p − p_H|/p0 = {p_dev:.4}",
        f.c / h.a,
        c / h.a
    );
    let (c_tol, q_tol, p_tol) = (0.01, 0.02, 0.01);
    assert!((f.c / c - 1.0).abs() < c_tol, "c = {} vs {c}", f.c);
    assert!(e < q_tol, "shear deviation {e}");
    assert!(
        p_dev < p_tol,
        "pressure deviation after tangential loading {p_dev}"
    );
    // The pressure before the tangential load (normal stage only) is the same to round-off.
    let n = run("vm272_cm.json", "cm5n", &|v: &mut Value| {
        with_mesh(5)(v);
        v["stages"].as_array_mut().unwrap().truncate(1);
    });
    let change =
        n.p.iter()
            .zip(&f.p)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / h.p0;
    println!("pressure change during tangential loading: {change:.2e} p0");
    // Measured 1.4e-4 p0: discretisation (β = 0: the continuum pressure does not change).
    let change_tol = 3e-4;
    assert!(change < change_tol, "pressure changed by {change} p0");
    validation_row(
        "200-cattaneo-mindlin",
        "Cattaneo–Mindlin, μ = 0.2, Q = 0.936 N/mm, L5",
        "C–M",
        &format!(
            "c/a = {:.4} vs {:.4} ({:+.1} %; asserted within {:.0} %); max |q − q_CM| = {:.1} % of μp0 outside two elements of |x| = c and of the contact edge (asserted < {:.0} %); max |p − p_H| = {p_dev:.4} p0 over |x| ≤ 0.95a after the tangential load (asserted < {p_tol}); pressure changes by {change:.1e} p0 during tangential loading (asserted < {change_tol:.0e})",
            f.c / h.a,
            c / h.a,
            100.0 * (f.c / c - 1.0),
            100.0 * c_tol,
            100.0 * e,
            100.0 * q_tol
        ),
        "friction_contact",
    );
}

/// §3: a step law whose Δ is far below the element size gives Cattaneo–Mindlin with f = f_d.
/// In the continuum the stick zone shrinks to the f_d solution because any excess of stick
/// would carry a square-root stress singularity at its edge; on a mesh that singularity is
/// capped at the element scale, so a sliver of extra stick survives and vanishes as h → 0.
/// Asserted: the stick semi-width error falls with each refinement and is below 5 % on the
/// finest mesh, and the traction outside two elements of |x| = c matches within 2 % of f_d p0.
#[test]
fn abrupt_transition_gives_cattaneo_mindlin_with_the_dynamic_coefficient() {
    let h = hertz();
    let cm = CattaneoMindlin::abrupt(h, 0.15, 0.1).unwrap();
    let c = cm.stick_half_width(0.8).unwrap();
    let mut errs = Vec::new();
    let mut last = None;
    for level in [3, 4, 5] {
        let f = run("fig2.json", &format!("abrupt{level}"), &|v: &mut Value| {
            with_mesh(level)(v);
            v["contact"]["friction"] =
                json!({"shape": "step", "fs": 0.15, "fd": 0.1, "delta": 1e-9});
            v["stages"][1]["steps"] = json!(10);
        });
        errs.push(f.c / c - 1.0);
        last = Some(f);
    }
    let f = last.unwrap();
    let e = worst(
        &f,
        &|x| cm.traction(x, c),
        0.1 * h.p0,
        &[(c, 2.0 * h.a / 102.4)],
    );
    println!(
        "abrupt: c/c_CM(f_d) − 1 on L3, L4, L5: {errs:?}; L5 max |q − q_CM|/(f_d p0) = {e:.4}"
    );
    let (c_tol, q_tol) = (0.05, 0.02);
    assert!(errs[0] > errs[1] && errs[1] > errs[2], "{errs:?}");
    assert!(errs[2].abs() < c_tol, "{errs:?}");
    assert!(e < q_tol, "{e}");
    validation_row(
        "210-abrupt",
        "abrupt transition (§3): step law, Δ = 1e-9 mm",
        "C–M with f_d",
        &format!(
            "c error {:+.1} %, {:+.1} %, {:+.1} % on L3, L4, L5 (asserted to fall, and within {:.0} % on L5; the mesh caps the edge singularity that would shrink the stick zone; it vanishes as h → 0); traction within {:.1} % of f_d p0 (asserted {:.0} %)",
            100.0 * errs[0],
            100.0 * errs[1],
            100.0 * errs[2],
            100.0 * c_tol,
            100.0 * e,
            100.0 * q_tol
        ),
        "friction_contact",
    );
}

/// Fig. 2 (ramp, Λ = 0.05, Q = 0.8 f_d P) as shipped: c within 2 % of the double C–M c, and
/// the traction within 3 % of f_d p0 of eq. (qx2CM) outside the transition zone c < |x| < b.
#[test]
fn figure_2_matches_double_cattaneo_mindlin() {
    let h = hertz();
    let f = run("fig2.json", "fig2", &|_| {});
    let dcm = DoubleCm::new(h, 0.15, 0.1).unwrap();
    let s = dcm.solve_delta(0.8, 2.8966e-4).unwrap();
    let elem = h.a / 102.4;
    let e = worst(
        &f,
        &|x| {
            if x.abs() > s.c && x.abs() < s.b {
                f64::NAN
            } else {
                dcm.traction(x, s.c, s.b)
            }
        },
        0.1 * h.p0,
        &[(s.c, 2.0 * elem), (s.b, 2.0 * elem)],
    );
    println!(
        "Fig. 2: c/a = {:.4} (double C–M {:.4}), b/a = {:.4} ({:.4}); max |q − q_2CM|/(f_d p0) outside c<|x|<b: {e:.4}",
        f.c / h.a,
        s.c / h.a,
        f.b / h.a,
        s.b / h.a
    );
    let (c_tol, q_tol, b_tol) = (0.02, 0.03, 0.03);
    assert!((f.c / s.c - 1.0).abs() < c_tol, "c = {} vs {}", f.c, s.c);
    assert!(e.is_finite() && e <= q_tol, "traction deviation {e}");
    assert!((f.b / s.b - 1.0).abs() < b_tol, "b = {} vs {}", f.b, s.b);
    validation_row(
        "220-fig2",
        "Fig. 2: ramp, Λ = 0.05, Q = 0.8 f_d P, L5",
        "double C–M",
        &format!(
            "c/a = {:.4} vs {:.4} ({:+.1} %; asserted within {:.0} %), b/a = {:.4} vs {:.4} ({:+.1} %; asserted within {:.0} %); traction within {:.1} % of f_d p0 outside the transition zone (asserted {:.0} %)",
            f.c / h.a,
            s.c / h.a,
            100.0 * (f.c / s.c - 1.0),
            100.0 * c_tol,
            f.b / h.a,
            s.b / h.a,
            100.0 * (f.b / s.b - 1.0),
            100.0 * b_tol,
            100.0 * e,
            100.0 * q_tol
        ),
        "friction_contact",
    );
}

/// Fig. 3 (Λ = 0.277, Q = 0.9 f_d P): ramp and step laws give stick zones within 2 % of each
/// other and close tractions (the paper's point). Against the double C–M closed form the FE
/// stick zone is 3–5 % smaller here (measured: ramp −4.4 %, step −2.8 %; converged in mesh and
/// step count): with the transition zone reaching b ≈ 0.94a, eq. (qx2CM) with W taken at p(c) is
/// itself an approximation. Asserted within 6 %.
#[test]
fn figure_3_ramp_and_step_agree() {
    let h = hertz();
    let ramp = run("fig3_ramp.json", "fig3r", &|_| {});
    let step = run("fig3_step.json", "fig3s", &|_| {});
    let dcm = DoubleCm::new(h, 0.15, 0.1).unwrap();
    let s = dcm.solve_delta(0.9, 1.605e-3).unwrap();
    let n = ramp.q.len() as f64;
    let rms = (ramp
        .q
        .iter()
        .zip(&step.q)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
        / (0.1 * h.p0);
    println!(
        "Fig. 3: c/a ramp {:.4}, step {:.4}, double C–M {:.4}; RMS |q_ramp − q_step|/(f_d p0) = {rms:.4}",
        ramp.c / h.a,
        step.c / h.a,
        s.c / h.a
    );
    let (pair_tol, dcm_tol, rms_tol) = (0.02, 0.06, 0.06);
    let (d_ramp, d_step) = (ramp.c / s.c - 1.0, step.c / s.c - 1.0);
    let d_pair = ramp.c / step.c - 1.0;
    assert!(d_pair.abs() < pair_tol);
    assert!(d_ramp.abs() < dcm_tol);
    assert!(d_step.abs() < dcm_tol);
    assert!(rms < rms_tol, "ramp and step differ by {rms} f_d p0 (RMS)");
    // The target for the stick zone against the closed form.
    let target = 0.02;
    let verdict = if d_ramp.abs() > target || d_step.abs() > target {
        format!("**outside the {:.0} % target**", 100.0 * target)
    } else {
        format!("within the {:.0} % target", 100.0 * target)
    };
    validation_row(
        "230-fig3",
        "Fig. 3: ramp and step, Λ = 0.277, Q = 0.9 f_d P, L5",
        "double C–M",
        &format!(
            "c/a = {:.3} (ramp), {:.3} (step) vs {:.3}: {:+.1} % and {:+.1} % (asserted within {:.0} %), {verdict}; ramp and step within {:.1} % of each other (asserted {:.0} %), RMS traction difference {rms:.2} f_d p0 (asserted < {rms_tol})",
            ramp.c / h.a,
            step.c / h.a,
            s.c / h.a,
            100.0 * d_ramp,
            100.0 * d_step,
            100.0 * dcm_tol,
            100.0 * d_pair.abs(),
            100.0 * pair_tol
        ),
        "friction_contact",
    );
}

/// Halving the load step changes the Fig. 2 traction by no more than the Newton tolerance.
#[test]
fn figure_2_is_converged_in_the_step_count() {
    let h = hertz();
    let a = run("fig2.json", "fig2-40", &with_mesh(4));
    let b = run("fig2.json", "fig2-80", &|v: &mut Value| {
        with_mesh(4)(v);
        v["stages"][1]["steps"] = json!(80);
    });
    let d =
        a.q.iter()
            .zip(&b.q)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / (0.1 * h.p0);
    println!("Fig. 2 on L4, 40 vs 80 tangential steps: max |Δq|/(f_d p0) = {d:.2e}");
    // Measured 1.0e-10: the Newton tolerance, not the path.
    let tol = 3e-10;
    assert!(d < tol, "{d}");
    validation_row(
        "260-step-count",
        "load-step count, Fig. 2 on L4, 40 vs 80 steps",
        "—",
        &format!(
            "tractions equal to {d:.0e} f_d p0 (asserted < {tol:.0e}): with monotonic loading the slip-weakening state is path-independent"
        ),
        "friction_contact",
    );
}

/// Finite-difference check of the Jacobian with slip-dependent μ: at an iterate inside a step
/// with nodes in the transition zone, the assembled matrix of each method (Newton, penalty,
/// augmented Lagrangian) under force and slip control equals the finite difference of the
/// residual of the same equations (relative to its largest entry: 1e-7 on the contact rows,
/// 1e-5 on the pilot rows, whose two cancelling terms cost digits to round-off).
#[test]
fn newton_jacobian_matches_finite_differences() {
    use stickslip::contact::solver::Method;
    // The model does not depend on the law (each solve takes it): built once.
    let (model, opt) = fig2_on_l1();
    // Force control, and slip control (the pilot's x equation replaced by the mean-slip row).
    // The largest deviation per law (ramp, exponential) over the methods and controls.
    let mut worst = [0.0f64; 2];
    for method in [Method::Newton, Method::Penalty, Method::AugmentedLagrangian] {
        for slip_drive in [false, true] {
            let w = jacobian_against_finite_differences(&model, &opt, method, slip_drive);
            for (a, b) in worst.iter_mut().zip(w) {
                *a = a.max(b);
            }
        }
    }
    validation_row(
        "270-jacobian",
        "Newton Jacobian with ramp and exponential μ(u), under force control and under slip control (the mean-slip row)",
        "central finite differences",
        &format!(
            "max deviation {:.1e} (ramp), {:.1e} (exponential) of the largest entry over Newton, penalty and augmented Lagrangian (asserted < {JACOBIAN_TOL:.0e})",
            worst[0], worst[1]
        ),
        "friction_contact",
    );
}

/// Bound on |J_FD − J|/max|J| (the pilot rows' deviations counted at 1 %).
const JACOBIAN_TOL: f64 = 1e-7;

/// The Jacobian of one Newton iteration of `method` against central finite differences of its
/// residual, at an iterate moved off a solution with transition nodes (μ′ ≠ 0). Returns the
/// largest deviation for the ramp and for the exponential law, each asserted here.
fn jacobian_against_finite_differences(
    model: &stickslip::model::Model,
    opt: &stickslip::contact::solver::Options,
    method: stickslip::contact::solver::Method,
    slip_drive: bool,
) -> Vec<f64> {
    let mut out = Vec::new();
    use stickslip::case::Control;
    use stickslip::contact::solver::{Iterate, PilotDrive, State, Status};
    use stickslip::friction::FrictionLaw;
    use stickslip::model::step::StepLoad;
    let cm = model.contact.as_ref().unwrap();
    for law in [
        FrictionLaw::ramp(0.15, 0.1, 2e-3).unwrap(),
        FrictionLaw::exponential(0.15, 0.1, 2e-3).unwrap(),
    ] {
        // The state after a force-controlled step to Q = q from `prev` (normal force 10).
        let step = |q: f64, prev: &State| {
            model
                .solve_contact_step(
                    StepLoad {
                        scale: 0.0,
                        control: [Control::Force(q), Control::Force(-10.0)],
                    },
                    prev,
                    None,
                    opt,
                    Some(&law),
                    None,
                )
                .unwrap()
                .state
        };
        let mut st = cm.system.initial_state();
        for q in [0.0, 0.3, 0.6] {
            st = step(q, &st);
        }
        // An iterate of the next step: the committed forces, sets and slip signs of a solve at
        // a higher load, so that transition nodes have Δv ≠ 0 and μ' ≠ 0.
        let next = step(0.7, &st);
        let ns = cm.system.ns;
        // Move off the solution a little so that the residual is not zero.
        let (mu, sign) = off_solution(&next);
        let w0 = vec![0.0; mu.len()];
        // Penalty stiffnesses (unused by Newton) and the augmented Lagrangian's multiplier
        // estimates: the committed forces.
        let eps: Vec<f64> = cm.system.eps_unit.iter().map(|e| e * opt.kappa).collect();
        let it = Iterate {
            w0: &w0,
            drive: [
                if slip_drive {
                    PilotDrive::Slip(next.mean_slip)
                } else {
                    PilotDrive::Force(0.7)
                },
                PilotDrive::Force(-10.0),
            ],
            law: Some(&law),
            substitute: true,
            prev: &st,
            mu: &mu,
            y: None,
            status: &next.status,
            sign: &sign,
            method,
            eps: &eps,
            fbar_n: &st.f_n,
            fbar_t: &st.f_t,
        };
        let sys = cm.system.newton_system(&it);
        let transition = (0..ns)
            .filter(|&j| next.status[j] == Status::Slip && !sys.substituted[j])
            .count();
        assert!(transition > 0, "{law:?}: no slip node with μ' ≠ 0");
        let x0: Vec<f64> = sys.unk.iter().map(|&u| mu[u]).collect();
        let r0 = cm.system.newton_residual(&it, &sys, &x0);
        let mut worst: f64 = 0.0;
        let mut worst_at = (0, 0, 0.0, 0.0);
        let scale = sys.a.norm_max();
        for q in 0..x0.len() {
            let hq = 1e-6 * x0[q].abs().max(1e-3);
            let mut xp = x0.clone();
            xp[q] += hq;
            let mut xm = x0.clone();
            xm[q] -= hq;
            let (rp, rm) = (
                cm.system.newton_residual(&it, &sys, &xp),
                cm.system.newton_residual(&it, &sys, &xm),
            );
            for r in 0..x0.len() {
                let fd = (rp[r] - rm[r]) / (2.0 * hq);
                // The pilot rows carry z − k_g u_P, two large terms that cancel: their finite
                // differences lose digits to round-off, so they get a looser bound below.
                let pilot_row = sys.unk[r] >= 2 * ns;
                let e = (fd - sys.a[(r, q)]).abs() / scale * if pilot_row { 0.01 } else { 1.0 };
                if e > worst {
                    worst = e;
                    worst_at = (sys.unk[r], sys.unk[q], fd, sys.a[(r, q)]);
                }
            }
        }
        println!(
            "{method:?}{}, {law:?}: {} unknowns, {transition} slip nodes with μ' ≠ 0; max |J_FD − J|/max|J| = {worst:.2e} at {worst_at:?}; residual {:.2e}",
            if slip_drive { " (slip control)" } else { "" },
            x0.len(),
            r0.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        );
        assert!(worst < JACOBIAN_TOL, "{method:?}: {worst} at {worst_at:?}");
        out.push(worst);
    }
    out
}

/// Why Fig. 3's stick zone sits 3–4 % below eq. (qx2CM): the double Cattaneo–Mindlin solution
/// matches the law's fracture energy W but not its shape (paper §5: "the exact form of the
/// function f(u) cannot be prescribed"). Given the friction law that the solution itself
/// implies (paper Fig. 1, `f = q/p` against the slip over c ≤ x ≤ b), the FE reproduces it:
/// c within 2 % (here well within), and the traction within 3 % of f_d p0 everywhere outside
/// two elements of |x| = c, |x| = b (where the implied law ends with an infinite slope) and the
/// contact edge — including the transition zone c < |x| < b.
#[test]
fn figure_3_with_the_law_implied_by_double_cattaneo_mindlin() {
    let h = hertz();
    let dcm = DoubleCm::new(h, 0.15, 0.1).unwrap();
    let s = dcm.solve_delta(0.9, 1.605e-3).unwrap();
    // The implied law, sampled densely (clustered at both ends), then f_d beyond x = b.
    let rows = dcm.implied_law(s.c, s.b, 400);
    assert!((rows[0][1] - 0.15).abs() < 1e-6, "f(0) = {}", rows[0][1]);
    let table: Vec<[f64; 2]> = rows
        .iter()
        .enumerate()
        .filter(|(i, r)| *i == 0 || r[0] > rows[i - 1][0] + 1e-15)
        .map(|(_, r)| *r)
        .collect();
    let f = run("fig3_ramp.json", "fig3i", &|v: &mut Value| {
        v["contact"]["friction"] = json!({"shape": "table", "rows": table});
    });
    let (ramp, rmc) = (run("fig3_ramp.json", "fig3i-ramp", &|_| {}), s.c / h.a);
    let q_ref = |x: f64| dcm.traction(x, s.c, s.b);
    let elem = h.a / 102.4;
    let skip = [(s.c, 2.0 * elem), (s.b, 2.0 * elem)];
    let dq = worst(&f, &q_ref, 0.1 * h.p0, &skip);
    let dq_ramp = worst(&ramp, &q_ref, 0.1 * h.p0, &skip);
    println!(
        "Fig. 3, double C–M c/a = {rmc:.4}: FE with the implied law {:.4} ({:+.2} %), with the ramp {:.4} ({:+.2} %); \
         max |q − q_2CM|/(f_d p0): implied {dq:.4}, ramp {dq_ramp:.4}",
        f.c / h.a,
        100.0 * (f.c / s.c - 1.0),
        ramp.c / h.a,
        100.0 * (ramp.c / s.c - 1.0),
    );
    let (c_tol, q_tol) = (0.02, 0.03);
    assert!((f.c / s.c - 1.0).abs() < c_tol, "c {} vs {}", f.c, s.c);
    assert!(dq < q_tol, "traction off by {dq} f_d p0");
    // The ramp's deviation is then a property of the closed form, not of the FE.
    assert!((f.c / s.c - 1.0).abs() < (ramp.c / s.c - 1.0).abs());
    validation_row(
        "240-fig3-implied-law",
        &format!(
            "Fig. 3 with the friction law the double C–M solution implies (paper Fig. 1: f = q/p against the slip over c ≤ x ≤ b, {}-row table)",
            table.len()
        ),
        "double C–M",
        &format!(
            "c/a = {:.4} vs {rmc:.4} (**{:+.2} %**; asserted within {:.0} %); max |q − q_2CM| = {:.1} % of f_d p0 including the transition zone (outside two elements of c, b and the contact edge; asserted < {:.0} %); with the ramp law on the same grid {:+.1} % and {:.0} % (the ramp's traction differs inside the transition zone): the Fig. 3 gap is the closed form's shape approximation",
            f.c / h.a,
            100.0 * (f.c / s.c - 1.0),
            100.0 * c_tol,
            100.0 * dq,
            100.0 * q_tol,
            100.0 * (ramp.c / s.c - 1.0),
            100.0 * dq_ramp
        ),
        "friction_contact",
    );
}

/// The cached structured solve (`LuCache::solve_rows`: a Cholesky factor of the Delassus block
/// and a capacitance system for the slip and anchor rows) gives the solution of the assembled
/// Newton system, both with the block factorised for the system's own unknowns and with a block
/// factorised for more unknowns than the system has (nodes that left the contact).
#[test]
fn structured_newton_solve_matches_the_dense_system() {
    use stickslip::contact::solver::{Iterate, LuCache, Method, PilotDrive, Status};
    use stickslip::friction::FrictionLaw;
    let law = FrictionLaw::ramp(0.15, 0.1, 2e-3).unwrap();
    let (model, opt) = fig2_on_l1();
    let cm = model.contact.as_ref().unwrap();
    let mut st = cm.system.initial_state();
    for q in [0.0, 0.3, 0.6, 0.7] {
        st = force_step(&model, &st, q, &opt, &law, None).unwrap().state;
    }
    let ns = cm.system.ns;
    // An iterate off the solution, so that slip rows have μ' ≠ 0 and Δv ≠ 0.
    let (mu, sign) = off_solution(&st);
    let w0 = vec![0.0; mu.len()];
    let zeros = vec![0.0; ns];
    let mut prev = st.clone();
    prev.slip.iter_mut().for_each(|s| *s *= 0.5);
    let mut status = st.status.clone();
    let mut cache = LuCache::default();
    // The third system is under slip control: the pilot's x row is a weighted sum of the
    // tangential rows of the nodes in contact (a `combo` row), with the first system's unknowns.
    for (case, opened, slip_control) in [
        ("own unknowns", 0, false),
        ("fewer unknowns than the block", 2, false),
        ("slip control", 0, true),
    ] {
        if slip_control {
            status = st.status.clone();
        }
        let drive = if slip_control {
            [
                PilotDrive::Slip(prev.mean_slip + 1e-4),
                PilotDrive::Force(-10.0),
            ]
        } else {
            [PilotDrive::Force(0.7), PilotDrive::Force(-10.0)]
        };
        // Open the outermost contact nodes on each side.
        for _ in 0..opened {
            let first = status.iter().position(|s| *s != Status::Open).unwrap();
            let last = status.iter().rposition(|s| *s != Status::Open).unwrap();
            status[first] = Status::Open;
            status[last] = Status::Open;
        }
        let it = Iterate {
            w0: &w0,
            drive,
            law: Some(&law),
            substitute: false,
            prev: &prev,
            mu: &mu,
            y: None,
            status: &status,
            sign: &sign,
            method: Method::Newton,
            eps: &zeros,
            fbar_n: &zeros,
            fbar_t: &zeros,
        };
        let sys = cm.system.newton_system(&it);
        let rows = cm.system.newton_rows(&it).unwrap();
        assert_eq!(rows.unk, sys.unk);
        let slip = (0..ns).filter(|&j| status[j] == Status::Slip).count();
        assert!(
            slip > 0 && rows.special.len() >= slip,
            "{case}: no slip rows"
        );
        assert_eq!(
            rows.special.iter().any(|r| !r.combo.is_empty()),
            slip_control,
            "{case}: slip-control row"
        );
        let (x, w_mu) = cache
            .solve_rows(&cm.system.w, cm.system.prefix.as_ref(), &rows, false)
            .unwrap();
        let dense = faer::linalg::solvers::Solve::solve(&sys.a.partial_piv_lu(), &sys.b);
        let xmax = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = (0..x.len())
            .map(|i| (x[i] - dense[(i, 0)]).abs())
            .fold(0.0, f64::max)
            / xmax;
        let res = (0..x.len())
            .map(|r| {
                ((0..x.len()).map(|q| sys.a[(r, q)] * x[q]).sum::<f64>() - sys.b[(r, 0)]).abs()
            })
            .fold(0.0, f64::max)
            / (sys.a.norm_max() * xmax);
        println!(
            "{case}: {} unknowns, {} special rows, {slip} slip nodes; |x − x_dense|/|x| = {diff:.2e}, residual {res:.2e}",
            x.len(),
            rows.special.len()
        );
        assert!(diff < 1e-10 && res < 1e-13, "{case}: {diff:e} {res:e}");
        // W μ of the solution, as returned, against the product.
        let mut mu_new = vec![0.0; mu.len()];
        for (q, &u) in rows.unk.iter().enumerate() {
            mu_new[u] = x[q];
        }
        let w = &cm.system.w;
        let wmax = w_mu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let w_diff = (0..mu.len())
            .map(|i| (w_mu[i] - (0..mu.len()).map(|j| w[(i, j)] * mu_new[j]).sum::<f64>()).abs())
            .fold(0.0, f64::max)
            / wmax;
        println!("{case}: |W μ returned − W μ|/|W μ| = {w_diff:.2e}");
        assert!(w_diff < 1e-10, "{case}: {w_diff:e}");
    }
    assert_eq!(
        cache.factorisations, 1,
        "the second and third systems reuse the block"
    );
}

/// The forces μ = (F_n, F_t, z) of a converged state, each scaled by 1 + 1e-3·(k mod 7 − 3) so
/// that the iterate is off the solution, and the slip signs of its tangential forces.
fn off_solution(st: &stickslip::contact::solver::State) -> (Vec<f64>, Vec<f64>) {
    let mut mu: Vec<f64> = st.f_n.iter().chain(&st.f_t).chain(&st.z).copied().collect();
    for (k, m) in mu.iter_mut().enumerate() {
        *m *= 1.0 + 1e-3 * ((k % 7) as f64 - 3.0);
    }
    let sign = st
        .f_t
        .iter()
        .map(|f| if *f < 0.0 { -1.0 } else { 1.0 })
        .collect();
    (mu, sign)
}

/// Fig. 2's case on mesh L1, built, and Newton options with a tight tolerance (for the checks
/// of the Newton system itself).
fn fig2_on_l1() -> (stickslip::model::Model, stickslip::contact::solver::Options) {
    let case: stickslip::case::Case =
        serde_json::from_value(shipped_case_on("fig2.json", "vm272_L1.msh")).unwrap();
    let model = stickslip::model::Model::build(&case, &repo().join("cases/fig2.json")).unwrap();
    let opt = stickslip::contact::solver::Options {
        method: stickslip::contact::solver::Method::Newton,
        kappa: 100.0,
        max_iterations: 80,
        tolerance: 1e-12,
        verbose: false,
        history: Default::default(),
        normal_first: true,
        hertz_start: true,
        settle_round_off: false,
    };
    (model, opt)
}

/// One contact step from `st` under Fig. 2's normal load P = 10 and the tangential force `q`.
fn force_step(
    model: &stickslip::model::Model,
    st: &stickslip::contact::solver::State,
    q: f64,
    opt: &stickslip::contact::solver::Options,
    law: &stickslip::friction::FrictionLaw,
    cache: Option<&mut stickslip::contact::solver::LuCache>,
) -> Result<stickslip::contact::solver::StepOutcome, stickslip::contact::solver::ContactError> {
    use stickslip::case::Control;
    let load = stickslip::model::step::StepLoad {
        scale: 0.0,
        control: [Control::Force(q), Control::Force(-10.0)],
    };
    model.solve_contact_step(load, st, None, opt, Some(law), cache)
}

/// Fig. 2's case on mesh L4 with the lower and upper bodies' (E, ν), built.
fn fig2_on_l4(lower: (f64, f64), upper: (f64, f64)) -> stickslip::model::Model {
    let mut v = shipped_case_on("fig2.json", "vm272_L4.msh");
    v["bodies"][0]["E"] = json!(lower.0);
    v["bodies"][0]["nu"] = json!(lower.1);
    v["bodies"][1]["E"] = json!(upper.0);
    v["bodies"][1]["nu"] = json!(upper.1);
    let case: stickslip::case::Case = serde_json::from_value(v).unwrap();
    stickslip::model::Model::build(&case, &repo().join("cases/fig2.json")).unwrap()
}

/// How far contact state `a` is from `b`: the largest difference of the normal and tangential
/// forces over `b`'s largest normal force, and of the pilot's displacements over `b`'s normal
/// one.
fn state_difference(
    a: &stickslip::contact::solver::State,
    b: &stickslip::contact::solver::State,
) -> (f64, f64) {
    let scale = b.f_n.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let dev = a
        .f_n
        .iter()
        .zip(&b.f_n)
        .chain(a.f_t.iter().zip(&b.f_t))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f64, f64::max)
        / scale;
    let du = (0..2)
        .map(|k| (a.pilot_u[k] - b.pilot_u[k]).abs() / b.pilot_u[1].abs())
        .fold(0.0f64, f64::max);
    (dev, du)
}

/// A frictional first contact (every node open before the step) starts from the frictionless
/// contact set, so that the Delassus block it factorises has the unknowns of the contact,
/// not of every candidate. The step's answer must not depend on that start: Fig. 2's normal
/// load on L4 (m ≥ 512 contact unknowns, where the start is taken), identical bodies and a
/// dissimilar pair (β ≠ 0, whose normal load slips the edges), each solved from both starts.
#[test]
fn first_contact_from_the_frictionless_set_gives_the_same_step() {
    use stickslip::case::Control;
    use stickslip::contact::solver::LuCache;
    use stickslip::friction::FrictionLaw;
    use stickslip::model::step::StepLoad;
    let law = FrictionLaw::ramp(0.15, 0.1, 2.9e-4).unwrap();
    for (name, lower, upper) in [
        ("identical", (200.0, 0.3), (200.0, 0.3)),
        ("steel on copper", (207.0, 0.3), (110.0, 0.34)),
    ] {
        let model = fig2_on_l4(lower, upper);
        let (_, mut opt) = fig2_on_l1();
        // 1e-12 floors in the dense solve of the dissimilar pair (updates ≈ 3e-11).
        opt.tolerance = 1e-10;
        let cm = model.contact.as_ref().unwrap();
        let st0 = cm.system.initial_state();
        let mut solve = |normal_first: bool| {
            opt.normal_first = normal_first;
            let mut cache = LuCache::default();
            let out = model
                .solve_contact_step(
                    StepLoad {
                        scale: 0.0,
                        control: [Control::Force(0.0), Control::Force(-10.0)],
                    },
                    &st0,
                    None,
                    &opt,
                    Some(&law),
                    Some(&mut cache),
                )
                .unwrap();
            (out, cache.largest_block)
        };
        let (a, block_a) = solve(true);
        let (b, block_b) = solve(false);
        let (sa, sb) = (&a.state, &b.state);
        let in_contact = sa
            .status
            .iter()
            .filter(|s| **s != stickslip::contact::solver::Status::Open)
            .count();
        let slipping = sa
            .status
            .iter()
            .filter(|s| **s == stickslip::contact::solver::Status::Slip)
            .count();
        let (dev, du) = state_difference(sa, sb);
        println!(
            "{name}: {} candidates, {in_contact} in contact ({slipping} slip); largest block {block_a} from the frictionless set, {block_b} from the closest nodes; iterations {} and {}; forces differ by {dev:.1e}, pilot displacement by {du:.1e}",
            cm.system.ns, a.iterations, b.iterations
        );
        assert_eq!(sa.status, sb.status, "{name}: the sets differ");
        assert!(dev < 1e-9 && du < 1e-9, "{name}: {dev:.2e}, {du:.2e}");
        // The start was taken: the block has the contact's unknowns (normal and tangential
        // force of each node in contact, the pilot's two), not every candidate's.
        assert_eq!(block_a, 2 * in_contact + 2, "{name}");
        assert!(block_b > block_a, "{name}: {block_b} vs {block_a}");
    }
}

/// The frictionless problem of a first contact starts from the contact set of a Hertzian line
/// contact under the pilot's normal force (`Options::hertz_start`) instead of the three
/// closest nodes, from which its iteration closed every candidate and gave the edges up a
/// few nodes at a time. The step's answer must not depend on that start, and the start must
/// pay: Fig. 2's normal load on L4 for identical bodies, a steel–copper pair, a fifth of the
/// load and a normal load with a tangential force, each solved from both starts; the same
/// sets and forces (bit for bit where measured, asserted to 1e-12), and the iterations from
/// the Hertzian set at most those measured (5 for the paper's case against 13; 16 against 22
/// for the pair, whose normal load slips the edges; 5 against 15; 14 against 22).
#[test]
fn first_contact_from_the_hertzian_set_gives_the_same_step_in_fewer_iterations() {
    use stickslip::case::Control;
    use stickslip::contact::solver::{LuCache, Status};
    use stickslip::friction::FrictionLaw;
    use stickslip::model::step::StepLoad;
    let law = FrictionLaw::ramp(0.15, 0.1, 2.9e-4).unwrap();
    // (name, lower body, upper body, pilot x force, pilot y force, iterations at most from
    // the Hertzian set, measured from the closest nodes)
    for (name, lower, upper, fx, fy, most, before) in [
        ("identical", (200.0, 0.3), (200.0, 0.3), 0.0, -10.0, 5, 13),
        (
            "steel on copper",
            (207.0, 0.3),
            (110.0, 0.34),
            0.0,
            -10.0,
            16,
            22,
        ),
        ("P = 2", (200.0, 0.3), (200.0, 0.3), 0.0, -2.0, 5, 15),
        (
            "with Q = 0.5",
            (200.0, 0.3),
            (200.0, 0.3),
            0.5,
            -10.0,
            14,
            22,
        ),
    ] {
        let model = fig2_on_l4(lower, upper);
        let (_, mut opt) = fig2_on_l1();
        opt.tolerance = 1e-8;
        let cm = model.contact.as_ref().unwrap();
        let st0 = cm.system.initial_state();
        let mut solve = |hertz_start: bool| {
            opt.hertz_start = hertz_start;
            let mut cache = LuCache::default();
            model
                .solve_contact_step(
                    StepLoad {
                        scale: 0.0,
                        control: [Control::Force(fx), Control::Force(fy)],
                    },
                    &st0,
                    None,
                    &opt,
                    Some(&law),
                    Some(&mut cache),
                )
                .unwrap()
        };
        let (a, b) = (solve(true), solve(false));
        let (sa, sb) = (&a.state, &b.state);
        let (dev, du) = state_difference(sa, sb);
        let in_contact = sa.status.iter().filter(|s| **s != Status::Open).count();
        println!(
            "{name}: {in_contact} of {} in contact; iterations {} from the Hertzian set, {} from the closest nodes; forces differ by {dev:.1e}, pilot displacement by {du:.1e}",
            cm.system.ns, a.iterations, b.iterations
        );
        assert_eq!(sa.status, sb.status, "{name}: the sets differ");
        assert!(dev <= 1e-12 && du <= 1e-12, "{name}: {dev:.2e}, {du:.2e}");
        assert!(a.iterations <= most, "{name}: {} iterations", a.iterations);
        assert_eq!(
            b.iterations, before,
            "{name}: the closest nodes' start changed"
        );
    }
}

/// Delassus blocks read from the Cholesky factor of `W` in the order of the initial gaps
/// (`PrefixFactor`: on L6 up the saddle-point factorisation gives it) instead of factorised
/// give the same steps. Fig. 2 on L4 (identical bodies and a steel–copper pair), normal load
/// then five tangential steps of growing size (those the driver takes for the pair, which
/// cuts the first step of 0.15 back three times) under a ramp law, solved with the model as built (every block factorised) and
/// with a prefix factor computed here independently (faer's dense Cholesky of
/// `W[order, order]`): the same contact sets and forces within 1e-9 of the largest, and the
/// stick blocks taken from the prefix factor.
#[test]
fn delassus_blocks_from_the_prefix_factor_give_the_same_steps() {
    use stickslip::contact::solver::{LuCache, PrefixFactor, prefix_order};
    use stickslip::friction::FrictionLaw;
    let law = FrictionLaw::ramp(0.15, 0.1, 0.05).unwrap();
    for (name, lower, upper) in [
        ("identical", (200.0, 0.3), (200.0, 0.3)),
        ("steel on copper", (207.0, 0.3), (110.0, 0.34)),
    ] {
        let mut model = fig2_on_l4(lower, upper);
        let (_, mut opt) = fig2_on_l1();
        opt.tolerance = 1e-10;
        let cm = model.contact.as_ref().unwrap();
        assert!(
            cm.system.prefix.is_none(),
            "{name}: L4 is below PREFIX_FROM"
        );
        let m = cm.system.w.nrows();
        let order = prefix_order(&cm.system.gap0, m);
        let wo = faer::Mat::from_fn(m, m, |i, j| cm.system.w[(order[i], order[j])]);
        let llt = wo.llt(faer::Side::Lower).expect("W is positive definite");
        let c = llt.L().to_owned();
        let prefix = std::sync::Arc::new(PrefixFactor::new(c, order));
        let mut run = |prefix: Option<std::sync::Arc<PrefixFactor>>| {
            model.contact.as_mut().unwrap().system.prefix = prefix;
            let mut cache = LuCache::default();
            let mut st = model.contact.as_ref().unwrap().system.initial_state();
            let mut states = Vec::new();
            for q in [0.0, 0.01875, 0.05625, 0.13125, 0.28125, 0.43125] {
                st = force_step(&model, &st, q, &opt, &law, Some(&mut cache))
                    .unwrap_or_else(|e| panic!("{name}: Q = {q}: {e}"))
                    .state;
                states.push(st.clone());
            }
            (states, cache.factorisations, cache.prefix_blocks)
        };
        let (a, fact_a, taken_a) = run(None);
        let (b, fact_b, taken_b) = run(Some(prefix));
        let mut dev = 0.0f64;
        for (sa, sb) in a.iter().zip(&b) {
            assert_eq!(sa.status, sb.status, "{name}: the sets differ");
            let scale = sa.f_n.iter().fold(0.0f64, |m, f| m.max(f.abs()));
            dev = sa
                .f_n
                .iter()
                .zip(&sb.f_n)
                .chain(sa.f_t.iter().zip(&sb.f_t))
                .map(|(x, y)| (x - y).abs() / scale)
                .fold(dev, f64::max);
            dev = dev.max((sa.pilot_u[0] - sb.pilot_u[0]).abs() / sa.pilot_u[1].abs());
        }
        println!(
            "{name}: {m} contact unknowns; factorised blocks {fact_a} without the prefix factor, {fact_b} with it and {taken_b} taken from it; forces and pilot displacement differ by {dev:.1e}"
        );
        assert!(dev < 1e-9, "{name}: {dev:.2e}");
        assert_eq!(taken_a, 0, "{name}");
        assert!(
            taken_b >= 1 && fact_b < fact_a,
            "{name}: {fact_b} vs {fact_a}, {taken_b}"
        );
    }
}
