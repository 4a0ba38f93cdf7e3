//! The `stages` list of a case file: stages, and cycle groups expanded in place.

use super::Stage;
use serde::Deserialize;

/// The largest cycle count of a group, and the most stages a case may expand to.
const MAX_CYCLES: usize = 10_000;
const MAX_STAGES: usize = 100_000;

/// An item of the `stages` list: a stage, or a group of stages repeated (for the schema; the
/// list is read by [`deserialize_stages`]).
#[derive(schemars::JsonSchema)]
#[allow(dead_code)]
#[serde(untagged)]
pub(super) enum StageItem {
    Stage(Stage),
    Cycles {
        /// A group of stages repeated `count` times.
        cycles: CycleGroup,
    },
}

/// A group of stages repeated `count` times (`count` ≥ 1, at least one stage, no nesting).
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub(super) struct CycleGroup {
    count: usize,
    stages: Vec<Stage>,
}

/// Reads the `stages` list, expanding cycle groups in place; a stage of cycle `k` (from 1)
/// carries `cycle = k`.
pub(crate) fn deserialize_stages<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Vec<Stage>, D::Error> {
    use serde::de::Error;
    let items = Vec::<serde_json::Value>::deserialize(d)?;
    let mut out = Vec::new();
    for (i, item) in items.into_iter().enumerate() {
        let group = item.as_object().and_then(|o| o.get("cycles")).cloned();
        match group {
            None => out.push(
                serde_json::from_value::<Stage>(item)
                    .map_err(|e| D::Error::custom(format!("stages[{i}]: {e}")))?,
            ),
            Some(g) => {
                if item.as_object().is_some_and(|o| o.len() > 1) {
                    return Err(D::Error::custom(format!(
                        "stages[{i}]: a cycle group is `{{\"cycles\": {{\"count\": N, \"stages\": [...]}}}}` with nothing beside `cycles`"
                    )));
                }
                if g.get("stages")
                    .and_then(|s| s.as_array())
                    .is_some_and(|s| s.iter().any(|x| x.get("cycles").is_some()))
                {
                    return Err(D::Error::custom(format!(
                        "stages[{i}].cycles.stages: cycle groups do not nest"
                    )));
                }
                let g: CycleGroup = serde_json::from_value(g)
                    .map_err(|e| D::Error::custom(format!("stages[{i}].cycles: {e}")))?;
                if g.count == 0 {
                    return Err(D::Error::custom(format!(
                        "stages[{i}].cycles.count must be at least 1"
                    )));
                }
                // Expanded before anything else is checked: bounded, so that a typo in the
                // count cannot exhaust the memory.
                if g.count > MAX_CYCLES || out.len() + g.count * g.stages.len() > MAX_STAGES {
                    return Err(D::Error::custom(format!(
                        "stages[{i}].cycles.count = {} is too large: at most {MAX_CYCLES} cycles and {MAX_STAGES} stages in all",
                        g.count
                    )));
                }
                if g.stages.is_empty() {
                    return Err(D::Error::custom(format!(
                        "stages[{i}].cycles.stages is empty: a cycle needs at least one stage"
                    )));
                }
                for k in 1..=g.count {
                    out.extend(g.stages.iter().cloned().map(|mut s| {
                        s.cycle = Some(k);
                        s
                    }));
                }
            }
        }
    }
    Ok(out)
}
