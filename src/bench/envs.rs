//! `hgym bench envs`: control steps (actions) per second of each lattice-Boltzmann environment
//! family (2D and 3D) and of the Kolmogorov flow at the coarse and default levels, with the grid,
//! the solver steps per action, the solver rate behind them, and the share of an action's time
//! spent outside the solver's steps (actuation, gusts, probes, forces, observation, reward,
//! info), read from the environment's [`SolverClock`](crate::env::clock::SolverClock). Reset (and
//! the one-time spin-up, cached) is not timed.
//!
//! 2D: the first ID of each family. 3D: every distinct grid and action (an ID whose flow set-up
//! or control interval differs from those timed before it), each after a spin-up of 1 L/U only:
//! a lattice-Boltzmann step costs the same whatever the flow's state, and the 3D spin-ups take
//! minutes to hours each.

use std::time::Instant;

use hgym_agents::Env;
use serde::{Deserialize, Serialize};

use crate::env::kolmogorov::KolmogorovSpec;
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
    /// Million grid-node updates per second (lattice nodes, or spectral grid points).
    pub mlups: f64,
    /// Fraction of the actions' time spent outside the solver's steps.
    #[serde(default)]
    pub outside_share: f64,
}

/// Largest share of a 2D action's time at coarse allowed outside the solver's steps.
pub const OUTSIDE_SHARE_TARGET: f64 = 0.05;

impl EnvBenchRow {
    /// Whether the row is judged against [`OUTSIDE_SHARE_TARGET`] (2D IDs at coarse).
    pub fn judged(&self) -> bool {
        self.level == Level::Coarse.name() && !self.id.contains("_3D_")
    }

    /// Whether the row is judged and spends [`OUTSIDE_SHARE_TARGET`] or more outside the solver.
    pub fn over_target(&self) -> bool {
        self.judged() && self.outside_share >= OUTSIDE_SHARE_TARGET
    }
}

/// The flow set-up and control interval of a lattice-Boltzmann spec (2D or 3D).
fn lbm_flow(spec: &Spec) -> Option<(FlowSetup, f64)> {
    if let Some(s) = spec.downcast::<EnvSpec>() {
        return Some((s.flow_setup(), s.control_interval));
    }
    spec.downcast::<Env3Spec>().map(|s| (s.flow_setup(), s.control_interval))
}

/// The grid nodes and solver steps per action of a spec `bench_envs` can time at `level`, and
/// the key that tells its 3D grids apart; `None` for the others.
fn grid(spec: &Spec, level: Level) -> Option<Result<(usize, u64, String), String>> {
    if let Some(k) = spec.downcast::<KolmogorovSpec>() {
        let n = k.n(level);
        let steps = (k.control_interval / k.dt(level)).round().max(1.0) as u64;
        return Some(Ok((n * n, steps, String::new())));
    }
    let (setup, interval) = lbm_flow(spec)?;
    let key = match spec.dimension() {
        3 => format!("{}:{}", setup.hash(), interval),
        _ => String::new(),
    };
    Some(setup.plan(level).map_err(|e| e.to_string()).map(|plan| {
        let cells = plan.nx * plan.ny * plan.nz.unwrap_or(1);
        (cells, plan.units.steps(interval).max(1), key)
    }))
}

/// The families `bench_envs` can time, sorted.
pub fn families() -> Vec<String> {
    let set: std::collections::BTreeSet<String> = registry::all()
        .into_iter()
        .filter(|s| grid(s, Level::Coarse).is_some())
        .map(|s| s.family().to_string())
        .collect();
    set.into_iter().collect()
}

/// What `bench_envs` times.
#[derive(Clone, Debug)]
pub struct EnvBenchOptions {
    pub levels: Vec<Level>,
    /// Actions timed per ID and level.
    pub actions: usize,
    /// Only these families (all when empty; see [`families`]).
    pub families: Vec<String>,
    /// Only IDs of this dimension (2 or 3; all when `None`).
    pub dimension: Option<u8>,
    /// Where developed flows are cached.
    pub cache: Option<std::path::PathBuf>,
}

/// Times `actions` alternating-sign actions on one ID per family in 2D (the first registered) and
/// on each distinct 3D grid (see the module documentation) at each level.
pub fn bench_envs(opts: &EnvBenchOptions, progress: &mut dyn FnMut(&str)) -> Result<Vec<EnvBenchRow>, hgym_agents::EnvError> {
    let EnvBenchOptions {
        levels,
        actions,
        families,
        dimension,
        cache,
    } = opts;
    let actions = *actions;
    let mut seen = std::collections::BTreeSet::new();
    let mut rows = Vec::new();
    for spec in registry::all() {
        let family = spec.family().to_string();
        if (!families.is_empty() && !families.contains(&family)) || dimension.is_some_and(|d| d != spec.dimension()) {
            continue;
        }
        let Some(first) = grid(&spec, Level::Coarse) else {
            continue;
        };
        let id = spec.id().to_string();
        let invalid = |e: String| hgym_agents::EnvError::InvalidSpec(format!("{id}: {e}"));
        let (_, _, key) = first.map_err(invalid)?;
        if !seen.insert((family.clone(), spec.dimension(), key)) {
            continue;
        }
        let spec = match spec.dimension() {
            3 => {
                let mut short = toml::Table::new();
                short.insert("spin_up".into(), toml::Value::Float(1.0));
                spec.with_overrides(&short).map_err(|e| invalid(e.to_string()))?
            }
            _ => spec,
        };
        for &level in levels {
            let Some(Ok((cells, steps_per_action, _))) = grid(&spec, level) else {
                return Err(invalid(format!("no grid at {}", level.name())));
            };
            let mut env = spec.make(level, cache.clone())?;
            progress(&format!("{} ({}): reset", spec.id(), level.name()));
            env.reset(0)?;
            let dim = spec.act_dim();
            let (mut stepping, solver0) = (0.0, env.solver_seconds());
            for k in 0..actions {
                let a = if k % 2 == 0 { 0.5 } else { -0.5 };
                let t = Instant::now();
                let r = env.step(&vec![a; dim])?;
                stepping += t.elapsed().as_secs_f64();
                if r.terminated || r.truncated {
                    env.reset(k as u64)?;
                }
            }
            let solver = env.solver_seconds() - solver0;
            let row = EnvBenchRow {
                id: spec.id().to_string(),
                family: family.clone(),
                level: level.name().into(),
                cells,
                steps_per_action,
                actions_per_s: actions as f64 / stepping,
                mlups: (cells as u64 * steps_per_action * actions as u64) as f64 / stepping / 1e6,
                outside_share: (1.0 - solver / stepping).max(0.0),
            };
            progress(&format!(
                "{} ({}): {:.1} actions/s, {:.1} % outside the solver",
                row.id,
                row.level,
                row.actions_per_s,
                100.0 * row.outside_share
            ));
            rows.push(row);
        }
    }
    Ok(rows)
}

pub fn table(rows: &[EnvBenchRow]) -> String {
    let mut s = format!(
        "{:<30} {:<8} {:>9} {:>12} {:>10} {:>9} {:>8} {:>8}\n",
        "ID", "level", "cells", "steps/action", "actions/s", "s/action", "MLUPS", "outside"
    );
    for r in rows {
        s += &format!(
            "{:<30} {:<8} {:>9} {:>12} {:>10.1} {:>9.3} {:>8.0} {:>7.1}%{}\n",
            r.id,
            r.level,
            r.cells,
            r.steps_per_action,
            r.actions_per_s,
            1.0 / r.actions_per_s,
            r.mlups,
            100.0 * r.outside_share,
            if r.over_target() { "  <- over target" } else { "" }
        );
    }
    let judged: Vec<_> = rows.iter().filter(|r| r.judged()).collect();
    if !judged.is_empty() {
        let met = judged.iter().filter(|r| !r.over_target()).count();
        s += &format!(
            "outside the solver's steps (actuation, probes, forces, observation, reward, info): under {:.0} % of the action in {met} of {} 2D IDs at coarse\n",
            100.0 * OUTSIDE_SHARE_TARGET,
            judged.len()
        );
    }
    s
}
