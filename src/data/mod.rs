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

use std::path::PathBuf;

/// Why a trajectory, snapshot or dataset could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    #[error("cannot read or write {}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("MCAP")]
    Mcap(#[from] mcap::McapError),
    #[error("JSON encoding")]
    Json(#[from] serde_json::Error),
    #[error("the trajectory writer is already finished")]
    Finished,
    #[error("building or writing a table")]
    Table(#[from] polars::error::PolarsError),
    /// Content that does not have the expected form (a file from elsewhere, or a damaged one).
    #[error("{0}")]
    Format(String),
}

impl DataError {
    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path) -> impl Fn(std::io::Error) -> DataError + '_ {
        move |source| DataError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
