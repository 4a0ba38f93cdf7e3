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
        cycles: CycleGroupSchema,
    },
}

/// A group of stages repeated `count` times (`1 ≤ count ≤ 10000`, at least one stage, no
/// nesting); for the schema.
#[derive(schemars::JsonSchema)]
#[allow(dead_code)]
#[serde(deny_unknown_fields)]
pub(super) struct CycleGroupSchema {
    count: usize,
    stages: Vec<Stage>,
}

/// A group of stages repeated `count` times, as read.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CycleGroup {
    count: usize,
    stages: Vec<RawStage>,
}

/// An item of the `stages` list as read straight from the file (so that serde's errors keep
/// their line and column): a stage's keys, or `cycles` alone.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStage {
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    steps: Option<usize>,
    #[serde(default)]
    pilot_x: Option<super::Control>,
    #[serde(default)]
    pilot_y: Option<super::Control>,
    #[serde(default)]
    traction_scale: Option<f64>,
    #[serde(default)]
    weaken: Vec<super::SlipPatch>,
    #[serde(default)]
    dynamic: Option<super::DynamicSpec>,
    #[serde(default)]
    cycles: Option<CycleGroup>,
}

impl RawStage {
    /// The stage of a plain item (`at`: its key path, for messages).
    fn stage(self, at: &str) -> Result<Stage, String> {
        if self.cycles.is_some() {
            return Err(format!(
                "{at}: a cycle group is `{{\"cycles\": {{\"count\": N, \"stages\": [...]}}}}` with nothing beside `cycles`"
            ));
        }
        let steps = match (&self.dynamic, self.steps) {
            (Some(_), Some(_)) => {
                return Err(format!(
                    "{at}: a dynamic stage takes its steps from `dynamic.duration` and `dynamic.dt`; remove `steps`"
                ));
            }
            (Some(d), None) => d.steps_and_dt().0,
            (None, s) => s.ok_or_else(|| format!("{at}: missing field `steps`"))?,
        };
        Ok(Stage {
            cycle: None,
            name: self.name.unwrap_or_default(),
            steps,
            pilot_x: self.pilot_x,
            pilot_y: self.pilot_y,
            traction_scale: self.traction_scale,
            weaken: self.weaken,
            dynamic: self.dynamic,
        })
    }

    fn is_bare_group(&self) -> bool {
        self.name.is_none()
            && self.steps.is_none()
            && self.pilot_x.is_none()
            && self.pilot_y.is_none()
            && self.traction_scale.is_none()
            && self.weaken.is_empty()
            && self.dynamic.is_none()
    }
}

/// Reads the `stages` list, expanding cycle groups in place; a stage of cycle `k` (from 1)
/// carries `cycle = k`.
pub(crate) fn deserialize_stages<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Vec<Stage>, D::Error> {
    use serde::de::Error;
    let items = Vec::<RawStage>::deserialize(d)?;
    expand(items).map_err(D::Error::custom)
}

fn expand(items: Vec<RawStage>) -> Result<Vec<Stage>, String> {
    let mut out = Vec::new();
    for (i, item) in items.into_iter().enumerate() {
        let at = format!("stages[{i}]");
        if item.cycles.is_none() || !item.is_bare_group() {
            out.push(item.stage(&at)?);
            continue;
        }
        let g = item.cycles.expect("checked");
        if g.count == 0 {
            return Err(format!("{at}.cycles.count must be at least 1"));
        }
        if g.stages.is_empty() {
            return Err(format!(
                "{at}.cycles.stages is empty: a cycle needs at least one stage"
            ));
        }
        // Bounded, so that a typo in the count cannot exhaust the memory.
        if g.count > MAX_CYCLES || out.len() + g.count * g.stages.len() > MAX_STAGES {
            return Err(format!(
                "{at}.cycles.count = {} is too large: at most {MAX_CYCLES} cycles and {MAX_STAGES} stages in all",
                g.count
            ));
        }
        let mut group = Vec::with_capacity(g.stages.len());
        for (k, s) in g.stages.into_iter().enumerate() {
            if s.cycles.is_some() {
                return Err(format!("{at}.cycles.stages[{k}]: cycle groups do not nest"));
            }
            group.push(s.stage(&format!("{at}.cycles.stages[{k}]"))?);
        }
        for k in 1..=g.count {
            out.extend(group.iter().cloned().map(|mut s| {
                s.cycle = Some(k);
                s
            }));
        }
    }
    Ok(out)
}
