//! # hgym: reinforcement-learning flow control
//!
//! This crate ties the numerics ([`hgym_solvers`]) to learning ([`hgym_agents`]): flow set-ups
//! and the one function that builds their solvers ([`flow`]), flow environments ([`env`]),
//! training, evaluation and comparison protocols ([`train`]), transfer between flows ([`transfer`]), trajectory files ([`data`]),
//! validation against the literature ([`validate`]) and of each environment's own flow
//! ([`fidelity`]), plots, reports and the leaderboard ([`report`]), speed benchmarks
//! ([`bench`]). The binary `hgym` is a thin command line over these modules (`src/main.rs`,
//! `src/cli/`); `hgym-mpi`, the same command line, runs one process per MPI rank ([`flow::ranks`]). `env` and `validate` both build on `flow` and never on each other.
//!
//! Units: environments and validation cases speak the paper's non-dimensional units (reference
//! length D = 1, free-stream velocity U = 1, time in D/U); lattice units stay inside the solvers
//! and are converted by [`hgym_solvers::lbm::Units`].

pub mod bench;
pub mod data;
pub mod env;
pub mod fidelity;
pub mod flow;
pub mod report;
pub mod train;
pub mod transfer;
pub mod validate;
