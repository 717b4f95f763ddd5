//! # hgym-agents: the Env contract and learning (no flows in here)
//!
//! [`Env`] mirrors Gymnasium 1.x exactly: `reset(seed) -> (obs, info)`,
//! `step(action) -> (obs, reward, terminated, truncated, info)`. Actions are always in
//! `[-1, 1]^n` (environments map them to physical bounds); observations are normalised to about
//! `[-1, 1]`. `truncated` is true exactly on the episode's last action; `terminated` only for a
//! real terminal state (e.g. the solver diverged, with the reason in `info`).

mod env;
mod spaces;

pub use env::{Env, EnvError, Info, StepResult};
pub use spaces::BoxSpace;
