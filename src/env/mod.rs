//! Flow environments: where solvers (`hgym-solvers`) meet the `Env` contract (`hgym-agents`).
//!
//! - [`family`]: the trait a family implements, the spec and environment types everything else
//!   sees ([`family::Spec`], [`family::FlowEnv`]);
//! - [`registry`]: the list of families and the lookup; [`cylinder`], [`pinball`], [`square`],
//!   [`cavity`], [`naca`], [`pipe`] (lattice Boltzmann), [`kolmogorov`] (spectral), [`channel`]
//!   (finite-difference channel DNS): one file each;
//! - [`spec`]: the serialisable description of a lattice-Boltzmann environment (its hash keys
//!   caches and results); [`lbm_env`]: its `Env` implementation;
//! - [`actuation`]: jets, rotation, and the temporal smoothing of actions;
//! - [`layout`]: what each observation and action means (probe positions, actuator names), for transfer;
//! - [`spin_up`]: progress reports of the first reset's spin-up, to an observer the program installs.

pub mod actuation;
pub mod calibrate;
pub mod cavity;
pub mod channel;
pub mod clock;
pub mod cube;
pub mod cylinder;
pub mod family;
pub mod fields;
pub mod kolmogorov;
pub mod layout;
pub mod lbm_env;
pub mod lbm_env3;
pub mod naca;
pub mod pinball;
pub mod pipe;
pub mod registry;
pub mod rollout;
mod seeding;
pub mod spec;
pub mod spec3;
pub mod sphere;
pub mod spin_up;
pub mod square;
pub mod wing_tbl;

pub use family::{FlowEnv, Spec};
pub use lbm_env::LbmEnv;
pub use lbm_env3::LbmEnv3;
pub use registry::{lbm_spec, lookup};
pub use spec::EnvSpec;

/// Errors of the environment commands that are the user's input (exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum EnvInputError {
    #[error("unknown environment ID '{id}'; did you mean {}? (`hgym envs` lists all)", closest.iter().take(3).map(|s| format!("'{s}'")).collect::<Vec<_>>().join(", "))]
    UnknownEnv { id: String, closest: Vec<String> },
    #[error("{id} runs on the {solver} solver; this command needs a lattice-Boltzmann flow (`hgym envs` lists the solver of each ID)")]
    NotLbm { id: String, solver: &'static str },
    #[error("[env] overrides of {id}: {message}")]
    Override { id: String, message: String },
}

/// Where developed-flow states are cached: `$HGYM_CACHE`, else `~/.cache/hgym/states`.
pub fn default_cache_dir() -> Option<std::path::PathBuf> {
    if let Some(p) = std::env::var_os("HGYM_CACHE") {
        return Some(std::path::PathBuf::from(p));
    }
    std::env::var_os("HOME").map(|h| std::path::PathBuf::from(h).join(".cache/hgym/states"))
}

/// `info[key]`, or an error naming the key the step did not write (no silent default).
pub fn info_value(info: &hgym_agents::Info, key: &str) -> Result<f64, hgym_agents::EnvError> {
    info.get(key)
        .ok_or_else(|| hgym_agents::EnvError::Backend(format!("the step's info has no '{key}'")))
}
