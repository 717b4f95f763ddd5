//! The environment contract (Gymnasium 1.x semantics).

use std::collections::BTreeMap;

use thiserror::Error;

use crate::multi::Agents;
use crate::spaces::BoxSpace;

/// Extra facts of a reset or step: at least `t`, force coefficients and the physical actuation
/// for flow environments (numbers), and messages such as the reason a run diverged (text).
/// Ordered maps, so that printed output is deterministic.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Info {
    pub values: BTreeMap<String, f64>,
    pub text: BTreeMap<String, String>,
}

impl Info {
    pub fn set(&mut self, key: &str, value: f64) {
        self.values.insert(key.to_string(), value);
    }

    pub fn get(&self, key: &str) -> Option<f64> {
        self.values.get(key).copied()
    }

    pub fn set_text(&mut self, key: &str, value: impl Into<String>) {
        self.text.insert(key.to_string(), value.into());
    }

    pub fn text(&self, key: &str) -> Option<&str> {
        self.text.get(key).map(|s| s.as_str())
    }
}

/// What one `step` returns.
#[derive(Clone, Debug, PartialEq)]
pub struct StepResult {
    pub obs: Vec<f64>,
    pub reward: f64,
    /// A real terminal state (e.g. the solver diverged).
    pub terminated: bool,
    /// True exactly on the episode's last action.
    pub truncated: bool,
    pub info: Info,
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum EnvError {
    #[error("action has {got} components, the action space has {expected}")]
    ActionShape { expected: usize, got: usize },
    #[error("action component {index} is {value}: actions must be finite numbers in [-1, 1]")]
    NonFiniteAction { index: usize, value: f64 },
    #[error("step called before reset (or after the episode ended): call reset first")]
    NeedsReset,
    /// The environment's spec (or its overrides) describes something that cannot run: the
    /// user's input, not a failure of the run.
    #[error("{0}")]
    InvalidSpec(String),
    #[error("{0}")]
    Backend(String),
}

/// The contract's action check, shared by every environment: the length must match the space,
/// NaN or infinite components are an error, finite values outside the box are clipped. Returns
/// the clipped action and how many components were clipped.
pub fn checked_action(space: &BoxSpace, action: &[f64]) -> Result<(Vec<f64>, usize), EnvError> {
    if action.len() != space.dim() {
        return Err(EnvError::ActionShape {
            expected: space.dim(),
            got: action.len(),
        });
    }
    if let Some((index, value)) = action.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(EnvError::NonFiniteAction { index, value: *value });
    }
    let mut a = action.to_vec();
    let clipped = space.clip(&mut a);
    Ok((a, clipped))
}

/// A reinforcement-learning environment.
pub trait Env {
    fn observation_space(&self) -> BoxSpace;
    fn action_space(&self) -> BoxSpace;
    /// Starts an episode; the same seed gives the same initial observation, bitwise.
    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError>;
    /// Applies one action for one control interval.
    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError>;
    /// How the environment splits into agents for multi-agent training ([`crate::multi`]), if
    /// it does.
    fn agents(&self) -> Option<Agents> {
        None
    }
    /// The last step's reward of each of [`Env::agents`] (local rewards); empty when the
    /// environment has none.
    fn agent_rewards(&self) -> Vec<f64> {
        vec![]
    }
    /// Hands over the action of the next `step` before it (the first of two phases of
    /// [`crate::rollout::step_all`]). Pseudo-environments sharing one flow step it here, once
    /// all their agents have handed theirs over; an ordinary environment does nothing.
    fn submit(&mut self, _action: &[f64]) -> Result<(), EnvError> {
        Ok(())
    }
    /// [`Env::submit`] for `reset`.
    fn submit_reset(&mut self, _seed: u64) -> Result<(), EnvError> {
        Ok(())
    }
}

/// The differentiable extension of the contract (the paper's JAX environments): the env keeps
/// its trajectory since the last reset and differentiates through it with vector-Jacobian
/// products of its steps (a discrete adjoint), not finite differences.
pub trait DifferentiableEnv: Env {
    /// For the last `k` steps (the segment `T-k+1..T`), the gradient of the segment's summed
    /// reward with respect to each step's action (in normalised action units, at the action
    /// the env applied after clipping), holding the other actions fixed: `out[j]` belongs to
    /// step `T-k+1+j`. One backward sweep over the segment.
    fn reward_action_gradients(&mut self, k: usize) -> Result<Vec<Vec<f64>>, EnvError>;
}

/// The contract through a box or a mutable reference to an environment.
macro_rules! forward_env {
    ($($ptr:ty),*) => {$(
        impl<E: Env + ?Sized> Env for $ptr {
            fn observation_space(&self) -> BoxSpace {
                (**self).observation_space()
            }

            fn action_space(&self) -> BoxSpace {
                (**self).action_space()
            }

            fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
                (**self).reset(seed)
            }

            fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
                (**self).step(action)
            }

            fn agents(&self) -> Option<Agents> {
                (**self).agents()
            }

            fn agent_rewards(&self) -> Vec<f64> {
                (**self).agent_rewards()
            }

            fn submit(&mut self, action: &[f64]) -> Result<(), EnvError> {
                (**self).submit(action)
            }

            fn submit_reset(&mut self, seed: u64) -> Result<(), EnvError> {
                (**self).submit_reset(seed)
            }
        }

        impl<E: DifferentiableEnv + ?Sized> DifferentiableEnv for $ptr {
            fn reward_action_gradients(&mut self, k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
                (**self).reward_action_gradients(k)
            }
        }
    )*};
}

forward_env!(Box<E>, &mut E);
