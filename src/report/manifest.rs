//! Facts every result carries: code version, machine, threads, wall time.

use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Machine {
    pub cpu: String,
    pub cores: usize,
    pub os: String,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    /// `hgym <version>`; `git_commit` is the commit the binary was built from.
    pub code_version: String,
    pub git_commit: Option<String>,
    pub machine: Machine,
    pub threads: usize,
    pub wall_time_s: f64,
    /// Seconds since the Unix epoch when the result was written.
    pub created_unix: u64,
}

/// The CPU model from /proc/cpuinfo (or "unknown").
pub fn machine() -> Machine {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    Machine {
        cpu,
        cores,
        os: std::env::consts::OS.into(),
    }
}

/// The commit the binary was built from (`-dirty` when tracked files had uncommitted changes;
/// `None` when it was not built in a git checkout), whatever directory it runs in.
pub fn git_commit() -> Option<String> {
    let c = env!("HGYM_GIT_COMMIT");
    (!c.is_empty()).then(|| c.to_string())
}

pub fn manifest(threads: usize, wall_time_s: f64) -> Manifest {
    let created_unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    Manifest {
        code_version: format!("hgym {}", env!("CARGO_PKG_VERSION")),
        git_commit: git_commit(),
        machine: machine(),
        threads,
        wall_time_s,
        created_unix,
    }
}
