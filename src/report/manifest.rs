//! Facts every result carries: code version, machine, threads, wall time, CPU time.

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
    /// CPU time (user + system, all threads) the result cost, over every session of a resumed
    /// run: the core-hours of the result even when the machine was shared. `None` where it was
    /// not measured (results written before it was recorded, or a resume of such a run).
    #[serde(default)]
    pub cpu_time_s: Option<f64>,
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
        cpu_time_s: None,
        created_unix,
    }
}

impl Manifest {
    pub fn with_cpu(self, cpu_time_s: Option<f64>) -> Self {
        Manifest { cpu_time_s, ..self }
    }
}

/// CPU time this process has used so far (user + system, all threads), by POSIX `getrusage`;
/// `None` where that is unavailable.
#[cfg(unix)]
pub fn process_cpu_seconds() -> Option<f64> {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: `usage` is a valid, writable `rusage` (all-zero bytes are a valid value of this
    // plain-integer struct), and `getrusage(RUSAGE_SELF, p)` writes only through `p`. On error it
    // returns -1 and we do not read the value.
    let ok = unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } == 0;
    ok.then(|| {
        // SAFETY: zero-initialised, then filled by a successful `getrusage`.
        let u = unsafe { usage.assume_init() };
        let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
        secs(u.ru_utime) + secs(u.ru_stime)
    })
}

#[cfg(not(unix))]
pub fn process_cpu_seconds() -> Option<f64> {
    None
}

/// CPU time of this process since [`CpuClock::start`].
#[derive(Clone, Copy, Debug)]
pub struct CpuClock(Option<f64>);

impl CpuClock {
    pub fn start() -> Self {
        CpuClock(process_cpu_seconds())
    }

    /// Seconds since the start, on top of what earlier sessions of the same result spent
    /// (`before`; `None` if unknown, which makes the total unknown).
    pub fn total(&self, before: Option<f64>) -> Option<f64> {
        Some(before? + process_cpu_seconds()? - self.0?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_clock_counts_work_and_carries_earlier_sessions() {
        let clock = CpuClock::start();
        let mut x = 0u64;
        for i in 0..30_000_000u64 {
            x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(i));
        }
        let spent = clock.total(Some(10.0)).expect("getrusage works on this platform") - 10.0;
        // (Other tests share the process, so this is a lower bound only.)
        assert!(spent > 0.0, "a busy loop used no CPU time ({spent} s)");
        assert_eq!(clock.total(None), None);
    }
}
