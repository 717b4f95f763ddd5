//! Flow environments: where solvers (`hgym-solvers`) meet the `Env` contract (`hgym-agents`).
//!
//! - [`spec`]: the serialisable description of an environment (its hash keys caches and results);
//! - [`registry`]: every ID; [`cylinder`]: the cylinder family's specs;
//! - [`lbm_env`]: the `Env` implementation for 2D lattice-Boltzmann families;
//! - [`actuation`]: jets, rotation, and the temporal smoothing of actions.

pub mod actuation;
pub mod cylinder;
pub mod lbm_env;
pub mod registry;
pub mod spec;

pub use lbm_env::LbmEnv;
pub use spec::EnvSpec;
