//! The training configuration: one TOML file with a `[train]` table (budget, evaluation,
//! checkpoints), one table per algorithm (`[ppo]`, `[ddpg]`, `[td3]`) and an optional `[env]`
//! table that overrides any field of the environment spec. Every field has a default;
//! `hgym train --print-config` prints the effective file.

use hgym_agents::ddpg::DdpgConfig;
use hgym_agents::learn::AlgoConfigs;
use hgym_agents::ppo::PpoConfig;
use hgym_agents::td3::Td3Config;
use serde::{Deserialize, Serialize};

use crate::env::EnvSpec;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainSettings {
    /// Environment transitions to collect (whole rounds: the last round may overshoot).
    pub steps: u64,
    /// Deterministic evaluation every this many rounds (0: only at the end).
    pub eval_every: u64,
    /// Episodes per periodic evaluation.
    pub eval_episodes: usize,
    /// Episodes of the final evaluation written to `metrics.json`.
    pub final_eval_episodes: usize,
    /// Seeds of evaluation episodes are `eval_seed + k`, shared by every run and baseline.
    pub eval_seed: u64,
    /// Write a checkpoint when this many seconds have passed since the last one (and at the end
    /// and on Ctrl-C).
    pub checkpoint_seconds: f64,
}

impl Default for TrainSettings {
    fn default() -> Self {
        TrainSettings {
            steps: 20_000,
            eval_every: 5,
            eval_episodes: 1,
            final_eval_episodes: 3,
            eval_seed: 1_000_000,
            checkpoint_seconds: 60.0,
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TrainConfig {
    pub train: TrainSettings,
    pub ppo: PpoConfig,
    pub ddpg: DdpgConfig,
    pub td3: Td3Config,
    /// Overrides of the environment spec (any field of `hgym envs show ID`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<toml::Table>,
}

impl TrainConfig {
    pub fn parse(text: &str, origin: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| format!("{origin}: {e}"))
    }

    pub fn algos(&self) -> AlgoConfigs {
        AlgoConfigs {
            ppo: self.ppo.clone(),
            ddpg: self.ddpg.clone(),
            td3: self.td3.clone(),
        }
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print the configuration: {e}\n"))
    }
}

/// Deep-merges `overrides` into the spec's TOML form and reads it back (unknown fields and wrong
/// types are errors that name the field).
pub fn override_spec(spec: &EnvSpec, overrides: &toml::Table) -> Result<EnvSpec, String> {
    let mut base = toml::Table::try_from(spec).map_err(|e| format!("cannot represent the spec as TOML: {e}"))?;
    merge(&mut base, overrides);
    let merged: EnvSpec = toml::Value::Table(base)
        .try_into()
        .map_err(|e| format!("[env] overrides of {}: {e}", spec.id))?;
    Ok(merged)
}

fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_and_unknown_fields_are_refused() {
        let c = TrainConfig::default();
        assert_eq!(TrainConfig::parse(&c.to_toml(), "x").unwrap(), c);
        let e = TrainConfig::parse("[td3]\nbatch = 3\n", "cfg.toml").unwrap_err();
        assert!(e.contains("batch"), "{e}");
        let c = TrainConfig::parse("[td3]\nbatch_size = 64\n[train]\nsteps = 10\n", "x").unwrap();
        assert_eq!((c.td3.batch_size, c.train.steps, c.ppo.n_epochs), (64, 10, 10));
    }

    #[test]
    fn env_overrides_merge_deeply() {
        let spec = crate::env::spec("Cylinder_2D_Re100").unwrap();
        let over: toml::Table = toml::from_str("control_interval = 0.5\n[actuation]\nmax_velocity = 0.5\n").unwrap();
        let s = override_spec(&spec, &over).unwrap();
        assert_eq!(s.control_interval, 0.5);
        match s.actuation {
            crate::env::spec::ActuationSpec::ZnmfJets {
                max_velocity, span_deg, ..
            } => {
                assert_eq!((max_velocity, span_deg), (0.5, 10.0))
            }
            _ => panic!("actuation kind changed"),
        }
        let bad: toml::Table = toml::from_str("control_intervall = 0.5\n").unwrap();
        assert!(override_spec(&spec, &bad).unwrap_err().contains("control_intervall"));
    }
}
