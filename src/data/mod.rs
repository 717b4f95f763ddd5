//! Data: trajectories as MCAP files (`trajectory.mcap`), readable by Foxglove and the Python
//! `mcap` reader, and the salvage of truncated files (`hgym data recover`).

pub mod trajectory;
