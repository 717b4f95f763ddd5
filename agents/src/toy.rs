//! Cheap control tasks for testing learners in seconds (no flows: they live in `hgym`).

use crate::env::{Env, EnvError, Info, StepResult};
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
        let mut info = Info::default();
        info.set("t", 0.0);
        Ok((vec![self.x, self.v], info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        if action.len() != 1 {
            return Err(EnvError::ActionShape {
                expected: 1,
                got: action.len(),
            });
        }
        if !action[0].is_finite() {
            return Err(EnvError::NonFiniteAction {
                index: 0,
                value: action[0],
            });
        }
        let u = action[0].clamp(-1.0, 1.0);
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
        info.set("clipped", if u != action[0] { 1.0 } else { 0.0 });
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
