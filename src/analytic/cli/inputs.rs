//! What the flags of `stickslip analytic …` resolve to: the geometry and load ([`Scene`]), the
//! friction coefficients and slip length, the force, the friction law and the dimensionless
//! numbers of a case (`--case`); and the errors of the subcommands ([`CliError`]).

use super::args::{CaseArg, ForceArgs, GeomArgs, LawSpec, ShapeArg};
use crate::analytic::AnalyticError;
use crate::analytic::case_scene::{CaseScene, SceneError};
use crate::analytic::hertz::{Geometry, Hertz};
use crate::analytic::scales::{self, Scales};
use crate::friction::{FrictionError, FrictionLaw, Shape};
use serde_json::{Value, json};
use std::path::Path;
use thiserror::Error;

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
