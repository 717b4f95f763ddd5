//! # hgym: reinforcement-learning flow control
//!
//! This crate ties the numerics ([`hgym_solvers`]) to learning ([`hgym_agents`]): flow
//! environments ([`env`]), training, evaluation and comparison protocols ([`train`]), trajectory
//! files ([`data`]), validation against the literature ([`validate`]), plots, reports and the
//! leaderboard ([`report`]), speed benchmarks ([`bench`]). The binary `hgym` is a thin command
//! line over these modules (`src/main.rs`, `src/cli/`).
//!
//! Units: environments and validation cases speak the paper's non-dimensional units (reference
//! length D = 1, free-stream velocity U = 1, time in D/U); lattice units stay inside the solvers
//! and are converted by [`hgym_solvers::lbm::Units`].

pub mod bench;
pub mod data;
pub mod env;
pub mod report;
pub mod train;
pub mod validate;
