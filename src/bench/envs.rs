//! `hgym bench envs`: control steps (actions) per second of each environment family at the
//! coarse and default levels, with the solver rate behind them. Reset (and the one-time spin-up,
//! cached) is not timed.

use std::time::Instant;

use hgym_agents::Env;
use serde::{Deserialize, Serialize};

use crate::env::{registry, LbmEnv};
use crate::flow::Level;

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

/// The lattice-Boltzmann families `bench_envs` can time, sorted.
pub fn families() -> Vec<String> {
    let set: std::collections::BTreeSet<String> = registry::lbm_specs().into_iter().map(|s| s.family).collect();
    set.into_iter().collect()
}

/// Times `actions` random-sign actions on one ID per family at each level; `families` limits
/// the run to those families (all when empty; see [`families`]).
pub fn bench_envs(
    levels: &[Level],
    actions: usize,
    families: &[String],
    cache: Option<std::path::PathBuf>,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<EnvBenchRow>, hgym_agents::EnvError> {
    let mut seen = std::collections::BTreeSet::new();
    let mut rows = Vec::new();
    for spec in registry::lbm_specs() {
        if !families.is_empty() && !families.contains(&spec.family) {
            continue;
        }
        if !seen.insert(spec.family.clone()) {
            continue;
        }
        for &level in levels {
            let mut env = LbmEnv::new(spec.clone(), level, cache.clone())?;
            progress(&format!("{} ({}): reset", spec.id, level.name()));
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
            let s = env.solver();
            let cells = s.nx() * s.ny();
            let row = EnvBenchRow {
                id: spec.id.clone(),
                family: spec.family.clone(),
                level: level.name().into(),
                cells,
                steps_per_action: env.steps_per_action(),
                actions_per_s: actions as f64 / dt,
                mlups: (cells as u64 * env.steps_per_action() * actions as u64) as f64 / dt / 1e6,
            };
            progress(&format!("{} ({}): {:.1} actions/s", row.id, row.level, row.actions_per_s));
            rows.push(row);
        }
    }
    Ok(rows)
}

pub fn table(rows: &[EnvBenchRow]) -> String {
    let mut s = format!(
        "{:<26} {:<8} {:>9} {:>12} {:>10} {:>8}\n",
        "ID", "level", "cells", "steps/action", "actions/s", "MLUPS"
    );
    for r in rows {
        s += &format!(
            "{:<26} {:<8} {:>9} {:>12} {:>10.1} {:>8.0}\n",
            r.id, r.level, r.cells, r.steps_per_action, r.actions_per_s, r.mlups
        );
    }
    s
}
