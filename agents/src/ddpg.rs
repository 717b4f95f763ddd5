//! DDPG (Lillicrap et al. 2016): one critic, target `y = r + gamma (1 - terminal) Q'(s', mu'(s'))`,
//! actor and targets updated every step, Ornstein-Uhlenbeck exploration with the paper's
//! theta = 0.15, sigma = 0.2, soft updates tau = 0.005, batch 256, 256x256 networks. The update
//! is TD3's with its three additions switched off (see [`crate::td3`]).

use serde::{Deserialize, Serialize};

use crate::learn::{complete_section, decode, AlgoConfigs, Algorithm, LearnError, Learner};
use crate::td3::{Td3, Td3Config};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DdpgConfig {
    pub hidden: Vec<usize>,
    pub gamma: f64,
    pub tau: f64,
    pub actor_lr: f64,
    pub critic_lr: f64,
    pub batch_size: usize,
    pub buffer_size: usize,
    pub learning_starts: usize,
    pub ou_theta: f64,
    pub ou_sigma: f64,
    pub n_envs: usize,
    /// As TD3's.
    pub gradient_steps: Option<usize>,
    /// As TD3's.
    pub action_l2: f64,
}

impl Default for DdpgConfig {
    fn default() -> Self {
        let t = Td3Config::default();
        DdpgConfig {
            hidden: t.hidden,
            gamma: t.gamma,
            tau: t.tau,
            actor_lr: t.actor_lr,
            critic_lr: t.critic_lr,
            batch_size: t.batch_size,
            buffer_size: t.buffer_size,
            learning_starts: t.learning_starts,
            ou_theta: 0.15,
            ou_sigma: 0.2,
            n_envs: t.n_envs,
            gradient_steps: t.gradient_steps,
            action_l2: t.action_l2,
        }
    }
}

/// A DDPG learner (a [`Td3`] with one critic, no smoothing, no delay, OU noise).
pub fn ddpg(cfg: &DdpgConfig, obs_dim: usize, act_dim: usize, seed: u64) -> Td3 {
    let t = Td3Config {
        hidden: cfg.hidden.clone(),
        gamma: cfg.gamma,
        tau: cfg.tau,
        actor_lr: cfg.actor_lr,
        critic_lr: cfg.critic_lr,
        batch_size: cfg.batch_size,
        buffer_size: cfg.buffer_size,
        learning_starts: cfg.learning_starts,
        exploration_noise: 0.0,
        ou_noise: Some((cfg.ou_theta, cfg.ou_sigma)),
        twin: false,
        policy_delay: 1,
        target_noise: 0.0,
        target_noise_clip: 0.0,
        n_envs: cfg.n_envs,
        gradient_steps: cfg.gradient_steps,
        action_l2: cfg.action_l2,
    };
    Td3::new("ddpg", t, obs_dim, act_dim, seed)
}

/// The registry entry (`--algo ddpg`, section `[ddpg]`).
pub struct DdpgAlgorithm;

impl Algorithm for DdpgAlgorithm {
    fn name(&self) -> &'static str {
        "ddpg"
    }

    fn about(&self) -> &'static str {
        "deep deterministic policy gradient (Lillicrap et al. 2016), off-policy"
    }

    fn config(&self, section: Option<&serde_json::Value>) -> Result<serde_json::Value, LearnError> {
        complete_section::<DdpgConfig>(self.name(), section)
    }

    fn n_envs(&self, cfg: &AlgoConfigs) -> Result<usize, LearnError> {
        Ok(cfg.section::<DdpgConfig>("ddpg")?.n_envs.max(1))
    }

    fn learner(&self, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(ddpg(&cfg.section("ddpg")?, obs_dim, act_dim, seed)))
    }

    fn decode(&self, bytes: &[u8]) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(decode::<Td3>(bytes)?))
    }
}
