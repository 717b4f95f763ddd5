//! The training configuration: one TOML file with a `[train]` table (budget, evaluation,
//! checkpoints), one table per registered algorithm (`[ppo]`, `[ddpg]`, `[td3]`, `[gppo]`: each
//! algorithm reads its own, see `hgym_agents::learn`) and an optional `[env]` table that
//! overrides any field of the environment spec. Every field has a default;
//! `hgym train --print-config` prints the effective file.

use hgym_agents::learn::AlgoConfigs;
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
    /// Train a flow that declares agents (the channel flows: one per actuator patch) as agents
    /// sharing one policy, each transition of each agent a sample (so `steps` counts agent
    /// transitions); false: one policy for the whole action.
    pub multi_agent: bool,
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
            multi_agent: true,
        }
    }
}

/// A configuration file that cannot be used (always the user's input).
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read the config file {}", path.display())]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{origin}: {message}")]
    Invalid { origin: String, message: String },
    #[error("{origin}: {source}")]
    Toml {
        origin: String,
        #[source]
        source: toml::de::Error,
    },
    #[error("{origin}: {source}")]
    Section {
        origin: String,
        #[source]
        source: hgym_agents::learn::LearnError,
    },
}

/// The file's tables. Every table but `[train]` and `[env]` is an algorithm's section
/// (unknown ones are refused by [`TrainConfig::parse`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrainConfig {
    pub train: TrainSettings,
    #[serde(flatten)]
    pub algos: AlgoConfigs,
    /// Overrides of the environment spec (any field of `hgym envs show ID`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub env: Option<toml::Table>,
}

impl Default for TrainConfig {
    /// Every section with its defaults.
    fn default() -> Self {
        TrainConfig {
            train: TrainSettings::default(),
            algos: AlgoConfigs::default()
                .complete()
                .expect("the algorithms' defaults are valid sections"),
            env: None,
        }
    }
}

impl TrainConfig {
    /// Parses a configuration file's text, filling every algorithm's section with its defaults;
    /// an unknown table or field is an error that names it (`origin` names the file).
    pub fn parse(text: &str, origin: &str) -> Result<Self, ConfigError> {
        let mut c: TrainConfig = toml::from_str(text).map_err(|source| ConfigError::Toml {
            origin: origin.to_string(),
            source,
        })?;
        c.algos = c.algos.complete().map_err(|source| ConfigError::Section {
            origin: origin.to_string(),
            source,
        })?;
        if c.train.steps == 0 {
            return Err(ConfigError::Invalid {
                origin: origin.to_string(),
                message: "[train] steps must be at least 1 (a run of no step would write an untrained policy)".into(),
            });
        }
        Ok(c)
    }

    /// Reads and parses the file `path`; a training result folder gives the configuration its
    /// run was made with (its manifest's `config_toml`), so `--config RUN_DIR` repeats a run.
    pub fn load(path: &std::path::Path) -> Result<Self, ConfigError> {
        let file = if path.is_dir() {
            path.join("manifest.json")
        } else {
            path.to_path_buf()
        };
        let text = std::fs::read_to_string(&file).map_err(|source| ConfigError::Read {
            path: file.clone(),
            source,
        })?;
        if !path.is_dir() {
            return Self::parse(&text, &path.display().to_string());
        }
        let origin = format!("{} (its config_toml)", file.display());
        let invalid = |message: String| ConfigError::Invalid {
            origin: origin.clone(),
            message,
        };
        let manifest: serde_json::Value = serde_json::from_str(&text).map_err(|e| invalid(format!("not JSON: {e}")))?;
        let toml = manifest["config_toml"]
            .as_str()
            .ok_or_else(|| invalid("no config_toml: not a training result folder".into()))?;
        Self::parse(toml, &origin)
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
        let e = TrainConfig::parse("[td3]\nbatch = 3\n", "cfg.toml").unwrap_err().to_string();
        assert!(e.contains("batch"), "{e}");
        let e = TrainConfig::parse("[tdd3]\nbatch_size = 3\n", "cfg.toml").unwrap_err().to_string();
        assert!(e.contains("tdd3"), "{e}");
        let c = TrainConfig::parse("[td3]\nbatch_size = 64\n[train]\nsteps = 10\n", "x").unwrap();
        let td3: hgym_agents::td3::Td3Config = c.algos.section("td3").unwrap();
        let ppo: hgym_agents::ppo::PpoConfig = c.algos.section("ppo").unwrap();
        assert_eq!((td3.batch_size, c.train.steps, ppo.n_epochs), (64, 10, 10));
    }

    #[test]
    fn env_overrides_merge_deeply() {
        let spec = crate::env::lookup("Cylinder_2D_Re100").unwrap();
        let over: toml::Table = toml::from_str("control_interval = 0.5\n[actuation]\nmax_velocity = 0.5\n").unwrap();
        let merged = spec.with_overrides(&over).unwrap();
        let s = merged.downcast::<crate::env::EnvSpec>().expect("family changed");
        assert_eq!(s.control_interval, 0.5);
        match &s.actuation {
            crate::env::spec::ActuationSpec::ZnmfJets {
                max_velocity, span_deg, ..
            } => {
                assert_eq!((*max_velocity, *span_deg), (0.5, 10.0))
            }
            _ => panic!("actuation kind changed"),
        }
        let bad: toml::Table = toml::from_str("control_intervall = 0.5\n").unwrap();
        assert!(spec.with_overrides(&bad).unwrap_err().to_string().contains("control_intervall"));
        let k = crate::env::lookup("Kolmogorov_2D_Re40").unwrap();
        let over: toml::Table = toml::from_str("[objective]\nkind = \"mixing\"\n").unwrap();
        let merged = k.with_overrides(&over).unwrap();
        let k = merged.downcast::<crate::env::kolmogorov::KolmogorovSpec>().expect("family changed");
        assert_eq!(k.objective, crate::env::kolmogorov::Objective::Mixing);
    }
}
