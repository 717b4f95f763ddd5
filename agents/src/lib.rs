//! # hgym-agents: the Env contract and learning (no flows in here)
//!
//! [`Env`] mirrors Gymnasium 1.x exactly: `reset(seed) -> (obs, info)`,
//! `step(action) -> (obs, reward, terminated, truncated, info)`. Actions are always in
//! `[-1, 1]^n` (environments map them to physical bounds); observations are normalised to about
//! `[-1, 1]`. `truncated` is true exactly on the episode's last action; `terminated` only for a
//! real terminal state (e.g. the solver diverged, with the reason in `info`).
//!
//! Learning: [`nn`] (MLP with backward pass and Adam), [`ppo`], [`ddpg`], [`td3`] (one algorithm
//! per file), classical controllers in [`baselines`], rounds of parallel episodes in
//! [`rollout`], one type over the learners with checkpoint bytes in [`learn`], one environment split into
//! agents that share a policy in [`multi`], and small control
//! tasks for tests in [`toy`].

pub mod baselines;
pub mod buffer;
pub mod check;
pub mod ddpg;
mod env;
pub mod gppo;
pub mod learn;
pub mod multi;
pub mod nn;
pub mod noise;
pub mod normalize;
pub mod policy;
pub mod ppo;
pub mod rng;
pub mod rollout;
mod spaces;
pub mod td3;
pub mod toy;
pub mod transplant;

pub use check::{check_env, Violation};
pub use env::{checked_action, DifferentiableEnv, Env, EnvError, Info, StepResult};
pub use spaces::BoxSpace;
