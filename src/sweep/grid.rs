//! The rows of a sweep: the sweep file (explicit lists of laws and loads, or a grid whose
//! Cartesian product is the sweep) expanded into one (load, law) pair per row, in a documented
//! and stable order.

use crate::case::{Case, Control, FrictionSpec, Stage};
use crate::error::SweepError;
use serde::Deserialize;
use serde_json::json;
use std::path::Path;

/// The sweep file. Laws come from `friction` (an explicit list) or from `grid` (a product of
/// value lists), not both; loads from `stages` (whole stage lists) or from `grid.pilot_x`
/// (targets of the case's last stage), not both; absent: the case's own law or load.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Friction laws, each as a case's `contact.friction`.
    #[serde(default)]
    pub friction: Vec<FrictionSpec>,
    /// Loads, each a whole replacement of the case's `stages` (cycle groups included).
    #[serde(default)]
    pub stages: Vec<StageList>,
    /// Value lists whose Cartesian product is the sweep.
    #[serde(default)]
    pub grid: Option<Grid>,
}

/// A list of stages as in a case file, cycle groups expanded.
#[derive(Debug, Clone, Deserialize)]
#[serde(transparent)]
pub struct StageList(#[serde(deserialize_with = "crate::case::deserialize_stages")] pub Vec<Stage>);

/// A grid of laws (shape × f_s × f_d × Δ or Λ) and loads (the last stage's `pilot_x`). The keys
/// are spelled as in a case's `contact.friction` (`fs`, `fd`); `f_s` and `f_d`, the old spelling,
/// are read as those ([`deprecated_keys`] names them for a note), and messages name the key as
/// it was written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grid {
    /// Shapes of the slip-weakening law (ramp, step, exponential); default `["ramp"]`.
    pub shape: Option<Vec<String>>,
    /// Static coefficients f_s.
    pub fs: Option<Vec<f64>>,
    /// Dynamic coefficients f_d.
    pub fd: Option<Vec<f64>>,
    /// `fs` in its old spelling.
    #[serde(rename = "f_s")]
    pub fs_old: Option<Vec<f64>>,
    /// `fd` in its old spelling.
    #[serde(rename = "f_d")]
    pub fd_old: Option<Vec<f64>>,
    /// Slip lengths Δ, or the dimensionless Λ = R Δ / ((f_s − f_d) a²) with the Hertz
    /// semi-width `a` of `radius` and `load` (one of the two lists).
    pub delta: Option<Vec<f64>>,
    pub lambda: Option<Vec<f64>>,
    pub radius: Option<f64>,
    pub load: Option<f64>,
    /// Histories of the law (accumulated, since_stick); default `["accumulated"]`.
    pub history: Option<Vec<crate::friction::History>>,
    /// Targets of the case's last stage along x (force, displacement or slip), one load each.
    pub pilot_x: Option<Vec<Control>>,
}

/// The expanded sweep: loads (cases that differ in their stages only) and laws; row
/// `r = load × laws + law`.
pub struct Rows {
    pub loads: Vec<Case>,
    pub laws: Vec<FrictionSpec>,
}

impl Rows {
    pub fn len(&self) -> usize {
        self.loads.len() * self.laws.len().max(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Expands the sweep file `file` (read from `path`) against `case`. Laws are empty when the
/// case's own law is to be used.
pub fn expand(case: &Case, file: &SweepFile, path: &Path) -> Result<Rows, SweepError> {
    let bad = |key: &str, why: String| SweepError::Input {
        path: path.display().to_string(),
        key: key.to_string(),
        why,
    };
    let grid = file.grid.as_ref();
    let grid_laws = grid.is_some_and(|g| {
        g.shape.is_some()
            || g.fs.is_some()
            || g.fd.is_some()
            || g.fs_old.is_some()
            || g.fd_old.is_some()
            || g.delta.is_some()
            || g.lambda.is_some()
            || g.history.is_some()
    });
    if grid_laws && !file.friction.is_empty() {
        return Err(bad(
            "grid",
            "give laws either as `friction` (a list) or as `grid` values, not both".into(),
        ));
    }
    if grid.is_some_and(|g| g.pilot_x.is_some()) && !file.stages.is_empty() {
        return Err(bad(
            "grid.pilot_x",
            "give loads either as `stages` (lists) or as `grid.pilot_x` targets, not both".into(),
        ));
    }
    let laws = match grid.filter(|_| grid_laws) {
        Some(g) => grid_laws_of(g, &bad)?,
        None => file.friction.clone(),
    };
    let stage_lists: Vec<Vec<Stage>> = match grid.and_then(|g| g.pilot_x.as_ref()) {
        Some(targets) => {
            if targets.is_empty() {
                return Err(bad("grid.pilot_x", "is empty: nothing to sweep".into()));
            }
            targets
                .iter()
                .map(|t| {
                    let mut st = case.stages.clone();
                    if let Some(last) = st.last_mut() {
                        last.pilot_x = Some(*t);
                    }
                    st
                })
                .collect()
        }
        None => file.stages.iter().map(|s| s.0.clone()).collect(),
    };
    if laws.is_empty() && stage_lists.is_empty() {
        return Err(bad(
            "",
            "neither `friction` (laws), `stages` (loads) nor `grid` lists anything to sweep".into(),
        ));
    }
    // One case per load, each checked like a case file (ranges, pilot, slip control).
    let loads = if stage_lists.is_empty() {
        vec![case.clone()]
    } else {
        stage_lists
            .into_iter()
            .enumerate()
            .map(|(i, st)| {
                let mut c = case.clone();
                c.stages = st;
                c.validate(&format!("{}: load {i}", path.display()))
                    .map(|()| c)
                    .map_err(SweepError::Case)
            })
            .collect::<Result<Vec<_>, _>>()?
    };
    // Every law checked whole before anything is built (Δ from Λ scales with the pair's E*,
    // which does not change whether the law is valid).
    for (i, f) in laws.iter().enumerate() {
        f.resolve(1.0).map_err(|e| {
            bad(
                &format!("friction[{i}]"),
                format!("{e} (law {})", describe(f)),
            )
        })?;
    }
    Ok(Rows { loads, laws })
}

/// The laws of a grid, shape outermost, then f_s, f_d, Δ or Λ, and history fastest.
fn grid_laws_of(
    g: &Grid,
    bad: &dyn Fn(&str, String) -> SweepError,
) -> Result<Vec<FrictionSpec>, SweepError> {
    let list = |key: &str, v: &Option<Vec<f64>>| -> Result<Vec<f64>, SweepError> {
        match v {
            None => Err(bad(&format!("grid.{key}"), "is required".into())),
            Some(v) if v.is_empty() => Err(bad(
                &format!("grid.{key}"),
                "is empty: the grid has no point".into(),
            )),
            Some(v) => Ok(v.clone()),
        }
    };
    let shapes = g.shape.clone().unwrap_or_else(|| vec!["ramp".into()]);
    if shapes.is_empty() {
        return Err(bad("grid.shape", "is empty: the grid has no point".into()));
    }
    // Each coefficient in the spelling it was given (the old one read as the new).
    let spelled = |new: &'static str,
                   v: &Option<Vec<f64>>,
                   old: &'static str,
                   v_old: &Option<Vec<f64>>|
     -> Result<Vec<f64>, SweepError> {
        match (v, v_old) {
            (Some(_), Some(_)) => Err(bad(
                &format!("grid.{old}"),
                format!("give `{new}` or its old spelling `{old}`, not both"),
            )),
            (None, Some(_)) => list(old, v_old),
            _ => list(new, v),
        }
    };
    let f_s = spelled("fs", &g.fs, "f_s", &g.fs_old)?;
    let f_d = spelled("fd", &g.fd, "f_d", &g.fd_old)?;
    let (key, xs) = match (&g.delta, &g.lambda) {
        (Some(_), Some(_)) => {
            return Err(bad(
                "grid.lambda",
                "give `delta` or `lambda`, not both".into(),
            ));
        }
        (Some(_), None) => ("delta", list("delta", &g.delta)?),
        (None, Some(_)) => ("lambda", list("lambda", &g.lambda)?),
        (None, None) => return Err(bad("grid.delta", "`delta` or `lambda` is required".into())),
    };
    if key == "lambda" && (g.radius.is_none() || g.load.is_none()) {
        return Err(bad(
            "grid.radius",
            "a grid over `lambda` needs `radius` and `load` (the Hertz scale of Λ)".into(),
        ));
    }
    let histories = g
        .history
        .clone()
        .unwrap_or_else(|| vec![crate::friction::History::Accumulated]);
    if histories.is_empty() {
        return Err(bad(
            "grid.history",
            "is empty: the grid has no point".into(),
        ));
    }
    let mut laws = Vec::new();
    for s in &shapes {
        for &fs in &f_s {
            for &fd in &f_d {
                for &x in &xs {
                    for h in &histories {
                        let mut v = if key == "delta" {
                            json!({"shape": s, "fs": fs, "fd": fd, "delta": x})
                        } else {
                            json!({"shape": s, "fs": fs, "fd": fd, "lambda": x,
                                   "radius": g.radius, "load": g.load})
                        };
                        v["history"] = json!(h);
                        let spec: FrictionSpec = serde_json::from_value(v.clone())
                            .map_err(|e| bad("grid", format!("point {v}: {e}")))?;
                        laws.push(spec);
                    }
                }
            }
        }
    }
    Ok(laws)
}

/// Notes on the old spellings a sweep file `v` uses (`grid.f_s`, `friction[0].f_d`, …), each
/// naming the key and its spelling now; empty when it uses none.
pub fn deprecated_keys(v: &serde_json::Value) -> Vec<String> {
    let mut notes = Vec::new();
    let mut look = |at: String, o: &serde_json::Value| {
        for (old, new) in crate::case::OLD_SPELLINGS {
            if o.get(old).is_some() {
                notes.push(crate::case::old_spelling_note(&format!("{at}{old}"), new));
            }
        }
    };
    look("grid.".into(), &v["grid"]);
    if let Some(laws) = v["friction"].as_array() {
        for (i, law) in laws.iter().enumerate() {
            look(format!("friction[{i}]."), law);
        }
    }
    notes
}

/// A law as compact JSON, for messages.
fn describe(f: &FrictionSpec) -> String {
    serde_json::to_string(f).unwrap_or_default()
}
