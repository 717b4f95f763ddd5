//! Multi-agent reinforcement learning through pseudo-environments (the paper's MARL, Methods
//! "Multi-agent RL"; Guastoni et al. 2023 for the channel, Suárez et al. 2025 for the cylinder).
//!
//! An environment that declares its agents ([`Env::agents`]) is split into one pseudo-environment
//! per agent ([`pseudo_envs`]). Every agent sees its local observation (a subset of the global
//! one), sets its own actuators and gets the global reward or its own ([`AgentReward`]). All
//! agents share one policy: a learner trains on the pseudo-environments exactly as on ordinary
//! ones, their transitions going into its one replay buffer or rollout. The actuators are a
//! partition (every global action belongs to exactly one agent) and local rewards come from
//! disjoint parts of the flow, so no part of the flow is counted twice in the shared data.
//!
//! The pseudo-environments of one flow share it. [`crate::rollout::step_all`] first hands every
//! agent's action to the flow ([`Env::submit`], one after another): the last agent's hand-over
//! steps the flow once. Then each `step` only collects its agent's result. Resets go the same way.
//! A trained actor acts on the global environment through [`crate::policy::ActorPolicy`] with
//! its [`Agents`] attached.

use std::sync::{Arc, Mutex};

use serde::{Deserialize, Serialize};

use crate::env::{DifferentiableEnv, Env, EnvError, Info, StepResult};
use crate::spaces::BoxSpace;

/// The reward each agent learns from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum AgentReward {
    /// The environment's reward, the same for every agent.
    #[default]
    Global,
    /// Each agent's own ([`Env::agent_rewards`]).
    Local,
}

/// How an environment's observations and actions split into agents.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Agents {
    /// The global observation and action dimensions.
    pub obs_dim: usize,
    pub act_dim: usize,
    /// Per agent, the global observation indices of its local observation, in order.
    pub obs: Vec<Vec<usize>>,
    /// Per agent, the global action indices it sets, in order.
    pub act: Vec<Vec<usize>>,
    pub reward: AgentReward,
}

impl Agents {
    /// Checks the decomposition: at least one agent, the same local sizes for every agent (one
    /// shared policy), indices inside the global spaces, every global action set by exactly one
    /// agent.
    pub fn new(obs_dim: usize, act_dim: usize, obs: Vec<Vec<usize>>, act: Vec<Vec<usize>>, reward: AgentReward) -> Result<Self, String> {
        let a = Agents {
            obs_dim,
            act_dim,
            obs,
            act,
            reward,
        };
        a.check()?;
        Ok(a)
    }

    /// The checks of [`Agents::new`] (also for a decomposition read from a file).
    pub fn check(&self) -> Result<(), String> {
        let n = self.obs.len();
        if n == 0 || self.act.len() != n {
            return Err(format!(
                "{} observation sets and {} action sets: one of each per agent, at least one agent",
                n,
                self.act.len()
            ));
        }
        for (what, sets, dim) in [("observation", &self.obs, self.obs_dim), ("action", &self.act, self.act_dim)] {
            let len = sets[0].len();
            if len == 0 || sets.iter().any(|s| s.len() != len) {
                return Err(format!("every agent needs the same number (at least one) of {what}s"));
            }
            if let Some(i) = sets.iter().flatten().find(|i| **i >= dim) {
                return Err(format!("{what} index {i} is outside the global {what} space of {dim}"));
            }
        }
        let mut owner = vec![usize::MAX; self.act_dim];
        for (agent, set) in self.act.iter().enumerate() {
            for &i in set {
                if owner[i] != usize::MAX {
                    return Err(format!(
                        "action {i} is set by agents {} and {agent}: actuators may not overlap",
                        owner[i]
                    ));
                }
                owner[i] = agent;
            }
        }
        if let Some(i) = owner.iter().position(|o| *o == usize::MAX) {
            return Err(format!("action {i} belongs to no agent"));
        }
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.obs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.obs.is_empty()
    }

    pub fn local_obs_dim(&self) -> usize {
        self.obs[0].len()
    }

    pub fn local_act_dim(&self) -> usize {
        self.act[0].len()
    }

    /// Agent `agent`'s local observation out of the global one.
    pub fn gather(&self, agent: usize, global: &[f64], local: &mut Vec<f64>) {
        local.clear();
        local.extend(self.obs[agent].iter().map(|&i| global[i]));
    }

    /// Agent `agent`'s local action written into the global one.
    pub fn scatter(&self, agent: usize, local: &[f64], global: &mut [f64]) {
        for (&i, a) in self.act[agent].iter().zip(local) {
            global[i] = *a;
        }
    }

    fn local_space(set: &[usize], global: &BoxSpace) -> BoxSpace {
        BoxSpace {
            low: set.iter().map(|&i| global.low[i]).collect(),
            high: set.iter().map(|&i| global.high[i]).collect(),
        }
    }
}

/// What the agents of one flow have handed over so far, and the results they have not collected.
struct Group<E> {
    env: E,
    agents: Agents,
    space: (BoxSpace, BoxSpace),
    seeds: Vec<Option<u64>>,
    resets: Vec<Option<(Vec<f64>, Info)>>,
    action: Vec<f64>,
    acted: Vec<bool>,
    results: Vec<Option<StepResult>>,
}

impl<E: Env> Group<E> {
    fn submit_reset(&mut self, agent: usize, seed: u64) -> Result<(), EnvError> {
        self.seeds[agent] = Some(seed);
        if self.seeds.iter().any(Option::is_none) {
            return Ok(());
        }
        // The flow starts from the first agent's seed; the seeds are cleared for the next reset.
        let seed = self.seeds[0].unwrap_or(seed);
        self.seeds.iter_mut().for_each(|s| *s = None);
        self.results.iter_mut().for_each(|r| *r = None);
        self.acted.iter_mut().for_each(|a| *a = false);
        let (obs, info) = self.env.reset(seed)?;
        for (i, slot) in self.resets.iter_mut().enumerate() {
            let mut local = vec![];
            self.agents.gather(i, &obs, &mut local);
            *slot = Some((local, info.clone()));
        }
        Ok(())
    }

    fn submit(&mut self, agent: usize, action: &[f64]) -> Result<(), EnvError> {
        let expected = self.agents.local_act_dim();
        if action.len() != expected {
            return Err(EnvError::ActionShape {
                expected,
                got: action.len(),
            });
        }
        self.agents.scatter(agent, action, &mut self.action);
        self.acted[agent] = true;
        if self.acted.iter().any(|a| !a) {
            return Ok(());
        }
        self.acted.iter_mut().for_each(|a| *a = false);
        let r = self.env.step(&self.action)?;
        let local = match self.agents.reward {
            AgentReward::Global => None,
            AgentReward::Local => {
                let rewards = self.env.agent_rewards();
                if rewards.len() != self.agents.len() {
                    return Err(EnvError::Backend(format!(
                        "local rewards were asked for, but the environment gave {} for {} agents",
                        rewards.len(),
                        self.agents.len()
                    )));
                }
                Some(rewards)
            }
        };
        for (i, slot) in self.results.iter_mut().enumerate() {
            let mut obs = vec![];
            self.agents.gather(i, &r.obs, &mut obs);
            *slot = Some(StepResult {
                obs,
                reward: local.as_ref().map_or(r.reward, |l| l[i]),
                terminated: r.terminated,
                truncated: r.truncated,
                info: r.info.clone(),
            });
        }
        Ok(())
    }
}

/// One agent's view of a flow shared with the other agents of its group.
pub struct PseudoEnv<E> {
    group: Arc<Mutex<Group<E>>>,
    agent: usize,
    agents: usize,
}

impl<E> PseudoEnv<E> {
    fn lock(&self) -> Result<std::sync::MutexGuard<'_, Group<E>>, EnvError> {
        self.group
            .lock()
            .map_err(|_| EnvError::Backend("another agent's step panicked while it held the shared flow; restart the run".into()))
    }

    fn waiting(&self, what: &str) -> EnvError {
        EnvError::Backend(format!(
            "agent {} of {}: the other agents sharing its flow have not {what}; step pseudo-environments \
             together with rollout::step_all / reset_all",
            self.agent, self.agents
        ))
    }
}

/// One pseudo-environment per agent of `env` (its [`Env::agents`]), in agent order.
pub fn pseudo_envs<E: Env>(env: E) -> Result<Vec<PseudoEnv<E>>, EnvError> {
    let agents = env
        .agents()
        .ok_or_else(|| EnvError::InvalidSpec("this environment declares no agents; train it as one agent".into()))?;
    agents.check().map_err(EnvError::InvalidSpec)?;
    let n = agents.len();
    let space = (
        Agents::local_space(&agents.obs[0], &env.observation_space()),
        Agents::local_space(&agents.act[0], &env.action_space()),
    );
    let group = Arc::new(Mutex::new(Group {
        action: vec![0.0; agents.act_dim],
        env,
        agents,
        space,
        seeds: vec![None; n],
        resets: vec![None; n],
        acted: vec![false; n],
        results: vec![None; n],
    }));
    Ok((0..n)
        .map(|agent| PseudoEnv {
            group: group.clone(),
            agent,
            agents: n,
        })
        .collect())
}

impl<E: Env> Env for PseudoEnv<E> {
    /// The first agent's bounds stand for all (every agent sees the same kind of quantities).
    fn observation_space(&self) -> BoxSpace {
        self.lock()
            .map(|g| g.space.0.clone())
            .unwrap_or_else(|_| BoxSpace::uniform(0, 0.0, 0.0))
    }

    fn action_space(&self) -> BoxSpace {
        self.lock()
            .map(|g| g.space.1.clone())
            .unwrap_or_else(|_| BoxSpace::uniform(0, 0.0, 0.0))
    }

    fn submit_reset(&mut self, seed: u64) -> Result<(), EnvError> {
        self.lock()?.submit_reset(self.agent, seed)
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        let mut g = self.lock()?;
        if g.resets[self.agent].is_none() && g.seeds[self.agent].is_none() {
            g.submit_reset(self.agent, seed)?;
        }
        g.resets[self.agent].take().ok_or_else(|| self.waiting("reset"))
    }

    fn submit(&mut self, action: &[f64]) -> Result<(), EnvError> {
        self.lock()?.submit(self.agent, action)
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        let mut g = self.lock()?;
        if g.results[self.agent].is_none() && !g.acted[self.agent] {
            g.submit(self.agent, action)?;
        }
        g.results[self.agent].take().ok_or_else(|| self.waiting("acted"))
    }
}

impl<E: Env> DifferentiableEnv for PseudoEnv<E> {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend(
            "gradients are not taken through multi-agent pseudo-environments; train the flow as one agent".into(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rollout::{reset_all, step_all};
    use crate::toy::Oscillators;

    #[test]
    fn refuses_overlapping_or_missing_actuators() {
        let obs = vec![vec![0], vec![1]];
        assert!(Agents::new(2, 2, obs.clone(), vec![vec![0], vec![0]], AgentReward::Global)
            .unwrap_err()
            .contains("may not overlap"));
        assert!(Agents::new(2, 3, obs.clone(), vec![vec![0], vec![1]], AgentReward::Global)
            .unwrap_err()
            .contains("action 2 belongs to no agent"));
        assert!(Agents::new(2, 2, vec![vec![0], vec![0, 1]], vec![vec![0], vec![1]], AgentReward::Global).is_err());
        assert!(Agents::new(2, 2, obs, vec![vec![0], vec![5]], AgentReward::Global).is_err());
    }

    /// Two groups of pseudo-environments stepped through step_all are, bitwise, the two global
    /// environments stepped with the scattered actions.
    #[test]
    fn pseudo_envs_are_the_global_env_split() {
        for reward in [AgentReward::Global, AgentReward::Local] {
            let make = || Oscillators::new(3, reward);
            let mut pseudo: Vec<_> = pseudo_envs(make())
                .unwrap()
                .into_iter()
                .chain(pseudo_envs(make()).unwrap())
                .collect();
            let mut global = [make(), make()];
            let seeds: Vec<u64> = vec![11, 0, 0, 12, 0, 0];
            let starts = reset_all(&mut pseudo, &seeds).unwrap();
            let g0 = [global[0].reset(11).unwrap().0, global[1].reset(12).unwrap().0];
            for (k, (o, _)) in starts.iter().enumerate() {
                assert_eq!(o, &g0[k / 3][2 * (k % 3)..2 * (k % 3) + 2]);
            }
            for t in 0..5 {
                let actions: Vec<Vec<f64>> = (0..6).map(|k| vec![0.1 * k as f64 - 0.2 * t as f64]).collect();
                let results = step_all(&mut pseudo, &actions, &[true; 6]).unwrap();
                for (f, env) in global.iter_mut().enumerate() {
                    let a: Vec<f64> = (0..3).map(|i| actions[3 * f + i][0]).collect();
                    let r = env.step(&a).unwrap();
                    let locals = env.agent_rewards();
                    for i in 0..3 {
                        let p = results[3 * f + i].as_ref().unwrap();
                        assert_eq!(p.obs, r.obs[2 * i..2 * i + 2]);
                        let want = if reward == AgentReward::Local { locals[i] } else { r.reward };
                        assert_eq!(p.reward.to_bits(), want.to_bits());
                        assert_eq!(p.truncated, r.truncated);
                    }
                }
            }
        }
    }

    /// The actor with agents attached acts on the global observation as the bare actor acts on
    /// each agent's local one (to f32 rounding).
    #[test]
    fn a_shared_actor_acts_for_every_agent() {
        use crate::nn::{Activation, Init, Mlp};
        use crate::policy::{ActorPolicy, Policy};
        let mut rng = crate::rng::Rng::seed(3);
        let net = Mlp::new(&[2, 8, 1], Activation::Tanh, Activation::Tanh, Init::FanIn, Init::FanIn, &mut rng);
        let mut local = ActorPolicy::new("t", net, None, 10.0);
        let agents = Oscillators::new(3, AgentReward::Global).agents().unwrap();
        let mut shared = local.clone().with_agents(agents);
        assert_eq!((shared.obs_dim(), shared.act_dim()), (6, 3));
        shared.validate().unwrap();
        let obs = [0.3, -0.2, 1.5, 0.7, -0.9, 0.1];
        let mut global = [0.0; 3];
        shared.act(&obs, &Info::default(), &mut global);
        for i in 0..3 {
            let mut a = [0.0];
            local.act(&obs[2 * i..2 * i + 2], &Info::default(), &mut a);
            // One batch of three rows against three batches of one: f32 sums in another order.
            assert!((a[0] - global[i]).abs() < 1e-6, "agent {i}: {} against {}", global[i], a[0]);
        }
    }

    #[test]
    fn a_lone_step_names_the_missing_agents() {
        let mut pseudo = pseudo_envs(Oscillators::new(2, AgentReward::Global)).unwrap();
        reset_all(&mut pseudo, &[1, 1]).unwrap();
        let e = pseudo[0].step(&[0.0]).unwrap_err().to_string();
        assert!(e.contains("agent 0 of 2") && e.contains("step_all"), "{e}");
    }
}
