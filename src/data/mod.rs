//! Data: trajectories as MCAP files (`trajectory.mcap`), readable by Foxglove and the Python
//! `mcap` reader, and the salvage of truncated files (`hgym data recover`); reading them back
//! ([`read`]); flow-field snapshots ([`field`]); tables and Hugging Face dataset folders
//! ([`table`], [`hf`], [`card`]); the Hub upload client ([`hub`]).

pub mod card;
pub mod field;
pub mod hf;
pub mod hub;
pub mod read;
pub mod table;
pub mod trajectory;
