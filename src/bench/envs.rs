//! `hgym bench envs`: control steps (actions) per second of each lattice-Boltzmann environment
//! family (2D and 3D) at the coarse and default levels, with the grid, the solver steps per
//! action and the solver rate behind them. Reset (and the one-time spin-up, cached) is not timed.
//!
//! 2D: the first ID of each family. 3D: every distinct grid and action (an ID whose flow set-up
//! or control interval differs from those timed before it), each after a spin-up of 1 L/U only:
//! a lattice-Boltzmann step costs the same whatever the flow's state, and the 3D spin-ups take
//! minutes to hours each.

use std::time::Instant;

use hgym_agents::Env;
use serde::{Deserialize, Serialize};

use crate::env::spec3::Env3Spec;
use crate::env::{registry, EnvSpec, Spec};
use crate::flow::{FlowSetup, Level};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EnvBenchRow {
    pub id: String,
    pub family: String,
    pub level: String,
    pub cells: usize,
    pub steps_per_action: u64,
    pub actions_per_s: f64,
    pub mlups: f64,
}

/// The flow set-up and control interval of a lattice-Boltzmann spec (2D or 3D).
fn lbm_flow(spec: &Spec) -> Option<(FlowSetup, f64)> {
    if let Some(s) = spec.downcast::<EnvSpec>() {
        return Some((s.flow_setup(), s.control_interval));
    }
    spec.downcast::<Env3Spec>().map(|s| (s.flow_setup(), s.control_interval))
}

/// The lattice-Boltzmann families `bench_envs` can time, sorted.
pub fn families() -> Vec<String> {
    let set: std::collections::BTreeSet<String> = registry::all()
        .into_iter()
        .filter(|s| lbm_flow(s).is_some())
        .map(|s| s.family().to_string())
        .collect();
    set.into_iter().collect()
}

/// Times `actions` alternating-sign actions on one ID per family in 2D (the first registered) and
/// on each distinct 3D grid (see the module documentation) at each level; `families` limits the
/// run to those families (all when empty; see [`families`]).
pub fn bench_envs(
    levels: &[Level],
    actions: usize,
    families: &[String],
    cache: Option<std::path::PathBuf>,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<EnvBenchRow>, hgym_agents::EnvError> {
    let mut seen = std::collections::BTreeSet::new();
    let mut rows = Vec::new();
    for spec in registry::all() {
        let Some((setup, interval)) = lbm_flow(&spec) else {
            continue;
        };
        let family = spec.family().to_string();
        if !families.is_empty() && !families.contains(&family) {
            continue;
        }
        let key = match spec.dimension() {
            3 => format!("{}:{}", setup.hash(), interval),
            _ => String::new(),
        };
        if !seen.insert((family.clone(), spec.dimension(), key)) {
            continue;
        }
        let spec = match spec.dimension() {
            3 => {
                let mut short = toml::Table::new();
                short.insert("spin_up".into(), toml::Value::Float(1.0));
                spec.with_overrides(&short)
                    .map_err(|e| hgym_agents::EnvError::InvalidSpec(format!("{}: {e}", spec.id())))?
            }
            _ => spec,
        };
        for &level in levels {
            let plan = setup
                .plan(level)
                .map_err(|e| hgym_agents::EnvError::InvalidSpec(format!("{}: {e}", spec.id())))?;
            let cells = plan.nx * plan.ny * plan.nz.unwrap_or(1);
            let steps_per_action = plan.units.steps(interval).max(1);
            let mut env = spec.make(level, cache.clone())?;
            progress(&format!("{} ({}): reset", spec.id(), level.name()));
            env.reset(0)?;
            let dim = spec.act_dim();
            let t = Instant::now();
            for k in 0..actions {
                let a = if k % 2 == 0 { 0.5 } else { -0.5 };
                let r = env.step(&vec![a; dim])?;
                if r.terminated || r.truncated {
                    env.reset(k as u64)?;
                }
            }
            let dt = t.elapsed().as_secs_f64();
            let row = EnvBenchRow {
                id: spec.id().to_string(),
                family: family.clone(),
                level: level.name().into(),
                cells,
                steps_per_action,
                actions_per_s: actions as f64 / dt,
                mlups: (cells as u64 * steps_per_action * actions as u64) as f64 / dt / 1e6,
            };
            progress(&format!("{} ({}): {:.1} actions/s", row.id, row.level, row.actions_per_s));
            rows.push(row);
        }
    }
    Ok(rows)
}

pub fn table(rows: &[EnvBenchRow]) -> String {
    let mut s = format!(
        "{:<30} {:<8} {:>9} {:>12} {:>10} {:>9} {:>8}\n",
        "ID", "level", "cells", "steps/action", "actions/s", "s/action", "MLUPS"
    );
    for r in rows {
        s += &format!(
            "{:<30} {:<8} {:>9} {:>12} {:>10.1} {:>9.3} {:>8.0}\n",
            r.id,
            r.level,
            r.cells,
            r.steps_per_action,
            r.actions_per_s,
            1.0 / r.actions_per_s,
            r.mlups
        );
    }
    s
}
