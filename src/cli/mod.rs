//! One file per command (its clap arguments and its `run`): `validate`, `bench`, `envs`, `run`,
//! `train`/`eval`/`compare`, `transfer`, `export`/`push`/`data`, `plot`/`leaderboard`; progress reports for
//! long runs; standard output that survives a closed pipe; outputs of ranks other than 0 under MPI.

pub mod bench;
pub mod data;
pub mod deployment;
pub mod envs;
pub mod out;
pub mod plot;
pub mod progress;
pub mod ranks;
pub mod run;
pub mod train;
pub mod transfer;
pub mod validate;
