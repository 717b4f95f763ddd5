//! GPPO: PPO whose policy loss adds the analytic gradient of the reward through a
//! differentiable environment (the paper's gradient-enhanced PPO, after Son et al. 2023,
//! "Gradient informed proximal policy optimization"):
//!
//! `L = L_PPO - w mean_t( g_hat_t . mu_theta(s_t) )`, `g_t = d(sum of the segment's rewards)/d a_t`,
//!
//! with `g_t` from a backward sweep of the environment's discrete adjoint over segments of
//! `horizon` actions (open loop: later actions held fixed), `g_hat = g / rms(g)` over the rollout
//! (so `w` is dimensionless: an adaptive coefficient on the gradient's magnitude), and the term
//! applied only where the sampled action was inside the bounds (the derivative of the clip).
//! It is the reparameterised (pathwise) gradient of the segment return through the policy mean,
//! added to PPO's likelihood-ratio gradient. Everything else is [`crate::ppo`].

use serde::{Deserialize, Serialize};

use crate::env::{DifferentiableEnv, EnvError};
use crate::learn::{complete_section, decode, encode, AlgoConfigs, Algorithm, LearnError, Learner, ParallelEnv};
use crate::policy::ActorPolicy;
use crate::ppo::{Ppo, PpoConfig};
use crate::rollout::EpisodeStats;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GppoConfig {
    /// Weight `w` of the analytic term.
    pub weight: f64,
    /// Actions per backward sweep.
    pub horizon: usize,
}

impl Default for GppoConfig {
    fn default() -> Self {
        GppoConfig { weight: 0.5, horizon: 4 }
    }
}

/// A GPPO learner: a [`Ppo`] with the analytic term switched on.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Gppo {
    pub cfg: GppoConfig,
    pub ppo: Ppo,
}

impl Gppo {
    pub fn new(ppo: PpoConfig, cfg: GppoConfig, obs_dim: usize, act_dim: usize, seed: u64) -> Self {
        let mut ppo = Ppo::new(ppo, obs_dim, act_dim, seed);
        ppo.analytic_weight = cfg.weight;
        Gppo { cfg, ppo }
    }

    pub fn round<E: DifferentiableEnv + Send>(&mut self, envs: &mut [E]) -> Result<Vec<EpisodeStats>, EnvError> {
        let h = self.cfg.horizon.max(1);
        self.ppo.round_with(envs, h, &|e: &mut E, k| e.reward_action_gradients(k))
    }
}

/// The registry entry (`--algo gppo`, section `[gppo]`; its PPO hyperparameters are `[ppo]`'s).
pub struct GppoAlgorithm;

impl Algorithm for GppoAlgorithm {
    fn name(&self) -> &'static str {
        "gppo"
    }

    fn about(&self) -> &'static str {
        "PPO plus the analytic reward gradient through a differentiable env (Kolmogorov flows)"
    }

    fn needs_gradients(&self) -> bool {
        true
    }

    fn config(&self, section: Option<&serde_json::Value>) -> Result<serde_json::Value, LearnError> {
        complete_section::<GppoConfig>(self.name(), section)
    }

    fn n_envs(&self, cfg: &AlgoConfigs) -> Result<usize, LearnError> {
        Ok(cfg.section::<PpoConfig>("ppo")?.n_envs.max(1))
    }

    fn learner(&self, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(Gppo::new(
            cfg.section("ppo")?,
            cfg.section("gppo")?,
            obs_dim,
            act_dim,
            seed,
        )))
    }

    fn decode(&self, bytes: &[u8]) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(decode::<Gppo>(bytes)?))
    }
}

impl Learner for Gppo {
    fn round(&mut self, envs: &mut [&mut dyn ParallelEnv]) -> Result<Vec<EpisodeStats>, EnvError> {
        Gppo::round(self, envs)
    }

    fn policy(&self) -> ActorPolicy {
        self.ppo.policy()
    }

    fn samples(&self) -> u64 {
        self.ppo.samples
    }

    fn updates(&self) -> u64 {
        self.ppo.updates
    }

    fn rounds(&self) -> u64 {
        self.ppo.round
    }

    fn to_bytes(&self) -> Result<Vec<u8>, LearnError> {
        encode(self)
    }

    fn init_actor(&mut self, policy: &ActorPolicy) -> Result<(), LearnError> {
        self.ppo.init_actor(policy)
    }
}
