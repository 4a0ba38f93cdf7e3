//! Patches of the contact weakened at the start of a stage (`stages[i].weaken`): the slip μ
//! sees is raised on a stretch of the slave face, e.g. the nucleation patch of a rupture on a
//! long interface.

use serde::{Deserialize, Serialize};

use super::{CaseError, invalid};

/// `{"x": [x0, x1], "slip": s}`: at the start of the stage, every slave node with
/// `x0 ≤ x ≤ x1` has the slip μ sees raised to at least `s`, so that its friction coefficient is
/// at most the law's `μ(s)` (`f_d` once `s` is past the weakening). The total slip and the
/// displacements do not change. With `"history": "since_stick"` the raised slip is forgotten
/// once a node sticks, like any slip.
///
/// With `"speed": v` (dynamic stages only) the patch grows instead: at time `t` into the stage
/// it spans `x_c ± min(v t, (x1 − x0)/2)`, `x_c` its centre, and each time step weakens the
/// nodes it has reached by the step's end (a nucleation forced at a prescribed speed).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SlipPatch {
    /// The patch's extent along x, `[x0, x1]` with `x0 < x1`.
    pub x: [f64; 2],
    /// The accumulated slip the patch's nodes are raised to (≥ 0, length units of the mesh).
    pub slip: f64,
    /// The speed at which each end of the patch moves out from its centre (> 0, length per
    /// unit time); absent: the whole patch at once.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speed: Option<f64>,
}

impl SlipPatch {
    /// The patch's extent at time `t` into its stage (see [`SlipPatch`]).
    pub fn extent(&self, t: f64) -> [f64; 2] {
        let [x0, x1] = self.x;
        match self.speed {
            None => self.x,
            Some(v) => {
                let (c, half) = (0.5 * (x0 + x1), 0.5 * (x1 - x0));
                let r = (v * t).min(half);
                [c - r, c + r]
            }
        }
    }
}

/// Each patch of stage `stage`: finite ends in order, a finite slip ≥ 0, a speed > 0 only in a
/// dynamic stage; patches need a friction law.
pub(super) fn validate(
    path: &str,
    stage: usize,
    patches: &[SlipPatch],
    (has_friction, dynamic): (bool, bool),
) -> Result<(), CaseError> {
    for (i, p) in patches.iter().enumerate() {
        let key = |k: &str| format!("stages[{stage}].weaken[{i}].{k}");
        if !has_friction {
            return Err(invalid(
                path,
                key("slip"),
                format!("{}", p.slip),
                "needs a friction law (`contact.friction`): slip changes nothing without one",
            ));
        }
        let [x0, x1] = p.x;
        if !(x0.is_finite() && x1.is_finite() && x0 < x1) {
            return Err(invalid(
                path,
                key("x"),
                format!("[{x0}, {x1}]"),
                "must be two finite numbers [x0, x1] with x0 < x1",
            ));
        }
        if !(p.slip >= 0.0 && p.slip.is_finite()) {
            return Err(invalid(
                path,
                key("slip"),
                format!("{}", p.slip),
                "must be ≥ 0 and finite",
            ));
        }
        if let Some(v) = p.speed {
            if !dynamic {
                return Err(invalid(
                    path,
                    key("speed"),
                    format!("{v}"),
                    "a growing patch needs time: only a dynamic stage takes `speed`",
                ));
            }
            if !(v > 0.0 && v.is_finite()) {
                return Err(invalid(
                    path,
                    key("speed"),
                    format!("{v}"),
                    "must be > 0 and finite",
                ));
            }
        }
    }
    Ok(())
}

/// Raises the slip μ sees, `slip_mu`, of the slave nodes at abscissae `xs` to at least
/// `slip` within each `(extent, slip)` of `patches`. `Err(i)`: patch `i` holds no node (the
/// others are applied).
pub fn weaken(
    xs: &[f64],
    patches: impl IntoIterator<Item = ([f64; 2], f64)>,
    slip_mu: &mut [f64],
) -> Result<(), usize> {
    let mut empty = None;
    for (i, ([x0, x1], slip)) in patches.into_iter().enumerate() {
        let mut held = false;
        for (sj, &x) in slip_mu.iter_mut().zip(xs) {
            if x >= x0 && x <= x1 {
                *sj = sj.max(slip);
                held = true;
            }
        }
        if !held && empty.is_none() {
            empty = Some(i);
        }
    }
    empty.map_or(Ok(()), Err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patch_raises_the_slip_of_the_nodes_inside_it_and_a_patch_without_nodes_is_named() {
        let xs = [-2.0, -1.0, 0.0, 1.0, 2.0];
        let run = |patches: &[([f64; 2], f64)]| {
            let mut s = vec![0.0, 0.0, 5.0, 0.0, 0.0];
            let r = weaken(&xs, patches.iter().copied(), &mut s);
            (r, s)
        };
        assert_eq!(
            run(&[([-1.0, 0.5], 3.0)]),
            (Ok(()), vec![0.0, 3.0, 5.0, 0.0, 0.0])
        );
        assert_eq!(
            run(&[([-5.0, 5.0], 1.0), ([1.5, 2.5], 2.0)]),
            (Ok(()), vec![1.0, 1.0, 5.0, 1.0, 2.0])
        );
        assert_eq!(
            run(&[([0.1, 0.9], 1.0), ([-1.0, -1.0], 4.0)]),
            (Err(0), vec![0.0, 4.0, 5.0, 0.0, 0.0]),
            "an empty patch is named and the others are applied"
        );
    }

    #[test]
    fn a_growing_patch_spreads_from_its_centre_at_its_speed_and_stops_at_its_ends() {
        let p = SlipPatch {
            x: [-2.0, 4.0],
            slip: 1.0,
            speed: Some(0.5),
        };
        assert_eq!(p.extent(0.0), [1.0, 1.0]);
        assert_eq!(p.extent(2.0), [0.0, 2.0]);
        assert_eq!(p.extent(6.0), [-2.0, 4.0]);
        assert_eq!(p.extent(60.0), [-2.0, 4.0]);
        let whole = SlipPatch { speed: None, ..p };
        assert_eq!(whole.extent(0.0), [-2.0, 4.0]);
    }

    #[test]
    fn bad_patches_are_refused_naming_the_key() {
        let p = |a: f64, b: f64, s: f64| {
            vec![SlipPatch {
                x: [a, b],
                slip: s,
                speed: None,
            }]
        };
        let grow = |v: f64| {
            vec![SlipPatch {
                x: [0.0, 1.0],
                slip: 1.0,
                speed: Some(v),
            }]
        };
        let key = |r: Result<(), CaseError>| match r {
            Err(CaseError::Value { key, .. }) => key,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            key(validate("c", 2, &p(1.0, 0.0, 1.0), (true, false))),
            "stages[2].weaken[0].x"
        );
        assert_eq!(
            key(validate("c", 0, &p(0.0, 1.0, -1.0), (true, false))),
            "stages[0].weaken[0].slip"
        );
        assert_eq!(
            key(validate("c", 0, &p(0.0, f64::NAN, 1.0), (true, false))),
            "stages[0].weaken[0].x"
        );
        assert_eq!(
            key(validate("c", 1, &p(0.0, 1.0, 1.0), (false, false))),
            "stages[1].weaken[0].slip"
        );
        assert_eq!(
            key(validate("c", 1, &grow(1.0), (true, false))),
            "stages[1].weaken[0].speed"
        );
        assert_eq!(
            key(validate("c", 1, &grow(0.0), (true, true))),
            "stages[1].weaken[0].speed"
        );
        assert!(validate("c", 0, &p(0.0, 1.0, 0.0), (true, false)).is_ok());
        assert!(validate("c", 0, &grow(2.0), (true, true)).is_ok());
    }
}
