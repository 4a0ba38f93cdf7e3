//! Convergence over the whole VM272 mesh ladder L0–L7 (docs/convergence.md).
//!
//! On every level one model is built (the shipped `cases/fig2.json` with the mesh replaced;
//! L6 and L7 are generated on demand by `meshes/generate.py`, which needs gmsh) and four runs
//! share it (the stages change only the loads, never the matrices):
//! * `hertz`: `cases/hertz.json` (frictionless, P = 10 N/mm): the contact semi-width a, the
//!   peak pressure p0, max |p − p_H|/p0 against the half-plane (Hertz) pressure;
//! * `cm`: `cases/vm272_cm.json` (Coulomb μ = 0.2, Q = 0.936 N/mm): the stick semi-width c;
//! * `fig2`: `cases/fig2.json` (ramp law of the paper's Fig. 2, Q = 0.8 f_d P): c and b;
//! * `qmax`: Fig. 2's law driven by the mean slip through the peak of the tangential force:
//!   Q_max.
//!
//! Each edge (a, c, b) is located below the node spacing from the nodal results (the figures
//! of `history.csv` are also recorded: the stick and slip-weakening widths there are placed
//! midway between two nodes, so they move in steps of a node spacing and need not converge
//! monotonically). How each quantity is measured is stated at its function below and in the
//! doc.
//!
//! The test asserts, per quantity, that the error against the finite-body reference (Richardson
//! extrapolation from L5, L6, L7, or L7 itself where the three finest levels oscillate)
//! decreases monotonically over a stated range of levels, the fitted rate (log-log least
//! squares of error against h) within a band around the measured one, and the finite-body
//! references against the half-plane closed forms within bands around the measured offsets.
//!
//! `LADDER_WRITE_DOC=1 cargo test --release --test ladder -- --nocapture` rewrites the
//! generated part of docs/convergence.md from the run.

mod common;
use common::{ensure_mesh, fitted_rate, repo, shipped_case_on, validation_row};
use serde_json::{Value, json};
use std::time::Instant;
use stickslip::analytic::apparent::apparent;
use stickslip::analytic::cattaneo::CattaneoMindlin;
use stickslip::analytic::dcm::DoubleCm;
use stickslip::analytic::hertz::{Geometry, Hertz};
use stickslip::case::Case;
use stickslip::contact::solver::{State, Status};
use stickslip::friction::FrictionLaw;
use stickslip::model::Model;
use stickslip::run::{LogLevel, Simulation, simulate};

/// The Hertz semi-width the ladder is built on (`meshes/generate.py`: h_c = A/(3.2·2^L)).
const A_MESH: f64 = 0.6808;
const LEVELS: usize = 8;
const MU_CM: f64 = 0.2;
const Q_CM: f64 = 0.936;
const FS: f64 = 0.15;
const FD: f64 = 0.1;
const Q_FIG2: f64 = 0.8;
/// Slip nodes beyond the stick zone used to locate its edge (per side).
const SLIP_NODES: usize = 6;

/// Element length along the arcs on level `level` (|x| ≤ 1.5a).
fn h(level: usize) -> f64 {
    A_MESH / (3.2 * 2f64.powi(level as i32))
}

/// Nodal results along the slave face, ordered by x.
struct Face {
    x: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    slip: Vec<f64>,
    status: Vec<Status>,
}

fn face(model: &Model, st: &State) -> Face {
    let m = &model.contact.as_ref().unwrap().pair.mortar;
    let mut idx: Vec<usize> = (0..m.slave_nodes.len()).collect();
    let x = |j: usize| model.mesh.nodes[m.slave_nodes[j]][0];
    idx.sort_by(|&i, &j| x(i).total_cmp(&x(j)));
    Face {
        x: idx.iter().map(|&j| x(j)).collect(),
        p: idx.iter().map(|&j| st.f_n[j] / m.weight[j]).collect(),
        q: idx.iter().map(|&j| -st.f_t[j] / m.weight[j]).collect(),
        slip: idx.iter().map(|&j| st.slip[j]).collect(),
        status: idx.iter().map(|&j| st.status[j]).collect(),
    }
}

/// The indices of one side of the face (x > 0 or x < 0), from the centre outwards.
fn side(f: &Face, s: f64) -> Vec<usize> {
    let mut v: Vec<usize> = (0..f.x.len()).filter(|&j| s * f.x[j] > 0.0).collect();
    v.sort_by(|&i, &j| (s * f.x[i]).total_cmp(&(s * f.x[j])));
    v
}

/// Least-squares fit y = α − β x² over the points; returns sqrt(α/β), the half-width where
/// the fitted y vanishes.
fn ellipse_root(pts: &[(f64, f64)]) -> f64 {
    let n = pts.len() as f64;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for &(x, y) in pts {
        let t = x * x;
        sx += t;
        sy += y;
        sxx += t * t;
        sxy += t * y;
    }
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let icpt = (sy - slope * sx) / n;
    (-icpt / slope).sqrt()
}

/// Straight line through the points by least squares: (slope, intercept).
fn line(pts: &[(f64, f64)]) -> (f64, f64) {
    let n = pts.len() as f64;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for &(x, y) in pts {
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    (slope, (sy - slope * sx) / n)
}

/// Contact semi-width: Hertz's pressure obeys p² = p0²(1 − x²/a²), so a is the root of the
/// least-squares fit p² = α − βx² over the contact nodes with |x| ≥ a/2 (a from the two
/// outermost nodes, as in `history.csv`). It uses some 25 % of the contact nodes instead of
/// the two outermost, whose pressures carry the largest discretisation error.
fn contact_width(f: &Face, a_nodes: f64) -> f64 {
    let pts: Vec<(f64, f64)> = (0..f.x.len())
        .filter(|&j| f.status[j] != Status::Open && f.x[j].abs() >= 0.5 * a_nodes)
        .map(|j| (f.x[j], f.p[j].max(0.0).powi(2)))
        .collect();
    ellipse_root(&pts)
}

/// The pressure at the contact point x = 0 (a vertex of every level).
fn peak_pressure(f: &Face) -> f64 {
    let j = (0..f.x.len())
        .min_by(|&i, &j| f.x[i].abs().total_cmp(&f.x[j].abs()))
        .unwrap();
    assert!(f.x[j].abs() < 1e-9, "no node at x = 0 ({})", f.x[j]);
    f.p[j]
}

/// Cattaneo–Mindlin stick semi-width: in the stick zone μp − |q| = (μ p0/a) sqrt(c² − x²), so c
/// is the root of the least-squares fit (μp − |q|)² = α − βx² over the stick nodes with
/// |x| ≥ c/2 (c from `history.csv`), leaving out the outermost stick node on each side (its
/// element straddles the stick–slip transition).
fn cm_stick_width(f: &Face, mu: f64, c_nodes: f64) -> f64 {
    let stick: Vec<usize> = (0..f.x.len())
        .filter(|&j| f.status[j] == Status::Stick)
        .collect();
    let (first, last) = (stick[0], *stick.last().unwrap());
    let pts: Vec<(f64, f64)> = stick
        .iter()
        .filter(|&&j| j != first && j != last && f.x[j].abs() >= 0.5 * c_nodes)
        .map(|&j| (f.x[j], (mu * f.p[j] - f.q[j].abs()).powi(2)))
        .collect();
    ellipse_root(&pts)
}

/// Stick semi-width of a slip-weakening law: the traction is continuous at the stick edge
/// (no closed form for it there), and the slip grows as (|x| − c)^{3/2} beyond it, like the
/// opening behind a cohesive crack tip. Per side, c is the root of the straight line fitted to
/// slip^{2/3} at the first [`SLIP_NODES`] slip nodes outside the stick zone; the two sides
/// are averaged.
fn slip_edge(f: &Face) -> f64 {
    let mut w = 0.0;
    for s in [1.0, -1.0] {
        let ids = side(f, s);
        let last_stick = ids
            .iter()
            .rposition(|&j| f.status[j] == Status::Stick)
            .expect("stick node");
        let pts: Vec<(f64, f64)> = ids[last_stick + 1..]
            .iter()
            .take_while(|&&j| f.status[j] == Status::Slip)
            .take(SLIP_NODES)
            .map(|&j| (s * f.x[j], f.slip[j].powf(2.0 / 3.0)))
            .collect();
        assert!(
            pts.len() >= 2,
            "fewer than two slip nodes beyond the stick zone"
        );
        let (m, b) = line(&pts);
        w += 0.5 * (-b / m);
    }
    w
}

/// Semi-width of the zone where μ has not reached f_d: where the slip reaches 2Δ (the ramp
/// law's end), by linear interpolation between the two nodes around it; sides averaged.
fn slip_crossing(f: &Face, level: f64) -> f64 {
    let mut w = 0.0;
    for s in [1.0, -1.0] {
        let ids = side(f, s);
        let k = ids
            .iter()
            .position(|&j| f.slip[j] >= level)
            .expect("slip reaches 2Δ");
        let (i, j) = (ids[k - 1], ids[k]);
        let t = (level - f.slip[i]) / (f.slip[j] - f.slip[i]);
        w += 0.5 * s * (f.x[i] + t * (f.x[j] - f.x[i]));
    }
    w
}

/// The peak of the tangential force along a slip-controlled path sampled at (mean slip, Q).
/// Between two changes of the contact state Q is linear in the mean slip; the peak is the
/// corner where a rising segment meets a falling one when a stick node lets go. It lies
/// between two samples: the corner is the intersection of the straight lines through the two
/// samples on each side of it (the larger of the two candidate corners next to the largest
/// sample, where one lies inside its interval; else the largest sample). Returns (Q_max, index
/// of the largest sample).
fn corner_peak(s: &[f64], q: &[f64]) -> (f64, usize) {
    let i = (0..q.len()).max_by(|&a, &b| q[a].total_cmp(&q[b])).unwrap();
    let mut best = q[i];
    let through = |j: usize, k: usize| {
        let m = (q[k] - q[j]) / (s[k] - s[j]);
        (m, q[j] - m * s[j])
    };
    for (l0, r0) in [(i.wrapping_sub(2), i), (i.wrapping_sub(1), i + 1)] {
        if l0 >= q.len() || r0 + 1 >= q.len() {
            continue;
        }
        let (ml, bl) = through(l0, l0 + 1);
        let (mr, br) = through(r0, r0 + 1);
        if ml <= 0.0 || mr >= 0.0 {
            continue;
        }
        let t = (br - bl) / (ml - mr);
        if t >= s[l0 + 1] && t <= s[r0] {
            best = best.max(ml * t + bl);
        }
    }
    (best, i)
}

/// What one level gives.
#[derive(Default, Clone)]
struct Level {
    level: usize,
    h: f64,
    dofs: usize,
    contact_nodes: usize,
    /// a, c, b as in history.csv (edges located on the node grid).
    a_nodes: f64,
    c_cm_nodes: f64,
    c_fig2_nodes: f64,
    b_nodes: f64,
    a: f64,
    p0: f64,
    /// max |p − p_H|/p0_H over the nodes with |x| ≤ 0.95 a_H.
    dev_hertz: f64,
    /// max |p − p_L7|/p0_H over the nodes with |x| ≤ 0.9 a_H (L7 interpolated).
    dev_finest: f64,
    c_cm: f64,
    /// NaN where the Fig. 2 run did not reach Q = 0.8 f_d P.
    c_fig2: f64,
    b: f64,
    q_max: f64,
    /// Largest sample of the slip-controlled path (before the corner correction) and the
    /// mean slip at it.
    q_max_sample: f64,
    s_peak: f64,
    fig2_status: String,
    /// Fig. 2's Δ as the case resolves it (from Λ, R and P).
    delta: f64,
    /// Hertz pressure, for the self-convergence column: (x, p).
    pressure: Vec<(f64, f64)>,
    build_s: f64,
    hertz_s: f64,
    cm_s: f64,
    fig2_s: f64,
    qmax_s: f64,
    wall_s: f64,
}

fn case_of(v: Value) -> Case {
    serde_json::from_value(v).unwrap()
}

fn run(model: &Model, case: &Case, law: Option<&FrictionLaw>) -> (Simulation, f64) {
    let t = Instant::now();
    let sim = simulate(model, case, law, LogLevel::Error, &mut |_| Ok(())).unwrap();
    (sim, t.elapsed().as_secs_f64())
}

/// The slip-controlled window through the peak: (coarse target, fine target, fine steps).
/// The peak lies at a mean slip of 2.49–2.57e-3 mm from L2 on (2.07e-3 on L0, 2.71e-3 on L1:
/// measured with a coarse run to 4e-3); the fine steps are 2e-6 mm.
fn qmax_window(level: usize) -> (f64, f64, usize) {
    if level <= 1 {
        (1.9e-3, 2.8e-3, 450)
    } else {
        (2.45e-3, 2.62e-3, 85)
    }
}

fn run_level(level: usize) -> Level {
    let t_level = Instant::now();
    let stem = format!("vm272_L{level}");
    ensure_mesh(&stem);
    let mesh = format!("{stem}.msh");
    let fig2 = case_of(shipped_case_on("fig2.json", &mesh));
    let t = Instant::now();
    let model = Model::build(&fig2, &repo().join("cases/fig2.json")).unwrap();
    let build_s = t.elapsed().as_secs_f64();
    let law = model.friction.clone().unwrap();
    let delta = match law {
        FrictionLaw::Ramp { delta, .. } => delta,
        _ => panic!("Fig. 2's law is a ramp"),
    };
    let hertz = case_of(shipped_case_on("hertz.json", &mesh));
    let cm = case_of(shipped_case_on("vm272_cm.json", &mesh));
    let cm_law = FrictionLaw::constant(MU_CM).unwrap();
    let (lo, hi, fine) = qmax_window(level);
    let mut v = shipped_case_on("fig2.json", &mesh);
    v["stages"] = json!([
        {"name": "normal", "steps": 1, "pilot_x": {"force": 0.0}, "pilot_y": {"force": -10.0}},
        {"name": "to f_d P", "steps": 10, "pilot_x": {"force": 1.0}},
        {"name": "slip, coarse", "steps": 20, "pilot_x": {"slip": lo}},
        {"name": "slip, fine", "steps": fine, "pilot_x": {"slip": hi}}
    ]);
    let qmax = case_of(v);
    let model = &model;
    // Two threads: the slip-controlled peak (the longest run) and the other three in turn.
    let ((h_sim, h_s, c_sim, c_s, f_sim, f_s), (q_sim, q_s)) = std::thread::scope(|sc| {
        let qh = sc.spawn(|| run(model, &qmax, Some(&law)));
        let (h_sim, h_s) = run(model, &hertz, None);
        let (c_sim, c_s) = run(model, &cm, Some(&cm_law));
        let (f_sim, f_s) = run(model, &fig2, Some(&law));
        ((h_sim, h_s, c_sim, c_s, f_sim, f_s), qh.join().unwrap())
    });
    let geo = Hertz::new(Geometry::vm272(), 10.0).unwrap();
    let last_fig = |s: &Simulation| s.records.last().unwrap().contact.unwrap();

    // Hertz.
    assert!(
        h_sim.failure.is_none(),
        "L{level} hertz: {:?}",
        h_sim.failure
    );
    let fh = face(model, h_sim.last_state.as_ref().unwrap());
    let a_nodes = last_fig(&h_sim).a;
    let dev_hertz =
        fh.x.iter()
            .zip(&fh.p)
            .filter(|(x, _)| x.abs() <= 0.95 * geo.a)
            .map(|(x, p)| (p - geo.pressure(*x)).abs() / geo.p0)
            .fold(0.0, f64::max);

    // Cattaneo–Mindlin.
    assert!(c_sim.failure.is_none(), "L{level} cm: {:?}", c_sim.failure);
    let fc = face(model, c_sim.last_state.as_ref().unwrap());
    let c_cm_nodes = last_fig(&c_sim).c;

    // Fig. 2 (L0 does not reach Q = 0.8 f_d P: see the doc).
    let (c_fig2, b, c_fig2_nodes, b_nodes, fig2_status) = match &f_sim.failure {
        None => {
            let ff = face(model, f_sim.last_state.as_ref().unwrap());
            let fig = last_fig(&f_sim);
            (
                slip_edge(&ff),
                slip_crossing(&ff, 2.0 * delta),
                fig.c,
                fig.b,
                "completed".to_string(),
            )
        }
        Some(why) => {
            let status = match f_sim.lost_equilibrium {
                Some((q, _)) => format!(
                    "stopped at Q = {q:.4} N/mm (`equilibrium lost` from the CLI, exit status 5)"
                ),
                None => why.to_string(),
            };
            (f64::NAN, f64::NAN, f64::NAN, f64::NAN, status)
        }
    };

    // Q_max: the fine stage's samples.
    assert!(
        q_sim.failure.is_none(),
        "L{level} qmax: {:?}",
        q_sim.failure
    );
    let fine_recs: Vec<_> = q_sim.records.iter().filter(|r| r.stage == 3).collect();
    let s: Vec<f64> = fine_recs
        .iter()
        .map(|r| r.contact.unwrap().mean_slip)
        .collect();
    let q: Vec<f64> = fine_recs.iter().map(|r| r.pilot.unwrap().fx).collect();
    let (q_max, i) = corner_peak(&s, &q);
    assert!(
        i >= 2 && i + 3 <= q.len(),
        "L{level}: the peak of Q (sample {i} of {}, mean slip {:e}) is not inside the fine window [{lo:e}, {hi:e}]",
        q.len(),
        s[i]
    );
    let out = Level {
        level,
        h: h(level),
        dofs: model.dofs.n_free(),
        contact_nodes: model
            .contact
            .as_ref()
            .unwrap()
            .pair
            .mortar
            .slave_nodes
            .len(),
        a_nodes,
        c_cm_nodes,
        c_fig2_nodes,
        b_nodes,
        a: contact_width(&fh, a_nodes),
        p0: peak_pressure(&fh),
        dev_hertz,
        dev_finest: f64::NAN,
        c_cm: cm_stick_width(&fc, MU_CM, c_cm_nodes),
        c_fig2,
        b,
        q_max,
        q_max_sample: q[i],
        s_peak: s[i],
        fig2_status,
        delta,
        pressure: fh.x.iter().copied().zip(fh.p.iter().copied()).collect(),
        build_s,
        hertz_s: h_s,
        cm_s: c_s,
        fig2_s: f_s,
        qmax_s: q_s,
        wall_s: 0.0,
    };
    Level {
        wall_s: t_level.elapsed().as_secs_f64(),
        ..out
    }
}

/// Linear interpolation in a table sorted by x.
fn interp(t: &[(f64, f64)], x: f64) -> f64 {
    let k = t.partition_point(|p| p.0 < x).clamp(1, t.len() - 1);
    let (a, b) = (t[k - 1], t[k]);
    a.1 + (x - a.0) / (b.0 - a.0) * (b.1 - a.1)
}

/// Richardson extrapolation from the three finest levels.
#[derive(Clone, Debug)]
struct Extrap {
    /// Observed order (None: the finest levels are not in the asymptotic range).
    p: Option<f64>,
    limit: f64,
    bar: f64,
}

/// From the values of all levels (h ratio 2 between neighbours), with q5, q6, q7 the three
/// finest, d1 = q6 − q5 and d2 = q7 − q6: where d1 and d2 have the same sign, |d2| < |d1| and
/// the next coarser level q4 lies farther from the result than q5, the observed order is
/// p = log2(d1/d2) and the limit q7 + d2/(2^p − 1); its error bar is the larger of
/// |limit − q7| and the difference between this three-level limit and the two-level one with
/// the rate `p_fit` fitted over the ladder. Otherwise the finest levels are not in the
/// asymptotic range (they oscillate, or q4 contradicts the fit): the limit is q7 and the error
/// bar the larger of |d1| and |d2|.
fn richardson(v: &[f64], p_fit: f64) -> Extrap {
    let n = v.len();
    let (q4, q) = (v[n - 4], [v[n - 3], v[n - 2], v[n - 1]]);
    let (d1, d2) = (q[1] - q[0], q[2] - q[1]);
    if d1 * d2 > 0.0 && d2.abs() < d1.abs() {
        let p = (d1 / d2).log2();
        let limit = q[2] + d2 / (2f64.powf(p) - 1.0);
        let limit2 = q[2] + d2 / (2f64.powf(p_fit) - 1.0);
        if (q4 - limit).abs() > (q[0] - limit).abs() {
            return Extrap {
                p: Some(p),
                limit,
                bar: (limit - q[2]).abs().max((limit - limit2).abs()),
            };
        }
    }
    Extrap {
        p: None,
        limit: q[2],
        bar: d1.abs().max(d2.abs()),
    }
}

/// What is asserted of one quantity (all from the measured run, see docs/convergence.md).
struct Expect {
    /// The error falls monotonically from this level to L6.
    monotone_from: usize,
    /// The rate is fitted from this level to L6.
    fit_from: usize,
    /// Measured rate and the band asserted around it.
    rate: f64,
    rate_tol: f64,
    /// Measured (limit / closed form − 1) and the band asserted around it.
    offset: Option<(f64, f64)>,
    /// Measured limit and the band asserted around it (quantities without a closed form).
    limit: Option<(f64, f64)>,
    /// Why the error is not monotone below `monotone_from`.
    note: &'static str,
}

/// |v| ≤ tol, false for NaN.
fn within(v: f64, tol: f64) -> bool {
    v.abs() <= tol
}

/// a < b, false for NaN.
fn below(a: f64, b: f64) -> bool {
    a < b
}

/// A figure of one level.
type Getter = fn(&Level) -> f64;

/// One quantity over the ladder.
struct Study {
    name: &'static str,
    values: Vec<f64>,
    /// The half-plane closed form and its name.
    closed: Option<(f64, &'static str)>,
    extrap: Extrap,
    /// |value − limit| per level (L7's is the extrapolation itself, or zero).
    errors: Vec<f64>,
    rate: f64,
    /// Fitted rate of the successive differences |q_{k+1} − q_k| (no reference needed).
    diff_rate: f64,
    expect: Expect,
}

/// The finest level whose error enters the rates and the monotonicity: L6 (L7's error is the
/// extrapolation itself, or zero where L7 is the reference).
const LAST: usize = LEVELS - 2;

fn study(
    name: &'static str,
    values: Vec<f64>,
    closed: Option<(f64, &'static str)>,
    expect: Expect,
) -> Study {
    let hs: Vec<f64> = (0..values.len()).map(h).collect();
    let from = expect.fit_from;
    let (dh, dd): (Vec<f64>, Vec<f64>) = (from..values.len() - 1)
        .map(|k| (hs[k], (values[k + 1] - values[k]).abs()))
        .unzip();
    let diff_rate = fitted_rate(&dh, &dd);
    let extrap = richardson(&values, diff_rate);
    let errors: Vec<f64> = values.iter().map(|v| (v - extrap.limit).abs()).collect();
    let rate = fitted_rate(&hs[from..=LAST], &errors[from..=LAST]);
    Study {
        name,
        values,
        closed,
        extrap,
        errors,
        rate,
        diff_rate,
        expect,
    }
}

/// A quantity that is itself an error against the finest level (its reference is 0, L7's
/// value undefined).
fn error_study(name: &'static str, errors: Vec<f64>, expect: Expect) -> Study {
    let hs: Vec<f64> = (0..errors.len()).map(h).collect();
    let from = expect.fit_from;
    let rate = fitted_rate(&hs[from..=LAST], &errors[from..=LAST]);
    Study {
        name,
        values: errors.clone(),
        closed: None,
        extrap: Extrap {
            p: None,
            limit: 0.0,
            bar: f64::NAN,
        },
        errors,
        rate,
        diff_rate: f64::NAN,
        expect,
    }
}

impl Study {
    fn offset(&self) -> Option<f64> {
        self.closed.map(|(c, _)| self.extrap.limit / c - 1.0)
    }

    /// Every assertion on this quantity; returns the failures.
    fn check(&self) -> Vec<String> {
        let mut bad = Vec::new();
        let e = &self.errors;
        let ex = &self.expect;
        for k in ex.monotone_from..LAST {
            if !below(e[k + 1], e[k]) {
                bad.push(format!(
                    "{}: error does not fall from L{k} to L{} ({:.3e} → {:.3e})",
                    self.name,
                    k + 1,
                    e[k],
                    e[k + 1]
                ));
            }
        }
        if !within(self.rate - ex.rate, ex.rate_tol) {
            bad.push(format!(
                "{}: fitted rate {:.3} (L{}–L{LAST}) outside {} ± {}",
                self.name, self.rate, ex.fit_from, ex.rate, ex.rate_tol
            ));
        }
        if let (Some(off), Some((want, tol))) = (self.offset(), ex.offset)
            && !within(off - want, tol)
        {
            bad.push(format!(
                "{}: finite-body limit {} is {:+.4} % from the closed form, expected {:+.4} ± {:.4} %",
                self.name,
                self.extrap.limit,
                100.0 * off,
                100.0 * want,
                100.0 * tol
            ));
        }
        if let Some((want, tol)) = ex.limit
            && !within(self.extrap.limit - want, tol)
        {
            bad.push(format!(
                "{}: finite-body limit {} outside {want} ± {tol}",
                self.name, self.extrap.limit
            ));
        }
        bad
    }
}

/// The convergence study: see the module comment and docs/convergence.md.
#[test]
fn ladder_converges() {
    let t0 = Instant::now();
    // The two finest meshes are generated on demand (gmsh), before anything is timed.
    for level in 0..LEVELS {
        ensure_mesh(&format!("vm272_L{level}"));
    }
    let t_mesh = t0.elapsed().as_secs_f64();
    let mut levels: Vec<Level> = Vec::new();
    for level in 0..LEVELS {
        let l = run_level(level);
        println!(
            "L{level}: h = {:.5} DOFs {} a {:.6} (nodes {:.6}) p0 {:.5} dev {:.5} | C–M c {:.6} ({:.6}) | Fig. 2 c {:.6} ({:.6}) b {:.6} ({:.6}) [{}] | Q_max {:.8} (sample {:.8} at {:.4e}) | build {:.1} s, hertz {:.1}, cm {:.1}, fig2 {:.1}, qmax {:.1}, level {:.1} s",
            l.h,
            l.dofs,
            l.a,
            l.a_nodes,
            l.p0,
            l.dev_hertz,
            l.c_cm,
            l.c_cm_nodes,
            l.c_fig2,
            l.c_fig2_nodes,
            l.b,
            l.b_nodes,
            l.fig2_status,
            l.q_max,
            l.q_max_sample,
            l.s_peak,
            l.build_s,
            l.hertz_s,
            l.cm_s,
            l.fig2_s,
            l.qmax_s,
            l.wall_s
        );
        levels.push(l);
    }
    let geo = Hertz::new(Geometry::vm272(), 10.0).unwrap();
    // Self-convergence of the pressure against the finest level (interpolated linearly).
    let finest = levels[LEVELS - 1].pressure.clone();
    for l in levels.iter_mut().take(LEVELS - 1) {
        l.dev_finest = l
            .pressure
            .iter()
            .filter(|(x, _)| x.abs() <= 0.9 * geo.a)
            .map(|&(x, p)| (p - interp(&finest, x)).abs() / geo.p0)
            .fold(0.0, f64::max);
    }
    let total = t0.elapsed().as_secs_f64();
    // Closed forms: Cattaneo–Mindlin c, the double C–M c and b of Fig. 2 (with Δ as the case
    // resolves it), and the JKR limit of Q_max (χ = RΔ/(f_d a²), f_s/f_d = 1.5).
    let c_cm = CattaneoMindlin::new(geo, MU_CM)
        .unwrap()
        .stick_half_width(Q_CM)
        .unwrap();
    let delta = levels[0].delta;
    let s2 = DoubleCm::new(geo, FS, FD)
        .unwrap()
        .solve_delta(Q_FIG2, delta)
        .unwrap();
    let chi = geo.geom.r * delta / (FD * geo.a * geo.a);
    let closed_qmax = apparent(chi, FS / FD, true).unwrap();
    let col = |f: &dyn Fn(&Level) -> f64| levels.iter().map(f).collect::<Vec<f64>>();
    let studies = [
        study(
            "a",
            col(&|l| l.a),
            Some((geo.a, "Hertz")),
            Expect {
                monotone_from: 4,
                fit_from: 0,
                rate: 2.03,
                rate_tol: 0.2,
                offset: Some((-0.003207, 0.0002)),
                limit: None,
                note: "L3 is closer than L4 (1.2e-4 against 1.5e-4)",
            },
        ),
        study(
            "p0",
            col(&|l| l.p0),
            Some((geo.p0, "Hertz")),
            Expect {
                monotone_from: 0,
                fit_from: 0,
                rate: 1.92,
                rate_tol: 0.2,
                offset: Some((0.002321, 0.0001)),
                limit: None,
                note: "",
            },
        ),
        study(
            "max |p − p_H|/p0",
            col(&|l| l.dev_hertz),
            None,
            Expect {
                monotone_from: 0,
                fit_from: 0,
                rate: 1.76,
                rate_tol: 0.2,
                offset: None,
                limit: Some((0.00875, 0.0001)),
                note: "",
            },
        ),
        error_study(
            "max |p − p_L7|/p0",
            col(&|l| l.dev_finest),
            Expect {
                monotone_from: 0,
                fit_from: 0,
                rate: 1.61,
                rate_tol: 0.2,
                offset: None,
                limit: None,
                note: "",
            },
        ),
        study(
            "c (C–M)",
            col(&|l| l.c_cm),
            Some((c_cm, "Cattaneo–Mindlin")),
            Expect {
                monotone_from: 1,
                fit_from: 1,
                rate: 2.23,
                rate_tol: 0.2,
                offset: Some((-0.003817, 0.0002)),
                limit: None,
                note: "L0: too few stick nodes for the fit",
            },
        ),
        study(
            "c (Fig. 2)",
            col(&|l| l.c_fig2),
            Some((s2.c, "double C–M")),
            Expect {
                monotone_from: 1,
                fit_from: 1,
                rate: 1.32,
                rate_tol: 0.2,
                offset: Some((-0.00834, 0.002)),
                limit: None,
                note: "L0: the Fig. 2 run stops at Q = 0.54 f_d P (see the text)",
            },
        ),
        study(
            "b (Fig. 2)",
            col(&|l| l.b),
            Some((s2.b, "double C–M")),
            Expect {
                monotone_from: 5,
                fit_from: 1,
                rate: 1.80,
                rate_tol: 0.25,
                offset: Some((0.011337, 0.0002)),
                limit: None,
                note: "L0 as c; L2 is farther than L1 (3.2e-3, 1.7e-3), L4 closer than L5 (2.0e-5, 5.3e-5)",
            },
        ),
        study(
            "Q_max",
            col(&|l| l.q_max),
            Some((closed_qmax.q_max_jkr * FD * 10.0, "JKR")),
            Expect {
                monotone_from: 2,
                fit_from: 0,
                rate: 1.89,
                rate_tol: 0.2,
                offset: Some((-0.000771, 0.0001)),
                limit: None,
                note: "L1 is closer than L2 (3.0e-3, 3.7e-3)",
            },
        ),
    ];
    for s in &studies {
        println!(
            "{}: values {:?}\n  errors {:?}\n  Richardson {:?}; rate {:.3} (L{}–L{LAST}), successive differences {:.3}; vs closed form {:?}",
            s.name,
            s.values,
            s.errors,
            s.extrap,
            s.rate,
            s.expect.fit_from,
            s.diff_rate,
            s.offset()
        );
    }
    // The figures of history.csv (edges on the node grid) stay within one node spacing (h/2)
    // of the finite-body limit from L2 on.
    let mut failures: Vec<String> = studies.iter().flat_map(|s| s.check()).collect();
    // The largest distance of history.csv's a, c and b to the limit, in node spacings.
    let mut grid_worst: f64 = 0.0;
    let grid_tol = 1.0;
    let grid: [(&str, Getter, usize); 4] = [
        ("a (history.csv)", |l| l.a_nodes, 0),
        ("c C–M (history.csv)", |l| l.c_cm_nodes, 4),
        ("c Fig. 2 (history.csv)", |l| l.c_fig2_nodes, 5),
        ("b Fig. 2 (history.csv)", |l| l.b_nodes, 6),
    ];
    for (name, get, k) in grid {
        let worst = levels[2..]
            .iter()
            .map(|l| (get(l) - studies[k].extrap.limit).abs() / (l.h / 2.0))
            .fold(0.0, f64::max);
        println!("{name}: largest distance to the limit, L2–L7: {worst:.2} node spacings");
        grid_worst = grid_worst.max(worst);
        if !within(worst, grid_tol) {
            failures.push(format!(
                "{name}: {worst:.2} node spacings from the finite-body limit"
            ));
        }
    }
    println!("whole ladder: {total:.0} s");
    let block = doc_block(&levels, &studies, total, t_mesh);
    println!("{block}");
    if std::env::var("LADDER_WRITE_DOC").is_ok_and(|v| v == "1") {
        write_doc(&block);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    validation_rows(&levels, &studies, grid_worst, grid_tol);
}

/// The two rows of the README's validation table that this test backs, from the asserted
/// studies (`Study::check`) and the distances of history.csv's edges to the limit.
fn validation_rows(levels: &[Level], studies: &[Study], grid_worst: f64, grid_tol: f64) {
    let short = [
        "a",
        "p0",
        "max |p − p_H|",
        "pressure against L7",
        "C–M c",
        "Fig. 2 c",
        "b",
        "Q_max",
    ];
    let monotone: Vec<String> = studies
        .iter()
        .zip(short)
        .map(|(s, n)| format!("{n} from L{}", s.expect.monotone_from))
        .collect();
    let rates: Vec<String> = studies
        .iter()
        .zip(short)
        .map(|(s, n)| {
            format!(
                "{n} {:.2} (asserted {} ± {})",
                s.rate, s.expect.rate, s.expect.rate_tol
            )
        })
        .collect();
    validation_row(
        "160-ladder-convergence",
        "convergence over the whole ladder L0–L7 (L6, L7 built on demand): a, p0, max |p − p_H|/p0, C–M c, Fig. 2 c and b, Q_max, each edge located below the node spacing; tables in [docs/convergence.md](docs/convergence.md)",
        "finite-body limit (Richardson from L5–L7, error bar from the last differences)",
        &format!(
            "errors fall monotonically to L{LAST} ({}); fitted rates {}; `history.csv`'s a, c, b within {grid_worst:.2} node spacings of the limit from L2 on (asserted ≤ {grid_tol})",
            monotone.join(", "),
            rates.join(", ")
        ),
        "ladder",
    );
    // Offsets of the finite-body limits from the half-plane closed forms, in per cent, and the
    // band each is asserted in.
    let off = |k: usize| 100.0 * studies[k].offset().unwrap();
    let band = |k: usize| 100.0 * studies[k].expect.offset.unwrap().1;
    // c/a of C–M against the closed forms' ratio.
    let (a, c) = (&studies[0], &studies[4]);
    let ca = 100.0
        * ((c.extrap.limit / a.extrap.limit) / (c.closed.unwrap().0 / a.closed.unwrap().0) - 1.0);
    let dev = &studies[2];
    let (want, tol) = dev.expect.limit.unwrap();
    validation_row(
        "170-ladder-finite-body",
        "finite-body references against the half-plane closed forms",
        "Hertz, C–M, double C–M, JKR",
        &format!(
            "a {:+.3} %, p0 {:+.3} %, C–M c {:+.3} % (c/a {ca:+.2} %), Fig. 2 c {:+.2} % and b {:+.2} %, Q_max = {:.6} f_d P ({:+.3} % from JKR) (asserted within ±{:.2}, ±{:.2}, ±{:.2}, ±{:.2}, ±{:.2}, ±{:.2} % of the measured offsets); the {:.4}/{:.4} p0 pressure deviation of L4/L5 converges to {:.4} ± {:.4} p0 (asserted {want} ± {tol}): the finite discs, not the mesh",
            off(0),
            off(1),
            off(4),
            off(5),
            off(6),
            studies[7].extrap.limit / (FD * 10.0),
            off(7),
            band(0),
            band(1),
            band(4),
            band(5),
            band(6),
            band(7),
            levels[4].dev_hertz,
            levels[5].dev_hertz,
            dev.extrap.limit,
            dev.extrap.bar
        ),
        "ladder",
    );
}

/// `v` with `prec` decimals, or a dash for NaN.
fn fx(v: f64, prec: usize) -> String {
    if v.is_nan() {
        "—".into()
    } else {
        format!("{v:.prec$}")
    }
}

/// `v` in scientific notation, or a dash for NaN.
fn sci(v: f64) -> String {
    if v.is_nan() {
        "—".into()
    } else {
        format!("{v:.2e}")
    }
}

/// The generated part of docs/convergence.md.
fn doc_block(levels: &[Level], studies: &[Study], total: f64, t_mesh: f64) -> String {
    let mut s = String::new();
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|t| t.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "?".into());
    s += &format!(
        "Whole ladder in {total:.0} s, of which {t_mesh:.0} s generating missing meshes ({} threads; load average {load} at the end of the run).\n\n",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    s += "**Per level.** h: element length along the arcs over |x| ≤ 1.5a; wall times in seconds: \
          building the model (read, assemble, factorise, condense), then the runs on it — `hertz`, \
          `cm` and `fig2` one after the other in one thread while the slip-controlled Q_max run \
          takes the other.\n\n";
    s += "| level | h (mm) | a_H/h | DOFs | contact candidates | a (mm) | p0 (N/mm²) | max\\|p − p_H\\|/p0 | max\\|p − p_L7\\|/p0 | c C–M (mm) | c Fig. 2 (mm) | b Fig. 2 (mm) | Q_max (N/mm; f_d P = 1) | build | hertz | cm | fig2 | Q_max | level |\n";
    s += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    let a_h = studies[0].closed.map_or(f64::NAN, |c| c.0);
    for l in levels {
        s += &format!(
            "| L{} | {:.5} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |\n",
            l.level,
            l.h,
            a_h / l.h,
            l.dofs,
            l.contact_nodes,
            fx(l.a, 6),
            fx(l.p0, 5),
            fx(l.dev_hertz, 5),
            sci(l.dev_finest),
            fx(l.c_cm, 6),
            fx(l.c_fig2, 6),
            fx(l.b, 6),
            fx(l.q_max, 7),
            l.build_s,
            l.hertz_s,
            l.cm_s,
            l.fig2_s,
            l.qmax_s,
            l.wall_s
        );
    }
    s += "\n**As `history.csv` and `summary.json` report them** (a: p² extrapolated from the two \
          outermost contact nodes; c, b: midway between the last node inside and the first outside, \
          so they move in steps of the node spacing h/2; Q_max: the largest sample of the \
          slip-controlled run, before the corner correction), and the Fig. 2 run's status:\n\n";
    s += "| level | node spacing h/2 (mm) | a (mm) | c C–M (mm) | c Fig. 2 (mm) | b Fig. 2 (mm) | Q_max sample (N/mm) | at mean slip (mm) | Fig. 2 run |\n";
    s += "|---|---|---|---|---|---|---|---|---|\n";
    for l in levels {
        s += &format!(
            "| L{} | {:.5} | {} | {} | {} | {} | {} | {:.4e} | {} |\n",
            l.level,
            l.h / 2.0,
            fx(l.a_nodes, 6),
            fx(l.c_cm_nodes, 6),
            fx(l.c_fig2_nodes, 6),
            fx(l.b_nodes, 6),
            fx(l.q_max_sample, 7),
            l.s_peak,
            l.fig2_status.replace('|', "\\|")
        );
    }
    s += "\n**Errors against the finite-body reference** (|value − limit|, the limit of the next \
          table; in the unit of the quantity) and what the test asserts: the error falls \
          monotonically over the stated levels, and the rate (least-squares slope of log error \
          against log h over the stated levels) lies in the stated band.\n\n";
    s += "| quantity |";
    for l in levels {
        s += &format!(" L{} |", l.level);
    }
    s += " falls monotonically | rate (asserted) | rate of successive differences | not monotone |\n|---|";
    for _ in levels {
        s += "---|";
    }
    s += "---|---|---|---|\n";
    for st in studies {
        s += &format!("| {} |", st.name.replace('|', "\\|"));
        for e in &st.errors {
            s += &format!(" {} |", if *e == 0.0 { "(ref.)".into() } else { sci(*e) });
        }
        let ex = &st.expect;
        s += &format!(
            " L{}–L{LAST} | {:.2} over L{}–L{LAST} ({}) | {} | {} |\n",
            ex.monotone_from,
            st.rate,
            ex.fit_from,
            if ex.rate_tol < 10.0 {
                format!("{} ± {}", ex.rate, ex.rate_tol)
            } else {
                "not asserted".into()
            },
            fx(st.diff_rate, 2),
            if ex.note.is_empty() { "—" } else { ex.note }
        );
    }
    s += "\n**Finite-body references**: Richardson extrapolation from L5, L6, L7 (rules above), \
          against the half-plane closed forms (the test asserts each offset within the stated \
          band):\n\n";
    s += "| quantity | observed order p | limit | error bar | closed form | limit vs closed form (asserted) |\n|---|---|---|---|---|---|\n";
    for st in studies.iter().filter(|st| !st.extrap.bar.is_nan()) {
        let ex = &st.extrap;
        let (closed, off) = match (st.closed, st.offset(), st.expect.offset) {
            (Some((c, name)), Some(o), Some((want, tol))) => (
                format!("{c:.6} ({name})"),
                format!(
                    "{:+.3} % ({:+.3} ± {:.3} %)",
                    100.0 * o,
                    100.0 * want,
                    100.0 * tol
                ),
            ),
            _ => ("—".into(), "—".into()),
        };
        s += &format!(
            "| {} | {} | {:.7} | {:.1e} | {closed} | {off} |\n",
            st.name.replace('|', "\\|"),
            ex.p.map_or("— (not asymptotic: limit = L7)".into(), |p| format!(
                "{p:.2}"
            )),
            ex.limit,
            ex.bar,
        );
    }
    // The widths over the finite-body contact semi-width, against the closed forms' ratios.
    let a = &studies[0];
    for (k, name) in [(4, "c/a (C–M)"), (5, "c/a (Fig. 2)"), (6, "b/a (Fig. 2)")] {
        let st = &studies[k];
        let (c, cname) = st.closed.unwrap();
        let (a_h, _) = a.closed.unwrap();
        let r = st.extrap.limit / a.extrap.limit;
        let bar = r * (st.extrap.bar / st.extrap.limit + a.extrap.bar / a.extrap.limit);
        s += &format!(
            "| {name} | — | {r:.5} | {bar:.1e} | {:.5} ({cname}) | {:+.3} % |\n",
            c / a_h,
            100.0 * (r / (c / a_h) - 1.0)
        );
    }
    s
}

fn write_doc(block: &str) {
    let path = repo().join("docs/convergence.md");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let begin = "<!-- BEGIN generated by tests/ladder.rs (LADDER_WRITE_DOC=1) -->";
    let end = "<!-- END generated -->";
    let block = format!("{begin}\n{block}{end}");
    let text = match (old.find(begin), old.find(end)) {
        (Some(a), Some(b)) => format!("{}{}{}", &old[..a], block, &old[b + end.len()..]),
        _ => format!("{old}\n{block}\n"),
    };
    std::fs::write(path, text).unwrap();
}
