//! `stickslip analytic …`: the closed forms from the command line.
//!
//! Scalars are printed as pretty JSON, curves as CSV with a header row. Geometry defaults to
//! VM272 (two cylinders of 8 mm, E = 200 N/mm², ν = 0.3, P = 10 N/mm); every subcommand that
//! needs it accepts `--r1 --r2 --e1 --nu1 --e2 --nu2 --load`. See `docs/analytic.md`.

use super::AnalyticError;
use super::apparent::{apparent, apparent_curve};
use super::cattaneo::CattaneoMindlin;
use super::dcm::{DoubleCm, Weakening, implied_law_normalized};
use super::hertz::{Geometry, Hertz, dundurs_beta};
use super::jkr::{Jkr, JkrCurve, k_ii};
use super::scales::{self, Scales, s0_over_c, small_scale_ok};
use crate::friction::{FrictionError, FrictionLaw, PRESETS, Shape};
use clap::{Args, Subcommand, ValueEnum};
use serde_json::{Value, json};
use std::io::Write;
use thiserror::Error;

/// Arguments of `stickslip analytic`.
#[derive(Args, Debug, Clone)]
pub struct AnalyticArgs {
    #[command(subcommand)]
    pub cmd: AnalyticCmd,
}

/// The subcommands.
#[derive(Subcommand, Debug, Clone)]
pub enum AnalyticCmd {
    /// Hertz contact: R, E*, a, p0, Dundurs' beta (JSON).
    Hertz(GeomArgs),
    /// Cattaneo–Mindlin with constant f, eq. (C-M): stick semi-width c (JSON).
    Cm(CmArgs),
    /// Abrupt static→dynamic transition (§3): C–M with f = f_d (JSON).
    Abrupt(AbruptArgs),
    /// Double Cattaneo–Mindlin, eqs. (Qx), (W1): c and b for given Q and W, Δ or Λ (JSON).
    Dcm(DcmArgs),
    /// Double C–M curve Q/(f_d P) vs c/a for given Λ and Ψ or f_s/f_d (CSV, Fig. 5).
    DcmCurve(DcmCurveArgs),
    /// Shear tractions q(x): double C–M, C–M with f_d, JKR limit (CSV, Figs. 2–3).
    Traction(TractionArgs),
    /// JKR limit, eq. (QJKR): Q_max/(f_d P) and c/a at the maximum (JSON).
    Jkr(JkrArgs),
    /// JKR curve Q/(f_d P) vs c/a for given Ψ (CSV, Fig. 4).
    JkrCurve(JkrCurveArgs),
    /// Length scales Λ, χ, Ψ, s0 and K_II (eqs. Lambda, chi, s0, KIIa) (JSON).
    Scales(ScalesArgs),
    /// A friction law f(u): f_s, f_d, W/p, Δ (eqs. Maugis, Maugis10) (JSON).
    Law(LawArgs),
    /// Samples of a friction law f(u) (CSV).
    LawCurve(LawCurveArgs),
    /// The Table 1 presets (JSON).
    Presets,
    /// Friction law implied by the double C–M solution for a/c, b/c (CSV, Fig. 1).
    ImpliedLaw(ImpliedLawArgs),
    /// Apparent static friction Q_max/(f_d P) for given χ and f_s/f_d (JSON, Fig. 6).
    Apparent(ApparentArgs),
    /// Fig. 6 curve: f_s/f_d vs Q_max/(f_d P) for given χ (CSV).
    ApparentCurve(ApparentCurveArgs),
}

/// Errors of the CLI runner (the binary prints them and exits non-zero).
#[derive(Debug, Error)]
pub enum CliError {
    #[error(transparent)]
    Analytic(#[from] AnalyticError),
    #[error(transparent)]
    Friction(#[from] FrictionError),
    #[error("{0}")]
    Usage(String),
    #[error("cannot write output: {0}")]
    Io(#[from] std::io::Error),
    #[error("JSON error: {0}")]
    Json(#[from] serde_json::Error),
}

type CliResult<T> = std::result::Result<T, CliError>;

/// Geometry and normal load (VM272 defaults).
#[derive(Args, Debug, Clone)]
pub struct GeomArgs {
    /// Radius of body 1 (mm).
    #[arg(long, default_value_t = 8.0)]
    pub r1: f64,
    /// Radius of body 2 (mm; `inf` for a flat).
    #[arg(long, default_value_t = 8.0)]
    pub r2: f64,
    /// Young's modulus of body 1 (N/mm²).
    #[arg(long, default_value_t = 200.0)]
    pub e1: f64,
    /// Poisson's ratio of body 1.
    #[arg(long, default_value_t = 0.3)]
    pub nu1: f64,
    /// Young's modulus of body 2 (N/mm²).
    #[arg(long, default_value_t = 200.0)]
    pub e2: f64,
    /// Poisson's ratio of body 2.
    #[arg(long, default_value_t = 0.3)]
    pub nu2: f64,
    /// Normal load P per unit thickness (N/mm).
    #[arg(long, default_value_t = 10.0)]
    pub load: f64,
}

impl GeomArgs {
    fn hertz(&self) -> CliResult<Hertz> {
        let g = Geometry::from_bodies(self.r1, self.r2, self.e1, self.nu1, self.e2, self.nu2)?;
        Ok(Hertz::new(g, self.load)?)
    }
}

/// Tangential force: absolute or as a ratio.
#[derive(Args, Debug, Clone)]
#[group(required = true, multiple = false)]
pub struct ForceArgs {
    /// Tangential force Q per unit thickness (N/mm).
    #[arg(long)]
    pub q: Option<f64>,
    /// Tangential force as a ratio: Q/(f P) for `cm`, Q/(f_d P) otherwise.
    #[arg(long)]
    pub q_ratio: Option<f64>,
}

impl ForceArgs {
    fn force(&self, f: f64, p: f64) -> f64 {
        match (self.q, self.q_ratio) {
            (Some(q), _) => q,
            (_, Some(r)) => r * f * p,
            _ => unreachable!("clap group is required"),
        }
    }
}

/// Fracture energy W, slip length Δ or Λ (exactly one).
#[derive(Args, Debug, Clone)]
#[group(required = true, multiple = false)]
pub struct WeakArgs {
    /// Slip length Δ (mm), eq. (Maugis10); W = (f_s − f_d) p(c) Δ.
    #[arg(long)]
    pub delta: Option<f64>,
    /// Λ = RΔ/((f_s − f_d) a²), eq. (Lambda).
    #[arg(long)]
    pub lambda: Option<f64>,
    /// Fracture energy W (N/mm), eq. (Maugis), used as given.
    #[arg(long)]
    pub w: Option<f64>,
}

/// Slip length Δ or Λ (exactly one).
#[derive(Args, Debug, Clone)]
#[group(required = true, multiple = false)]
pub struct LengthArgs {
    /// Slip length Δ (mm), eq. (Maugis10).
    #[arg(long)]
    pub delta: Option<f64>,
    /// Λ = RΔ/((f_s − f_d) a²), eq. (Lambda).
    #[arg(long)]
    pub lambda: Option<f64>,
}

impl LengthArgs {
    fn delta(&self, h: &Hertz, fs: f64, fd: f64) -> CliResult<f64> {
        match (self.delta, self.lambda) {
            (Some(d), _) => {
                if !d.is_finite() || d < 0.0 {
                    return Err(AnalyticError::NegativeDelta { delta: d }.into());
                }
                Ok(d)
            }
            (_, Some(l)) => Ok(scales::delta_from_lambda(l, h.geom.r, fs, fd, h.a)?),
            _ => unreachable!("clap group is required"),
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct CmArgs {
    /// Friction coefficient f.
    #[arg(long)]
    pub mu: f64,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

#[derive(Args, Debug, Clone)]
pub struct AbruptArgs {
    /// Static coefficient f_s.
    #[arg(long)]
    pub fs: f64,
    /// Dynamic coefficient f_d.
    #[arg(long)]
    pub fd: f64,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

#[derive(Args, Debug, Clone)]
pub struct DcmArgs {
    /// Static coefficient f_s.
    #[arg(long)]
    pub fs: f64,
    /// Dynamic coefficient f_d.
    #[arg(long)]
    pub fd: f64,
    #[command(flatten)]
    pub weak: WeakArgs,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

/// Friction ratio for dimensionless curves.
#[derive(Args, Debug, Clone)]
#[group(required = true, multiple = false)]
pub struct RatioArgs {
    /// Ψ = (f_s/f_d − 1)² Λ; then f_s/f_d = 1 + sqrt(Ψ/Λ).
    #[arg(long)]
    pub psi: Option<f64>,
    /// f_s/f_d directly.
    #[arg(long)]
    pub fs_over_fd: Option<f64>,
}

#[derive(Args, Debug, Clone)]
pub struct DcmCurveArgs {
    /// Λ = RΔ/((f_s − f_d) a²).
    #[arg(long)]
    pub lambda: f64,
    #[command(flatten)]
    pub ratio: RatioArgs,
    /// Number of points (c/a uniform in [0, 1]).
    #[arg(long, default_value_t = 201)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct TractionArgs {
    /// Static coefficient f_s.
    #[arg(long)]
    pub fs: f64,
    /// Dynamic coefficient f_d.
    #[arg(long)]
    pub fd: f64,
    #[command(flatten)]
    pub len: LengthArgs,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
    /// Number of points (x uniform in [−a, a]).
    #[arg(long, default_value_t = 401)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct JkrArgs {
    /// Ψ = (f_s/f_d − 1) RΔ/(f_d a²).
    #[arg(long)]
    pub psi: f64,
    /// Also give the stable c/a at this Q/(f_d P).
    #[arg(long)]
    pub q_ratio: Option<f64>,
    /// Also check the small-scale criterion at the maximum for this Λ.
    #[arg(long)]
    pub lambda: Option<f64>,
}

#[derive(Args, Debug, Clone)]
pub struct JkrCurveArgs {
    /// Ψ.
    #[arg(long)]
    pub psi: f64,
    /// Number of points (c/a uniform in [0, 1]).
    #[arg(long, default_value_t = 201)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct ScalesArgs {
    /// Static coefficient f_s.
    #[arg(long)]
    pub fs: f64,
    /// Dynamic coefficient f_d.
    #[arg(long)]
    pub fd: f64,
    #[command(flatten)]
    pub len: LengthArgs,
    /// Also evaluate s0/c, W, K_II and the JKR zone width δ at this stick radius c/a.
    #[arg(long)]
    pub c_over_a: Option<f64>,
    #[command(flatten)]
    pub geom: GeomArgs,
}

/// Parametric shapes for `--shape`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShapeArg {
    Constant,
    Ramp,
    Step,
    Exponential,
}

/// A friction law: `--json`, `--preset` or `--shape` with coefficients.
#[derive(Args, Debug, Clone)]
pub struct LawSpec {
    /// The law as JSON, e.g. '{"shape":"ramp","fs":0.15,"fd":0.1,"delta":2.9e-4}'.
    #[arg(long, conflicts_with_all = ["preset", "shape"])]
    pub json: Option<String>,
    /// A Table 1 preset (see `presets`); a ramp unless --shape is given.
    #[arg(long)]
    pub preset: Option<String>,
    /// Parametric shape.
    #[arg(long, value_enum)]
    pub shape: Option<ShapeArg>,
    /// f_s (or mu for `constant`).
    #[arg(long)]
    pub fs: Option<f64>,
    /// f_d.
    #[arg(long)]
    pub fd: Option<f64>,
    /// Δ (mm).
    #[arg(long)]
    pub delta: Option<f64>,
}

impl LawSpec {
    fn law(&self) -> CliResult<FrictionLaw> {
        if let Some(j) = &self.json {
            return serde_json::from_str(j)
                .map_err(|e| CliError::Usage(format!("invalid friction law JSON: {e}")));
        }
        if let Some(name) = &self.preset {
            let shape = match self.shape {
                None | Some(ShapeArg::Ramp) => Shape::Ramp,
                Some(ShapeArg::Step) => Shape::Step,
                Some(ShapeArg::Exponential) => Shape::Exponential,
                Some(ShapeArg::Constant) => {
                    return Err(CliError::Usage(
                        "a preset cannot have shape `constant`".into(),
                    ));
                }
            };
            return Ok(FrictionLaw::preset_shaped(name, shape)?);
        }
        let need = |v: Option<f64>, n: &str| {
            v.ok_or_else(|| CliError::Usage(format!("--{n} is required with --shape")))
        };
        match self.shape {
            None => Err(CliError::Usage(
                "give the law with --json, --preset or --shape (+ --fs --fd --delta)".into(),
            )),
            Some(ShapeArg::Constant) => Ok(FrictionLaw::constant(need(self.fs, "fs")?)?),
            Some(s) => {
                let (fs, fd, d) = (
                    need(self.fs, "fs")?,
                    need(self.fd, "fd")?,
                    need(self.delta, "delta")?,
                );
                let shape = match s {
                    ShapeArg::Ramp => Shape::Ramp,
                    ShapeArg::Step => Shape::Step,
                    _ => Shape::Exponential,
                };
                Ok(FrictionLaw::shaped(shape, fs, fd, d)?)
            }
        }
    }
}

#[derive(Args, Debug, Clone)]
pub struct LawArgs {
    #[command(flatten)]
    pub spec: LawSpec,
    /// Also evaluate f(u) and df/du at this slip (mm).
    #[arg(long)]
    pub u: Option<f64>,
}

#[derive(Args, Debug, Clone)]
pub struct LawCurveArgs {
    #[command(flatten)]
    pub spec: LawSpec,
    /// Largest slip (mm); default 3Δ (or 1.5 × the last table slip).
    #[arg(long)]
    pub u_max: Option<f64>,
    /// Number of points.
    #[arg(long, default_value_t = 301)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct ImpliedLawArgs {
    /// a/c.
    #[arg(long)]
    pub a_over_c: f64,
    /// b/c, in (1, a/c].
    #[arg(long)]
    pub b_over_c: f64,
    /// Number of points.
    #[arg(long, default_value_t = 201)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct ApparentArgs {
    /// χ = RΔ/(f_d a²), eq. (chi).
    #[arg(long)]
    pub chi: f64,
    /// f_s/f_d.
    #[arg(long)]
    pub fs_over_fd: f64,
    /// Skip the double C–M value.
    #[arg(long)]
    pub no_dcm: bool,
}

#[derive(Args, Debug, Clone)]
pub struct ApparentCurveArgs {
    /// χ = RΔ/(f_d a²), eq. (chi).
    #[arg(long)]
    pub chi: f64,
    /// Largest f_s/f_d.
    #[arg(long, default_value_t = 3.0)]
    pub ratio_max: f64,
    /// Number of points (f_s/f_d uniform in [1, ratio-max]).
    #[arg(long, default_value_t = 81)]
    pub n: usize,
    /// Add the double C–M columns (slower).
    #[arg(long)]
    pub dcm: bool,
}

fn print_json(out: &mut dyn Write, v: &Value) -> CliResult<()> {
    serde_json::to_writer_pretty(&mut *out, v)?;
    writeln!(out)?;
    Ok(())
}

fn csv_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// Runs one `analytic` subcommand, writing JSON or CSV to `out`.
pub fn run(args: &AnalyticArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.cmd {
        AnalyticCmd::Hertz(g) => {
            let h = g.hertz()?;
            print_json(
                out,
                &json!({
                    "r_eff": h.geom.r, "e_star": h.geom.e_star, "load": h.p_load,
                    "a": h.a, "p0": h.p0,
                    "dundurs_beta": dundurs_beta(g.e1, g.nu1, g.e2, g.nu2),
                }),
            )
        }
        AnalyticCmd::Cm(c) => {
            let h = c.geom.hertz()?;
            let cm = CattaneoMindlin::new(h, c.mu)?;
            let q = c.force.force(c.mu, h.p_load);
            let cc = cm.stick_half_width(q)?;
            print_json(
                out,
                &json!({
                    "mu": c.mu, "q": q, "q_over_mu_p": q / (c.mu * h.p_load),
                    "a": h.a, "p0": h.p0, "c": cc, "c_over_a": cc / h.a,
                }),
            )
        }
        AnalyticCmd::Abrupt(c) => {
            let h = c.geom.hertz()?;
            let cm = CattaneoMindlin::abrupt(h, c.fs, c.fd)?;
            let q = c.force.force(c.fd, h.p_load);
            let cc = cm.stick_half_width(q)?;
            print_json(
                out,
                &json!({
                    "fs": c.fs, "fd": c.fd, "q": q, "q_over_fd_p": q / (c.fd * h.p_load),
                    "a": h.a, "c": cc, "c_over_a": cc / h.a,
                    "note": "abrupt transition (Delta = 0): Cattaneo-Mindlin with f = f_d",
                }),
            )
        }
        AnalyticCmd::Dcm(d) => run_dcm(d, out),
        AnalyticCmd::DcmCurve(d) => {
            let r = match (d.ratio.psi, d.ratio.fs_over_fd) {
                (Some(psi), _) => {
                    JkrCurve::new(psi)?;
                    if d.lambda <= 0.0 {
                        return Err(AnalyticError::NotPositive {
                            name: "Lambda",
                            value: d.lambda,
                        }
                        .into());
                    }
                    1.0 + (psi / d.lambda).sqrt()
                }
                (_, Some(r)) => r,
                _ => unreachable!(),
            };
            let (m, weak) = DoubleCm::normalized(r, d.lambda)?;
            let pts = m.curve(weak, d.n)?;
            writeln!(out, "c_over_a,b_over_a,mid_over_a,q_ratio,branch,stable")?;
            for p in pts {
                writeln!(
                    out,
                    "{},{},{},{},{},{}",
                    p.c,
                    p.b,
                    0.5 * (p.c + p.b),
                    p.q / (m.fd * m.hertz.p_load),
                    match p.branch {
                        super::dcm::Branch::Dcm => "dcm",
                        super::dcm::Branch::CmFs => "cm_fs",
                    },
                    p.stable
                )?;
            }
            Ok(())
        }
        AnalyticCmd::Traction(t) => {
            let h = t.geom.hertz()?;
            let delta = t.len.delta(&h, t.fs, t.fd)?;
            let dcm = DoubleCm::new(h, t.fs, t.fd)?;
            let q = t.force.force(t.fd, h.p_load);
            let st = dcm.solve_delta(q, delta)?;
            let cm = CattaneoMindlin::new(h, t.fd)?;
            let c_cm = cm.stick_half_width(q).ok();
            let jkr = Jkr::new(h, t.fs, t.fd, delta)?;
            let c_jkr = jkr
                .curve()
                .stick_half_width(q / (t.fd * h.p_load))
                .ok()
                .map(|x| x * h.a);
            writeln!(out, "x,x_over_a,p,q_dcm,q_cm_fd,q_jkr,f_dcm")?;
            let n = t.n.max(2);
            for i in 0..n {
                let x = -h.a + 2.0 * h.a * i as f64 / (n - 1) as f64;
                let p = h.pressure(x);
                let qd = dcm.traction(x, st.c, st.b);
                let f = if p > 0.0 { Some(qd / p) } else { None };
                let qj = c_jkr.map(|c| jkr.traction(x, c)).filter(|v| v.is_finite());
                writeln!(
                    out,
                    "{},{},{},{},{},{},{}",
                    x,
                    x / h.a,
                    p,
                    qd,
                    csv_opt(c_cm.map(|c| cm.traction(x, c))),
                    csv_opt(qj),
                    csv_opt(f)
                )?;
            }
            Ok(())
        }
        AnalyticCmd::Jkr(j) => {
            let cur = JkrCurve::new(j.psi)?;
            let m = cur.maximum();
            let mut v = json!({
                "psi": j.psi, "q_max_ratio": m.q_ratio, "c_max_over_a": m.c_over_a,
            });
            if let Some(q) = j.q_ratio {
                v["q_ratio"] = json!(q);
                v["c_over_a"] = json!(cur.stick_half_width(q)?);
            }
            if let Some(l) = j.lambda {
                super::non_negative("Lambda", l)?;
                let s = (m.c_over_a > 0.0).then(|| s0_over_c(l, m.c_over_a));
                v["lambda"] = json!(l);
                v["s0_over_c_at_max"] = json!(s);
                v["small_scale_ok"] = json!(s.is_some_and(small_scale_ok));
            }
            print_json(out, &v)
        }
        AnalyticCmd::JkrCurve(j) => {
            let cur = JkrCurve::new(j.psi)?;
            writeln!(out, "c_over_a,q_ratio,stable")?;
            for (c, q, s) in cur.curve(j.n) {
                writeln!(out, "{c},{q},{s}")?;
            }
            Ok(())
        }
        AnalyticCmd::Scales(s) => {
            let h = s.geom.hertz()?;
            let delta = s.len.delta(&h, s.fs, s.fd)?;
            let sc = Scales::new(&h, s.fs, s.fd, delta)?;
            let mut v = serde_json::to_value(sc)?;
            v["a"] = json!(h.a);
            v["p0"] = json!(h.p0);
            v["small_scale_limit"] = json!(scales::SMALL_SCALE_LIMIT);
            if let Some(ct) = s.c_over_a {
                if !(ct > 0.0 && ct < 1.0) {
                    return Err(AnalyticError::OutOfRange {
                        name: "c/a",
                        value: ct,
                        lo: 0.0,
                        hi: 1.0,
                    }
                    .into());
                }
                let c = ct * h.a;
                let jkr = Jkr::new(h, s.fs, s.fd, delta)?;
                let pc = h.pressure(c);
                let s0c = scales::s0(h.geom.e_star, delta, s.fs, s.fd, pc)?;
                v["c_over_a"] = json!(ct);
                v["p_c"] = json!(pc);
                v["s0_c"] = json!(s0c);
                v["s0_over_c"] = json!(s0c / c);
                v["small_scale_ok"] = json!(small_scale_ok(s0c / c));
                v["w_c"] = json!(jkr.energy(c));
                v["k_ii_c"] = json!(k_ii(jkr.energy(c), h.geom.e_star));
                v["jkr_zone_width_c"] = json!(jkr.transition_width(c));
            }
            print_json(out, &v)
        }
        AnalyticCmd::Law(l) => {
            let law = l.spec.law()?;
            let mut v = json!({
                "law": serde_json::to_value(&law)?,
                "f_static": law.f_static(),
            });
            match law.f_dynamic() {
                Ok(fd) => {
                    v["f_dynamic"] = json!(fd);
                    v["w_over_p"] = json!(law.w_over_p()?);
                    v["delta"] = json!(law.delta().ok());
                }
                Err(e) => {
                    v["f_dynamic"] = Value::Null;
                    v["note"] = json!(e.to_string());
                }
            }
            if let Some(u) = l.u {
                v["u"] = json!(u);
                v["mu_u"] = json!(law.mu(u));
                v["dmu_du"] = json!(law.dmu_du(u));
            }
            print_json(out, &v)
        }
        AnalyticCmd::LawCurve(l) => {
            let law = l.spec.law()?;
            let u_max = match l.u_max {
                Some(u) if u.is_finite() && u > 0.0 => u,
                Some(u) => {
                    return Err(AnalyticError::NotPositive {
                        name: "u-max",
                        value: u,
                    }
                    .into());
                }
                None => match &law {
                    FrictionLaw::Table(t) => 1.5 * t.rows().last().map(|r| r[0]).unwrap_or(1.0),
                    _ => 3.0 * law.delta().unwrap_or(0.0),
                }
                .max(1e-12),
            };
            writeln!(out, "u,mu,dmu_du")?;
            let n = l.n.max(2);
            for i in 0..n {
                let u = u_max * i as f64 / (n - 1) as f64;
                writeln!(out, "{},{},{}", u, law.mu(u), csv_opt(law.dmu_du(u)))?;
            }
            Ok(())
        }
        AnalyticCmd::Presets => {
            let v: Vec<Value> = PRESETS
                .iter()
                .map(|p| {
                    json!({"name": p.0, "fs": p.1, "fd": p.2, "delta_um": p.3, "delta_mm": p.3 * 1e-3})
                })
                .collect();
            print_json(out, &json!(v))
        }
        AnalyticCmd::ImpliedLaw(i) => {
            let pts = implied_law_normalized(i.a_over_c, i.b_over_c, i.n)?;
            writeln!(out, "u_over_delta,f_norm")?;
            for p in pts {
                writeln!(out, "{},{}", p[0], p[1])?;
            }
            Ok(())
        }
        AnalyticCmd::Apparent(a) => {
            let p = apparent(a.chi, a.fs_over_fd, !a.no_dcm)?;
            print_json(out, &serde_json::to_value(p)?)
        }
        AnalyticCmd::ApparentCurve(a) => {
            let pts = apparent_curve(a.chi, a.ratio_max, a.n, a.dcm)?;
            writeln!(
                out,
                "fs_over_fd,q_max_jkr,c_max_jkr,s0_over_c,small_scale_ok,q_max_dcm,c_max_dcm,b_max_dcm"
            )?;
            for p in pts {
                writeln!(
                    out,
                    "{},{},{},{},{},{},{},{}",
                    p.fs_over_fd,
                    p.q_max_jkr,
                    p.c_max_jkr,
                    csv_opt(p.s0_over_c),
                    p.small_scale_ok,
                    csv_opt(p.q_max_dcm),
                    csv_opt(p.c_max_dcm),
                    csv_opt(p.b_max_dcm)
                )?;
            }
            Ok(())
        }
    }
}

fn run_dcm(d: &DcmArgs, out: &mut dyn Write) -> CliResult<()> {
    let h = d.geom.hertz()?;
    let m = DoubleCm::new(h, d.fs, d.fd)?;
    let q = d.force.force(d.fd, h.p_load);
    let weak = match (d.weak.delta, d.weak.lambda, d.weak.w) {
        (Some(x), _, _) => Weakening::SlipLength(x),
        (_, Some(l), _) => {
            Weakening::SlipLength(scales::delta_from_lambda(l, h.geom.r, d.fs, d.fd, h.a)?)
        }
        (_, _, Some(w)) => Weakening::Energy(w),
        _ => unreachable!("clap group is required"),
    };
    let st = m.solve(q, weak)?;
    let mut v = json!({
        "fs": d.fs, "fd": d.fd, "load": h.p_load, "a": h.a,
        "q": q, "q_over_fd_p": q / (d.fd * h.p_load),
        "c": st.c, "b": st.b, "c_over_a": st.c / h.a, "b_over_a": st.b / h.a,
        "w": st.w, "p_c": st.p_c,
    });
    if let Weakening::SlipLength(delta) = weak {
        v["delta"] = json!(delta);
        if d.fs > d.fd {
            v["lambda"] = json!(scales::lambda(h.geom.r, delta, d.fs, d.fd, h.a)?);
            let jkr = JkrCurve::new(Jkr::new(h, d.fs, d.fd, delta)?.psi())?;
            v["psi"] = json!(jkr.psi);
            v["jkr_c_over_a"] = json!(jkr.stick_half_width(q / (d.fd * h.p_load)).ok());
        }
    }
    v["cm_fd_c_over_a"] = json!(
        CattaneoMindlin::new(h, d.fd)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    v["cm_fs_c_over_a"] = json!(
        CattaneoMindlin::new(h, d.fs)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    print_json(out, &v)
}
