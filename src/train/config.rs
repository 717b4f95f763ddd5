//! The training configuration: one TOML file with a `[train]` table (budget, evaluation,
//! checkpoints), one table per algorithm (`[ppo]`, `[ddpg]`, `[td3]`, `[gppo]`) and an optional `[env]`
//! table that overrides any field of the environment spec. Every field has a default;
//! `hgym train --print-config` prints the effective file.

use hgym_agents::ddpg::DdpgConfig;
use hgym_agents::gppo::GppoConfig;
use hgym_agents::learn::AlgoConfigs;
use hgym_agents::ppo::PpoConfig;
use hgym_agents::td3::Td3Config;
use serde::{Deserialize, Serialize};

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
    /// Flow-field snapshots (u, v, vorticity) in the final evaluation's trajectory.mcap at each
    /// reset and every this many actions (0: none).
    pub fields_every: u64,
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
            fields_every: 0,
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
    /// GPPO's own settings; its PPO hyperparameters are those of `[ppo]`.
    pub gppo: GppoConfig,
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
            gppo: self.gppo.clone(),
        }
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print the configuration: {e}\n"))
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
        let spec = crate::env::any::lookup("Cylinder_2D_Re100").unwrap();
        let over: toml::Table = toml::from_str("control_interval = 0.5\n[actuation]\nmax_velocity = 0.5\n").unwrap();
        let crate::env::any::AnySpec::Lbm(s) = spec.with_overrides(&over).unwrap() else {
            panic!("family changed")
        };
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
        assert!(spec.with_overrides(&bad).unwrap_err().contains("control_intervall"));
        let k = crate::env::any::lookup("Kolmogorov_2D_Re40").unwrap();
        let over: toml::Table = toml::from_str("[objective]\nkind = \"mixing\"\n").unwrap();
        let crate::env::any::AnySpec::Kolmogorov(k) = k.with_overrides(&over).unwrap() else {
            panic!("family changed")
        };
        assert_eq!(k.objective, crate::env::kolmogorov::Objective::Mixing);
    }
}
