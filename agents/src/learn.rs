//! The learners behind one trait, and the registry of algorithms. An algorithm is one file
//! (`ppo.rs`, `td3.rs`, ...) implementing [`Algorithm`] and one line in [`ALGORITHMS`]; its
//! configuration is its own section of the training configuration (`[ppo]`, `[td3]`, ...), kept
//! here as JSON and read by the algorithm into its typed config.
//!
//! A learner advances in rounds (one episode per environment); its whole state, replay buffer
//! and random generators included, serialises to bytes between rounds, so a resumed run
//! continues bitwise where it stopped.

use std::collections::BTreeMap;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::env::{DifferentiableEnv, EnvError};
use crate::policy::ActorPolicy;
use crate::rollout::EpisodeStats;
use crate::transplant::{Parts, SpaceMap};

/// Every algorithm `train` knows, in listing order.
pub const ALGORITHMS: &[&dyn Algorithm] = &[
    &crate::ppo::PpoAlgorithm,
    &crate::ddpg::DdpgAlgorithm,
    &crate::td3::Td3Algorithm,
    &crate::gppo::GppoAlgorithm,
];

/// The algorithm called `name`, or an error listing them.
pub fn algorithm(name: &str) -> Result<&'static dyn Algorithm, LearnError> {
    ALGORITHMS
        .iter()
        .copied()
        .find(|a| a.name() == name)
        .ok_or_else(|| LearnError::UnknownAlgorithm {
            name: name.to_string(),
            known: names().join(", "),
        })
}

/// The registered names.
pub fn names() -> Vec<&'static str> {
    ALGORITHMS.iter().map(|a| a.name()).collect()
}

/// A learning algorithm: its configuration section and the learners it makes.
pub trait Algorithm: Sync {
    /// Its name on the command line and its configuration section's.
    fn name(&self) -> &'static str;
    /// One line for `--help`.
    fn about(&self) -> &'static str;
    /// Whether it differentiates through the environment ([`DifferentiableEnv`]).
    fn needs_gradients(&self) -> bool {
        false
    }
    /// Its section with every field, defaults filled in where `section` lacks them; an error
    /// names an unknown field or a wrong type.
    fn config(&self, section: Option<&serde_json::Value>) -> Result<serde_json::Value, LearnError>;
    /// Parallel environments per round.
    fn n_envs(&self, cfg: &AlgoConfigs) -> Result<usize, LearnError>;
    /// A fresh learner.
    fn learner(&self, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Result<Box<dyn Learner>, LearnError>;
    /// A learner from [`Learner::to_bytes`].
    fn decode(&self, bytes: &[u8]) -> Result<Box<dyn Learner>, LearnError>;
}

/// An environment a learner steps from worker threads.
pub trait ParallelEnv: DifferentiableEnv + Send {}

impl<T: DifferentiableEnv + Send + ?Sized> ParallelEnv for T {}

/// A learner of any algorithm.
pub trait Learner: Send {
    /// One episode on every environment and the updates that go with it (GPPO differentiates
    /// through the environments; the others only step them).
    fn round(&mut self, envs: &mut [&mut dyn ParallelEnv]) -> Result<Vec<EpisodeStats>, EnvError>;
    /// The current deterministic policy.
    fn policy(&self) -> ActorPolicy;
    /// Environment transitions collected so far.
    fn samples(&self) -> u64;
    /// Gradient updates so far.
    fn updates(&self) -> u64;
    /// Rounds completed.
    fn rounds(&self) -> u64;
    /// The whole state as bytes (bincode), for checkpoints.
    fn to_bytes(&self) -> Result<Vec<u8>, LearnError>;
    /// Starts from a trained policy already mapped onto this learner's spaces (`--init-from`):
    /// its network becomes the actor (and the actor's target), its observation statistics the
    /// learner's; optimiser state starts fresh. An error names what does not fit.
    fn init_actor(&mut self, policy: &ActorPolicy) -> Result<(), LearnError>;
    /// Also takes the critics of `source` (bytes of a learner of this algorithm, as
    /// [`Learner::to_bytes`] wrote them), mapped by `map`, and with `parts.buffer` its replay
    /// buffer. Only off-policy learners have these.
    fn init_critics(&mut self, _source: &[u8], _map: &SpaceMap, _parts: Parts) -> Result<(), LearnError> {
        Err(LearnError::Init(
            "this algorithm is on-policy: it keeps no critics or replay buffer to carry over (they are for td3 and ddpg)".into(),
        ))
    }
}

impl dyn Learner {
    /// [`Learner::round`] over a slice of environments of one type.
    pub fn round_on<E: ParallelEnv>(&mut self, envs: &mut [E]) -> Result<Vec<EpisodeStats>, EnvError> {
        let mut refs: Vec<&mut dyn ParallelEnv> = envs.iter_mut().map(|e| e as &mut dyn ParallelEnv).collect();
        self.round(&mut refs)
    }
}

/// The algorithms' configuration sections by name (`[ppo]`, `[td3]`, ...), as JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct AlgoConfigs(pub BTreeMap<String, serde_json::Value>);

impl AlgoConfigs {
    /// Every registered algorithm's section, defaults filled in; an unknown section or field is an
    /// error that names it.
    pub fn complete(&self) -> Result<AlgoConfigs, LearnError> {
        if let Some(unknown) = self.0.keys().find(|k| algorithm(k).is_err()) {
            return Err(LearnError::Config {
                section: unknown.clone(),
                message: format!("no such algorithm; the sections are {}", names().join(", ")),
            });
        }
        let mut out = BTreeMap::new();
        for a in ALGORITHMS {
            out.insert(a.name().to_string(), a.config(self.0.get(a.name()))?);
        }
        Ok(AlgoConfigs(out))
    }

    /// Section `name` read as `T` (its defaults when absent).
    pub fn section<T: DeserializeOwned + Default>(&self, name: &str) -> Result<T, LearnError> {
        match self.0.get(name) {
            None => Ok(T::default()),
            Some(v) => serde_json::from_value(v.clone()).map_err(|e| LearnError::Config {
                section: name.to_string(),
                message: e.to_string(),
            }),
        }
    }

    /// Replaces section `name` with `value`.
    pub fn set<T: Serialize>(&mut self, name: &str, value: &T) -> Result<(), LearnError> {
        let v = serde_json::to_value(value).map_err(|e| LearnError::Config {
            section: name.to_string(),
            message: e.to_string(),
        })?;
        self.0.insert(name.to_string(), v);
        Ok(())
    }
}

/// An algorithm's section with every field of `T` (see [`Algorithm::config`]).
pub fn complete_section<T: DeserializeOwned + Serialize + Default>(
    name: &str,
    section: Option<&serde_json::Value>,
) -> Result<serde_json::Value, LearnError> {
    let bad = |e: serde_json::Error| LearnError::Config {
        section: name.to_string(),
        message: e.to_string(),
    };
    let typed: T = match section {
        None => T::default(),
        Some(v) => serde_json::from_value(v.clone()).map_err(bad)?,
    };
    let mut v = serde_json::to_value(typed).map_err(bad)?;
    drop_nulls(&mut v);
    Ok(v)
}

/// Removes `null` members (absent options), which TOML cannot write; reading them back gives
/// the same `None`.
fn drop_nulls(v: &mut serde_json::Value) {
    if let serde_json::Value::Object(m) = v {
        m.retain(|_, x| !x.is_null());
        m.values_mut().for_each(drop_nulls);
    }
}

/// A learner's state as bytes.
pub fn encode<T: Serialize>(learner: &T) -> Result<Vec<u8>, LearnError> {
    bincode::serialize(learner).map_err(|e| LearnError::Encode(e.to_string()))
}

/// A learner from [`encode`]'s bytes.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, LearnError> {
    bincode::deserialize(bytes).map_err(|e| LearnError::Decode(e.to_string()))
}

#[derive(Debug, Error)]
pub enum LearnError {
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error("unknown algorithm '{name}'; the algorithms are {known}")]
    UnknownAlgorithm { name: String, known: String },
    #[error("[{section}] of the training configuration: {message}")]
    Config { section: String, message: String },
    #[error("checkpoint could not be decoded ({0}); it was written by another hgym version or is damaged")]
    Decode(String),
    #[error("the learner's state could not be encoded: {0}")]
    Encode(String),
    /// A starting point (`--init-from`) that does not fit this learner.
    #[error("{0}")]
    Init(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_sections_complete() {
        let mut n = names();
        n.sort();
        n.dedup();
        assert_eq!(n.len(), ALGORITHMS.len());
        let full = AlgoConfigs::default().complete().unwrap();
        assert_eq!(full.0.len(), ALGORITHMS.len());
        let mut bad = AlgoConfigs::default();
        bad.0.insert("td3".into(), serde_json::json!({"batch": 3}));
        assert!(bad.complete().unwrap_err().to_string().contains("batch"));
        let mut unknown = AlgoConfigs::default();
        unknown.0.insert("tdd3".into(), serde_json::json!({}));
        assert!(unknown.complete().unwrap_err().to_string().contains("tdd3"));
    }
}
