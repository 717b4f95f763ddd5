//! Observation and action mappings between a source and a target environment, as data (the
//! `[mapping]` table of a protocol file, or any TOML file given to `--mapping`):
//!
//! ```toml
//! [mapping]
//! tolerance = 0.01            # probes match when they sit within this distance (in D)
//! [mapping.actions]           # target actuator = source actuator, "-" for the opposite sign
//! jet_front_top = "jet_pair"
//! jet_front_bottom = "-jet_pair"
//! ```
//!
//! Every source observation is read from the target observation of the same quantity at the same
//! position relative to the body (or, for observations known by index, of the same name, and
//! only between flows with as many observations).
//! Without `[mapping.actions]`, actuators of equal names drive each other; a target actuator with
//! no source stays at zero.

use std::collections::BTreeMap;

use hgym_agents::transplant::SpaceMap;
use serde::{Deserialize, Serialize};

use crate::env::layout::Layout;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MappingSpec {
    /// Largest distance, in body lengths, between a source probe and the target probe it reads.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Target actuator name -> source actuator name (prefixed `-` for the opposite sign).
    #[serde(default)]
    pub actions: BTreeMap<String, String>,
}

fn default_tolerance() -> f64 {
    0.01
}

impl Default for MappingSpec {
    fn default() -> Self {
        MappingSpec {
            tolerance: default_tolerance(),
            actions: BTreeMap::new(),
        }
    }
}

/// A mapping that cannot be made (always the user's input); the message names both layouts.
#[derive(Debug, thiserror::Error)]
#[error("{message}\n  source {source_id}: {source_layout}\n  target {target_id}: {target_layout}")]
pub struct MappingError {
    pub message: String,
    pub source_id: String,
    pub source_layout: String,
    pub target_id: String,
    pub target_layout: String,
}

/// The map from `source`'s layout onto `target`'s under `spec` (IDs name them in errors).
pub fn resolve(source: (&str, &Layout), target: (&str, &Layout), spec: &MappingSpec) -> Result<SpaceMap, MappingError> {
    let err = |message: String| MappingError {
        message,
        source_id: source.0.to_string(),
        source_layout: source.1.to_string(),
        target_id: target.0.to_string(),
        target_layout: target.1.to_string(),
    };
    let (src, dst) = (source.1, target.1);
    if !(spec.tolerance.is_finite() && spec.tolerance >= 0.0) {
        return Err(err(format!("[mapping] tolerance must be a distance >= 0, got {}", spec.tolerance)));
    }
    // Observations known by index mean the same thing only on flows of the same shape.
    let indexed = |l: &Layout| l.observations.iter().all(|c| c.at.is_none() && c.quantity.starts_with("obs"));
    if (indexed(src) || indexed(dst)) && src.observations.len() != dst.observations.len() {
        return Err(err(format!(
            "the observations are known only by index and the flows have {} and {} of them: nothing says which \
             source observation a target one is",
            src.observations.len(),
            dst.observations.len()
        )));
    }
    let obs = src
        .observations
        .iter()
        .map(|c| {
            let dist = |t: &crate::env::layout::Channel| match (c.at, t.at) {
                (Some(a), Some(b)) => Some(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()),
                (None, None) => Some(0.0),
                _ => None,
            };
            dst.observations
                .iter()
                .enumerate()
                .filter(|(_, t)| t.quantity == c.quantity)
                .filter_map(|(k, t)| dist(t).map(|d| (k, d)))
                .filter(|(_, d)| *d <= spec.tolerance)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(k, _)| k)
                .ok_or_else(|| {
                    err(match c.at {
                        Some(p) => format!(
                            "the source observes {} at ({}, {}) D from the body and the target has no such probe within {} D",
                            c.quantity, p[0], p[1], spec.tolerance
                        ),
                        None => format!("the source observes {} and the target has no observation of that name", c.quantity),
                    })
                })
        })
        .collect::<Result<Vec<usize>, _>>()?;
    let find = |names: &[String], n: &str| names.iter().position(|a| a == n);
    let act = if spec.actions.is_empty() {
        dst.actuators.iter().map(|a| find(&src.actuators, a).map(|j| (j, 1.0))).collect()
    } else {
        if let Some(k) = spec.actions.keys().find(|k| find(&dst.actuators, k).is_none()) {
            return Err(err(format!("[mapping.actions] names '{k}', which is not a target actuator")));
        }
        let mut act = vec![None; dst.actuators.len()];
        for (k, from) in &spec.actions {
            let (sign, name) = from.strip_prefix('-').map_or((1.0, from.as_str()), |n| (-1.0, n));
            let j = find(&src.actuators, name)
                .ok_or_else(|| err(format!("[mapping.actions] {k} = \"{from}\": '{name}' is not a source actuator")))?;
            if let Some(t) = find(&dst.actuators, k) {
                act[t] = Some((j, sign));
            }
        }
        act
    };
    let map = SpaceMap {
        target_obs_dim: dst.observations.len(),
        obs,
        source_act_dim: src.actuators.len(),
        act,
    };
    map.check().map_err(|m| {
        err(if map.act.iter().all(Option::is_none) {
            format!("{m}: no actuator names match; give [mapping.actions] (target = \"source\" or \"-source\")")
        } else {
            m
        })
    })?;
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::lookup;

    fn layout(id: &str) -> Layout {
        lookup(id).unwrap().layout()
    }

    #[test]
    fn same_family_maps_by_identity_and_square_needs_its_actions_named() {
        let c200 = layout("Cylinder_2D_Re200");
        let id = resolve(("a", &c200), ("b", &layout("Cylinder_2D_Re1000")), &MappingSpec::default()).unwrap();
        assert!(id.is_identity());
        let sq = layout("SquareCylinder_2D_Re200");
        let e = resolve(
            ("Cylinder_2D_Re200", &c200),
            ("SquareCylinder_2D_Re200", &sq),
            &MappingSpec::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("no actuator names match") && e.contains("jet_pair") && e.contains("jet_rear_top"),
            "{e}"
        );
        let spec: MappingSpec = toml::from_str("[actions]\njet_rear_top = \"jet_pair\"\njet_rear_bottom = \"-jet_pair\"\n").unwrap();
        let m = resolve(("a", &c200), ("b", &sq), &spec).unwrap();
        assert_eq!(m.act, vec![None, None, Some((0, 1.0)), Some((0, -1.0))]);
        assert_eq!(m.obs, (0..60).collect::<Vec<_>>());
        let bad: MappingSpec = toml::from_str("[actions]\njet_rear_top = \"jets\"\n").unwrap();
        assert!(resolve(("a", &c200), ("b", &sq), &bad)
            .unwrap_err()
            .to_string()
            .contains("'jets' is not a source actuator"));
    }

    #[test]
    fn probes_match_by_position_and_a_missing_one_is_named() {
        let c = layout("Cylinder_2D_Re200");
        let mut moved = c.clone();
        moved.observations.reverse();
        let m = resolve(("a", &c), ("b", &moved), &MappingSpec::default()).unwrap();
        // Reversed order: the source's first observation (u at the first probe) is the target's last.
        assert_eq!(m.obs[0], 59);
        let mut fewer = c.clone();
        fewer.observations.truncate(57);
        let e = resolve(("a", &c), ("b", &fewer), &MappingSpec::default()).unwrap_err().to_string();
        assert!(e.contains("u at (5, 1) D") && e.contains("19 probes"), "{e}");
        let k = layout("Kolmogorov_2D_Re40");
        assert!(resolve(("a", &c), ("b", &k), &MappingSpec::default()).is_err());
    }
}
