//! Stepping several environments in lockstep, in parallel (rayon), and running evaluation
//! episodes of any [`Policy`].

use std::collections::BTreeMap;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::env::{Env, EnvError, Info, StepResult};
use crate::policy::Policy;

/// What one finished episode looked like.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EpisodeStats {
    pub ret: f64,
    pub length: usize,
    pub terminated: bool,
    /// The reason a real terminal state was reached (info text `reason`).
    pub reason: Option<String>,
    /// Mean over the episode's steps of every numeric info value (e.g. `C_D`), and of
    /// `|C_L|`-style magnitudes under `abs_<key>`.
    pub info_means: BTreeMap<String, f64>,
    /// How many action components the environment clipped (info `clipped`, summed).
    pub clipped: f64,
}

/// Accumulates an [`EpisodeStats`] step by step.
#[derive(Clone, Debug, Default)]
pub struct EpisodeAccumulator {
    stats: EpisodeStats,
    sums: BTreeMap<String, f64>,
}

impl EpisodeAccumulator {
    pub fn add(&mut self, r: &StepResult) {
        self.stats.ret += r.reward;
        self.stats.length += 1;
        for (k, v) in &r.info.values {
            *self.sums.entry(k.clone()).or_insert(0.0) += v;
            *self.sums.entry(format!("abs_{k}")).or_insert(0.0) += v.abs();
        }
        self.stats.clipped += r.info.get("clipped").unwrap_or(0.0);
        if r.terminated {
            self.stats.terminated = true;
            self.stats.reason = r.info.text("reason").map(|s| s.to_string());
        }
    }

    pub fn finish(mut self) -> EpisodeStats {
        let n = self.stats.length.max(1) as f64;
        self.stats.info_means = self.sums.into_iter().map(|(k, v)| (k, v / n)).collect();
        self.stats
    }
}

/// Steps every environment whose `active` flag is set with its action, in parallel; inactive
/// environments return `None`. The order of results is the order of the environments, so the
/// outcome does not depend on the number of threads. The actions are first handed over in
/// order ([`Env::submit`]: multi-agent pseudo-environments step their shared flow there).
pub fn step_all<E: Env + Send>(envs: &mut [E], actions: &[Vec<f64>], active: &[bool]) -> Result<Vec<Option<StepResult>>, EnvError> {
    for ((env, a), on) in envs.iter_mut().zip(actions).zip(active) {
        if *on {
            env.submit(a)?;
        }
    }
    envs.par_iter_mut()
        .zip(actions.par_iter())
        .zip(active.par_iter())
        .map(|((env, a), on)| if *on { env.step(a).map(Some) } else { Ok(None) })
        .collect()
}

/// Resets every environment with its seed, in parallel (after [`Env::submit_reset`] in order).
pub fn reset_all<E: Env + Send>(envs: &mut [E], seeds: &[u64]) -> Result<Vec<(Vec<f64>, Info)>, EnvError> {
    for (env, s) in envs.iter_mut().zip(seeds) {
        env.submit_reset(*s)?;
    }
    envs.par_iter_mut().zip(seeds.par_iter()).map(|(env, s)| env.reset(*s)).collect()
}

/// Runs one episode of `policy` on `env` from `reset(seed)`; `on_step` sees every step.
pub fn episode<E: Env + ?Sized, P: Policy + ?Sized>(
    env: &mut E,
    policy: &mut P,
    seed: u64,
    on_step: &mut dyn FnMut(&[f64], &StepResult),
) -> Result<EpisodeStats, EnvError> {
    let (mut obs, mut info) = env.reset(seed)?;
    policy.reset();
    let mut action = vec![0.0; env.action_space().dim()];
    let mut acc = EpisodeAccumulator::default();
    loop {
        policy.act(&obs, &info, &mut action);
        let r = env.step(&action)?;
        on_step(&action, &r);
        acc.add(&r);
        let done = r.terminated || r.truncated;
        obs = r.obs;
        info = r.info;
        if done {
            return Ok(acc.finish());
        }
    }
}

/// The seed of environment `env` in round `round` of a run seeded `seed` (SplitMix64 mix), so
/// a resumed run resets exactly as an uninterrupted one.
pub fn episode_seed(seed: u64, round: u64, env: usize) -> u64 {
    let mut z = seed ^ round.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (env as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
