//! TD3 (Fujimoto, van Hoof & Meger 2018): deterministic actor, twin critics with the minimum
//! in the target `y = r + gamma (1 - terminal) min_i Q'_i(s', clip(mu'(s') + clip(N(0, sigma),
//! -c, c), -1, 1))`, actor updated every `policy_delay` critic updates through Q_1, Polyak
//! target updates. DDPG (Lillicrap et al. 2016) is this update with one critic, no smoothing,
//! no delay and Ornstein-Uhlenbeck exploration; [`crate::ddpg`] builds it from here.
//!
//! Collection: every environment steps in parallel; each transition is followed by one
//! gradient update (SB3's `train_freq = 1`, `gradient_steps = 1` per environment step), or
//! `gradient_steps` updates follow each lockstep step of all environments.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::buffer::{Batch, ReplayBuffer};
use crate::env::{Env, EnvError};
use crate::learn::{complete_section, decode, encode, AlgoConfigs, Algorithm, LearnError, Learner, ParallelEnv};
use crate::nn::{Activation, Adam, Init, Mlp, Tape};
use crate::noise::OrnsteinUhlenbeck;
use crate::policy::ActorPolicy;
use crate::rng::Rng;
use crate::rollout::{episode_seed, reset_all, step_all, EpisodeAccumulator, EpisodeStats};
use crate::transplant::{Parts, SpaceMap};

/// TD3 hyperparameters. Defaults: the paper's stated values (sigma 0.2 clipped at 0.5, delay 2,
/// tau 0.005, batch 256, 256x256 networks, replay 1e5), the rest from CleanRL's `td3_continuous_action`
/// (gamma 0.99, lr 3e-4, Gaussian exploration 0.1) with a shorter random warm-up.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Td3Config {
    pub hidden: Vec<usize>,
    pub gamma: f64,
    pub tau: f64,
    pub actor_lr: f64,
    pub critic_lr: f64,
    pub batch_size: usize,
    pub buffer_size: usize,
    /// Uniformly random actions for this many transitions before learning starts.
    pub learning_starts: usize,
    /// Std of the Gaussian exploration noise (ignored when `ou_noise` is set).
    pub exploration_noise: f64,
    /// Ornstein-Uhlenbeck exploration `(theta, sigma)` instead of Gaussian.
    pub ou_noise: Option<(f64, f64)>,
    pub twin: bool,
    pub policy_delay: usize,
    pub target_noise: f64,
    pub target_noise_clip: f64,
    /// Environments stepped in parallel.
    pub n_envs: usize,
    /// Gradient updates after each lockstep step of the environments; absent: one per collected
    /// transition (SB3's `gradient_steps = -1`). Multi-agent runs collect one transition per
    /// agent per step and set a number here.
    pub gradient_steps: Option<usize>,
    /// Weight `lambda` of the actor's action penalty: the actor minimises
    /// `-Q_1(s, mu(s)) + lambda |mu(s)|^2` (OpenAI Baselines' `action_l2`, Andrychowicz et al.
    /// 2017). 0 is TD3 itself. It keeps actions that no reward distinguishes (such as the common
    /// part of zero-net-mass-flux actuators, which the flow never sees) from drifting into the
    /// saturation of the actor's tanh, where its gradient vanishes.
    pub action_l2: f64,
}

impl Default for Td3Config {
    fn default() -> Self {
        Td3Config {
            hidden: vec![256, 256],
            gamma: 0.99,
            tau: 0.005,
            actor_lr: 3e-4,
            critic_lr: 3e-4,
            batch_size: 256,
            buffer_size: 100_000,
            learning_starts: 1000,
            exploration_noise: 0.1,
            ou_noise: None,
            twin: true,
            policy_delay: 2,
            target_noise: 0.2,
            target_noise_clip: 0.5,
            n_envs: 2,
            gradient_steps: None,
            action_l2: 0.0,
        }
    }
}

/// Network and optimiser of one critic with its target.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Critic {
    net: Mlp<f32>,
    target: Mlp<f32>,
    opt: Adam<f32>,
}

/// Reused buffers (not checkpointed; rebuilt on first use).
#[derive(Clone, Debug, Default)]
struct Scratch {
    batch: Batch,
    sa: Vec<f32>,
    sa_next: Vec<f32>,
    y: Vec<f32>,
    dq: Vec<f32>,
    dsa: Vec<f32>,
    da: Vec<f32>,
    actor_grad: Vec<f32>,
    critic_grads: Vec<Vec<f32>>,
    critic_dq: Vec<Vec<f32>>,
    actor_tape: Tape<f32>,
    critic_tapes: Vec<Tape<f32>>,
    obs32: Vec<f32>,
}

/// A TD3 (or DDPG) learner with everything a checkpoint needs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Td3 {
    pub name: String,
    pub cfg: Td3Config,
    pub seed: u64,
    obs_dim: usize,
    act_dim: usize,
    actor: Mlp<f32>,
    actor_target: Mlp<f32>,
    actor_opt: Adam<f32>,
    critics: Vec<Critic>,
    buffer: ReplayBuffer,
    rng: Rng,
    ou: Vec<OrnsteinUhlenbeck>,
    pub samples: u64,
    pub updates: u64,
    pub round: u64,
    /// The actor is a trained policy (`init_actor`): it acts, with its exploration noise, from
    /// the first transition instead of the uniformly random warm-up, which would fill the
    /// buffer with what a fine-tuned run has no use for and teach the critics that policy.
    warm: bool,
    #[serde(skip)]
    scratch: Scratch,
}

/// Concatenates `obs` (b x o) and `act` (b x a) row by row into `out` (b x (o + a)).
fn concat_rows(obs: &[f32], act: &[f32], o: usize, a: usize, out: &mut Vec<f32>) {
    out.clear();
    for (so, sa) in obs.chunks_exact(o).zip(act.chunks_exact(a)) {
        out.extend_from_slice(so);
        out.extend_from_slice(sa);
    }
}

impl Td3 {
    pub fn new(name: &str, cfg: Td3Config, obs_dim: usize, act_dim: usize, seed: u64) -> Self {
        let mut rng = Rng::seed(seed);
        let mut sizes = vec![obs_dim];
        sizes.extend(&cfg.hidden);
        sizes.push(act_dim);
        let actor = Mlp::new(&sizes, Activation::Relu, Activation::Tanh, Init::FanIn, Init::FanIn, &mut rng);
        let mut csizes = vec![obs_dim + act_dim];
        csizes.extend(&cfg.hidden);
        csizes.push(1);
        let n_critics = if cfg.twin { 2 } else { 1 };
        let critics = (0..n_critics)
            .map(|_| {
                let net = Mlp::new(&csizes, Activation::Relu, Activation::Identity, Init::FanIn, Init::FanIn, &mut rng);
                Critic {
                    target: net.clone(),
                    opt: Adam::new(net.params.len(), cfg.critic_lr),
                    net,
                }
            })
            .collect();
        let ou = match cfg.ou_noise {
            Some((theta, sigma)) => (0..cfg.n_envs).map(|_| OrnsteinUhlenbeck::new(act_dim, theta, sigma)).collect(),
            None => vec![],
        };
        Td3 {
            name: name.to_string(),
            seed,
            obs_dim,
            act_dim,
            actor_target: actor.clone(),
            actor_opt: Adam::new(actor.params.len(), cfg.actor_lr),
            actor,
            critics,
            buffer: ReplayBuffer::new(cfg.buffer_size, obs_dim, act_dim),
            rng,
            ou,
            samples: 0,
            updates: 0,
            warm: false,
            round: 0,
            cfg,
            scratch: Scratch::default(),
        }
    }

    /// The deterministic policy `mu(s)`.
    pub fn policy(&self) -> ActorPolicy {
        ActorPolicy::new(&self.name, self.actor.clone(), None, 10.0)
    }

    /// Exploratory action for environment `env`: random before `learning_starts` (unless the
    /// actor is a trained policy), then `clip(mu(s) + noise)`.
    fn explore(&mut self, env: usize, obs: &[f64], action: &mut [f64]) {
        if !self.warm && (self.samples as usize) < self.cfg.learning_starts {
            action.iter_mut().for_each(|a| *a = 2.0 * self.rng.uniform() - 1.0);
            return;
        }
        let s = &mut self.scratch;
        s.obs32.clear();
        s.obs32.extend(obs.iter().map(|v| *v as f32));
        let mu = self.actor.forward(&s.obs32, 1, &mut s.actor_tape);
        for (j, a) in action.iter_mut().enumerate() {
            let noise = if let Some(ou) = self.ou.get_mut(env) {
                ou.x[j]
            } else {
                self.cfg.exploration_noise * self.rng.normal()
            };
            *a = (mu[j] as f64 + noise).clamp(-1.0, 1.0);
        }
        if let Some(ou) = self.ou.get_mut(env) {
            ou.sample(&mut self.rng);
        }
    }

    /// One round: an episode on every environment (in lockstep, stepped in parallel), one
    /// gradient update per collected transition once learning has started.
    pub fn round<E: Env + Send>(&mut self, envs: &mut [E]) -> Result<Vec<EpisodeStats>, EnvError> {
        let n = envs.len();
        let seeds: Vec<u64> = (0..n).map(|i| episode_seed(self.seed, self.round, i)).collect();
        let mut obs: Vec<Vec<f64>> = reset_all(envs, &seeds)?.into_iter().map(|(o, _)| o).collect();
        if let Some((theta, sigma)) = self.cfg.ou_noise {
            // One process per environment, however many the round brings (multi-agent runs).
            while self.ou.len() < n {
                self.ou.push(OrnsteinUhlenbeck::new(self.act_dim, theta, sigma));
            }
        }
        self.ou.iter_mut().for_each(|o| o.reset());
        let mut active = vec![true; n];
        let mut actions = vec![vec![0.0; self.act_dim]; n];
        let mut acc = vec![EpisodeAccumulator::default(); n];
        while active.iter().any(|a| *a) {
            for i in 0..n {
                if active[i] {
                    let mut a = std::mem::take(&mut actions[i]);
                    self.explore(i, &obs[i], &mut a);
                    actions[i] = a;
                }
            }
            let results = step_all(envs, &actions, &active)?;
            let mut collected = 0;
            for (i, r) in results.into_iter().enumerate() {
                let Some(r) = r else { continue };
                self.buffer.push(&obs[i], &actions[i], r.reward, &r.obs, r.terminated);
                acc[i].add(&r);
                self.samples += 1;
                collected += 1;
                if r.terminated || r.truncated {
                    active[i] = false;
                }
                obs[i] = r.obs;
            }
            if self.samples as usize >= self.cfg.learning_starts {
                for _ in 0..self.cfg.gradient_steps.unwrap_or(collected) {
                    self.update();
                }
            }
        }
        self.round += 1;
        Ok(acc.into_iter().map(|a| a.finish()).collect())
    }

    /// Stores a transition (for replaying recorded data, and for benchmarks).
    pub fn remember(&mut self, obs: &[f64], action: &[f64], reward: f64, next_obs: &[f64], terminal: bool) {
        self.buffer.push(obs, action, reward, next_obs, terminal);
    }

    /// One gradient update from a sampled minibatch.
    pub fn update(&mut self) {
        let (o, a, b) = (self.obs_dim, self.act_dim, self.cfg.batch_size);
        let s = &mut self.scratch;
        if s.critic_tapes.len() != self.critics.len() {
            s.critic_tapes = vec![Tape::new(); self.critics.len()];
            s.critic_grads = self.critics.iter().map(|c| vec![0.0; c.net.params.len()]).collect();
            s.critic_dq = vec![vec![0.0; b]; self.critics.len()];
            s.actor_grad = vec![0.0; self.actor.params.len()];
        }
        self.buffer.sample(b, &mut self.rng, &mut s.batch);

        // Target: y = r + gamma (1 - terminal) min_i Q'_i(s', smoothed mu'(s')).
        let next_act = self.actor_target.forward(&s.batch.next_obs, b, &mut s.actor_tape);
        s.da.clear();
        s.da.extend_from_slice(next_act);
        if self.cfg.twin {
            let (sigma, c) = (self.cfg.target_noise, self.cfg.target_noise_clip);
            for v in s.da.iter_mut() {
                let eps = (sigma * self.rng.normal()).clamp(-c, c);
                *v = (*v as f64 + eps).clamp(-1.0, 1.0) as f32;
            }
        }
        concat_rows(&s.batch.next_obs, &s.da, o, a, &mut s.sa_next);
        s.y.clear();
        s.y.resize(b, f32::INFINITY);
        let sa_next = &s.sa_next;
        self.critics.par_iter().zip(s.critic_tapes.par_iter_mut()).for_each(|(c, tape)| {
            c.target.forward(sa_next, b, tape);
        });
        for tape in &s.critic_tapes {
            s.y.iter_mut().zip(tape.output()).for_each(|(y, q)| *y = y.min(*q));
        }
        let gamma = self.cfg.gamma as f32;
        for ((y, r), t) in s.y.iter_mut().zip(&s.batch.reward).zip(&s.batch.terminal) {
            *y = r + gamma * (1.0 - t) * *y;
        }

        // Critics: minimise mean (Q_i(s, a) - y)^2, each on its own core.
        concat_rows(&s.batch.obs, &s.batch.act, o, a, &mut s.sa);
        let (sa, y) = (&s.sa, &s.y);
        self.critics
            .par_iter_mut()
            .zip(s.critic_tapes.par_iter_mut())
            .zip(s.critic_grads.par_iter_mut())
            .zip(s.critic_dq.par_iter_mut())
            .for_each(|(((c, tape), grad), dq)| {
                let q = c.net.forward(sa, b, tape);
                dq.resize(b, 0.0);
                dq.iter_mut()
                    .zip(q.iter().zip(y))
                    .for_each(|(d, (q, y))| *d = 2.0 * (q - y) / b as f32);
                grad.iter_mut().for_each(|g| *g = 0.0);
                c.net.backward(tape, dq, Some(grad), None);
                c.opt.step(&mut c.net.params, grad);
            });
        self.updates += 1;

        // Actor: maximise Q_1(s, mu(s)) - lambda |mu(s)|^2 every `policy_delay` updates, then
        // move the targets.
        if self.updates.is_multiple_of(self.cfg.policy_delay.max(1) as u64) {
            let mu = self.actor.forward(&s.batch.obs, b, &mut s.actor_tape);
            concat_rows(&s.batch.obs, mu, o, a, &mut s.sa);
            let c0 = &self.critics[0];
            c0.net.forward(&s.sa, b, &mut s.critic_tapes[0]);
            s.dq.clear();
            s.dq.resize(b, -1.0 / b as f32);
            s.dsa.resize(b * (o + a), 0.0);
            c0.net.backward(&mut s.critic_tapes[0], &s.dq, None, Some(&mut s.dsa));
            s.da.clear();
            for row in s.dsa.chunks_exact(o + a) {
                s.da.extend_from_slice(&row[o..]);
            }
            if self.cfg.action_l2 > 0.0 {
                let w = (2.0 * self.cfg.action_l2 / b as f64) as f32;
                s.da.iter_mut().zip(s.actor_tape.output()).for_each(|(d, m)| *d += w * m);
            }
            s.actor_grad.iter_mut().for_each(|g| *g = 0.0);
            self.actor.backward(&mut s.actor_tape, &s.da, Some(&mut s.actor_grad), None);
            self.actor_opt.step(&mut self.actor.params, &s.actor_grad);
            let tau = self.cfg.tau;
            self.actor_target.soft_update(&self.actor, tau);
            for c in &mut self.critics {
                c.target.soft_update(&c.net, tau);
            }
        }
    }
}

/// The registry entry (`--algo td3`, section `[td3]`).
pub struct Td3Algorithm;

impl Algorithm for Td3Algorithm {
    fn name(&self) -> &'static str {
        "td3"
    }

    fn about(&self) -> &'static str {
        "twin delayed deep deterministic policy gradient (Fujimoto et al. 2018), off-policy"
    }

    fn config(&self, section: Option<&serde_json::Value>) -> Result<serde_json::Value, LearnError> {
        complete_section::<Td3Config>(self.name(), section)
    }

    fn n_envs(&self, cfg: &AlgoConfigs) -> Result<usize, LearnError> {
        Ok(cfg.section::<Td3Config>("td3")?.n_envs.max(1))
    }

    fn learner(&self, cfg: &AlgoConfigs, obs_dim: usize, act_dim: usize, seed: u64) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(Td3::new("td3", cfg.section("td3")?, obs_dim, act_dim, seed)))
    }

    fn decode(&self, bytes: &[u8]) -> Result<Box<dyn Learner>, LearnError> {
        Ok(Box::new(decode::<Td3>(bytes)?))
    }
}

/// TD3 and DDPG (a TD3 with its additions switched off) share this learner.
impl Learner for Td3 {
    fn round(&mut self, envs: &mut [&mut dyn ParallelEnv]) -> Result<Vec<EpisodeStats>, EnvError> {
        Td3::round(self, envs)
    }

    fn policy(&self) -> ActorPolicy {
        Td3::policy(self)
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
        crate::transplant::fits(policy, &self.actor, &[self.name.as_str()])?;
        if policy.obs_norm.is_some() {
            return Err(LearnError::Init(format!(
                "{} reads raw observations; the policy normalises its own",
                self.name
            )));
        }
        self.actor = policy.net.clone();
        self.actor_target = policy.net.clone();
        self.warm = true;
        Ok(())
    }

    /// The source's critics (and targets) through [`SpaceMap::critic`]; its replay buffer only
    /// between environments of one layout (a transition of another layout has no value for the
    /// target's unmapped observations).
    fn init_critics(&mut self, source: &[u8], map: &SpaceMap, parts: Parts) -> Result<(), LearnError> {
        let src: Td3 = decode(source)?;
        if src.name != self.name || src.critics.len() != self.critics.len() {
            return Err(LearnError::Init(format!(
                "the source learner is {} with {} critics, this one {} with {}",
                src.name,
                src.critics.len(),
                self.name,
                self.critics.len()
            )));
        }
        for (mine, theirs) in self.critics.iter_mut().zip(&src.critics) {
            let (net, target) = (map.critic(&theirs.net), map.critic(&theirs.target));
            if net.sizes != mine.net.sizes {
                return Err(LearnError::Init(format!(
                    "the source critic maps to layers {:?}, this learner's critic has {:?}: give it the source's hidden sizes",
                    net.sizes, mine.net.sizes
                )));
            }
            mine.net = net;
            mine.target = target;
        }
        if parts.buffer {
            if !map.is_identity() {
                return Err(LearnError::Init(
                    "the replay buffer carries over only between environments of one observation and action layout".into(),
                ));
            }
            self.buffer = src.buffer;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--init-from` with critics: the actor and both critics (with targets) arrive mapped, the
    /// buffer only under the identity map, and a foreign network is refused by name.
    #[test]
    fn init_takes_the_actor_critics_and_buffer() {
        let cfg = Td3Config {
            hidden: vec![8, 8],
            ..Td3Config::default()
        };
        let mut src = Td3::new("td3", cfg.clone(), 3, 1, 1);
        src.remember(&[0.1, 0.2, 0.3], &[0.5], -1.0, &[0.2, 0.3, 0.4], false);
        let bytes = encode(&src).unwrap();
        let mut dst = Td3::new("td3", cfg.clone(), 3, 1, 2);
        Learner::init_actor(&mut dst, &src.policy()).unwrap();
        dst.init_critics(
            &bytes,
            &SpaceMap::identity(3, 1),
            Parts {
                critics: true,
                buffer: true,
            },
        )
        .unwrap();
        assert_eq!(
            (dst.actor.clone(), dst.actor_target.clone()),
            (src.actor.clone(), src.actor.clone())
        );
        for (a, b) in dst.critics.iter().zip(&src.critics) {
            assert_eq!((&a.net, &a.target), (&b.net, &b.target));
        }
        assert_eq!(encode(&dst.buffer).unwrap(), encode(&src.buffer).unwrap());

        let fan_out = SpaceMap {
            target_obs_dim: 4,
            obs: vec![1, 2, 3],
            source_act_dim: 1,
            act: vec![Some((0, 1.0)), Some((0, -1.0))],
        };
        let mut wide = Td3::new("td3", cfg.clone(), 4, 2, 3);
        let e = wide
            .init_critics(
                &bytes,
                &fan_out,
                Parts {
                    critics: true,
                    buffer: true,
                },
            )
            .unwrap_err();
        assert!(e.to_string().contains("one observation and action layout"), "{e}");
        let mut ddpg = Td3::new("ddpg", cfg.clone(), 3, 1, 4);
        assert!(Learner::init_actor(&mut ddpg, &src.policy())
            .unwrap_err()
            .to_string()
            .contains("--algo td3"));
        let mut small = Td3::new("td3", Td3Config { hidden: vec![4], ..cfg }, 3, 1, 5);
        assert!(Learner::init_actor(&mut small, &src.policy())
            .unwrap_err()
            .to_string()
            .contains("hidden sizes"));
    }
}
