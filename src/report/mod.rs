//! Reports: plots (plotters, PNG, with an embedded DejaVu Sans so no system fonts are needed),
//! the machine facts every manifest carries, the evaluation report's format and the leaderboard
//! that aggregates them. Depends on no other module of the crate but `flow` (its field type).

pub mod eval;
pub mod leaderboard;
pub mod manifest;
pub mod plots;
pub mod table;

/// Why a report (plots, tables, JSON) could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error(transparent)]
    Plot(#[from] plots::PlotError),
    #[error("cannot write {}", path.display())]
    Io {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode {what} as JSON")]
    Json {
        what: String,
        #[source]
        source: serde_json::Error,
    },
}

impl ReportError {
    /// An I/O error on `path`.
    pub fn io(path: &std::path::Path) -> impl Fn(std::io::Error) -> ReportError + '_ {
        move |source| ReportError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// An error and its sources as one line (`a: b: c`), for carriers that hold text.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(c) = source {
        s += &format!(": {c}");
        source = c.source();
    }
    s
}
