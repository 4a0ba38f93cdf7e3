//! Randomly drawn scenes (fixed seed) against the closed forms that apply to each.
//!
//! Each scene is two cylinders of radii R1 ≠ R2, or a cylinder on a flat, meshed by
//! `meshes/scene.py` (sized from the scene's Hertz a, and from s0 = 2Λa/π when a slip-weakening
//! law applies), with the elastic constants of each body (identical, dissimilar with Dundurs'
//! β = 0, dissimilar with β ≠ 0), a normal load P (through a/R), and either Coulomb friction μ
//! with a tangential load Q < μP or a slip-weakening law (ramp, step, exponential) with
//! Λ = 0.03–0.06 and a tangential force ramp past its peak. The case loads P in 10 steps (with
//! β ≠ 0 friction makes the normal problem path-dependent, and the closed forms below are for
//! a monotonic load), then Q. Checked, from the run's outputs:
//!
//! * Hertz a (`history.csv`, end of the normal stage) and p0 (largest nodal pressure in that
//!   step's contact CSV) against `a = sqrt(4PR/(πE*))`, `p0 = 2P/(πa)` with 1/R = 1/R1 + 1/R2
//!   and the plane-strain E*. With β ≠ 0 friction couples the normal and tangential problems
//!   and the pressure is not Hertz's (Spence): the allowed deviation grows as β² (see
//!   `A_BETA2`).
//! * Cattaneo–Mindlin c = a sqrt(1 − Q/(μP)) for Coulomb friction when β = 0.
//! * The JKR limit Q_max (eq. QJKR at its maximum) for the slip-weakening laws, whose s0 the
//!   mesh resolves (h ≤ s0/2, asserted from `summary.json`); the run must lose equilibrium
//!   (exit 5) at Q_max.
//! * Every self-check in `summary.json` at level `ok`.
//!
//! Fails, never skips, when gmsh is missing (`pip install gmsh==4.15.2`). Scenes run in parallel
//! worker threads, each run single-threaded and killed after `RUN_TIMEOUT`.

mod common;
use common::{Table, repo, tempdir, validation_row};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};
use stickslip::analytic::cattaneo::CattaneoMindlin;
use stickslip::analytic::hertz::{Geometry, Hertz, dundurs_beta};
use stickslip::analytic::jkr::Jkr;
use stickslip::analytic::scales;

/// Number of scenes and the seed of their draw.
const SCENES: usize = 24;
const SEED: u64 = 0x05ee_d272;
/// Steps of the normal stage (its last step is written: `output.every`).
const NORMAL_STEPS: usize = 10;
/// Wall-clock limit of one `stickslip run`.
const RUN_TIMEOUT: Duration = Duration::from_secs(240);

// Tolerances, each about 1.5× the worst case measured over the 24 scenes (the test prints the
// table and the worst cases; run with `-- --nocapture`).
/// |a_FE/a − 1| ≤ A_TOL + A_BETA2 β². Measured worst: 0.33 % with β = 0 (where the Hertz edge
/// falls between nodes; with h = a/24 it sits on a node and the error is 0.04 %), and, with
/// β ≠ 0, 0.90 % at β = 0.076 (0.69 β² above A_TOL).
const A_TOL: f64 = 0.005;
const A_BETA2: f64 = 1.0;
/// |p0_FE/p0 − 1| ≤ P_TOL + P_BETA2 β². Measured worst: 0.16 % with β = 0; with β ≠ 0 p0 is
/// 0.9 β² above Hertz (4.34 % at β = −0.215; 0.89 β² above P_TOL). An independent half-plane
/// influence-coefficient solution of the same monotonic, frictional normal load at β = 0.13
/// gives −0.77 % in a and +1.49 % in p0 (the FE: −0.98 %, +1.55 %).
const P_TOL: f64 = 0.0025;
const P_BETA2: f64 = 1.3;
/// |c_FE − c_CM| ≤ C_TOL h (β = 0; h the contact element size). The FE's c is midway between
/// the outermost stick node and the next (node spacing h/2), so it is quantised to ±h/4.
/// Measured worst 0.26 h.
const C_TOL: f64 = 0.375;
/// |Q_max,FE/Q_max,JKR − 1| ≤ Q_TOL (β = 0) for the ramp and exponential laws. Measured worst
/// 0.20 % (exponential; ramp 0.07 %).
const Q_TOL: f64 = 0.003;
/// The same for the step law, whose jump in μ no mesh resolves: Q_max converges slowly from
/// above (scene 11: +0.91 % at h = s0/2, +0.63 % at s0/3, +0.50 % at s0/4; the ramp law on the
/// same scene −0.04 % throughout). Measured worst +0.91 %.
const Q_TOL_STEP: f64 = 0.014;

/// SplitMix64: a small, fixed pseudo-random sequence (no crate needed).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Log-uniform in [lo, hi).
    fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.uniform(lo.ln(), hi.ln()).exp()
    }
    /// `x` or `1/x`, each with probability 1/2.
    fn invert(&mut self, x: f64) -> f64 {
        if self.next_u64() & 1 == 0 { x } else { 1.0 / x }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Pair {
    /// Both bodies of one material (β = 0).
    Same,
    /// Different E and ν with (1 − 2ν)/G equal, so β = 0.
    Beta0,
    /// Different materials, β ≠ 0.
    Dissimilar,
}

#[derive(Clone, Debug)]
enum Law {
    /// Constant μ, tangential load Q = q_frac μ P.
    Coulomb { mu: f64, q_frac: f64 },
    /// A slip-weakening law through Λ, tangential force ramp past the JKR peak.
    Weakening {
        shape: &'static str,
        fs: f64,
        fd: f64,
        lambda: f64,
    },
}

#[derive(Clone, Debug)]
struct Scene {
    id: usize,
    /// Upper cylinder (body 1, under the pilot).
    r1: f64,
    /// Lower body (body 2): a cylinder, or a flat (`None`).
    r2: Option<f64>,
    e1: f64,
    nu1: f64,
    e2: f64,
    nu2: f64,
    pair: Pair,
    /// Hertz a over the effective radius (sets P).
    a_over_r: f64,
    law: Law,
}

impl Scene {
    fn geometry(&self) -> Geometry {
        Geometry::from_bodies(
            self.r1,
            self.r2.unwrap_or(f64::INFINITY),
            self.e1,
            self.nu1,
            self.e2,
            self.nu2,
        )
        .unwrap()
    }

    fn hertz(&self) -> Hertz {
        let g = self.geometry();
        Hertz::with_half_width(g, self.a_over_r * g.r).unwrap()
    }

    fn beta(&self) -> f64 {
        dundurs_beta(self.e1, self.nu1, self.e2, self.nu2)
    }

    /// The slip length Δ of a weakening law (from Λ and the Hertz a).
    fn delta(&self) -> Option<f64> {
        let h = self.hertz();
        match self.law {
            Law::Weakening { fs, fd, lambda, .. } => {
                Some(scales::delta_from_lambda(lambda, h.geom.r, fs, fd, h.a).unwrap())
            }
            Law::Coulomb { .. } => None,
        }
    }

    /// Q_max of the JKR limit (eq. QJKR at its maximum).
    fn q_jkr(&self) -> Option<f64> {
        match self.law {
            Law::Weakening { fs, fd, .. } => {
                let h = self.hertz();
                let m = Jkr::new(h, fs, fd, self.delta()?)
                    .unwrap()
                    .curve()
                    .maximum();
                Some(m.q_ratio * fd * h.p_load)
            }
            Law::Coulomb { .. } => None,
        }
    }

    /// The tangential load at the end of the run.
    fn q_end(&self) -> f64 {
        match self.law {
            Law::Coulomb { mu, q_frac } => q_frac * mu * self.hertz().p_load,
            Law::Weakening { .. } => 1.05 * self.q_jkr().unwrap(),
        }
    }

    fn law_text(&self) -> String {
        match &self.law {
            Law::Coulomb { mu, q_frac } => format!("μ={mu:.3} Q={q_frac:.2}μP"),
            Law::Weakening {
                shape,
                fs,
                fd,
                lambda,
            } => format!("{shape} fs={fs:.3} fd={fd:.3} Λ={lambda:.3}"),
        }
    }
}

/// The scenes: the kinds follow a fixed schedule (so that every combination is covered
/// whatever the draw), the values come from the seeded generator.
fn draw() -> Vec<Scene> {
    let mut rng = Rng(SEED);
    (0..SCENES)
        .map(|id| {
            let pair = [Pair::Same, Pair::Beta0, Pair::Dissimilar][(id / 3) % 3];
            let flat = id % 4 == 0 || id % 4 == 3;
            let r1 = rng.log_uniform(4.0, 40.0);
            let ratio = rng.log_uniform(1.3, 3.0);
            let r2 = (!flat).then(|| r1 * rng.invert(ratio));
            let e1 = rng.log_uniform(50e3, 400e3);
            let nu1 = rng.uniform(0.2, 0.45);
            let (e2, nu2) = match pair {
                Pair::Same => (e1, nu1),
                Pair::Beta0 => {
                    let mut nu2 = rng.uniform(0.2, 0.45);
                    while (nu2 - nu1).abs() < 0.05 {
                        nu2 = rng.uniform(0.2, 0.45);
                    }
                    // (1 − 2ν)/G equal on both sides: β = 0.
                    let e2 =
                        e1 * (1.0 + nu2) * (1.0 - 2.0 * nu2) / ((1.0 + nu1) * (1.0 - 2.0 * nu1));
                    (e2, nu2)
                }
                Pair::Dissimilar => {
                    let r = rng.log_uniform(1.5, 4.0);
                    let r = rng.invert(r);
                    (e1 * r, rng.uniform(0.2, 0.45))
                }
            };
            let a_over_r = rng.log_uniform(0.005, 0.03);
            let law = if id % 3 == 2 {
                let fs = rng.uniform(0.3, 0.6);
                let fd = fs / rng.uniform(1.3, 2.5);
                Law::Weakening {
                    // k = id/3 sets the pair (k % 3); the shape cycles independently of it
                    shape: ["ramp", "step", "exponential"][(id / 3 + id / 9) % 3],
                    fs,
                    fd,
                    lambda: rng.log_uniform(0.03, 0.06),
                }
            } else {
                Law::Coulomb {
                    mu: rng.uniform(0.15, 0.6),
                    q_frac: rng.uniform(0.2, 0.9),
                }
            };
            Scene {
                id,
                r1,
                r2,
                e1,
                nu1,
                e2,
                nu2,
                pair,
                a_over_r,
                law,
            }
        })
        .collect()
}

/// What one scene gave.
#[derive(Debug)]
struct Outcome {
    code: i32,
    stderr: String,
    /// From `meshes/scene.py --json`.
    mesh: Value,
    /// Contact element size, a and p0 at the end of the normal stage.
    h: f64,
    a: f64,
    p0: f64,
    /// Largest accumulated slip at the end of the normal stage (β ≠ 0: Spence's microslip).
    slip_normal: f64,
    /// Stick semi-width at the last step (Coulomb scenes).
    c: f64,
    /// Tangential load at the last converged step, and `friction.q_max` of the summary.
    q_last: f64,
    q_max: f64,
    summary: Value,
    wall_mesh: f64,
    wall_run: f64,
}

/// Runs `cmd`, killing it after `limit`; returns (exit status, stdout, stderr).
fn run_with_timeout(cmd: &mut Command, limit: Duration) -> (i32, String, String) {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {cmd:?}: {e}"));
    let t = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if t.elapsed() > limit {
            child.kill().unwrap();
            let out = child.wait_with_output().unwrap();
            return (
                -2,
                String::from_utf8_lossy(&out.stdout).into(),
                format!(
                    "killed after {limit:?}: {}",
                    String::from_utf8_lossy(&out.stderr)
                ),
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Meshes the scene with `meshes/scene.py` into `dir/scene.msh`; returns its JSON summary.
fn mesh_scene(s: &Scene, dir: &Path) -> Value {
    let h = s.hertz();
    let mut args: Vec<String> = vec![
        repo().join("meshes/scene.py").to_str().unwrap().into(),
        "--r1".into(),
        format!("{:e}", s.r1),
    ];
    match s.r2 {
        Some(r2) => args.extend(["--r2".into(), format!("{r2:e}")]),
        None => args.push("--flat".into()),
    }
    args.extend(["--a".into(), format!("{:e}", h.a)]);
    if let Law::Weakening { lambda, .. } = s.law {
        // s0 resolved: h ≤ s0/2; the contact never grows past a, so the fine zone is narrower.
        args.extend([
            "--lambda".into(),
            format!("{lambda:e}"),
            "--fine-factor".into(),
            "1.25".into(),
        ]);
    }
    args.extend([
        "--out".into(),
        dir.join("scene.msh").to_str().unwrap().into(),
        "--json".into(),
    ]);
    let (code, out, err) = run_with_timeout(
        Command::new("python3").args(&args),
        Duration::from_secs(120),
    );
    assert!(
        code == 0,
        "scene {}: `python3 {}` failed ({code}); gmsh is required: pip install gmsh==4.15.2\n{err}",
        s.id,
        args.join(" ")
    );
    serde_json::from_str(out.trim()).unwrap()
}

/// The case file of a scene (mesh `scene.msh` beside it).
fn case(s: &Scene) -> Value {
    let h = s.hertz();
    let (friction, tangential_steps, zone) = match &s.law {
        Law::Coulomb { mu, .. } => (json!({"shape": "constant", "mu": mu}), 10, 1.25),
        Law::Weakening {
            shape,
            fs,
            fd,
            lambda,
        } => (
            json!({"shape": shape, "fs": fs, "fd": fd, "lambda": lambda,
                   "radius": h.geom.r, "load": h.p_load}),
            20,
            1.15,
        ),
    };
    json!({
        "title": format!("scene {}: R1 = {:.4}, R2 = {}, {}", s.id, s.r1,
                         s.r2.map_or("flat".into(), |r| format!("{r:.4}")), s.law_text()),
        "mesh": "scene.msh",
        "bodies": [
            {"group": "lower_body", "E": s.e2, "nu": s.nu2},
            {"group": "upper_body", "E": s.e1, "nu": s.nu1}
        ],
        "supports": [{"group": "bottom", "ux": 0.0, "uy": 0.0}],
        "pilot": {"group": "top"},
        "contact": {
            "slave": "lower_arc",
            "master": "upper_arc",
            "method": "newton",
            // the initial gap at |x| = zone·a: the candidate zone covers the contact with a margin
            "candidate_gap": (zone * h.a).powi(2) / (2.0 * h.geom.r),
            "friction": friction
        },
        "stages": [
            {"name": "normal", "steps": NORMAL_STEPS,
             "pilot_x": {"force": 0.0}, "pilot_y": {"force": -h.p_load}},
            {"name": "tangential", "steps": tangential_steps, "pilot_x": {"force": s.q_end()}}
        ],
        "output": {"every": NORMAL_STEPS}
    })
}

fn run_scene(s: &Scene, root: &Path) -> Outcome {
    let dir: PathBuf = root.join(format!("scene{:02}", s.id));
    std::fs::create_dir_all(&dir).unwrap();
    let t = Instant::now();
    let mesh = mesh_scene(s, &dir);
    let wall_mesh = t.elapsed().as_secs_f64();
    let path = dir.join("case.json");
    std::fs::write(&path, serde_json::to_string_pretty(&case(s)).unwrap()).unwrap();
    let out = dir.join("out");
    let t = Instant::now();
    let (code, _, stderr) = run_with_timeout(
        Command::new(env!("CARGO_BIN_EXE_stickslip"))
            // No model cache: tests leave the user's cache directory alone.
            .env("STICKSLIP_NO_CACHE", "1")
            .args([
                "run",
                path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--quiet",
                "--threads",
                "1",
            ]),
        RUN_TIMEOUT,
    );
    let wall_run = t.elapsed().as_secs_f64();
    let nan = f64::NAN;
    let mut o = Outcome {
        code,
        stderr,
        mesh,
        h: nan,
        a: nan,
        p0: nan,
        slip_normal: nan,
        c: nan,
        q_last: nan,
        q_max: nan,
        summary: Value::Null,
        wall_mesh,
        wall_run,
    };
    let Ok(text) = std::fs::read_to_string(out.join("summary.json")) else {
        return o;
    };
    o.summary = serde_json::from_str(&text).unwrap();
    o.h = o.summary["friction"]["h_contact"].as_f64().unwrap_or(nan);
    o.q_max = o.summary["friction"]["q_max"].as_f64().unwrap_or(nan);
    let hist = Table::read(&out.join("history.csv"));
    let (stage, a_col) = (hist.col("stage"), hist.col("a"));
    if let Some(row) = hist.rows.iter().rfind(|r| r[stage] == 0.0) {
        o.a = row[a_col];
        let step = row[0] as usize;
        let mut file = out.join(format!("contact_{step:04}.csv"));
        if !file.exists() {
            // Cut-backs in the normal stage moved its end off `output.every`: the normal
            // stage alone again (the same steps), every step written.
            let mut v = case(s);
            v["stages"].as_array_mut().unwrap().truncate(1);
            v["output"] = json!({"every": 1});
            let p = dir.join("normal.json");
            std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            let n_out = dir.join("out_normal");
            let (code, _, err) = run_with_timeout(
                Command::new(env!("CARGO_BIN_EXE_stickslip"))
                    // No model cache: tests leave the user's cache directory alone.
                    .env("STICKSLIP_NO_CACHE", "1")
                    .args([
                        "run",
                        p.to_str().unwrap(),
                        "--out",
                        n_out.to_str().unwrap(),
                        "--quiet",
                        "--threads",
                        "1",
                    ]),
                RUN_TIMEOUT,
            );
            assert_eq!(code, 0, "scene {}: normal stage alone: {err}", s.id);
            file = n_out.join(format!("contact_{step:04}.csv"));
        }
        if file.exists() {
            let c = Table::read(&file);
            let (ip, is) = (c.col("pressure"), c.col("slip"));
            o.p0 = c.rows.iter().map(|r| r[ip]).fold(0.0, f64::max);
            o.slip_normal = c.rows.iter().map(|r| r[is].abs()).fold(0.0, f64::max);
        }
    }
    o.c = hist.last("c");
    o.q_last = hist.last("pilot_fx");
    o
}

/// `value ≤ limit`, false for NaN.
fn within(value: f64, limit: f64) -> bool {
    value <= limit
}

/// `value/reference − 1`.
fn rel(value: f64, reference: f64) -> f64 {
    value / reference - 1.0
}

#[test]
fn random_scenes_match_the_closed_forms() {
    let t0 = Instant::now();
    let scenes = draw();
    // Coverage of the schedule.
    let count = |f: &dyn Fn(&Scene) -> bool| scenes.iter().filter(|s| f(s)).count();
    assert!(count(&|s| s.r2.is_none()) >= 8 && count(&|s| s.r2.is_some()) >= 8);
    assert!(count(&|s| s.pair == Pair::Dissimilar && s.beta().abs() > 0.02) >= 6);
    assert!(count(&|s| s.pair == Pair::Beta0) >= 6);
    assert!(count(&|s| matches!(s.law, Law::Weakening { .. })) >= 6);
    for s in &scenes {
        if s.pair != Pair::Dissimilar {
            assert!(s.beta().abs() < 1e-12, "scene {}: β = {}", s.id, s.beta());
        }
        if let Some(r2) = s.r2 {
            assert!((r2 / s.r1 - 1.0).abs() > 0.2, "scene {}: R1 ≈ R2", s.id);
        }
    }

    let root = tempdir("scenes");
    let workers = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .clamp(1, 4);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Outcome>>> =
        Mutex::new((0..scenes.len()).map(|_| None).collect());
    // The slow (slip-weakening) scenes first, so that the workers finish together.
    let mut order: Vec<usize> = (0..scenes.len()).collect();
    order.sort_by_key(|&i| matches!(scenes[i].law, Law::Coulomb { .. }));
    std::thread::scope(|sc| {
        for _ in 0..workers {
            sc.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&i) = order.get(k) else { break };
                    let o = run_scene(&scenes[i], &root);
                    results.lock().unwrap()[i] = Some(o);
                }
            });
        }
    });
    let results: Vec<Outcome> = results
        .into_inner()
        .unwrap()
        .into_iter()
        .map(Option::unwrap)
        .collect();

    // The table (markdown), then the assertions (all failures listed at once). Closed forms
    // that do not apply (β ≠ 0) are printed in parentheses and not asserted.
    println!(
        "| # | R1 | R2 | E1, ν1 | E2, ν2 | β | P | a/R | law | a/h | triangles | Δa % | Δp0 % | c/a: C–M, FE | Q_max/(f_d P): JKR, FE (Δ %) | slip after P / Δ | wall s |"
    );
    println!("|{}", "---|".repeat(17));
    let mut failures = Vec::new();
    let mut worst = [0.0f64; 7];
    // β ≠ 0: the least-squares k of Δp0 = k β² (sums of Δp0 β² and β⁴), the largest |β|, and the
    // largest slip of the normal stage over Δ of the slip-weakening scenes.
    let (mut fit, mut beta_max, mut slip_max) = ((0.0f64, 0.0f64), 0.0f64, 0.0f64);
    for (s, o) in scenes.iter().zip(&results) {
        let h = s.hertz();
        let beta = s.beta();
        let mut fail = |msg: String| failures.push(format!("scene {}: {msg}", s.id));
        let (da, dp) = (rel(o.a, h.a), rel(o.p0, h.p0));
        beta_max = beta_max.max(beta.abs());
        let (a_lim, p_lim) = (A_TOL + A_BETA2 * beta * beta, P_TOL + P_BETA2 * beta * beta);
        let b0 = beta.abs() < 1e-12;
        let (mut c_cm, mut q_jkr) = (f64::NAN, f64::NAN);
        match &s.law {
            Law::Coulomb { mu, .. } => {
                if o.code != 0 {
                    fail(format!("exit {} (expected 0): {}", o.code, o.stderr.trim()));
                }
                if (o.q_last / s.q_end() - 1.0).abs() > 1e-6 {
                    fail(format!("Q reached {} of {}", o.q_last, s.q_end()));
                }
                c_cm = CattaneoMindlin::new(h, *mu)
                    .unwrap()
                    .stick_half_width(s.q_end())
                    .unwrap();
                if b0 {
                    let dc = (o.c - c_cm).abs() / o.h;
                    worst[4] = worst[4].max(dc);
                    if !within(dc, C_TOL) {
                        fail(format!(
                            "c = {:.5e} vs Cattaneo–Mindlin {c_cm:.5e}: {dc:.3} h > {C_TOL} h",
                            o.c
                        ));
                    }
                }
            }
            Law::Weakening { shape, fs, fd, .. } => {
                q_jkr = s.q_jkr().unwrap();
                // (`--quiet` keeps exit 5 off the terminal: the status is in summary.json.)
                let status = o.summary["status"].as_str().unwrap_or("");
                if o.code != 5 || !status.starts_with("equilibrium lost") {
                    fail(format!(
                        "exit {} (expected 5, equilibrium lost at Q_max): {status} {}",
                        o.code,
                        o.stderr.trim()
                    ));
                }
                let f = &o.summary["friction"];
                let s0 = f["s0_over_a"].as_f64().unwrap_or(f64::NAN)
                    * f["a_hertz"].as_f64().unwrap_or(f64::NAN);
                if !within(o.h, 0.5 * s0) || f["resolved"] != json!(true) {
                    fail(format!("s0 not resolved: h = {:.3e}, s0 = {s0:.3e}", o.h));
                }
                let dq = rel(o.q_max, q_jkr);
                if b0 {
                    let (k, lim) = if *shape == "step" {
                        (6, Q_TOL_STEP)
                    } else {
                        (5, Q_TOL)
                    };
                    worst[k] = worst[k].max(dq.abs());
                    if !within(dq.abs(), lim) {
                        fail(format!(
                            "Q_max = {:.6e} vs JKR {q_jkr:.6e}: {:+.3} % (limit {:.3} %)",
                            o.q_max,
                            100.0 * dq,
                            100.0 * lim
                        ));
                    }
                } else {
                    slip_max = slip_max.max(o.slip_normal / s.delta().unwrap());
                    // The JKR limit assumes β = 0: μ = f_s everywhere until Q acts. With β ≠ 0
                    // the normal load already slips the contact edges (measured up to 4.2 Δ,
                    // μ there down to ≈ f_d), so only the bounds of any law with
                    // f_d ≤ μ ≤ f_s hold.
                    let p = h.p_load;
                    if !(o.q_max > 0.999 * fd * p && o.q_max < fs * p) {
                        fail(format!(
                            "Q_max/P = {:.5} outside (f_d, f_s) = ({fd:.5}, {fs:.5})",
                            o.q_max / p
                        ));
                    }
                }
            }
        }
        if !b0 {
            fit.0 += dp * beta * beta;
            fit.1 += beta.powi(4);
        }
        let k = if b0 { 0 } else { 2 };
        worst[k] = worst[k].max(da.abs());
        worst[k + 1] = worst[k + 1].max(dp.abs());
        if !within(da.abs(), a_lim) {
            fail(format!(
                "a = {:.6e} vs Hertz {:.6e}: {:+.3} % (limit {:.3} %)",
                o.a,
                h.a,
                100.0 * da,
                100.0 * a_lim
            ));
        }
        if !within(dp.abs(), p_lim) {
            fail(format!(
                "p0 = {:.6e} vs Hertz {:.6e}: {:+.3} % (limit {:.3} %)",
                o.p0,
                h.p0,
                100.0 * dp,
                100.0 * p_lim
            ));
        }
        let checks = o.summary["checks"].as_array().cloned().unwrap_or_default();
        if checks.is_empty() {
            fail("no checks in summary.json".into());
        }
        for c in checks.iter().filter(|c| c["level"] != "ok") {
            fail(format!(
                "check {} = {} (limit {}) at level {}: {}",
                c["name"], c["value"], c["limit"], c["level"], c["note"]
            ));
        }
        let (cm_text, q_text, slip_text) = match &s.law {
            Law::Coulomb { .. } => {
                let t = format!("{:.4}, {:.4}", c_cm / h.a, o.c / h.a);
                (if b0 { t } else { format!("({t})") }, "".into(), "".into())
            }
            Law::Weakening { fd, .. } => {
                let fdp = fd * h.p_load;
                let t = format!(
                    "{:.4}, {:.4} ({:+.2})",
                    q_jkr / fdp,
                    o.q_max / fdp,
                    100.0 * rel(o.q_max, q_jkr)
                );
                let delta = s.delta().unwrap();
                (
                    "".into(),
                    if b0 { t } else { format!("({t})") },
                    format!("{:.2e}", o.slip_normal / delta),
                )
            }
        };
        println!(
            "| {} | {:.3} | {} | {:.4e}, {:.3} | {:.4e}, {:.3} | {:+.3} | {:.4e} | {:.4} | {} | {:.1} | {} | {:+.3} | {:+.3} | {cm_text} | {q_text} | {slip_text} | {:.1} + {:.1} |",
            s.id,
            s.r1,
            s.r2.map_or("flat".into(), |r| format!("{r:.3}")),
            s.e1,
            s.nu1,
            s.e2,
            s.nu2,
            beta,
            h.p_load,
            s.a_over_r,
            s.law_text(),
            h.a / o.h,
            o.mesh["triangles"],
            100.0 * da,
            100.0 * dp,
            o.wall_mesh,
            o.wall_run
        );
    }
    println!(
        "worst: β = 0: |Δa| {:.3} %, |Δp0| {:.3} %; β ≠ 0: |Δa| {:.3} %, |Δp0| {:.3} %; |c − c_CM| {:.3} h (β = 0); |ΔQ_max| (β = 0) {:.3} % (ramp, exponential), {:.3} % (step)",
        100.0 * worst[0],
        100.0 * worst[1],
        100.0 * worst[2],
        100.0 * worst[3],
        worst[4],
        100.0 * worst[5],
        100.0 * worst[6]
    );
    println!(
        "{} scenes on {workers} workers in {:.1} s",
        scenes.len(),
        t0.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&root);
    let pct = |v: f64| format!("{:.2} %", 100.0 * v);
    validation_row(
        "300-scenes",
        &format!(
            "{} random scenes (fixed seed; `meshes/scene.py`): two cylinders R1 ≠ R2 or a cylinder on a flat; identical, dissimilar β = 0 and β ≠ 0 pairs (|β| ≤ {beta_max:.3}); Coulomb μ with Q < μP, or ramp/step/exponential laws with Λ = 0.03–0.06, s0 resolved (h ≤ s0/2), loaded past the peak; every self-check ok",
            scenes.len()
        ),
        "Hertz a, p0 (1/R = 1/R1 + 1/R2, E*); C–M c (β = 0); JKR Q_max (β = 0)",
        &format!(
            "β = 0: a within {}, p0 within {} (asserted {}, {}); c within {:.2} h (asserted {C_TOL} h); Q_max within {} of JKR for ramp/exponential, {} for step (asserted {}, {}). β ≠ 0: p0 ≈ {:.1} β² above Hertz (least squares; the normal–tangential coupling; β ≠ 0 |Δa| up to {}, |Δp0| up to {}), asserted within {} + {P_BETA2} β² (a: {} + {A_BETA2} β²); JKR does not apply there (the normal load already slips the edges by up to {slip_max:.1}Δ): f_d P < Q_max < f_s P",
            pct(worst[0]),
            pct(worst[1]),
            pct(A_TOL),
            pct(P_TOL),
            worst[4],
            pct(worst[5]),
            pct(worst[6]),
            pct(Q_TOL),
            pct(Q_TOL_STEP),
            fit.0 / fit.1,
            pct(worst[2]),
            pct(worst[3]),
            pct(P_TOL),
            pct(A_TOL)
        ),
        "scenes",
    );
}

/// `meshes/scene.py` itself: the same options give the same bytes; the groups and tags are
/// those of `vm272.geo`; the mesh reads without reoriented triangles and with sound angles; the
/// contact faces carry h = min(a/24, 0.97 s0/2) (so h ≤ s0/2) along |x| ≤ 1.5a.
#[test]
fn scene_generator_is_deterministic_and_sized() {
    let dir = tempdir("scene-gen");
    let generate = |name: &str, extra: &[&str]| -> (Value, Vec<u8>) {
        let out = dir.join(name);
        let mut args = vec![
            repo().join("meshes/scene.py").to_str().unwrap().to_string(),
            "--out".into(),
            out.to_str().unwrap().into(),
            "--json".into(),
        ];
        args.extend(extra.iter().map(|s| s.to_string()));
        let (code, stdout, err) = run_with_timeout(
            Command::new("python3").args(&args),
            Duration::from_secs(120),
        );
        assert_eq!(
            code, 0,
            "scene.py {extra:?} failed (gmsh is required: pip install gmsh==4.15.2): {err}"
        );
        (
            serde_json::from_str(stdout.trim()).unwrap(),
            std::fs::read(&out).unwrap(),
        )
    };
    let two = ["--r1", "10", "--r2", "15", "--a", "0.2", "--lambda", "0.04"];
    let (j1, b1) = generate("a.msh", &two);
    let (_, b2) = generate("b.msh", &two);
    assert!(b1 == b2, "scene.py is not deterministic");
    let s0 = 2.0 * 0.04 * 0.2 / std::f64::consts::PI;
    let h = j1["h_contact"].as_f64().unwrap();
    assert!(
        (h - 0.97 * s0 / 2.0).abs() < 1e-12 * s0,
        "h = {h}, s0 = {s0}"
    );
    let chord = j1["fine_chord"][1].as_f64().unwrap();
    assert!(
        chord <= 0.5 * s0 && chord > 0.95 * h,
        "chord {chord}, h {h}"
    );
    assert!((j1["x_fine"].as_f64().unwrap() - 0.3).abs() < 1e-12);
    let (jf, _) = generate(
        "flat.msh",
        &[
            "--r1", "25", "--flat", "--load", "15", "--e1", "110000", "--nu1", "0.34", "--e2",
            "207000", "--nu2", "0.3",
        ],
    );
    // a of the copper pad on mild steel at 15 N/mm (docs/material_pairs.md: 0.07706 mm).
    let a = Hertz::new(
        Geometry::from_bodies(25.0, f64::INFINITY, 110e3, 0.34, 207e3, 0.3).unwrap(),
        15.0,
    )
    .unwrap()
    .a;
    assert!((jf["a"].as_f64().unwrap() / a - 1.0).abs() < 1e-12);
    assert!((jf["h_contact"].as_f64().unwrap() - a / 24.0).abs() < 1e-12 * a);
    assert!((jf["depth"].as_f64().unwrap() - 20.0 * a).abs() < 1e-12 * a);
    for file in ["a.msh", "flat.msh"] {
        let (code, out, err) = common::stickslip(&["mesh-info", dir.join(file).to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        let info: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(info["reoriented_triangles"], 0, "{file}");
        let mut groups: Vec<(String, u64, u64)> = info["groups"]
            .as_array()
            .unwrap()
            .iter()
            .map(|g| {
                (
                    g["name"].as_str().unwrap().to_string(),
                    g["dim"].as_u64().unwrap(),
                    g["tag"].as_u64().unwrap(),
                )
            })
            .collect();
        groups.sort_by_key(|g| g.2);
        let want = [
            ("lower_body", 2, 1),
            ("upper_body", 2, 2),
            ("bottom", 1, 3),
            ("top", 1, 4),
            ("lower_arc", 1, 5),
            ("upper_arc", 1, 6),
        ];
        assert_eq!(
            groups,
            want.map(|(n, d, t)| (n.to_string(), d, t)).to_vec(),
            "{file}"
        );
        for g in info["groups"].as_array().unwrap() {
            if g["dim"] == 2 {
                let angle = g["min_angle_deg"].as_f64().unwrap();
                // A shallow segment's tips have the corner angle acos(1 − D/R): 20° for the pad.
                assert!(angle > 15.0, "{file}: {} min angle {angle}", g["name"]);
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
