//! The case file: a JSON document that names the mesh, the bodies and their materials, the
//! supports, the rigid pilot, the loads, the load stages and the output.
//!
//! Parsing rejects unknown keys (serde names the key, line and column); [`Case::validate`]
//! then checks every value against its allowed range, naming the key, before anything is
//! allocated.

use serde::{Deserialize, Serialize};

mod dynamic;
mod friction_spec;
mod patches;
mod stages;

pub use dynamic::{DynamicSpec, MAX_TIME_STEPS, OnLostEquilibrium, RampShape, Until};
pub use friction_spec::{FrictionKind, FrictionSpec, OLD_SPELLINGS};
pub use patches::{SlipPatch, weaken};
use stages::StageItem;
pub(crate) use stages::deserialize_stages;
use std::path::{Path, PathBuf};

/// How the contact conditions are enforced.
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Semi-smooth Newton (primal–dual active set) on the complementarity functions: exact.
    Newton,
    /// Penalty: `F_n = ε max(0, −ĝ)`, tangential spring `ε`; `ε = κ E* w_j / h_j`.
    Penalty,
    /// Augmented Lagrangian: penalty with an outer multiplier update (Uzawa) until the largest
    /// penetration is below `tolerance × h`.
    AugmentedLagrangian,
}

/// A whole case.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Optional free text.
    #[serde(default)]
    pub title: String,
    /// Mesh file, relative to the case file.
    pub mesh: PathBuf,
    /// The bodies to model (surface groups) with their materials. Other surfaces of the mesh
    /// are left out.
    pub bodies: Vec<Body>,
    /// Prescribed displacements on curve groups (constant over the run).
    #[serde(default)]
    pub supports: Vec<Support>,
    /// The rigid pilot: a curve group whose nodes translate together without rotating.
    #[serde(default)]
    pub pilot: Option<Pilot>,
    /// Distributed loads on curve groups, scaled by each stage's `traction_scale`.
    #[serde(default)]
    pub tractions: Vec<TractionSpec>,
    /// Contact between two curve groups (frictionless unless `friction` is given).
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// Load stages, applied in order; each ramps linearly from the end of the previous one. An
    /// item may also be a group repeated `count` times, `{"cycles": {"count": N, "stages":
    /// [stage, …]}}` (fretting): it expands in place, each stage remembering its cycle.
    #[serde(deserialize_with = "deserialize_stages")]
    #[schemars(with = "Vec<StageItem>")]
    pub stages: Vec<Stage>,
    /// What to write.
    #[serde(default)]
    pub output: Output,
    /// When a force-controlled tangential load passes the peak: absent, the run stops there
    /// (exit 5); `{"dynamic": {...}}` integrates the jump in time ([`OnLostEquilibrium`]).
    #[serde(default)]
    pub on_lost_equilibrium: Option<OnLostEquilibrium>,
}

/// A body and its material.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Name of the surface physical group.
    pub group: String,
    /// Young's modulus E (> 0).
    #[serde(rename = "E")]
    pub e: f64,
    /// Poisson's ratio ν (−1 < ν < 0.5).
    pub nu: f64,
    /// Mass density ρ (> 0, mass per unit volume in the units of E and the mesh): required
    /// where the case integrates in time, unused otherwise.
    #[serde(default)]
    pub density: Option<f64>,
}

/// Prescribed displacement components on a curve group.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Support {
    pub group: String,
    /// Prescribed x displacement; absent = free.
    #[serde(default)]
    pub ux: Option<f64>,
    /// Prescribed y displacement; absent = free.
    #[serde(default)]
    pub uy: Option<f64>,
}

/// The rigid pilot face.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Pilot {
    pub group: String,
}

/// A contact pair.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Curve group carrying the multipliers (the mortar side).
    pub slave: String,
    /// Curve group it is projected onto.
    pub master: String,
    /// `newton` (semi-smooth Newton / primal–dual active set, default), `penalty` or
    /// `augmented_lagrangian`.
    #[serde(default = "default_method")]
    pub method: Method,
    /// Penalty factor κ: stiffness `κ E* w_j / h_j` per node (penalty and augmented
    /// Lagrangian; default 100).
    #[serde(default)]
    pub penalty: Option<f64>,
    /// Friction law of the accumulated slip; absent = frictionless. See [`FrictionSpec`].
    #[serde(default)]
    pub friction: Option<FrictionSpec>,
    /// Slave edges with an initial gap up to this value are contact candidates (default
    /// 0.5 % of the slave face's bounding-box diagonal; doubled automatically if the contact
    /// reaches the edge of the zone).
    #[serde(default)]
    pub candidate_gap: Option<f64>,
    /// `common` (default): gaps and forces along one normal for the pair, the slave normal at
    /// the first touch — the classical small-strain theory of two curved bodies; `local`: each
    /// slave point's own normal.
    #[serde(default)]
    pub normal: NormalKind,
    /// Newton iterations per step before the step is cut back (default 60).
    #[serde(default)]
    pub max_iterations: Option<usize>,
    /// Relative tolerance of the contact iteration: the largest force update over the largest
    /// force (default 1e-8).
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// How the contact normal is chosen.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NormalKind {
    #[default]
    Common,
    Local,
}

fn default_method() -> Method {
    Method::Newton
}

/// How one pilot component is driven at the end of a stage.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Control {
    /// Total force on the pilot in this direction (per unit thickness).
    Force(f64),
    /// Pilot displacement in this direction.
    Displacement(f64),
    /// `pilot_x` only, with frictional contact: the mean slip over the contact (the mortar-
    /// weighted mean of the nodes' slip increments, summed over steps, positive in the direction
    /// the pilot is pushed). The pilot force follows. Unlike force or displacement control it
    /// traces the softening branch past the peak tangential force, where both turn back.
    Slip(f64),
}

/// A distributed load on a curve group.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TractionSpec {
    pub group: String,
    /// `uniform` (with `tx`, `ty`), `pressure` (with `p`) or `hertz` (with `p0`, `a`, `x0`).
    pub kind: TractionKind,
    #[serde(default)]
    pub tx: Option<f64>,
    #[serde(default)]
    pub ty: Option<f64>,
    #[serde(default)]
    pub p: Option<f64>,
    #[serde(default)]
    pub p0: Option<f64>,
    #[serde(default)]
    pub a: Option<f64>,
    #[serde(default)]
    pub x0: Option<f64>,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TractionKind {
    Uniform,
    Pressure,
    Hertz,
}

/// A load stage.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Stage {
    /// The cycle (from 1) of a stage expanded from a cycle group; none otherwise.
    #[serde(skip)]
    #[schemars(skip)]
    pub cycle: Option<usize>,
    #[serde(default)]
    pub name: String,
    /// Number of load steps (≥ 1); absent in a dynamic stage, whose steps are its time steps.
    #[serde(default)]
    pub steps: usize,
    /// Pilot control at the end of the stage, per component; absent = as at the end of the
    /// previous stage (force 0 at the start).
    #[serde(default)]
    pub pilot_x: Option<Control>,
    #[serde(default)]
    pub pilot_y: Option<Control>,
    /// Multiplier of the `tractions` at the end of the stage; absent = as before (0 at the start).
    #[serde(default)]
    pub traction_scale: Option<f64>,
    /// Patches of the contact weakened at the start of the stage ([`SlipPatch`]), e.g. the
    /// nucleation patch of a rupture.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub weaken: Vec<SlipPatch>,
    /// Integrate this stage in time ([`DynamicSpec`]); its `steps` are then the time steps
    /// (`⌈duration/dt⌉`, not given in the file).
    #[serde(default)]
    pub dynamic: Option<DynamicSpec>,
}

/// Output settings.
#[derive(Clone, Debug, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output directory, relative to the current directory; default `out/<case name>`.
    #[serde(default)]
    pub dir: Option<PathBuf>,
    /// Write `.vtu` files and the `.pvd` series.
    #[serde(default = "yes")]
    pub vtu: bool,
    /// Write every n-th nominal step (the last step is always written). Steps land on the
    /// nominal loads of their stage whatever the cutbacks between them.
    #[serde(default = "one")]
    pub every: usize,
    /// Also write the sub-steps that cutbacks insert between two nominal steps. Default: off.
    #[serde(default)]
    pub substeps: bool,
    /// Write the contact table `contact_NNNN.csv` with each written step (with or without the
    /// `.vtu` files). Default: on.
    #[serde(default = "yes")]
    pub contact_csv: bool,
    /// Compress the arrays of the `.vtu` files (zlib, one block per array): smaller files,
    /// slower to write. Default: raw binary.
    #[serde(default)]
    pub compress: bool,
    /// Keep the energy balance of every step (`energy.csv`, `summary.json`'s `energy`): the
    /// work of the pilot, tractions and supports, the elastic energy and the frictional
    /// dissipation. Default: on for cases with a cycle group, off otherwise (it recovers the
    /// whole displacement field at every step).
    #[serde(default)]
    pub energy: Option<bool>,
}

fn yes() -> bool {
    true
}
fn one() -> usize {
    1
}

impl Default for Output {
    fn default() -> Self {
        Output {
            dir: None,
            vtu: true,
            every: 1,
            substeps: false,
            contact_csv: true,
            compress: false,
            energy: None,
        }
    }
}

/// A case that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("{path}: cannot read the case file: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{path}: {detail}")]
    Syntax { path: String, detail: String },
    #[error("{path}: `{key}` = {value}: {why}")]
    Value {
        path: String,
        key: String,
        value: String,
        why: String,
    },
}

/// Physical groups with the case keys that name them: (`contact.slave`, `lower_arc`), ….
pub type NamedGroups<'a> = Vec<(String, &'a str)>;

/// The note for a key written in its old spelling: `key` (with its path) is read as `new`.
pub fn old_spelling_note(key: &str, new: &str) -> String {
    format!(
        "`{key}` is the old spelling of `{new}`; it is read as `{new}` (rename it: the old \
         spelling may be refused in a later version)"
    )
}

/// Notes on the old spellings a case file `v` uses (`contact.friction.f_s`, …); empty when it
/// uses none.
pub fn deprecated_keys(v: &serde_json::Value) -> Vec<String> {
    let law = &v["contact"]["friction"];
    OLD_SPELLINGS
        .iter()
        .filter(|(old, _)| law.get(old).is_some())
        .map(|(old, new)| old_spelling_note(&format!("contact.friction.{old}"), new))
        .collect()
}

impl Case {
    /// The physical groups the case names, with the key that names each: the surfaces
    /// (`bodies[i].group`) and the curves (`supports[i].group`, `tractions[i].group`,
    /// `pilot.group`, `contact.slave`, `contact.master`, in that order), for messages that say
    /// which key names a group the mesh cannot give.
    pub fn named_groups(&self) -> (NamedGroups<'_>, NamedGroups<'_>) {
        let surfaces = self
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| (format!("bodies[{i}].group"), b.group.as_str()))
            .collect();
        let mut curves: Vec<(String, &str)> = self
            .supports
            .iter()
            .enumerate()
            .map(|(i, s)| (format!("supports[{i}].group"), s.group.as_str()))
            .collect();
        curves.extend(
            self.tractions
                .iter()
                .enumerate()
                .map(|(i, t)| (format!("tractions[{i}].group"), t.group.as_str())),
        );
        if let Some(p) = &self.pilot {
            curves.push(("pilot.group".into(), p.group.as_str()));
        }
        if let Some(c) = &self.contact {
            curves.push(("contact.slave".into(), c.slave.as_str()));
            curves.push(("contact.master".into(), c.master.as_str()));
        }
        (surfaces, curves)
    }

    /// Reads, parses and validates a case file.
    pub fn load(path: &Path) -> Result<Case, CaseError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Io {
            path: p.clone(),
            source,
        })?;
        let case: Case = serde_json::from_str(&text).map_err(|e| CaseError::Syntax {
            path: p.clone(),
            detail: e.to_string(),
        })?;
        case.validate(&p)?;
        Ok(case)
    }

    /// The mesh path resolved against the directory of the case file.
    pub fn mesh_path(&self, case_path: &Path) -> PathBuf {
        case_path
            .parent()
            .unwrap_or(Path::new("."))
            .join(&self.mesh)
    }

    /// Checks every value against its allowed range; the error names the key.
    pub fn validate(&self, path: &str) -> Result<(), CaseError> {
        self.validate_bodies(path)?;
        self.validate_supports(path)?;
        for (i, t) in self.tractions.iter().enumerate() {
            validate_traction(path, i, t)?;
        }
        self.validate_stages(path)?;
        self.validate_dynamics(path)?;
        if let Some(c) = &self.contact {
            validate_contact(path, c)?;
        }
        if self.output.every == 0 {
            return Err(invalid(
                path,
                "output.every".into(),
                "0".into(),
                "must be ≥ 1",
            ));
        }
        Ok(())
    }

    /// At least one body; E > 0, −1 < ν < 0.5 and no group listed twice.
    fn validate_bodies(&self, path: &str) -> Result<(), CaseError> {
        let bad = |key: String, value: String, why: &str| invalid(path, key, value, why);
        if self.bodies.is_empty() {
            return Err(bad(
                "bodies".into(),
                "[]".into(),
                "at least one body is needed",
            ));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if !(b.e > 0.0 && b.e.is_finite()) {
                return Err(bad(
                    format!("bodies[{i}].E"),
                    format!("{}", b.e),
                    "must be > 0 and finite",
                ));
            }
            if !(b.nu > -1.0 && b.nu < 0.5) {
                return Err(bad(
                    format!("bodies[{i}].nu"),
                    format!("{}", b.nu),
                    "must satisfy −1 < ν < 0.5",
                ));
            }
            if self.bodies[..i].iter().any(|o| o.group == b.group) {
                return Err(bad(
                    format!("bodies[{i}].group"),
                    b.group.clone(),
                    "body listed twice",
                ));
            }
        }
        Ok(())
    }

    /// Every support fixes `ux`, `uy` or both, to finite values.
    fn validate_supports(&self, path: &str) -> Result<(), CaseError> {
        for (i, s) in self.supports.iter().enumerate() {
            if s.ux.is_none() && s.uy.is_none() {
                return Err(invalid(
                    path,
                    format!("supports[{i}]"),
                    s.group.clone(),
                    "give `ux`, `uy` or both",
                ));
            }
            for (k, v) in [("ux", s.ux), ("uy", s.uy)] {
                if let Some(v) = v {
                    check_finite(path, format!("supports[{i}].{k}"), v)?;
                }
            }
        }
        Ok(())
    }

    /// At least one stage; step counts in range; pilot controls only with a `pilot`, finite, and
    /// slip control only on `pilot_x` of a frictional contact.
    fn validate_stages(&self, path: &str) -> Result<(), CaseError> {
        let bad = |key: String, value: String, why: &str| invalid(path, key, value, why);
        let finite = |key: String, v: f64| check_finite(path, key, v);
        if self.stages.is_empty() {
            return Err(bad(
                "stages".into(),
                "[]".into(),
                "at least one stage is needed",
            ));
        }
        for (i, s) in self.stages.iter().enumerate() {
            if s.dynamic.is_none() && (s.steps == 0 || s.steps > 100_000) {
                return Err(bad(
                    format!("stages[{i}].steps"),
                    format!("{}", s.steps),
                    "must be between 1 and 100000",
                ));
            }
            for (k, c) in [("pilot_x", s.pilot_x), ("pilot_y", s.pilot_y)] {
                if let Some(c) = c {
                    if self.pilot.is_none() {
                        return Err(bad(
                            format!("stages[{i}].{k}"),
                            format!("{c:?}"),
                            "there is no `pilot` in this case",
                        ));
                    }
                    let (Control::Force(v) | Control::Displacement(v) | Control::Slip(v)) = c;
                    finite(format!("stages[{i}].{k}"), v)?;
                    if let Control::Slip(_) = c {
                        let frictional = self
                            .contact
                            .as_ref()
                            .is_some_and(|ct| ct.friction.is_some());
                        if k != "pilot_x" || !frictional {
                            return Err(bad(
                                format!("stages[{i}].{k}"),
                                format!("{c:?}"),
                                "slip control drives `pilot_x` only, and needs a `contact` with `friction`",
                            ));
                        }
                    }
                }
            }
            if let Some(v) = s.traction_scale {
                finite(format!("stages[{i}].traction_scale"), v)?;
            }
            let frictional = self.contact.as_ref().is_some_and(|c| c.friction.is_some());
            patches::validate(path, i, &s.weaken, (frictional, s.dynamic.is_some()))?;
        }
        Ok(())
    }

    /// Whether the run keeps its energy balance (see [`Output::energy`]).
    pub fn tracks_energy(&self) -> bool {
        self.output
            .energy
            .unwrap_or_else(|| self.stages.iter().any(|s| s.cycle.is_some()))
    }

    /// Total number of load steps.
    pub fn total_steps(&self) -> usize {
        self.stages.iter().map(|s| s.steps).sum()
    }
}

/// The error for `key` = `value` in the case file at `path`, with the reason.
fn invalid(path: &str, key: String, value: String, why: &str) -> CaseError {
    CaseError::Value {
        path: path.into(),
        key,
        value,
        why: why.into(),
    }
}

/// `v` must be a finite number.
fn check_finite(path: &str, key: String, v: f64) -> Result<(), CaseError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(invalid(
            path,
            key,
            format!("{v}"),
            "must be a finite number",
        ))
    }
}

/// Traction `i` gives exactly the values its kind uses, finite, with a > 0 for `hertz`.
fn validate_traction(path: &str, i: usize, t: &TractionSpec) -> Result<(), CaseError> {
    let need = |k: &str, v: Option<f64>| -> Result<f64, CaseError> {
        let v = v.ok_or_else(|| {
            invalid(
                path,
                format!("tractions[{i}].{k}"),
                "missing".into(),
                "required for this kind",
            )
        })?;
        check_finite(path, format!("tractions[{i}].{k}"), v)?;
        Ok(v)
    };
    let forbid = |k: &str, v: Option<f64>| -> Result<(), CaseError> {
        match v {
            Some(x) => Err(invalid(
                path,
                format!("tractions[{i}].{k}"),
                format!("{x}"),
                "not used by this kind",
            )),
            None => Ok(()),
        }
    };
    match t.kind {
        TractionKind::Uniform => {
            need("tx", t.tx.or(Some(0.0)))?;
            need("ty", t.ty.or(Some(0.0)))?;
            for (k, v) in [("p", t.p), ("p0", t.p0), ("a", t.a), ("x0", t.x0)] {
                forbid(k, v)?;
            }
        }
        TractionKind::Pressure => {
            need("p", t.p)?;
            for (k, v) in [
                ("tx", t.tx),
                ("ty", t.ty),
                ("p0", t.p0),
                ("a", t.a),
                ("x0", t.x0),
            ] {
                forbid(k, v)?;
            }
        }
        TractionKind::Hertz => {
            need("p0", t.p0)?;
            let a = need("a", t.a)?;
            if a <= 0.0 {
                return Err(invalid(
                    path,
                    format!("tractions[{i}].a"),
                    format!("{a}"),
                    "must be > 0",
                ));
            }
            need("x0", t.x0.or(Some(0.0)))?;
            for (k, v) in [("tx", t.tx), ("ty", t.ty), ("p", t.p)] {
                forbid(k, v)?;
            }
        }
    }
    Ok(())
}

/// The contact: two different groups, positive finite numerical parameters, a friction law that
/// resolves, and an iteration limit in range.
fn validate_contact(path: &str, c: &ContactSpec) -> Result<(), CaseError> {
    let bad = |key: String, value: String, why: &str| invalid(path, key, value, why);
    if c.slave == c.master {
        return Err(bad(
            "contact.master".into(),
            c.master.clone(),
            "must differ from `contact.slave`",
        ));
    }
    for (k, v) in [
        ("penalty", c.penalty),
        ("candidate_gap", c.candidate_gap),
        ("tolerance", c.tolerance),
    ] {
        if let Some(v) = v
            && !(v > 0.0 && v.is_finite())
        {
            return Err(bad(
                format!("contact.{k}"),
                format!("{v}"),
                "must be > 0 and finite",
            ));
        }
    }
    // The friction law whole (preset, shape, f_s ≥ f_d, Λ data) before anything is
    // read or allocated; Δ from Λ scales with the pair's E*, which does not change
    // whether the law is valid, so any positive value serves here.
    if let Some(f) = &c.friction
        && let Err(why) = f.resolve(1.0)
    {
        return Err(bad(
            "contact.friction".into(),
            serde_json::to_string(f).unwrap_or_default(),
            &why.to_string(),
        ));
    }
    if let Some(n) = c.max_iterations
        && (n == 0 || n > 10_000)
    {
        return Err(bad(
            "contact.max_iterations".into(),
            format!("{n}"),
            "must be between 1 and 10000",
        ));
    }
    Ok(())
}

/// The JSON Schema of the case file (draft 2020-12), for editors and validators.
pub fn schema() -> serde_json::Value {
    serde_json::to_value(schemars::schema_for!(Case)).expect("a schema serialises")
}
