//! Cheap control tasks for testing learners in seconds (no flows: they live in `hgym`).

use crate::env::{checked_action, DifferentiableEnv, Env, EnvError, Info, StepResult};
use crate::multi::{AgentReward, Agents};
use crate::rng::Rng;
use crate::spaces::BoxSpace;

/// An unstable linear oscillator to be stabilised:
/// `x' = v, v' = -omega^2 x + 2 zeta omega v + b u` (negative damping `zeta > 0` makes every
/// uncontrolled trajectory grow like `exp(zeta omega t)`), advanced by symplectic Euler with
/// step `dt`. Observation `(x, v)`, action `u` in [-1, 1], reward
/// `-(x^2 + 0.1 v^2 + 0.01 u^2)`. The episode is truncated after `horizon` steps and
/// terminates (a real terminal state) if `|x| > 10`. Initial state uniform in [-1, 1]^2.
#[derive(Clone, Debug)]
pub struct Oscillator {
    pub omega: f64,
    pub zeta: f64,
    pub gain: f64,
    pub dt: f64,
    pub horizon: usize,
    x: f64,
    v: f64,
    k: usize,
    live: bool,
    /// `(x, v, u)` before each step of the episode (for the adjoint).
    history: Vec<(f64, f64, f64)>,
}

impl Default for Oscillator {
    fn default() -> Self {
        Oscillator {
            omega: 1.0,
            zeta: 0.1,
            gain: 2.0,
            dt: 0.1,
            horizon: 100,
            x: 0.0,
            v: 0.0,
            k: 0,
            live: false,
            history: vec![],
        }
    }
}

impl Env for Oscillator {
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(2, -10.0, 10.0)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(1)
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        let mut rng = Rng::seed(seed);
        self.x = 2.0 * rng.uniform() - 1.0;
        self.v = 2.0 * rng.uniform() - 1.0;
        self.k = 0;
        self.live = true;
        self.history.clear();
        let mut info = Info::default();
        info.set("t", 0.0);
        Ok((vec![self.x, self.v], info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let u = a[0];
        self.history.push((self.x, self.v, u));
        let (w, z) = (self.omega, self.zeta);
        self.v += self.dt * (-w * w * self.x + 2.0 * z * w * self.v + self.gain * u);
        self.x += self.dt * self.v;
        self.k += 1;
        let reward = -(self.x * self.x + 0.1 * self.v * self.v + 0.01 * u * u);
        let terminated = self.x.abs() > 10.0;
        let truncated = !terminated && self.k >= self.horizon;
        self.live = !(terminated || truncated);
        let mut info = Info::default();
        info.set("t", self.k as f64 * self.dt);
        info.set("x", self.x);
        info.set("clipped", clipped as f64);
        if terminated {
            info.set_text("reason", "|x| exceeded 10");
        }
        Ok(StepResult {
            obs: vec![self.x.clamp(-10.0, 10.0), self.v.clamp(-10.0, 10.0)],
            reward,
            terminated,
            truncated,
            info,
        })
    }
}

impl DifferentiableEnv for Oscillator {
    /// Reverse sweep of the symplectic-Euler step over the last `k` steps.
    fn reward_action_gradients(&mut self, k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        let k = k.min(self.history.len());
        let start = self.history.len() - k;
        let (w, z, dt, b) = (self.omega, self.zeta, self.dt, self.gain);
        // Cotangents of (x, v) after the current step.
        let (mut lx, mut lv) = (0.0, 0.0);
        let mut out = vec![vec![0.0]; k];
        for j in (start..self.history.len()).rev() {
            let (x, v, u) = self.history[j];
            let v1 = v + dt * (-w * w * x + 2.0 * z * w * v + b * u);
            let x1 = x + dt * v1;
            // r = -(x1^2 + 0.1 v1^2 + 0.01 u^2)
            lx += -2.0 * x1;
            lv += -0.2 * v1;
            // x1 = x + dt v1
            let lv1 = lv + dt * lx;
            let lx0 = lx;
            // v1 = v + dt (-w^2 x + 2 z w v + b u)
            out[j - start][0] = lv1 * dt * b - 0.02 * u;
            lx = lx0 - lv1 * dt * w * w;
            lv = lv1 * (1.0 + dt * 2.0 * z * w);
        }
        Ok(out)
    }
}

/// `n` independent [`Oscillator`]s in one environment, each its own agent
/// ([`crate::multi`]): observation `(x_0, v_0, x_1, v_1, ...)`, action `(u_0, u_1, ...)`, reward
/// the mean of the oscillators' rewards, each oscillator's reward its agent's local one. The
/// oscillator `i` starts from the seed `seed + i`; the episode ends when the first one does.
#[derive(Clone, Debug)]
pub struct Oscillators {
    parts: Vec<Oscillator>,
    rewards: Vec<f64>,
    reward: AgentReward,
}

impl Oscillators {
    pub fn new(n: usize, reward: AgentReward) -> Self {
        Oscillators {
            parts: vec![Oscillator::default(); n],
            rewards: vec![0.0; n],
            reward,
        }
    }
}

impl Env for Oscillators {
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(2 * self.parts.len(), -10.0, 10.0)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.parts.len())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        let mut obs = vec![];
        for (i, p) in self.parts.iter_mut().enumerate() {
            obs.extend(p.reset(seed.wrapping_add(i as u64))?.0);
        }
        let mut info = Info::default();
        info.set("t", 0.0);
        Ok((obs, info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let mut out = StepResult {
            obs: vec![],
            reward: 0.0,
            terminated: false,
            truncated: false,
            info: Info::default(),
        };
        for (i, p) in self.parts.iter_mut().enumerate() {
            let r = p.step(&a[i..i + 1])?;
            out.obs.extend(r.obs);
            self.rewards[i] = r.reward;
            out.terminated |= r.terminated;
            out.truncated |= r.truncated;
            out.info = r.info;
        }
        out.truncated &= !out.terminated;
        if out.terminated || out.truncated {
            // Every oscillator's episode ends with the first one's.
            self.parts.iter_mut().for_each(|p| p.live = false);
        }
        out.reward = self.rewards.iter().sum::<f64>() / self.parts.len() as f64;
        out.info.set("clipped", clipped as f64);
        Ok(out)
    }

    fn agents(&self) -> Option<Agents> {
        let n = self.parts.len();
        Agents::new(
            2 * n,
            n,
            (0..n).map(|i| vec![2 * i, 2 * i + 1]).collect(),
            (0..n).map(|i| vec![i]).collect(),
            self.reward,
        )
        .ok()
    }

    fn agent_rewards(&self) -> Vec<f64> {
        self.rewards.clone()
    }
}

impl DifferentiableEnv for Oscillators {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend("Oscillators has no adjoint".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The adjoint sweep against central differences of the segment's summed reward.
    #[test]
    fn oscillator_reward_gradients_match_finite_differences() {
        let actions = [0.3, -0.7, 0.5, 0.1, -0.2];
        let run = |acts: &[f64]| -> f64 {
            let mut env = Oscillator::default();
            env.reset(5).unwrap();
            acts.iter().map(|a| env.step(&[*a]).unwrap().reward).sum()
        };
        let mut env = Oscillator::default();
        env.reset(5).unwrap();
        for a in actions {
            env.step(&[a]).unwrap();
        }
        let g = env.reward_action_gradients(actions.len()).unwrap();
        for j in 0..actions.len() {
            let h = 1e-6;
            let (mut p, mut m) = (actions, actions);
            p[j] += h;
            m[j] -= h;
            let fd = (run(&p) - run(&m)) / (2.0 * h);
            assert!(
                (fd - g[j][0]).abs() < 1e-7 * (1.0 + fd.abs()),
                "action {j}: adjoint {} vs {fd}",
                g[j][0]
            );
        }
    }
}
