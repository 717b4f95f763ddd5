//! One type over the learners, so that training loops, checkpoints and resumption treat them
//! alike. A learner advances in rounds (one episode per environment); its whole state, replay
//! buffer and random generators included, serialises to bytes between rounds, so a resumed
//! run continues bitwise where it stopped.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::ddpg::{ddpg, DdpgConfig};
use crate::env::{DifferentiableEnv, EnvError};
use crate::gppo::{Gppo, GppoConfig};
use crate::policy::ActorPolicy;
use crate::ppo::{Ppo, PpoConfig};
use crate::rollout::EpisodeStats;
use crate::td3::{Td3, Td3Config};

/// The algorithms `train` knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    Ppo,
    Ddpg,
    Td3,
    Gppo,
}

impl Algo {
    pub fn name(self) -> &'static str {
        match self {
            Algo::Gppo => "gppo",
            Algo::Ppo => "ppo",
            Algo::Ddpg => "ddpg",
            Algo::Td3 => "td3",
        }
    }
}

/// Hyperparameters of every algorithm (a TOML file overrides any field).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AlgoConfigs {
    pub ppo: PpoConfig,
    pub ddpg: DdpgConfig,
    pub td3: Td3Config,
    pub gppo: GppoConfig,
}

impl AlgoConfigs {
    pub fn n_envs(&self, algo: Algo) -> usize {
        match algo {
            Algo::Ppo | Algo::Gppo => self.ppo.n_envs,
            Algo::Ddpg => self.ddpg.n_envs,
            Algo::Td3 => self.td3.n_envs,
        }
        .max(1)
    }
}

#[derive(Debug, Error)]
pub enum LearnError {
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error("checkpoint could not be decoded ({0}); it was written by another hgym version or is damaged")]
    Decode(String),
}

/// A learner of any algorithm.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub enum Learner {
    Ppo(Box<Ppo>),
    Gppo(Box<Gppo>),
    OffPolicy(Box<Td3>),
}

impl Learner {
    pub fn new(algo: Algo, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Self {
        match algo {
            Algo::Ppo => Learner::Ppo(Box::new(Ppo::new(cfg.ppo.clone(), obs_dim, act_dim, seed))),
            Algo::Gppo => Learner::Gppo(Box::new(Gppo::new(cfg.ppo.clone(), cfg.gppo.clone(), obs_dim, act_dim, seed))),
            Algo::Ddpg => Learner::OffPolicy(Box::new(ddpg(&cfg.ddpg, obs_dim, act_dim, seed))),
            Algo::Td3 => Learner::OffPolicy(Box::new(Td3::new("td3", cfg.td3.clone(), obs_dim, act_dim, seed))),
        }
    }

    /// One episode on every environment and the updates that go with it (GPPO differentiates
    /// through the environments; the others only step them).
    pub fn round<E: DifferentiableEnv + Send>(&mut self, envs: &mut [E]) -> Result<Vec<EpisodeStats>, EnvError> {
        match self {
            Learner::Ppo(p) => p.round(envs),
            Learner::Gppo(g) => g.round(envs),
            Learner::OffPolicy(t) => t.round(envs),
        }
    }

    /// The current deterministic policy.
    pub fn policy(&self) -> ActorPolicy {
        match self {
            Learner::Ppo(p) => p.policy(),
            Learner::Gppo(g) => g.ppo.policy(),
            Learner::OffPolicy(t) => t.policy(),
        }
    }

    /// Environment transitions collected so far.
    pub fn samples(&self) -> u64 {
        match self {
            Learner::Ppo(p) => p.samples,
            Learner::Gppo(g) => g.ppo.samples,
            Learner::OffPolicy(t) => t.samples,
        }
    }

    /// Gradient updates so far.
    pub fn updates(&self) -> u64 {
        match self {
            Learner::Ppo(p) => p.updates,
            Learner::Gppo(g) => g.ppo.updates,
            Learner::OffPolicy(t) => t.updates,
        }
    }

    /// Rounds completed.
    pub fn rounds(&self) -> u64 {
        match self {
            Learner::Ppo(p) => p.round,
            Learner::Gppo(g) => g.ppo.round,
            Learner::OffPolicy(t) => t.round,
        }
    }

    /// The whole state as bytes (bincode), for checkpoints.
    pub fn to_bytes(&self) -> Vec<u8> {
        bincode::serialize(self).unwrap_or_default()
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<Self, LearnError> {
        bincode::deserialize(bytes).map_err(|e| LearnError::Decode(e.to_string()))
    }
}
