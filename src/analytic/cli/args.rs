//! The arguments of `stickslip analytic …`: one clap struct per subcommand and the groups of
//! flags they share. What each resolves to (the scene, the friction law, the force) is in
//! [`super::inputs`].

use clap::{Args, Subcommand, ValueEnum};
use std::path::PathBuf;

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
