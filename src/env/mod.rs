//! Flow environments: where solvers (`hgym-solvers`) meet the `Env` contract (`hgym-agents`).
//!
//! - [`spec`]: the serialisable description of an environment (its hash keys caches and results);
//! - [`registry`]: every ID; [`cylinder`], [`pinball`], [`square`], [`cavity`], [`naca`],
//!   [`pipe`]: the families' specs;
//! - [`lbm_env`]: the `Env` implementation for 2D lattice-Boltzmann families;
//! - [`actuation`]: jets, rotation, and the temporal smoothing of actions;
//! - [`spin_up`]: progress reports of the first reset's spin-up, to an observer the program installs.

pub mod actuation;
pub mod any;
pub mod calibrate;
pub mod cavity;
pub mod cylinder;
pub mod fields;
pub mod kolmogorov;
pub mod lbm_env;
pub mod naca;
pub mod pinball;
pub mod pipe;
pub mod registry;
pub mod rollout;
mod seeding;
pub mod spec;
pub mod spin_up;
pub mod square;

pub use lbm_env::LbmEnv;
pub use spec::EnvSpec;

/// Errors of the environment commands that are the user's input (exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum EnvInputError {
    #[error("unknown environment ID '{id}'; did you mean {}? (`hgym envs` lists all)", closest.iter().take(3).map(|s| format!("'{s}'")).collect::<Vec<_>>().join(", "))]
    UnknownEnv { id: String, closest: Vec<String> },
}

/// The spec of `id`, or an error that names the closest IDs.
pub fn spec(id: &str) -> Result<EnvSpec, EnvInputError> {
    registry::get(id).map_err(|closest| EnvInputError::UnknownEnv {
        id: id.to_string(),
        closest,
    })
}

/// Where developed-flow states are cached: `$HGYM_CACHE`, else `~/.cache/hgym/states`.
pub fn default_cache_dir() -> Option<std::path::PathBuf> {
    if let Some(p) = std::env::var_os("HGYM_CACHE") {
        return Some(std::path::PathBuf::from(p));
    }
    std::env::var_os("HOME").map(|h| std::path::PathBuf::from(h).join(".cache/hgym/states"))
}
