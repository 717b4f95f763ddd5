//! One type over every environment family, so that training, evaluation and listings treat
//! lattice-Boltzmann flows and the spectral Kolmogorov flow alike.

use std::path::PathBuf;

use hgym_agents::{BoxSpace, DifferentiableEnv, Env, EnvError, Info, StepResult};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::kolmogorov::{KolmogorovEnv, KolmogorovSpec};
use super::{EnvInputError, EnvSpec, LbmEnv};
use crate::flow::Level;

/// A spec of any family (serialised without a tag: the fields tell them apart).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum AnySpec {
    Lbm(EnvSpec),
    Kolmogorov(KolmogorovSpec),
}

impl AnySpec {
    pub fn id(&self) -> &str {
        match self {
            AnySpec::Lbm(s) => &s.id,
            AnySpec::Kolmogorov(s) => &s.id,
        }
    }

    pub fn family(&self) -> &str {
        match self {
            AnySpec::Lbm(s) => &s.family,
            AnySpec::Kolmogorov(s) => &s.family,
        }
    }

    pub fn reynolds(&self) -> f64 {
        match self {
            AnySpec::Lbm(s) => s.reynolds,
            AnySpec::Kolmogorov(s) => s.reynolds,
        }
    }

    pub fn solver(&self) -> &'static str {
        match self {
            AnySpec::Lbm(s) if s.thermal.is_some() => "lbm-d2q9+q5",
            AnySpec::Lbm(_) => "lbm-d2q9",
            AnySpec::Kolmogorov(_) => "spectral",
        }
    }

    pub fn differentiable(&self) -> bool {
        matches!(self, AnySpec::Kolmogorov(_))
    }

    pub fn hash(&self) -> String {
        match self {
            AnySpec::Lbm(s) => s.hash(),
            AnySpec::Kolmogorov(s) => s.hash(),
        }
    }

    pub fn obs_dim(&self) -> usize {
        match self {
            AnySpec::Lbm(s) => s.obs_dim(),
            AnySpec::Kolmogorov(s) => s.obs_dim(),
        }
    }

    pub fn act_dim(&self) -> usize {
        match self {
            AnySpec::Lbm(s) => s.act_dim(),
            AnySpec::Kolmogorov(s) => s.act_dim(),
        }
    }

    /// Physical time between actions.
    pub fn control_interval(&self) -> f64 {
        match self {
            AnySpec::Lbm(s) => s.control_interval,
            AnySpec::Kolmogorov(s) => s.control_interval,
        }
    }

    /// The metadata record of a trajectory file: spec, hash, level, policy, seeds, code version.
    pub fn trajectory_manifest(&self, level: Level, policy: &str, seeds: &[u64]) -> std::collections::BTreeMap<String, String> {
        let m = crate::report::manifest::manifest(rayon::current_num_threads(), 0.0);
        [
            ("env_id", self.id().to_string()),
            ("spec_hash", self.hash()),
            ("spec", serde_json::to_string(self).unwrap_or_default()),
            ("level", level.name().to_string()),
            ("policy", policy.to_string()),
            ("seeds", format!("{seeds:?}")),
            ("code_version", m.code_version),
            ("git_commit", m.git_commit.unwrap_or_default()),
            ("control_interval", self.control_interval().to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }

    pub fn to_toml(&self) -> String {
        match self {
            AnySpec::Lbm(s) => s.to_toml(),
            AnySpec::Kolmogorov(s) => s.to_toml(),
        }
    }

    /// A running environment at `level` (`cache`: where LBM attractor states are kept).
    pub fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<AnyEnv, EnvError> {
        Ok(match self {
            AnySpec::Lbm(s) => AnyEnv::Lbm(Box::new(LbmEnv::new(s.clone(), level, cache)?)),
            AnySpec::Kolmogorov(s) => AnyEnv::Kolmogorov(Box::new(KolmogorovEnv::new(s.clone(), level)?)),
        })
    }

    /// Deep-merges TOML overrides into the spec (unknown fields and wrong types are errors that
    /// name the field).
    pub fn with_overrides(&self, over: &toml::Table) -> Result<AnySpec, String> {
        Ok(match self {
            AnySpec::Lbm(s) => AnySpec::Lbm(merged(s, over, &s.id)?),
            AnySpec::Kolmogorov(s) => AnySpec::Kolmogorov(merged(s, over, &s.id)?),
        })
    }
}

fn merged<T: Serialize + DeserializeOwned>(value: &T, over: &toml::Table, id: &str) -> Result<T, String> {
    let mut base = toml::Table::try_from(value).map_err(|e| format!("cannot represent the spec of {id} as TOML: {e}"))?;
    merge(&mut base, over);
    toml::Value::Table(base)
        .try_into()
        .map_err(|e| format!("[env] overrides of {id}: {e}"))
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

/// Every registered spec: the lattice-Boltzmann families, then the Kolmogorov flows.
pub fn all() -> Vec<AnySpec> {
    let mut v: Vec<AnySpec> = super::registry::all().into_iter().map(AnySpec::Lbm).collect();
    v.extend(super::kolmogorov::all().into_iter().map(AnySpec::Kolmogorov));
    v
}

/// The spec of `id` in any family, or an error naming the closest IDs.
pub fn lookup(id: &str) -> Result<AnySpec, EnvInputError> {
    let specs = all();
    if let Some(s) = specs.iter().find(|s| s.id() == id) {
        return Ok(s.clone());
    }
    let mut ids: Vec<(usize, String)> = specs
        .iter()
        .map(|s| {
            (
                super::registry::edit_distance(&s.id().to_lowercase(), &id.to_lowercase()),
                s.id().to_string(),
            )
        })
        .collect();
    ids.sort();
    Err(EnvInputError::UnknownEnv {
        id: id.to_string(),
        closest: ids.into_iter().map(|(_, id)| id).collect(),
    })
}

/// A running environment of any family.
pub enum AnyEnv {
    Lbm(Box<LbmEnv>),
    Kolmogorov(Box<KolmogorovEnv>),
}

impl Env for AnyEnv {
    fn observation_space(&self) -> BoxSpace {
        match self {
            AnyEnv::Lbm(e) => e.observation_space(),
            AnyEnv::Kolmogorov(e) => e.observation_space(),
        }
    }

    fn action_space(&self) -> BoxSpace {
        match self {
            AnyEnv::Lbm(e) => e.action_space(),
            AnyEnv::Kolmogorov(e) => e.action_space(),
        }
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        match self {
            AnyEnv::Lbm(e) => e.reset(seed),
            AnyEnv::Kolmogorov(e) => e.reset(seed),
        }
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        match self {
            AnyEnv::Lbm(e) => e.step(action),
            AnyEnv::Kolmogorov(e) => e.step(action),
        }
    }
}

impl DifferentiableEnv for AnyEnv {
    fn reward_action_gradients(&mut self, k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        match self {
            AnyEnv::Kolmogorov(e) => e.reward_action_gradients(k),
            AnyEnv::Lbm(_) => Err(EnvError::Backend(
                "this environment is not differentiable (only the spectral Kolmogorov flows are); use ppo, ddpg or td3".into(),
            )),
        }
    }
}
