//! The friction law of a case file as written (`contact.friction`): a law, a preset of the
//! paper's Table 1 or a shaped law with Δ from Λ, each with its slip history; resolved into a
//! [`crate::friction::FrictionLaw`] once the pair's E* is known.

use serde::{Deserialize, Serialize};

/// A friction law in a case file, one of:
/// * a law: `{"shape": "constant", "mu": 0.2}`, `{"shape": "ramp"|"step"|"exponential", "fs",
///   "fd", "delta"}` or `{"shape": "table", "rows": [[slip, mu], …]}`;
/// * a Rabinowicz pair of the paper's Table 1: `{"preset": "copper-mild-steel", "shape": "ramp"}`
///   (shape optional, default ramp; Δ in mm);
/// * a shaped law with Δ through the paper's Λ = R Δ/((f_s − f_d) a²):
///   `{"shape": "ramp", "fs", "fd", "lambda", "radius", "load"}` where `radius` is the effective
///   radius R and `load` the normal load P that set `a = sqrt(4PR/(πE*))` (E* of the pair);
///
/// each with an optional `"history": "accumulated" | "since_stick"` (see
/// [`crate::friction::History`]). `f_s` and `f_d`, the spelling sweep grids once used, are read
/// as `fs` and `fd` ([`OLD_SPELLINGS`]; [`crate::case::deprecated_keys`] names them for a note).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct FrictionSpec {
    #[serde(flatten)]
    pub kind: FrictionKind,
    #[serde(skip_serializing_if = "crate::friction::History::is_accumulated")]
    pub history: crate::friction::History,
}

/// The law part of a [`FrictionSpec`].
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum FrictionKind {
    Law(crate::friction::FrictionLaw),
    Preset {
        preset: String,
        shape: Option<String>,
    },
    Lambda {
        shape: String,
        fs: f64,
        fd: f64,
        lambda: f64,
        radius: f64,
        load: f64,
    },
}

/// Old spellings of friction keys, read as the new ones: (old, new).
pub const OLD_SPELLINGS: [(&str, &str); 2] = [("f_s", "fs"), ("f_d", "fd")];

impl<'de> Deserialize<'de> for FrictionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut v = serde_json::Value::deserialize(d)?;
        if let Some(o) = v.as_object_mut() {
            for (old, new) in OLD_SPELLINGS {
                if let Some(x) = o.remove(old) {
                    if o.contains_key(new) {
                        return Err(D::Error::custom(format!(
                            "friction: give `{new}` or its old spelling `{old}`, not both"
                        )));
                    }
                    o.insert(new.to_string(), x);
                }
            }
        }
        let history = match v.as_object_mut().and_then(|o| o.remove("history")) {
            None => crate::friction::History::Accumulated,
            Some(h) => serde_json::from_value(h.clone()).map_err(|_| {
                D::Error::custom(format!(
                    "friction: `history` = {h} is not one of \"accumulated\", \"since_stick\""
                ))
            })?,
        };
        let kind = FrictionKind::from_value(v).map_err(D::Error::custom)?;
        Ok(FrictionSpec { kind, history })
    }
}

impl FrictionKind {
    fn from_value(v: serde_json::Value) -> Result<Self, String> {
        fn err(s: impl std::fmt::Display) -> String {
            s.to_string()
        }
        let obj = v
            .as_object()
            .ok_or_else(|| err("a friction law must be an object"))?;
        let num = |k: &str| -> Result<f64, String> {
            obj.get(k)
                .and_then(|x| x.as_f64())
                .ok_or_else(|| err(format!("friction: `{k}` (a number) is required")))
        };
        if let Some(p) = obj.get("preset") {
            for k in obj.keys() {
                if k != "preset" && k != "shape" {
                    return Err(err(format!(
                        "friction: unknown field `{k}` with `preset` (expected `shape`)"
                    )));
                }
            }
            let preset = p
                .as_str()
                .ok_or_else(|| err("friction: `preset` must be a name"))?
                .to_string();
            let shape = obj.get("shape").and_then(|x| x.as_str()).map(String::from);
            return Ok(FrictionKind::Preset { preset, shape });
        }
        if obj.contains_key("lambda") {
            for k in obj.keys() {
                if !["shape", "fs", "fd", "lambda", "radius", "load"].contains(&k.as_str()) {
                    return Err(err(format!(
                        "friction: unknown field `{k}` with `lambda` (expected shape, fs, fd, lambda, radius, load)"
                    )));
                }
            }
            let shape = obj
                .get("shape")
                .and_then(|x| x.as_str())
                .ok_or_else(|| err("friction: `shape` is required"))?
                .to_string();
            return Ok(FrictionKind::Lambda {
                shape,
                fs: num("fs")?,
                fd: num("fd")?,
                lambda: num("lambda")?,
                radius: num("radius")?,
                load: num("load")?,
            });
        }
        serde_json::from_value::<crate::friction::FrictionLaw>(v)
            .map(FrictionKind::Law)
            .map_err(|e| err(format!("friction: {e}")))
    }
}

impl FrictionSpec {
    /// The law, with Δ from Λ resolved with the pair's composite modulus `e_star`.
    pub fn resolve(
        &self,
        e_star: f64,
    ) -> Result<crate::friction::FrictionLaw, crate::friction::FrictionError> {
        use crate::friction::{FrictionError, FrictionLaw, Shape};
        let shape = |s: &str| match s {
            "ramp" => Ok(Shape::Ramp),
            "step" => Ok(Shape::Step),
            "exponential" => Ok(Shape::Exponential),
            other => Err(FrictionError::UnknownShape {
                name: other.to_string(),
            }),
        };
        match &self.kind {
            FrictionKind::Law(l) => Ok(l.clone()),
            FrictionKind::Preset { preset, shape: s } => {
                FrictionLaw::preset_shaped(preset, shape(s.as_deref().unwrap_or("ramp"))?)
            }
            FrictionKind::Lambda {
                shape: s,
                fs,
                fd,
                lambda,
                radius,
                load,
            } => {
                for (k, v) in [("lambda", lambda), ("radius", radius), ("load", load)] {
                    if !(*v > 0.0 && v.is_finite()) {
                        return Err(FrictionError::NotPositive { name: k, value: *v });
                    }
                }
                let a2 = 4.0 * load * radius / (std::f64::consts::PI * e_star);
                let delta = lambda * (fs - fd) * a2 / radius;
                FrictionLaw::shaped(shape(s)?, *fs, *fd, delta)
            }
        }
    }
}

impl schemars::JsonSchema for FrictionSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "FrictionSpec".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let num = serde_json::json!({"type": "number"});
        let shaped = serde_json::json!({"enum": ["ramp", "step", "exponential"]});
        let history = serde_json::json!({"enum": ["accumulated", "since_stick"],
            "description": "Which slip μ is a function of: the total slip path (default), or the slip since the node last stuck (healing)."});
        schemars::json_schema!({
            "description": "A friction law of the accumulated slip: a law, a preset of the paper's Table 1, or a shaped law with Δ from Λ.",
            "oneOf": [
                {"type": "object", "additionalProperties": false, "required": ["shape", "mu"],
                 "properties": {"shape": {"const": "constant"}, "mu": num, "history": history}},
                {"type": "object", "additionalProperties": false, "required": ["shape", "fs", "fd", "delta"],
                 "properties": {"shape": shaped, "fs": num, "fd": num, "delta": num, "history": history}},
                {"type": "object", "additionalProperties": false, "required": ["shape", "rows"],
                 "properties": {"shape": {"const": "table"},
                                "rows": {"type": "array", "minItems": 2, "items": {"type": "array", "items": num, "minItems": 2, "maxItems": 2}},
                                "history": history}},
                {"type": "object", "additionalProperties": false, "required": ["preset"],
                 "properties": {"preset": {"enum": crate::friction::FrictionLaw::preset_names()}, "shape": shaped, "history": history}},
                {"type": "object", "additionalProperties": false, "required": ["shape", "fs", "fd", "lambda", "radius", "load"],
                 "properties": {"shape": shaped, "fs": num, "fd": num, "lambda": num, "radius": num, "load": num, "history": history}}
            ]
        })
    }
}
