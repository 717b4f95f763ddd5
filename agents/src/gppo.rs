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
