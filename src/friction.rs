//! Slip-weakening friction laws `f(u)` of the accumulated slip `u`.
//!
//! One implementation shared by the closed forms ([`crate::analytic`]) and the FE solver.
//! Every law starts at the static coefficient `f_s = f(0)` and (except an unsettled table)
//! ends at the dynamic coefficient `f_d = f(∞)`. Two integral measures of the paper are
//! available for every law:
//!
//! * `W/p = ∫₀^∞ (f(u) − f_d) du` — the fracture energy per unit pressure, eq. (Maugis);
//! * `Δ = W / ((f_s − f_d) p)` — the slip length of eq. (Maugis10).
//!
//! The parametric shapes are all defined so that `W/p = (f_s − f_d) Δ` holds **exactly** with
//! the `delta` parameter they carry (the convention of `docs/reference.md`):
//!
//! | shape | definition |
//! |---|---|
//! | `constant` | `f = mu` (no weakening, `Δ = 0`) |
//! | `ramp` | `f = f_s − (f_s − f_d) u / (2Δ)` for `u < 2Δ`, then `f_d` |
//! | `step` | `f = f_s` for `u ≤ Δ`, `f_d` for `u > Δ` |
//! | `exponential` | `f = f_d + (f_s − f_d) exp(−u/Δ)` (the decay length equals `Δ`) |
//! | `table` | rows `(slip, mu)` linearly interpolated, constant beyond both ends |
//!
//! Note the step convention `f(Δ) = f_s`: with `Δ = 0` any of the three parametric shapes gives
//! `f(0) = f_s` and `f(u > 0) = f_d`, i.e. the abrupt static→dynamic law of the paper's §3.
//! A negative slip argument is treated as `u = 0`.
//!
//! # Serialized form (case files)
//!
//! Internally tagged by `"shape"`, unknown fields rejected, values validated on load:
//!
//! ```json
//! {"shape":"constant","mu":0.2}
//! {"shape":"ramp","fs":0.15,"fd":0.1,"delta":2.9e-4}
//! {"shape":"step","fs":0.15,"fd":0.1,"delta":1.6e-3}
//! {"shape":"exponential","fs":0.15,"fd":0.1,"delta":1e-3}
//! {"shape":"table","rows":[[0.0,0.15],[5.8e-4,0.1]]}
//! ```
//!
//! Lengths are in the crate's length unit (millimetres for the VM272 model).

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Which slip a node's friction coefficient is a function of.
///
/// * `accumulated` (the default, the paper's model): the total slip path since the start of
///   the run. Weakening is permanent: a node that has slipped Δ stays at f_d, whatever happens
///   after, as for wear that polishes the asperities away for good.
/// * `since_stick`: the slip since the node last stuck (or was out of contact). A node that
///   sticks regains f_s, as in the slip-weakening laws of earthquake-rupture codes that heal
///   (the weakened state is a transient of sliding, not a property of the surface).
///
/// Under monotonic loading the two are the same: a node that slips keeps slipping.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum History {
    #[default]
    Accumulated,
    SinceStick,
}

impl History {
    pub fn is_accumulated(&self) -> bool {
        *self == History::Accumulated
    }

    /// The slip μ sees after a step: `prev + |Δv̂|` for a node that slipped; for one that
    /// stuck or opened, unchanged (accumulated) or zero (healed).
    pub fn advance(self, prev: f64, slipped: Option<f64>) -> f64 {
        match (slipped, self) {
            (Some(dv), _) => prev + dv.abs(),
            (None, History::Accumulated) => prev,
            (None, History::SinceStick) => 0.0,
        }
    }
}

/// Errors of friction-law construction and evaluation.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrictionError {
    /// A parameter is NaN or infinite.
    #[error("friction law parameter `{name}` must be finite, got {value}")]
    NotFinite { name: &'static str, value: f64 },
    /// A coefficient is negative.
    #[error("friction coefficient `{name}` must be non-negative, got {value}")]
    NegativeCoefficient { name: &'static str, value: f64 },
    /// The dynamic coefficient exceeds the static one (parametric shapes must weaken).
    #[error("dynamic friction coefficient f_d = {fd} exceeds static coefficient f_s = {fs}")]
    FdExceedsFs { fs: f64, fd: f64 },
    /// The slip length is negative.
    #[error("slip length delta must be non-negative, got {delta}")]
    NegativeDelta { delta: f64 },
    /// A shape name that is not one of the parametric shapes.
    #[error("shape `{name}` is not one of ramp, step, exponential")]
    UnknownShape { name: String },
    /// A parameter that must be positive (Λ, radius, load of a Λ-given law).
    #[error("`{name}` = {value} must be > 0")]
    NotPositive { name: &'static str, value: f64 },
    /// A table needs at least two rows.
    #[error("friction table needs at least 2 rows, got {rows}")]
    TooFewRows { rows: usize },
    /// A table row has a NaN/infinite entry.
    #[error("friction table row {row}: non-finite entry (slip = {slip}, mu = {mu})")]
    RowNotFinite { row: usize, slip: f64, mu: f64 },
    /// A table row has a negative slip.
    #[error("friction table row {row}: slip must be non-negative, got {slip}")]
    RowNegativeSlip { row: usize, slip: f64 },
    /// A table row has a negative coefficient.
    #[error("friction table row {row}: mu must be non-negative, got {mu}")]
    RowNegativeMu { row: usize, mu: f64 },
    /// Slip values in a table decrease.
    #[error("friction table row {row}: slip {slip} is smaller than the previous row's slip {prev}")]
    RowSlipDecreasing { row: usize, slip: f64, prev: f64 },
    /// More than two consecutive rows share one slip value.
    #[error(
        "friction table row {row}: slip {slip} already appears in the two previous rows (a jump takes exactly two rows)"
    )]
    RowTripleSlip { row: usize, slip: f64 },
    /// The table ends on a sloped segment, so `f_d` (and `W`, `Δ`) are undefined.
    #[error(
        "friction table does not settle: its last segment (rows {row_a}..{row_b}) still has slope {slope}; add a final flat segment at f_d"
    )]
    TableNotSettled {
        row_a: usize,
        row_b: usize,
        slope: f64,
    },
    /// `Δ` is undefined because the law does not weaken (`f_s ≤ f_d`) while `W ≠ 0`.
    #[error("slip length undefined: f_s = {fs} is not larger than f_d = {fd} but W/p = {w_over_p}")]
    NotWeakening { fs: f64, fd: f64, w_over_p: f64 },
    /// Unknown preset name.
    #[error("unknown friction preset `{name}`; known presets: {known}")]
    UnknownPreset { name: String, known: String },
}

/// Piecewise-linear tabulated friction coefficient, validated on construction.
///
/// Rules (checked by [`Table::new`], also when deserializing):
/// * at least **2** rows (a single value is a [`FrictionLaw::Constant`]);
/// * all entries finite, slip `≥ 0`, mu `≥ 0`;
/// * slip non-decreasing; two consecutive rows with equal slip define a jump (a third row with
///   the same slip is rejected). At the jump slip `mu` returns the first of the two values
///   (the left limit), so a table `[(0,fs),(Δ,fs),(Δ,fd)]` equals [`FrictionLaw::Step`].
///
/// Below the first slip and above the last slip `mu` is constant (first/last value).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TableRepr", into = "TableRepr")]
pub struct Table {
    slip: Vec<f64>,
    mu: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TableRepr {
    rows: Vec<[f64; 2]>,
}

impl TryFrom<TableRepr> for Table {
    type Error = FrictionError;
    fn try_from(r: TableRepr) -> Result<Self, Self::Error> {
        Table::new(&r.rows)
    }
}

impl From<Table> for TableRepr {
    fn from(t: Table) -> Self {
        TableRepr { rows: t.rows() }
    }
}

impl Table {
    /// Builds a table from `(slip, mu)` rows; see the type documentation for the rules.
    /// Row numbers in errors are 0-based.
    pub fn new(rows: &[[f64; 2]]) -> Result<Self, FrictionError> {
        if rows.len() < 2 {
            return Err(FrictionError::TooFewRows { rows: rows.len() });
        }
        for (i, &[s, m]) in rows.iter().enumerate() {
            if !s.is_finite() || !m.is_finite() {
                return Err(FrictionError::RowNotFinite {
                    row: i,
                    slip: s,
                    mu: m,
                });
            }
            if s < 0.0 {
                return Err(FrictionError::RowNegativeSlip { row: i, slip: s });
            }
            if m < 0.0 {
                return Err(FrictionError::RowNegativeMu { row: i, mu: m });
            }
            if i >= 1 && s < rows[i - 1][0] {
                return Err(FrictionError::RowSlipDecreasing {
                    row: i,
                    slip: s,
                    prev: rows[i - 1][0],
                });
            }
            if i >= 2 && s == rows[i - 1][0] && s == rows[i - 2][0] {
                return Err(FrictionError::RowTripleSlip { row: i, slip: s });
            }
        }
        Ok(Table {
            slip: rows.iter().map(|r| r[0]).collect(),
            mu: rows.iter().map(|r| r[1]).collect(),
        })
    }

    /// The rows as `(slip, mu)` pairs.
    pub fn rows(&self) -> Vec<[f64; 2]> {
        self.slip
            .iter()
            .zip(&self.mu)
            .map(|(&s, &m)| [s, m])
            .collect()
    }

    /// Linear interpolation, constant beyond the ends, left value at a jump.
    fn mu_at(&self, u: f64) -> f64 {
        let n = self.slip.len();
        if u <= self.slip[0] {
            return self.mu[0];
        }
        if u > self.slip[n - 1] {
            return self.mu[n - 1];
        }
        // first index with slip >= u (u > slip[0], so k >= 1)
        let k = self.slip.partition_point(|&s| s < u);
        let (s0, s1, m0, m1) = (self.slip[k - 1], self.slip[k], self.mu[k - 1], self.mu[k]);
        if s1 == s0 {
            m0
        } else {
            m0 + (m1 - m0) * (u - s0) / (s1 - s0)
        }
    }

    /// Right derivative; `None` exactly at a jump.
    fn dmu_at(&self, u: f64) -> Option<f64> {
        let n = self.slip.len();
        // a jump at u?
        for i in 0..n - 1 {
            if self.slip[i] == self.slip[i + 1] && self.slip[i] == u && self.mu[i] != self.mu[i + 1]
            {
                return None;
            }
        }
        if u < self.slip[0] || u >= self.slip[n - 1] {
            return Some(0.0);
        }
        // segment with slip[k-1] <= u < slip[k], non-degenerate
        let k = self.slip.partition_point(|&s| s <= u);
        let (s0, s1) = (self.slip[k - 1], self.slip[k]);
        Some((self.mu[k] - self.mu[k - 1]) / (s1 - s0))
    }

    /// `∫₀^{last slip} (mu − mu_last) du`, exact for the piecewise-linear table.
    fn excess_integral(&self, fd: f64) -> f64 {
        let mut w = self.slip[0] * (self.mu[0] - fd);
        for i in 0..self.slip.len() - 1 {
            let h = self.slip[i + 1] - self.slip[i];
            w += 0.5 * h * (self.mu[i] + self.mu[i + 1] - 2.0 * fd);
        }
        w
    }

    fn settled(&self) -> Result<f64, FrictionError> {
        let n = self.slip.len();
        let (s0, s1, m0, m1) = (
            self.slip[n - 2],
            self.slip[n - 1],
            self.mu[n - 2],
            self.mu[n - 1],
        );
        if s1 > s0 && m1 != m0 {
            return Err(FrictionError::TableNotSettled {
                row_a: n - 2,
                row_b: n - 1,
                slope: (m1 - m0) / (s1 - s0),
            });
        }
        Ok(m1)
    }
}

/// A friction coefficient as a function of accumulated slip. See the module docs for the
/// definitions and the JSON form. Construct through the checked constructors
/// ([`FrictionLaw::ramp`] …) or deserialization; both validate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "LawRepr", into = "LawRepr")]
pub enum FrictionLaw {
    /// Coulomb friction, `f = mu`.
    Constant { mu: f64 },
    /// Linear decrease from `fs` to `fd` over a slip of `2·delta`.
    Ramp { fs: f64, fd: f64, delta: f64 },
    /// `fs` up to slip `delta` (inclusive), `fd` beyond.
    Step { fs: f64, fd: f64, delta: f64 },
    /// `fd + (fs − fd) exp(−u/delta)`.
    Exponential { fs: f64, fd: f64, delta: f64 },
    /// Tabulated `(slip, mu)` rows.
    Table(Table),
}

#[derive(Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
enum LawRepr {
    Constant { mu: f64 },
    Ramp { fs: f64, fd: f64, delta: f64 },
    Step { fs: f64, fd: f64, delta: f64 },
    Exponential { fs: f64, fd: f64, delta: f64 },
    Table { rows: Vec<[f64; 2]> },
}

impl TryFrom<LawRepr> for FrictionLaw {
    type Error = FrictionError;
    fn try_from(r: LawRepr) -> Result<Self, Self::Error> {
        match r {
            LawRepr::Constant { mu } => FrictionLaw::constant(mu),
            LawRepr::Ramp { fs, fd, delta } => FrictionLaw::ramp(fs, fd, delta),
            LawRepr::Step { fs, fd, delta } => FrictionLaw::step(fs, fd, delta),
            LawRepr::Exponential { fs, fd, delta } => FrictionLaw::exponential(fs, fd, delta),
            LawRepr::Table { rows } => Ok(FrictionLaw::Table(Table::new(&rows)?)),
        }
    }
}

impl From<FrictionLaw> for LawRepr {
    fn from(l: FrictionLaw) -> Self {
        match l {
            FrictionLaw::Constant { mu } => LawRepr::Constant { mu },
            FrictionLaw::Ramp { fs, fd, delta } => LawRepr::Ramp { fs, fd, delta },
            FrictionLaw::Step { fs, fd, delta } => LawRepr::Step { fs, fd, delta },
            FrictionLaw::Exponential { fs, fd, delta } => LawRepr::Exponential { fs, fd, delta },
            FrictionLaw::Table(t) => LawRepr::Table { rows: t.rows() },
        }
    }
}

/// Parametric shape used to turn a `(f_s, f_d, Δ)` triple (e.g. a preset) into a law.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Ramp,
    Step,
    Exponential,
}

/// Rabinowicz's metal pairs, paper Table 1: `(name, f_s, f_d, Δ in µm)`.
/// Names are `first-second` in the paper's order (material order matters in the table).
pub const PRESETS: [(&str, f64, f64, f64); 5] = [
    ("copper-mild-steel", 0.46, 0.31, 1.0),
    ("lead-mild-steel", 0.72, 0.47, 3.0),
    ("mild-steel-copper", 0.54, 0.39, 0.9),
    ("mild-steel-titanium", 0.63, 0.45, 6.0),
    ("mild-steel-zinc", 0.65, 0.47, 2.0),
];

fn check_finite(name: &'static str, value: f64) -> Result<(), FrictionError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(FrictionError::NotFinite { name, value })
    }
}

fn check_weakening(fs: f64, fd: f64, delta: f64) -> Result<(), FrictionError> {
    check_finite("fs", fs)?;
    check_finite("fd", fd)?;
    check_finite("delta", delta)?;
    if fd < 0.0 {
        return Err(FrictionError::NegativeCoefficient {
            name: "fd",
            value: fd,
        });
    }
    if fs < 0.0 {
        return Err(FrictionError::NegativeCoefficient {
            name: "fs",
            value: fs,
        });
    }
    if fd > fs {
        return Err(FrictionError::FdExceedsFs { fs, fd });
    }
    if delta < 0.0 {
        return Err(FrictionError::NegativeDelta { delta });
    }
    Ok(())
}

impl FrictionLaw {
    /// Coulomb law `f = mu`, `mu ≥ 0`.
    pub fn constant(mu: f64) -> Result<Self, FrictionError> {
        check_finite("mu", mu)?;
        if mu < 0.0 {
            return Err(FrictionError::NegativeCoefficient {
                name: "mu",
                value: mu,
            });
        }
        Ok(FrictionLaw::Constant { mu })
    }
    /// Ramp law (requires `fs ≥ fd ≥ 0`, `delta ≥ 0`).
    pub fn ramp(fs: f64, fd: f64, delta: f64) -> Result<Self, FrictionError> {
        check_weakening(fs, fd, delta)?;
        Ok(FrictionLaw::Ramp { fs, fd, delta })
    }
    /// Step law (requires `fs ≥ fd ≥ 0`, `delta ≥ 0`).
    pub fn step(fs: f64, fd: f64, delta: f64) -> Result<Self, FrictionError> {
        check_weakening(fs, fd, delta)?;
        Ok(FrictionLaw::Step { fs, fd, delta })
    }
    /// Exponential law (requires `fs ≥ fd ≥ 0`, `delta ≥ 0`).
    pub fn exponential(fs: f64, fd: f64, delta: f64) -> Result<Self, FrictionError> {
        check_weakening(fs, fd, delta)?;
        Ok(FrictionLaw::Exponential { fs, fd, delta })
    }
    /// Tabulated law from `(slip, mu)` rows.
    pub fn table(rows: &[[f64; 2]]) -> Result<Self, FrictionError> {
        Ok(FrictionLaw::Table(Table::new(rows)?))
    }
    /// Parametric law of the given shape.
    pub fn shaped(shape: Shape, fs: f64, fd: f64, delta: f64) -> Result<Self, FrictionError> {
        match shape {
            Shape::Ramp => Self::ramp(fs, fd, delta),
            Shape::Step => Self::step(fs, fd, delta),
            Shape::Exponential => Self::exponential(fs, fd, delta),
        }
    }

    /// Names accepted by [`FrictionLaw::preset`].
    pub fn preset_names() -> Vec<&'static str> {
        PRESETS.iter().map(|p| p.0).collect()
    }

    /// A Table 1 metal pair as a **ramp** law, `Δ` converted from µm to mm (the crate's unit).
    /// Table 1 gives only `f_s, f_d, Δ`; use [`FrictionLaw::preset_shaped`] for another shape.
    pub fn preset(name: &str) -> Result<Self, FrictionError> {
        Self::preset_shaped(name, Shape::Ramp)
    }

    /// A Table 1 metal pair with the chosen shape (`Δ` in mm).
    pub fn preset_shaped(name: &str, shape: Shape) -> Result<Self, FrictionError> {
        let p =
            PRESETS
                .iter()
                .find(|p| p.0 == name)
                .ok_or_else(|| FrictionError::UnknownPreset {
                    name: name.to_string(),
                    known: Self::preset_names().join(", "),
                })?;
        Self::shaped(shape, p.1, p.2, p.3 * 1e-3)
    }

    /// Checks the invariants (useful after constructing a variant by hand).
    pub fn validate(&self) -> Result<(), FrictionError> {
        FrictionLaw::try_from(LawRepr::from(self.clone())).map(|_| ())
    }

    /// Friction coefficient at accumulated slip `u` (`u < 0` is treated as 0).
    pub fn mu(&self, u: f64) -> f64 {
        let u = u.max(0.0);
        match *self {
            FrictionLaw::Constant { mu } => mu,
            FrictionLaw::Ramp { fs, fd, delta } => {
                if u == 0.0 {
                    fs
                } else if u >= 2.0 * delta {
                    fd
                } else {
                    fs - (fs - fd) * u / (2.0 * delta)
                }
            }
            FrictionLaw::Step { fs, fd, delta } => {
                if u <= delta {
                    fs
                } else {
                    fd
                }
            }
            FrictionLaw::Exponential { fs, fd, delta } => {
                if u == 0.0 {
                    fs
                } else if delta == 0.0 {
                    fd
                } else {
                    fd + (fs - fd) * (-u / delta).exp()
                }
            }
            FrictionLaw::Table(ref t) => t.mu_at(u),
        }
    }

    /// Derivative `df/du` at `u`: the **right** derivative at kinks (ramp end, table nodes),
    /// `None` where the law jumps (step at `u = Δ`, a zero-length ramp/exponential at `u = 0`,
    /// a table jump). `u < 0` is treated as 0.
    pub fn dmu_du(&self, u: f64) -> Option<f64> {
        let u = u.max(0.0);
        match *self {
            FrictionLaw::Constant { .. } => Some(0.0),
            FrictionLaw::Ramp { fs, fd, delta } => {
                if delta == 0.0 {
                    if u == 0.0 && fs != fd {
                        None
                    } else {
                        Some(0.0)
                    }
                } else if u < 2.0 * delta {
                    Some(-(fs - fd) / (2.0 * delta))
                } else {
                    Some(0.0)
                }
            }
            FrictionLaw::Step { fs, fd, delta } => {
                if u == delta && fs != fd {
                    None
                } else {
                    Some(0.0)
                }
            }
            FrictionLaw::Exponential { fs, fd, delta } => {
                if delta == 0.0 {
                    if u == 0.0 && fs != fd {
                        None
                    } else {
                        Some(0.0)
                    }
                } else {
                    Some(-(fs - fd) / delta * (-u / delta).exp())
                }
            }
            FrictionLaw::Table(ref t) => t.dmu_at(u),
        }
    }

    /// Static coefficient `f_s = f(0)`.
    pub fn f_static(&self) -> f64 {
        self.mu(0.0)
    }

    /// The largest coefficient over all slips, `max_u f(u)`: `f_s` for the parametric shapes
    /// (`f_s ≥ f_d` or not), the largest tabulated value for a table (piecewise linear, so its
    /// maximum is at a row).
    pub fn mu_max(&self) -> f64 {
        match *self {
            FrictionLaw::Constant { mu } => mu,
            FrictionLaw::Ramp { fs, fd, .. }
            | FrictionLaw::Step { fs, fd, .. }
            | FrictionLaw::Exponential { fs, fd, .. } => fs.max(fd),
            FrictionLaw::Table(ref t) => t.rows().iter().map(|r| r[1]).fold(f64::MIN, f64::max),
        }
    }

    /// Dynamic coefficient `f_d = lim f(u)`, u → ∞. Errors for a table whose last segment is
    /// still sloped ([`FrictionError::TableNotSettled`]).
    pub fn f_dynamic(&self) -> Result<f64, FrictionError> {
        match *self {
            FrictionLaw::Constant { mu } => Ok(mu),
            FrictionLaw::Ramp { fd, .. }
            | FrictionLaw::Step { fd, .. }
            | FrictionLaw::Exponential { fd, .. } => Ok(fd),
            FrictionLaw::Table(ref t) => t.settled(),
        }
    }

    /// `W/p = ∫₀^∞ (f(u) − f_d) du`, eq. (Maugis) divided by the (uniform) pressure.
    /// Exact for every shape (`(f_s − f_d) Δ` for the parametric ones, the trapezoid sum for a
    /// table, which is exact for piecewise-linear data).
    pub fn w_over_p(&self) -> Result<f64, FrictionError> {
        match *self {
            FrictionLaw::Constant { .. } => Ok(0.0),
            FrictionLaw::Ramp { fs, fd, delta }
            | FrictionLaw::Step { fs, fd, delta }
            | FrictionLaw::Exponential { fs, fd, delta } => Ok((fs - fd) * delta),
            FrictionLaw::Table(ref t) => {
                let fd = t.settled()?;
                Ok(t.excess_integral(fd))
            }
        }
    }

    /// Slip length `Δ = (W/p) / (f_s − f_d)`, eq. (Maugis10). `0` for a constant law and for
    /// any law with `W = 0`; an error when `W ≠ 0` but `f_s ≤ f_d` or the table does not settle.
    pub fn delta(&self) -> Result<f64, FrictionError> {
        match *self {
            FrictionLaw::Constant { .. } => Ok(0.0),
            FrictionLaw::Ramp { delta, .. }
            | FrictionLaw::Step { delta, .. }
            | FrictionLaw::Exponential { delta, .. } => Ok(delta),
            FrictionLaw::Table(_) => {
                let w = self.w_over_p()?;
                let (fs, fd) = (self.f_static(), self.f_dynamic()?);
                if w == 0.0 {
                    Ok(0.0)
                } else if fs > fd {
                    Ok(w / (fs - fd))
                } else {
                    Err(FrictionError::NotWeakening {
                        fs,
                        fd,
                        w_over_p: w,
                    })
                }
            }
        }
    }

    /// Tabulates the law as `(slip, mu)` rows (exact for ramp/step/table, sampled with `n`
    /// points up to `10 Δ` for the exponential). Useful for FE input and plotting.
    pub fn to_rows(&self, n: usize) -> Vec<[f64; 2]> {
        match *self {
            FrictionLaw::Constant { mu } => vec![[0.0, mu], [1.0, mu]],
            FrictionLaw::Ramp { fs, fd, delta } => vec![[0.0, fs], [2.0 * delta, fd]],
            FrictionLaw::Step { fs, fd, delta } => vec![[0.0, fs], [delta, fs], [delta, fd]],
            FrictionLaw::Exponential { fd, delta, .. } => {
                let n = n.max(2);
                (0..n)
                    .map(|i| {
                        let u = 10.0 * delta * i as f64 / (n - 1) as f64;
                        [u, self.mu(u)]
                    })
                    .chain(std::iter::once([10.0 * delta, fd]))
                    .collect()
            }
            FrictionLaw::Table(ref t) => t.rows(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_roundtrip_and_unknown_fields() {
        let l: FrictionLaw =
            serde_json::from_str(r#"{"shape":"ramp","fs":0.15,"fd":0.1,"delta":2.9e-4}"#).unwrap();
        assert_eq!(
            l,
            FrictionLaw::Ramp {
                fs: 0.15,
                fd: 0.1,
                delta: 2.9e-4
            }
        );
        let s = serde_json::to_string(&l).unwrap();
        assert!(s.contains("\"shape\":\"ramp\""));
        assert!(
            serde_json::from_str::<FrictionLaw>(
                r#"{"shape":"ramp","fs":0.15,"fd":0.1,"delta":1,"x":1}"#
            )
            .is_err()
        );
        let t: FrictionLaw =
            serde_json::from_str(r#"{"shape":"table","rows":[[0,0.15],[1e-3,0.1]]}"#).unwrap();
        assert!(matches!(t, FrictionLaw::Table(_)));
        let e =
            serde_json::from_str::<FrictionLaw>(r#"{"shape":"table","rows":[[0,0.15],[-1,0.1]]}"#)
                .unwrap_err()
                .to_string();
        assert!(e.contains("row 1"), "{e}");
        assert!(
            serde_json::from_str::<FrictionLaw>(r#"{"shape":"step","fs":0.1,"fd":0.15,"delta":1}"#)
                .is_err()
        );
    }
}
