//! PPO (Schulman et al. 2017) with the clipped surrogate
//! `L = -E[min(r A, clip(r, 1 - eps, 1 + eps) A)] + c_v E[(V - R)^2] / 2 - c_e H`,
//! GAE (Schulman et al. 2016, lambda = 0.95), a Gaussian policy with a state-independent
//! log-std, separate actor and critic networks, running observation normalisation and reward
//! scaling by the return's standard deviation (Gymnasium's wrappers). Implementation details
//! follow CleanRL's `ppo_continuous_action` (orthogonal init, per-minibatch advantage
//! normalisation, global-norm clipping 0.5); the paper states ReLU layers and GAE 0.95.
//!
//! A rollout is one round: one whole episode on each of `n_envs` environments stepped in
//! parallel. A truncated episode is bootstrapped with `gamma V(s_T)` (as SB3 does), a
//! terminated one is not.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::env::{Env, EnvError};
use crate::learn::{complete_section, decode, encode, AlgoConfigs, Algorithm, LearnError, Learner, ParallelEnv};
use crate::nn::{clip_grad_norm, Activation, Adam, Init, Mlp, Tape};
use crate::normalize::{RewardScaler, RunningMeanStd};
use crate::policy::ActorPolicy;
use crate::rng::Rng;
use crate::rollout::{episode_seed, reset_all, step_all, EpisodeAccumulator, EpisodeStats};

const LN_2PI: f64 = 1.837_877_066_409_345_5;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {
    pub hidden: Vec<usize>,
    pub activation: Activation,
    pub lr: f64,
    pub gamma: f64,
    pub gae_lambda: f64,
    pub clip: f64,
    pub n_epochs: usize,
    pub minibatch_size: usize,
    pub ent_coef: f64,
    pub vf_coef: f64,
    pub max_grad_norm: f64,
    pub init_log_std: f64,
    pub norm_obs: bool,
    pub norm_reward: bool,
    pub norm_adv: bool,
    /// Environments stepped in parallel (episodes per update).
    pub n_envs: usize,
}

impl Default for PpoConfig {
    fn default() -> Self {
        PpoConfig {
            hidden: vec![64, 64],
            activation: Activation::Relu,
            lr: 3e-4,
            gamma: 0.99,
            gae_lambda: 0.95,
            clip: 0.2,
            n_epochs: 10,
            minibatch_size: 64,
            ent_coef: 0.0,
            vf_coef: 0.5,
            max_grad_norm: 0.5,
            init_log_std: 0.0,
            norm_obs: true,
            norm_reward: true,
            norm_adv: true,
            n_envs: 2,
        }
    }
}

/// Minibatch buffers reused across updates (not checkpointed).
#[derive(Clone, Debug, Default)]
struct Scratch {
    obs: Vec<f32>,
    dmu: Vec<f32>,
    dv: Vec<f32>,
    actor_grad: Vec<f32>,
    log_std_grad: Vec<f32>,
    critic_grad: Vec<f32>,
    actor_tape: Tape<f32>,
    critic_tape: Tape<f32>,
}

/// One collected transition (normalised observation, raw Gaussian sample, its log-probability
/// and value estimate, the scaled reward, and after GAE its advantage and return).
#[derive(Clone, Debug)]
pub struct Sample {
    pub obs: Vec<f32>,
    pub action: Vec<f64>,
    pub logp: f64,
    pub value: f64,
    pub reward: f64,
    pub advantage: f64,
    pub ret: f64,
    /// GPPO: gradient of the reward (over the env's segment) with respect to the applied action.
    pub action_grad: Option<Vec<f64>>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Ppo {
    pub cfg: PpoConfig,
    pub seed: u64,
    obs_dim: usize,
    act_dim: usize,
    actor: Mlp<f32>,
    log_std: Vec<f32>,
    critic: Mlp<f32>,
    actor_opt: Adam<f32>,
    log_std_opt: Adam<f32>,
    critic_opt: Adam<f32>,
    obs_rms: RunningMeanStd,
    reward_scaler: RewardScaler,
    rng: Rng,
    pub samples: u64,
    pub updates: u64,
    pub round: u64,
    /// Weight of the analytic reward gradient in the policy loss (0 for PPO; GPPO sets it).
    #[serde(default)]
    pub analytic_weight: f64,
    #[serde(skip)]
    scratch: Scratch,
}

impl Ppo {
    pub fn new(cfg: PpoConfig, obs_dim: usize, act_dim: usize, seed: u64) -> Self {
        let mut rng = Rng::seed(seed);
        let hidden_init = Init::Orthogonal { gain: 2f64.sqrt() };
        let mut sizes = vec![obs_dim];
        sizes.extend(&cfg.hidden);
        sizes.push(act_dim);
        let actor = Mlp::new(
            &sizes,
            cfg.activation,
            Activation::Identity,
            hidden_init,
            Init::Orthogonal { gain: 0.01 },
            &mut rng,
        );
        let last = sizes.len() - 1;
        sizes[last] = 1;
        let critic = Mlp::new(
            &sizes,
            cfg.activation,
            Activation::Identity,
            hidden_init,
            Init::Orthogonal { gain: 1.0 },
            &mut rng,
        );
        Ppo {
            seed,
            obs_dim,
            act_dim,
            actor_opt: Adam::new(actor.params.len(), cfg.lr),
            log_std_opt: Adam::new(act_dim, cfg.lr),
            critic_opt: Adam::new(critic.params.len(), cfg.lr),
            actor,
            log_std: vec![cfg.init_log_std as f32; act_dim],
            critic,
            obs_rms: RunningMeanStd::new(obs_dim),
            reward_scaler: RewardScaler::new(cfg.n_envs.max(1), cfg.gamma),
            rng,
            samples: 0,
            updates: 0,
            round: 0,
            analytic_weight: 0.0,
            cfg,
            scratch: Scratch::default(),
        }
    }

    /// The deterministic policy: `clip(mu(normalise(s)), -1, 1)`.
    pub fn policy(&self) -> ActorPolicy {
        ActorPolicy::new("ppo", self.actor.clone(), self.cfg.norm_obs.then(|| self.obs_rms.clone()), 10.0)
    }

    /// Starts from `policy` (see [`Learner::init_actor`]); its normalisation must match `norm_obs`.
    pub fn init_actor(&mut self, policy: &ActorPolicy) -> Result<(), LearnError> {
        crate::transplant::fits(policy, &self.actor, &["ppo"])?;
        match (&policy.obs_norm, self.cfg.norm_obs) {
            (Some(n), true) => self.obs_rms = n.clone(),
            (None, false) => {}
            (n, norm) => {
                return Err(LearnError::Init(format!(
                    "the policy {} its observations and this learner has norm_obs = {norm}: set [ppo] norm_obs = {}",
                    if n.is_some() { "normalises" } else { "does not normalise" },
                    n.is_some()
                )))
            }
        }
        self.actor = policy.net.clone();
        Ok(())
    }

    pub fn log_std(&self) -> &[f32] {
        &self.log_std
    }

    /// Normalised observation as the networks see it; updates the running statistics first.
    fn observe(&mut self, raw: &[f64]) -> Vec<f32> {
        let mut x = raw.to_vec();
        if self.cfg.norm_obs {
            self.obs_rms.update(raw);
            self.obs_rms.normalize(&mut x, 10.0);
        }
        x.iter().map(|v| *v as f32).collect()
    }

    fn value(&mut self, obs: &[f32]) -> f64 {
        self.critic.forward(obs, 1, &mut self.scratch.critic_tape)[0] as f64
    }

    /// One round: an episode per environment, then `n_epochs` of minibatch updates.
    pub fn round<E: Env + Send>(&mut self, envs: &mut [E]) -> Result<Vec<EpisodeStats>, EnvError> {
        self.round_with(envs, 0, &|_: &mut E, _| Ok(vec![]))
    }

    /// A round in which, when `segment > 0`, every `segment` actions of an environment (and at
    /// its episode's end) `gradients(env, k)` returns the reward gradients with respect to its
    /// last `k` actions (GPPO); they are stored on the samples for [`Ppo::update`].
    pub fn round_with<E, G>(&mut self, envs: &mut [E], segment: usize, gradients: &G) -> Result<Vec<EpisodeStats>, EnvError>
    where
        E: Env + Send,
        G: Fn(&mut E, usize) -> Result<Vec<Vec<f64>>, EnvError> + Sync,
    {
        let n = envs.len();
        if self.reward_scaler.returns.len() < n {
            self.reward_scaler.returns.resize(n, 0.0);
        }
        let seeds: Vec<u64> = (0..n).map(|i| episode_seed(self.seed, self.round, i)).collect();
        let mut obs: Vec<Vec<f32>> = Vec::with_capacity(n);
        for (o, _) in reset_all(envs, &seeds)? {
            obs.push(self.observe(&o));
        }
        let mut active = vec![true; n];
        let mut actions = vec![vec![0.0; self.act_dim]; n];
        let mut acc = vec![EpisodeAccumulator::default(); n];
        let mut trajectories: Vec<Vec<Sample>> = vec![vec![]; n];
        let mut pending: Vec<Option<Sample>> = vec![None; n];
        let mut want = vec![0usize; n];
        while active.iter().any(|a| *a) {
            for i in 0..n {
                if !active[i] {
                    continue;
                }
                let mu = self.actor.forward(&obs[i], 1, &mut self.scratch.actor_tape).to_vec();
                let mut raw = vec![0.0; self.act_dim];
                let mut logp = 0.0;
                for j in 0..self.act_dim {
                    let (ls, eps) = (self.log_std[j] as f64, self.rng.normal());
                    raw[j] = mu[j] as f64 + ls.exp() * eps;
                    logp += -0.5 * eps * eps - ls - 0.5 * LN_2PI;
                    actions[i][j] = raw[j].clamp(-1.0, 1.0);
                }
                let value = self.value(&obs[i]);
                pending[i] = Some(Sample {
                    obs: obs[i].clone(),
                    action: raw,
                    logp,
                    value,
                    reward: 0.0,
                    advantage: 0.0,
                    ret: 0.0,
                    action_grad: None,
                });
            }
            let results = step_all(envs, &actions, &active)?;
            for (i, r) in results.into_iter().enumerate() {
                let (Some(r), Some(mut s)) = (r, pending[i].take()) else { continue };
                acc[i].add(&r);
                self.samples += 1;
                let done = r.terminated || r.truncated;
                let mut reward = if self.cfg.norm_reward {
                    self.reward_scaler.scale(i, r.reward, done)
                } else {
                    r.reward
                };
                let next = self.observe(&r.obs);
                if r.truncated && !r.terminated {
                    reward += self.cfg.gamma * self.value(&next);
                }
                s.reward = reward;
                trajectories[i].push(s);
                obs[i] = next;
                if done {
                    active[i] = false;
                }
                if segment > 0 {
                    let since = trajectories[i].iter().rev().take_while(|s| s.action_grad.is_none()).count();
                    if since >= segment || done {
                        want[i] = since;
                    }
                }
            }
            if want.iter().any(|k| *k > 0) {
                let grads: Vec<Option<Vec<Vec<f64>>>> = envs
                    .par_iter_mut()
                    .zip(want.par_iter())
                    .map(|(e, k)| if *k > 0 { gradients(e, *k).map(Some) } else { Ok(None) })
                    .collect::<Result<_, _>>()?;
                for (i, g) in grads.into_iter().enumerate() {
                    if let Some(g) = g {
                        let len = trajectories[i].len();
                        for (s, gj) in trajectories[i][len - g.len()..].iter_mut().zip(g) {
                            s.action_grad = Some(gj);
                        }
                    }
                    want[i] = 0;
                }
            }
        }
        // GAE per trajectory; every trajectory ends done, so the value after it is zero.
        let (gamma, lambda) = (self.cfg.gamma, self.cfg.gae_lambda);
        let mut samples = vec![];
        for mut tr in trajectories {
            let mut gae = 0.0;
            let mut next_value = 0.0;
            for s in tr.iter_mut().rev() {
                let delta = s.reward + gamma * next_value - s.value;
                gae = delta + gamma * lambda * gae;
                s.advantage = gae;
                s.ret = gae + s.value;
                next_value = s.value;
            }
            samples.extend(tr);
        }
        self.update(&samples);
        self.round += 1;
        Ok(acc.into_iter().map(|a| a.finish()).collect())
    }

    /// `n_epochs` passes of shuffled minibatches over the rollout.
    pub fn update(&mut self, samples: &[Sample]) {
        let (o, a, m) = (self.obs_dim, self.act_dim, self.cfg.minibatch_size.max(1));
        let n = samples.len();
        let mut order: Vec<usize> = (0..n).collect();
        let s = &mut self.scratch;
        s.actor_grad.resize(self.actor.params.len(), 0.0);
        s.critic_grad.resize(self.critic.params.len(), 0.0);
        s.log_std_grad.resize(a, 0.0);
        // GPPO: analytic gradients scaled to unit RMS over the rollout, so that the weight is
        // dimensionless (an adaptive coefficient on the gradient's magnitude).
        let g_rms = {
            let (sum, count) = samples
                .iter()
                .filter_map(|s| s.action_grad.as_ref())
                .flat_map(|g| g.iter())
                .fold((0.0, 0usize), |(s, c), g| (s + g * g, c + 1));
            if count > 0 {
                (sum / count as f64).sqrt().max(1e-12)
            } else {
                1.0
            }
        };
        for _ in 0..self.cfg.n_epochs {
            // Fisher-Yates with the learner's generator.
            for i in (1..n).rev() {
                order.swap(i, self.rng.below(i + 1));
            }
            for chunk in order.chunks(m) {
                let b = chunk.len();
                s.obs.clear();
                for &k in chunk {
                    s.obs.extend_from_slice(&samples[k].obs);
                }
                debug_assert_eq!(s.obs.len(), b * o);
                let (mut adv_mean, mut adv_std) = (0.0, 1.0);
                if self.cfg.norm_adv && b > 1 {
                    adv_mean = chunk.iter().map(|&k| samples[k].advantage).sum::<f64>() / b as f64;
                    let var = chunk.iter().map(|&k| (samples[k].advantage - adv_mean).powi(2)).sum::<f64>() / (b - 1) as f64;
                    adv_std = var.sqrt() + 1e-8;
                }
                // Policy: gradient of the clipped surrogate through log pi = sum_j log N(a_j; mu_j, sigma_j).
                let mu = self.actor.forward(&s.obs, b, &mut s.actor_tape);
                s.dmu.clear();
                s.dmu.resize(b * a, 0.0);
                s.log_std_grad.iter_mut().for_each(|g| *g = 0.0);
                for (r, &k) in chunk.iter().enumerate() {
                    let smp = &samples[k];
                    let adv = (smp.advantage - adv_mean) / adv_std;
                    let mut logp = 0.0;
                    for j in 0..a {
                        let ls = self.log_std[j] as f64;
                        let z = (smp.action[j] - mu[r * a + j] as f64) / ls.exp();
                        logp += -0.5 * z * z - ls - 0.5 * LN_2PI;
                    }
                    let ratio = (logp - smp.logp).exp();
                    let eps = self.cfg.clip;
                    let clipped = (adv >= 0.0 && ratio > 1.0 + eps) || (adv < 0.0 && ratio < 1.0 - eps);
                    // dL/dlogp = -ratio * adv / b where the unclipped branch is active.
                    let g = if clipped { 0.0 } else { -ratio * adv / b as f64 };
                    for j in 0..a {
                        let ls = self.log_std[j] as f64;
                        let sig = ls.exp();
                        let z = (smp.action[j] - mu[r * a + j] as f64) / sig;
                        let mut dmu = g * z / sig;
                        // GPPO: L -= w mean(g_hat . mu); through clip(a) only inside [-1, 1].
                        if let Some(ga) = &smp.action_grad {
                            if smp.action[j].abs() <= 1.0 {
                                dmu -= self.analytic_weight * ga[j] / g_rms / b as f64;
                            }
                        }
                        s.dmu[r * a + j] = dmu as f32;
                        s.log_std_grad[j] += (g * (z * z - 1.0)) as f32;
                    }
                }
                // Entropy bonus: H = sum_j (log sigma_j + (1 + ln 2 pi) / 2); dH/dlog sigma_j = 1.
                for g in s.log_std_grad.iter_mut() {
                    *g -= self.cfg.ent_coef as f32;
                }
                s.actor_grad.iter_mut().for_each(|g| *g = 0.0);
                self.actor.backward(&mut s.actor_tape, &s.dmu, Some(&mut s.actor_grad), None);
                clip_joint(&mut s.actor_grad, &mut s.log_std_grad, self.cfg.max_grad_norm);
                self.actor_opt.step(&mut self.actor.params, &s.actor_grad);
                self.log_std_opt.step(&mut self.log_std, &s.log_std_grad);

                // Value: vf_coef * mean((V - R)^2) / 2.
                let v = self.critic.forward(&s.obs, b, &mut s.critic_tape);
                s.dv.clear();
                for (r, &k) in chunk.iter().enumerate() {
                    s.dv.push((self.cfg.vf_coef * (v[r] as f64 - samples[k].ret) / b as f64) as f32);
                }
                s.critic_grad.iter_mut().for_each(|g| *g = 0.0);
                self.critic.backward(&mut s.critic_tape, &s.dv, Some(&mut s.critic_grad), None);
                clip_grad_norm(&mut s.critic_grad, self.cfg.max_grad_norm);
                self.critic_opt.step(&mut self.critic.params, &s.critic_grad);
                self.updates += 1;
            }
        }
    }
}

/// Global-norm clipping over the actor's weights and its log-std together.
fn clip_joint(a: &mut [f32], b: &mut [f32], max_norm: f64) {
    let norm = a.iter().chain(b.iter()).map(|g| (*g as f64).powi(2)).sum::<f64>().sqrt();
    if norm > max_norm {
        let s = (max_norm / norm) as f32;
        a.iter_mut().chain(b.iter_mut()).for_each(|g| *g *= s);
    }
}

/// The registry entry (`--algo ppo`, section `[ppo]`).
pub struct PpoAlgorithm;

impl Algorithm for PpoAlgorithm {
    fn name(&self) -> &'static str {
        "ppo"
    }

    fn about(&self) -> &'static str {
        "proximal policy optimisation (Schulman et al. 2017), on-policy"
    }

    fn config(&self, section: Option<&serde_json::Value>) -> Result<serde_json::Value, LearnError> {
        complete_section::<PpoConfig>(self.name(), section)
    }

    fn n_envs(&self, cfg: &AlgoConfigs) -> Result<usize, LearnError> {
        Ok(cfg.section::<PpoConfig>("ppo")?.n_envs.max(1))
    }

    fn learner(&self, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(Ppo::new(cfg.section("ppo")?, obs_dim, act_dim, seed)))
    }

    fn decode(&self, bytes: &[u8]) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(decode::<Ppo>(bytes)?))
    }
}

impl Learner for Ppo {
    fn round(&mut self, envs: &mut [&mut dyn ParallelEnv]) -> Result<Vec<EpisodeStats>, EnvError> {
        Ppo::round(self, envs)
    }

    fn policy(&self) -> ActorPolicy {
        Ppo::policy(self)
    }

    fn samples(&self) -> u64 {
        self.samples
    }

    fn updates(&self) -> u64 {
        self.updates
    }

    fn rounds(&self) -> u64 {
        self.round
    }

    fn to_bytes(&self) -> Result<Vec<u8>, LearnError> {
        encode(self)
    }

    fn init_actor(&mut self, policy: &ActorPolicy) -> Result<(), LearnError> {
        Ppo::init_actor(self, policy)
    }
}
