//! `stickslip analytic …`: the closed forms from the command line.
//!
//! Scalars are printed as pretty JSON, curves as CSV with a header row (the CSV writers are in
//! `cli_curves.rs`). Geometry defaults to VM272 (two cylinders of 8 mm, E = 200 N/mm², ν = 0.3,
//! P = 10 N/mm); every subcommand that needs it accepts `--r1 --r2 --e1 --nu1 --e2 --nu2 --load`,
//! and `--case CASE` takes the radii, moduli, load and friction law from a case file
//! ([`super::case_scene`]), each flag given as well overriding the case's value. See
//! `docs/analytic.md`.

use super::AnalyticError;
use super::apparent::apparent;
use super::case_scene::{CaseScene, SceneError};
use super::cattaneo::CattaneoMindlin;
use super::cli_curves;
use super::dcm::{DoubleCm, Weakening};
use super::hertz::{Geometry, Hertz, dundurs_beta};
use super::jkr::{Jkr, JkrCurve, k_ii};
use super::scales::{self, Scales, s0_over_c, small_scale_ok};
use crate::friction::{FrictionError, FrictionLaw, PRESETS, Shape};
use clap::{Args, Subcommand, ValueEnum};
use serde_json::{Value, json};
use std::io::Write;
use std::path::{Path, PathBuf};
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
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Usage(String),
    #[error("cannot write output: {0}")]
    Io(#[from] std::io::Error),
    #[error("JSON error: {0}")]
    Json(#[from] serde_json::Error),
}

/// Result of a subcommand runner.
pub(super) type CliResult<T> = std::result::Result<T, CliError>;

/// Geometry and normal load: VM272's, or a case's with `--case`; a flag given overrides either.
#[derive(Args, Debug, Clone)]
pub struct GeomArgs {
    /// Take the radii, moduli, normal load and friction law from a case file: body 1 holds
    /// `contact.slave`, body 2 `contact.master`; each radius is fitted to its face's nodes at
    /// the first touch; the load is the first `pilot_y` force of the stages.
    #[arg(long, value_name = "CASE")]
    pub case: Option<PathBuf>,
    /// Radius of body 1 (mm; `inf` for a flat) [default: 8, or the case's]
    #[arg(long)]
    pub r1: Option<f64>,
    /// Radius of body 2 (mm; `inf` for a flat) [default: 8, or the case's]
    #[arg(long)]
    pub r2: Option<f64>,
    /// Young's modulus of body 1 (N/mm²) [default: 200, or the case's]
    #[arg(long)]
    pub e1: Option<f64>,
    /// Poisson's ratio of body 1 [default: 0.3, or the case's]
    #[arg(long)]
    pub nu1: Option<f64>,
    /// Young's modulus of body 2 (N/mm²) [default: 200, or the case's]
    #[arg(long)]
    pub e2: Option<f64>,
    /// Poisson's ratio of body 2 [default: 0.3, or the case's]
    #[arg(long)]
    pub nu2: Option<f64>,
    /// Normal load P per unit thickness (N/mm) [default: 10, or the case's]
    #[arg(long)]
    pub load: Option<f64>,
}

/// The geometry and load a subcommand works on: the flags, else the case's (`--case`), else
/// VM272's.
#[derive(Debug, Clone)]
pub(super) struct Scene {
    pub r1: f64,
    pub r2: f64,
    pub e1: f64,
    pub nu1: f64,
    pub e2: f64,
    pub nu2: f64,
    pub load: f64,
    /// The case's scene, when `--case` was given.
    pub case: Option<CaseScene>,
}

impl GeomArgs {
    /// The scene: each value from its flag, else from the case, else VM272's.
    pub(super) fn scene(&self) -> CliResult<Scene> {
        let case = self.case.as_deref().map(CaseScene::load).transpose()?;
        let c = case.as_ref();
        let load = match (self.load, c) {
            (Some(p), _) => p,
            (None, Some(c)) => c.load.ok_or_else(|| {
                CliError::Usage(format!(
                    "--case {}: no stage gives `pilot_y` as a force, so the normal load is not \
                     known: give --load",
                    c.path.display()
                ))
            })?,
            (None, None) => 10.0,
        };
        Ok(Scene {
            r1: self.r1.or(c.map(|c| c.body1.r)).unwrap_or(8.0),
            r2: self.r2.or(c.map(|c| c.body2.r)).unwrap_or(8.0),
            e1: self.e1.or(c.map(|c| c.body1.e)).unwrap_or(200.0),
            nu1: self.nu1.or(c.map(|c| c.body1.nu)).unwrap_or(0.3),
            e2: self.e2.or(c.map(|c| c.body2.e)).unwrap_or(200.0),
            nu2: self.nu2.or(c.map(|c| c.body2.nu)).unwrap_or(0.3),
            load,
            case,
        })
    }
}

impl Scene {
    /// The Hertz solution of this geometry and load.
    pub(super) fn hertz(&self) -> CliResult<Hertz> {
        let g = Geometry::from_bodies(self.r1, self.r2, self.e1, self.nu1, self.e2, self.nu2)?;
        Ok(Hertz::new(g, self.load)?)
    }

    /// The case's friction law, if `--case` gave one.
    pub(super) fn law(&self) -> Option<&FrictionLaw> {
        self.case.as_ref().and_then(|c| c.law.as_ref())
    }

    /// f_s and f_d: the flags, else the case's law.
    pub(super) fn coefficients(&self, fs: Option<f64>, fd: Option<f64>) -> CliResult<(f64, f64)> {
        let law = self.law();
        let fs = fs.or(law.map(FrictionLaw::f_static));
        let fd = match fd {
            Some(fd) => Some(fd),
            None => law.map(FrictionLaw::f_dynamic).transpose()?,
        };
        match (fs, fd) {
            (Some(fs), Some(fd)) => Ok((fs, fd)),
            _ => Err(CliError::Usage(
                "--fs and --fd are required (or --case with a case that has a friction law)".into(),
            )),
        }
    }

    /// The slip length: `--delta`, else Δ from `--lambda`, else the case law's Δ.
    pub(super) fn delta(
        &self,
        delta: Option<f64>,
        lambda: Option<f64>,
        h: &Hertz,
        fs: f64,
        fd: f64,
    ) -> CliResult<f64> {
        match (delta, lambda, self.law()) {
            (Some(d), _, _) => {
                if !d.is_finite() || d < 0.0 {
                    return Err(AnalyticError::NegativeDelta { delta: d }.into());
                }
                Ok(d)
            }
            (_, Some(l), _) => Ok(scales::delta_from_lambda(l, h.geom.r, fs, fd, h.a)?),
            (None, None, Some(law)) => Ok(law.delta()?),
            (None, None, None) => Err(CliError::Usage(
                "--delta or --lambda is required (or --case with a case that has a friction law)"
                    .into(),
            )),
        }
    }

    /// `v` with the case's scene under `"scene"`, when `--case` was given.
    pub(super) fn annotate(&self, mut v: Value) -> Value {
        if let Some(c) = &self.case {
            v["scene"] = c.to_json();
        }
        v
    }
}

/// The dimensionless numbers of a case's scene (its Hertz a under its load, its law): Λ, χ, Ψ
/// and f_s/f_d, for the subcommands that take those rather than a geometry.
pub(super) fn case_scales(path: &Path) -> CliResult<(Scales, f64, f64, Value)> {
    let g = GeomArgs {
        case: Some(path.to_path_buf()),
        r1: None,
        r2: None,
        e1: None,
        nu1: None,
        e2: None,
        nu2: None,
        load: None,
    };
    let scene = g.scene()?;
    let h = scene.hertz()?;
    let (fs, fd) = scene.coefficients(None, None)?;
    let delta = scene.delta(None, None, &h, fs, fd)?;
    let sc = Scales::new(&h, fs, fd, delta)?;
    let v = scene.annotate(json!({}))["scene"].clone();
    Ok((sc, fs, fd, v))
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
    /// Q itself, or the ratio times `f p`.
    pub(super) fn force(&self, f: f64, p: f64) -> f64 {
        match (self.q, self.q_ratio) {
            (Some(q), _) => q,
            (_, Some(r)) => r * f * p,
            _ => unreachable!("clap group is required"),
        }
    }
}

/// Fracture energy W, slip length Δ or Λ (at most one; with `--case` and none, the case law's Δ).
#[derive(Args, Debug, Clone)]
#[group(required = false, multiple = false)]
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

/// Slip length Δ or Λ (at most one; with `--case` and neither, the case law's Δ).
#[derive(Args, Debug, Clone)]
#[group(required = false, multiple = false)]
pub struct LengthArgs {
    /// Slip length Δ (mm), eq. (Maugis10).
    #[arg(long)]
    pub delta: Option<f64>,
    /// Λ = RΔ/((f_s − f_d) a²), eq. (Lambda).
    #[arg(long)]
    pub lambda: Option<f64>,
}

#[derive(Args, Debug, Clone)]
pub struct CmArgs {
    /// Friction coefficient f [default with --case: the case's constant μ].
    #[arg(long)]
    pub mu: Option<f64>,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

#[derive(Args, Debug, Clone)]
pub struct AbruptArgs {
    /// Static coefficient f_s [default with --case: the case law's].
    #[arg(long)]
    pub fs: Option<f64>,
    /// Dynamic coefficient f_d [default with --case: the case law's].
    #[arg(long)]
    pub fd: Option<f64>,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

#[derive(Args, Debug, Clone)]
pub struct DcmArgs {
    /// Static coefficient f_s [default with --case: the case law's].
    #[arg(long)]
    pub fs: Option<f64>,
    /// Dynamic coefficient f_d [default with --case: the case law's].
    #[arg(long)]
    pub fd: Option<f64>,
    #[command(flatten)]
    pub weak: WeakArgs,
    #[command(flatten)]
    pub force: ForceArgs,
    #[command(flatten)]
    pub geom: GeomArgs,
}

/// Friction ratio for dimensionless curves (one of them, or `--case`).
#[derive(Args, Debug, Clone)]
#[group(required = false, multiple = false)]
pub struct RatioArgs {
    /// Ψ = (f_s/f_d − 1)² Λ; then f_s/f_d = 1 + sqrt(Ψ/Λ).
    #[arg(long)]
    pub psi: Option<f64>,
    /// f_s/f_d directly.
    #[arg(long)]
    pub fs_over_fd: Option<f64>,
}

/// `--case` for the subcommands that take dimensionless numbers (Λ, χ, Ψ, f_s/f_d): computed
/// from the case's scene (radii, moduli, load, law); a number given as well overrides.
#[derive(Args, Debug, Clone)]
pub struct CaseArg {
    /// Take Λ, χ, Ψ and f_s/f_d from a case file (its geometry, load and friction law).
    #[arg(long, value_name = "CASE")]
    pub case: Option<PathBuf>,
}

impl CaseArg {
    /// The case's scales, f_s, f_d and scene, when `--case` was given.
    pub(super) fn scales(&self) -> CliResult<Option<(Scales, f64, f64, Value)>> {
        self.case.as_deref().map(case_scales).transpose()
    }
}

/// `value`, else `from_case`, else a usage error naming `flag`.
pub(super) fn given_or_case(
    value: Option<f64>,
    from_case: Option<f64>,
    flag: &str,
) -> CliResult<f64> {
    value.or(from_case).ok_or_else(|| {
        CliError::Usage(format!(
            "{flag} is required (or --case with a slip-weakening law)"
        ))
    })
}

#[derive(Args, Debug, Clone)]
pub struct DcmCurveArgs {
    /// Λ = RΔ/((f_s − f_d) a²).
    #[arg(long)]
    pub lambda: Option<f64>,
    #[command(flatten)]
    pub ratio: RatioArgs,
    #[command(flatten)]
    pub case: CaseArg,
    /// Number of points (c/a uniform in [0, 1]).
    #[arg(long, default_value_t = 201)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct TractionArgs {
    /// Static coefficient f_s [default with --case: the case law's].
    #[arg(long)]
    pub fs: Option<f64>,
    /// Dynamic coefficient f_d [default with --case: the case law's].
    #[arg(long)]
    pub fd: Option<f64>,
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
    /// Ψ = (f_s/f_d − 1) RΔ/(f_d a²) [default with --case: the case's].
    #[arg(long)]
    pub psi: Option<f64>,
    /// Also give the stable c/a at this Q/(f_d P).
    #[arg(long)]
    pub q_ratio: Option<f64>,
    /// Also check the small-scale criterion at the maximum for this Λ [default with --case: the
    /// case's].
    #[arg(long)]
    pub lambda: Option<f64>,
    #[command(flatten)]
    pub case: CaseArg,
}

#[derive(Args, Debug, Clone)]
pub struct JkrCurveArgs {
    /// Ψ [default with --case: the case's].
    #[arg(long)]
    pub psi: Option<f64>,
    #[command(flatten)]
    pub case: CaseArg,
    /// Number of points (c/a uniform in [0, 1]).
    #[arg(long, default_value_t = 201)]
    pub n: usize,
}

#[derive(Args, Debug, Clone)]
pub struct ScalesArgs {
    /// Static coefficient f_s [default with --case: the case law's].
    #[arg(long)]
    pub fs: Option<f64>,
    /// Dynamic coefficient f_d [default with --case: the case law's].
    #[arg(long)]
    pub fd: Option<f64>,
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

/// A friction law: `--json`, `--preset`, `--shape` with coefficients, or `--case`.
#[derive(Args, Debug, Clone)]
pub struct LawSpec {
    /// The law as JSON, e.g. '{"shape":"ramp","fs":0.15,"fd":0.1,"delta":2.9e-4}'.
    #[arg(long, conflicts_with_all = ["preset", "shape", "case"])]
    pub json: Option<String>,
    /// The law of a case file's `contact.friction` (Δ from Λ with the pair's E*).
    #[arg(long, value_name = "CASE", conflicts_with_all = ["preset", "shape"])]
    pub case: Option<PathBuf>,
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
    /// The friction law from `--json`, `--preset` or `--shape` with its coefficients.
    pub(super) fn law(&self) -> CliResult<FrictionLaw> {
        if let Some(path) = &self.case {
            let scene = CaseScene::load(path)?;
            return scene.law.ok_or_else(|| {
                CliError::Usage(format!(
                    "--case {}: the case is frictionless (no `contact.friction`)",
                    path.display()
                ))
            });
        }
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
                "give the law with --json, --preset, --shape (+ --fs --fd --delta) or --case"
                    .into(),
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
    /// Which slip u is (as a case's `"history"`): the accumulated slip path, or the slip since
    /// the node last stuck (healing).
    #[arg(long, value_enum, default_value = "accumulated")]
    pub history: HistoryArg,
}

/// The `--history` of `law`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum HistoryArg {
    Accumulated,
    #[value(name = "since_stick", alias = "since-stick")]
    SinceStick,
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
    /// χ = RΔ/(f_d a²), eq. (chi) [default with --case: the case's].
    #[arg(long)]
    pub chi: Option<f64>,
    /// f_s/f_d [default with --case: the case law's].
    #[arg(long)]
    pub fs_over_fd: Option<f64>,
    #[command(flatten)]
    pub case: CaseArg,
    /// Skip the double C–M value.
    #[arg(long)]
    pub no_dcm: bool,
}

#[derive(Args, Debug, Clone)]
pub struct ApparentCurveArgs {
    /// χ = RΔ/(f_d a²), eq. (chi) [default with --case: the case's].
    #[arg(long)]
    pub chi: Option<f64>,
    #[command(flatten)]
    pub case: CaseArg,
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

/// Writes `v` as pretty JSON followed by a newline.
fn print_json(out: &mut dyn Write, v: &Value) -> CliResult<()> {
    serde_json::to_writer_pretty(&mut *out, v)?;
    writeln!(out)?;
    Ok(())
}

/// A CSV cell: the number, or empty for `None`.
pub(super) fn csv_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// Runs one `analytic` subcommand, writing JSON or CSV to `out`.
pub fn run(args: &AnalyticArgs, out: &mut dyn Write) -> Result<(), CliError> {
    match &args.cmd {
        AnalyticCmd::Hertz(g) => run_hertz(g, out),
        AnalyticCmd::Cm(c) => run_cm(c, out),
        AnalyticCmd::Abrupt(c) => run_abrupt(c, out),
        AnalyticCmd::Dcm(d) => run_dcm(d, out),
        AnalyticCmd::DcmCurve(d) => cli_curves::dcm_curve(d, out),
        AnalyticCmd::Traction(t) => cli_curves::traction(t, out),
        AnalyticCmd::Jkr(j) => run_jkr(j, out),
        AnalyticCmd::JkrCurve(j) => cli_curves::jkr_curve(j, out),
        AnalyticCmd::Scales(s) => run_scales(s, out),
        AnalyticCmd::Law(l) => run_law(l, out),
        AnalyticCmd::LawCurve(l) => cli_curves::law_curve(l, out),
        AnalyticCmd::Presets => run_presets(out),
        AnalyticCmd::ImpliedLaw(i) => cli_curves::implied_law(i, out),
        AnalyticCmd::Apparent(a) => run_apparent(a, out),
        AnalyticCmd::ApparentCurve(a) => cli_curves::apparent_curve(a, out),
    }
}

/// `hertz`: R, E*, a, p0 and Dundurs' β as JSON.
fn run_hertz(g: &GeomArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = g.scene()?;
    let h = sc.hertz()?;
    print_json(
        out,
        &sc.annotate(json!({
            "r_eff": h.geom.r, "e_star": h.geom.e_star, "load": h.p_load,
            "a": h.a, "p0": h.p0,
            "dundurs_beta": dundurs_beta(sc.e1, sc.nu1, sc.e2, sc.nu2),
        })),
    )
}

/// `cm`: the Cattaneo–Mindlin stick semi-width for constant f as JSON.
fn run_cm(c: &CmArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = c.geom.scene()?;
    let h = sc.hertz()?;
    let mu = match (c.mu, sc.law()) {
        (Some(mu), _) => mu,
        (None, Some(law)) => match law.f_dynamic() {
            Ok(fd) if fd == law.f_static() => fd,
            _ => {
                return Err(CliError::Usage(format!(
                    "the case's friction law is not constant (f_s = {}): --mu is required",
                    law.f_static()
                )));
            }
        },
        (None, None) => {
            return Err(CliError::Usage(
                "--mu is required (or --case with a case that has a friction law)".into(),
            ));
        }
    };
    let cm = CattaneoMindlin::new(h, mu)?;
    let q = c.force.force(mu, h.p_load);
    let cc = cm.stick_half_width(q)?;
    print_json(
        out,
        &sc.annotate(json!({
            "mu": mu, "q": q, "q_over_mu_p": q / (mu * h.p_load),
            "a": h.a, "p0": h.p0, "c": cc, "c_over_a": cc / h.a,
        })),
    )
}

/// `abrupt`: the abrupt static→dynamic transition (C–M with f = f_d) as JSON.
fn run_abrupt(c: &AbruptArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = c.geom.scene()?;
    let h = sc.hertz()?;
    let (fs, fd) = sc.coefficients(c.fs, c.fd)?;
    let cm = CattaneoMindlin::abrupt(h, fs, fd)?;
    let q = c.force.force(fd, h.p_load);
    let cc = cm.stick_half_width(q)?;
    print_json(
        out,
        &sc.annotate(json!({
            "fs": fs, "fd": fd, "q": q, "q_over_fd_p": q / (fd * h.p_load),
            "a": h.a, "c": cc, "c_over_a": cc / h.a,
            "note": "abrupt transition (Delta = 0): Cattaneo-Mindlin with f = f_d",
        })),
    )
}

/// `jkr`: the JKR maximum, optionally the stable c/a at a force and the small-scale check, as JSON.
fn run_jkr(j: &JkrArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = j.case.scales()?;
    let psi = given_or_case(j.psi, case.as_ref().map(|c| c.0.psi), "--psi")?;
    let lambda = j.lambda.or(case.as_ref().map(|c| c.0.lambda));
    let cur = JkrCurve::new(psi)?;
    let m = cur.maximum();
    let mut v = json!({
        "psi": psi, "q_max_ratio": m.q_ratio, "c_max_over_a": m.c_over_a,
    });
    if let Some((_, _, _, scene)) = &case {
        v["scene"] = scene.clone();
    }
    if let Some(q) = j.q_ratio {
        v["q_ratio"] = json!(q);
        v["c_over_a"] = json!(cur.stick_half_width(q)?);
    }
    if let Some(l) = lambda {
        super::non_negative("Lambda", l)?;
        let s = (m.c_over_a > 0.0).then(|| s0_over_c(l, m.c_over_a));
        v["lambda"] = json!(l);
        v["s0_over_c_at_max"] = json!(s);
        v["small_scale_ok"] = json!(s.is_some_and(small_scale_ok));
    }
    print_json(out, &v)
}

/// `scales`: the length scales as JSON, plus the values at a stick radius if `--c-over-a` is given.
fn run_scales(s: &ScalesArgs, out: &mut dyn Write) -> CliResult<()> {
    let scene = s.geom.scene()?;
    let h = scene.hertz()?;
    let (fs, fd) = scene.coefficients(s.fs, s.fd)?;
    let delta = scene.delta(s.len.delta, s.len.lambda, &h, fs, fd)?;
    let sc = Scales::new(&h, fs, fd, delta)?;
    let mut v = scene.annotate(serde_json::to_value(sc)?);
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
        let jkr = Jkr::new(h, fs, fd, delta)?;
        let pc = h.pressure(c);
        let s0c = scales::s0(h.geom.e_star, delta, fs, fd, pc)?;
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

/// `law`: a friction law with f_s, f_d, W/p and Δ, optionally f(u) and df/du at a slip, as JSON.
fn run_law(l: &LawArgs, out: &mut dyn Write) -> CliResult<()> {
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
    let weakens = law.f_dynamic().is_ok_and(|fd| fd < law.f_static());
    let (name, note) = match (l.history, weakens) {
        (_, false) => (
            "accumulated",
            "the law does not weaken: the history makes no difference".to_string(),
        ),
        (HistoryArg::Accumulated, true) => (
            "accumulated",
            "u is the total slip path of a point: weakening is permanent".to_string(),
        ),
        (HistoryArg::SinceStick, true) => (
            "since_stick",
            format!(
                "u is the slip since the point last stuck or was out of contact: a point that \
                 sticks regains f_s = {}; under monotonic loading the same as accumulated",
                law.f_static()
            ),
        ),
    };
    v["history"] = json!(name);
    v["history_note"] = json!(note);
    print_json(out, &v)
}

/// `presets`: the Table 1 presets as a JSON array.
fn run_presets(out: &mut dyn Write) -> CliResult<()> {
    let v: Vec<Value> = PRESETS
        .iter()
        .map(
            |p| json!({"name": p.0, "fs": p.1, "fd": p.2, "delta_um": p.3, "delta_mm": p.3 * 1e-3}),
        )
        .collect();
    print_json(out, &json!(v))
}

/// `apparent`: the apparent static friction for given χ and f_s/f_d as JSON.
fn run_apparent(a: &ApparentArgs, out: &mut dyn Write) -> CliResult<()> {
    let case = a.case.scales()?;
    let chi = given_or_case(a.chi, case.as_ref().map(|c| c.0.chi), "--chi")?;
    let ratio = given_or_case(
        a.fs_over_fd,
        case.as_ref().map(|c| c.1 / c.2),
        "--fs-over-fd",
    )?;
    let p = apparent(chi, ratio, !a.no_dcm)?;
    let mut v = serde_json::to_value(p)?;
    if let Some((_, _, _, scene)) = case {
        v["scene"] = scene;
    }
    print_json(out, &v)
}

/// `dcm`: the double Cattaneo–Mindlin state (c, b, W) with the JKR and C–M comparisons as JSON.
fn run_dcm(d: &DcmArgs, out: &mut dyn Write) -> CliResult<()> {
    let sc = d.geom.scene()?;
    let h = sc.hertz()?;
    let (fs, fd) = sc.coefficients(d.fs, d.fd)?;
    let m = DoubleCm::new(h, fs, fd)?;
    let q = d.force.force(fd, h.p_load);
    let weak = match (d.weak.w, d.weak.delta, d.weak.lambda, sc.law()) {
        (Some(w), _, _, _) => Weakening::Energy(w),
        (None, None, None, None) => {
            return Err(CliError::Usage(
                "--delta, --lambda or --w is required (or --case with a case that has a \
                 friction law)"
                    .into(),
            ));
        }
        _ => Weakening::SlipLength(sc.delta(d.weak.delta, d.weak.lambda, &h, fs, fd)?),
    };
    let st = m.solve(q, weak)?;
    let mut v = sc.annotate(json!({
        "fs": fs, "fd": fd, "load": h.p_load, "a": h.a,
        "q": q, "q_over_fd_p": q / (fd * h.p_load),
        "c": st.c, "b": st.b, "c_over_a": st.c / h.a, "b_over_a": st.b / h.a,
        "w": st.w, "p_c": st.p_c,
    }));
    if let Weakening::SlipLength(delta) = weak {
        v["delta"] = json!(delta);
        if fs > fd {
            v["lambda"] = json!(scales::lambda(h.geom.r, delta, fs, fd, h.a)?);
            let jkr = JkrCurve::new(Jkr::new(h, fs, fd, delta)?.psi())?;
            v["psi"] = json!(jkr.psi);
            v["jkr_c_over_a"] = json!(jkr.stick_half_width(q / (fd * h.p_load)).ok());
        }
    }
    v["cm_fd_c_over_a"] = json!(
        CattaneoMindlin::new(h, fd)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    v["cm_fs_c_over_a"] = json!(
        CattaneoMindlin::new(h, fs)?
            .stick_half_width(q)
            .ok()
            .map(|c| c / h.a)
    );
    print_json(out, &v)
}
