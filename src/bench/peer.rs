//! A peer measured beside hgym in the same run: a Python program from `scripts/peers/`
//! (embedded in the binary, written to a temporary file) run by the peers' interpreter, which
//! answers one JSON line per command on stdin. hgym alternates its own measurement with the
//! peer's (A B A B ...), so both see the same minute of the machine, and reports every pair's
//! ratio and the medians.
//!
//! The interpreter is `$HGYM_PEERS_PYTHON`, else `~/.cache/hgym-peers/bin/python`, which `make
//! peers` creates (Stable-Baselines3 with torch on the CPU, and `hydrogym[jax]`, in a venv of
//! their own: hydrogym pins huggingface-hub 0.16 and pandas 2.3, which the data tools' venv cannot
//! take).

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Stable-Baselines3's TD3 at hgym's shapes.
pub const SB3_TD3: (&str, &str) = ("sb3_td3.py", include_str!("../../scripts/peers/sb3_td3.py"));
/// HydroGym's JAX Kolmogorov environment.
pub const HYDROGYM_KOLMOGOROV: (&str, &str) = ("hydrogym_kolmogorov.py", include_str!("../../scripts/peers/hydrogym_kolmogorov.py"));
/// HydroGym's JAX channel.
pub const HYDROGYM_CHANNEL: (&str, &str) = ("hydrogym_channel.py", include_str!("../../scripts/peers/hydrogym_channel.py"));

#[derive(Debug, Error)]
pub enum PeerError {
    #[error("the peers are not installed ({python} not found): run `make peers` (Stable-Baselines3 with CPU torch and hydrogym[jax], about 7 GB, into ~/.cache/hgym-peers), or set HGYM_PEERS_PYTHON")]
    Missing { python: PathBuf },
    #[error("the peer {script} failed: {message}")]
    Failed { script: String, message: String },
    #[error("cannot run the peer {script}")]
    Io {
        script: String,
        #[source]
        source: std::io::Error,
    },
}

/// The peers' interpreter.
pub fn python() -> PathBuf {
    interpreter("HGYM_PEERS_PYTHON", "hgym-peers")
}

/// `$var` if set, else the Python of the venv `~/.cache/<venv>` that a Makefile target creates.
pub fn interpreter(var: &str, venv: &str) -> PathBuf {
    if let Some(p) = std::env::var_os(var) {
        return PathBuf::from(p);
    }
    let home = std::env::var_os("HOME").map_or_else(|| PathBuf::from("."), PathBuf::from);
    home.join(".cache").join(venv).join("bin/python")
}

/// A running peer.
pub struct Peer {
    script: String,
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    /// The script as written for the interpreter (removed when the peer is dropped).
    path: PathBuf,
    /// The peer's answer to `ready`: its name, versions and settings.
    pub about: serde_json::Value,
}

impl Peer {
    /// Starts `script` (one of the constants above) with `threads` worker threads.
    pub fn start(script: (&str, &str), threads: usize) -> Result<Peer, PeerError> {
        Peer::start_with(&python(), script, threads)
    }

    /// [`Peer::start`] with the interpreter `python`.
    pub fn start_with(python: &Path, script: (&str, &str), threads: usize) -> Result<Peer, PeerError> {
        let (name, text) = script;
        if !python.exists() {
            return Err(PeerError::Missing {
                python: python.to_path_buf(),
            });
        }
        let io = |source| PeerError::Io {
            script: name.to_string(),
            source,
        };
        let path = std::env::temp_dir().join(format!("hgym-peer-{}-{name}", std::process::id()));
        std::fs::write(&path, text).map_err(io)?;
        let mut child = Command::new(python)
            .arg(&path)
            .arg(threads.to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(io)?;
        let failed = |message: &str| PeerError::Failed {
            script: name.to_string(),
            message: message.to_string(),
        };
        let stdin = child.stdin.take().ok_or_else(|| failed("no stdin"))?;
        let stdout = BufReader::new(child.stdout.take().ok_or_else(|| failed("no stdout"))?);
        let mut peer = Peer {
            script: name.to_string(),
            child,
            stdin,
            stdout,
            path,
            about: serde_json::Value::Null,
        };
        peer.about = peer.ask("ready")?;
        Ok(peer)
    }

    /// Sends one command and reads its answer.
    pub fn ask(&mut self, command: &str) -> Result<serde_json::Value, PeerError> {
        let script = self.script.clone();
        let io = |source| PeerError::Io {
            script: script.clone(),
            source,
        };
        writeln!(self.stdin, "{command}").map_err(io)?;
        self.stdin.flush().map_err(io)?;
        let mut line = String::new();
        if self.stdout.read_line(&mut line).map_err(io)? == 0 {
            return Err(PeerError::Failed {
                script,
                message: format!("it exited while answering '{command}' (its error is printed above)"),
            });
        }
        let v: serde_json::Value = serde_json::from_str(&line).map_err(|e| PeerError::Failed {
            script: script.clone(),
            message: format!("answer to '{command}' is not JSON ({e}): {line}"),
        })?;
        if let Some(e) = v.get("error") {
            return Err(PeerError::Failed {
                script,
                message: e.to_string(),
            });
        }
        // The peer's idle OpenMP workers (torch's) spin for a while after its turn: let them
        // settle before ours is timed (a passive wait policy instead slows the peer itself).
        std::thread::sleep(std::time::Duration::from_millis(500));
        Ok(v)
    }

    /// The numbers `keys` of the answer to `command`; a missing or non-numeric one is an error.
    pub fn numbers<const K: usize>(&mut self, command: &str, keys: [&str; K]) -> Result<[f64; K], PeerError> {
        let v = self.ask(command)?;
        let mut out = [0.0; K];
        for (o, key) in out.iter_mut().zip(keys) {
            *o = v.get(key).and_then(|x| x.as_f64()).ok_or_else(|| PeerError::Failed {
                script: self.script.clone(),
                message: format!("answer to '{command}' has no number '{key}': {v}"),
            })?;
        }
        Ok(out)
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.path);
    }
}

/// One quantity measured in alternating pairs (ours, then the peer's).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Pairs {
    pub quantity: String,
    pub unit: String,
    pub ours: Vec<f64>,
    pub peer: Vec<f64>,
    /// hgym's speed-up in each pair: ours / peer for rates, peer / ours for times.
    pub speedups: Vec<f64>,
    pub median_ours: f64,
    pub median_peer: f64,
    pub median_speedup: f64,
}

impl Pairs {
    /// `pairs` of (ours, peer's); `rate`: larger is faster (per second), else a time.
    pub fn new(quantity: &str, unit: &str, pairs: &[(f64, f64)], rate: bool) -> Pairs {
        let ours: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let peer: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        let speedups: Vec<f64> = pairs.iter().map(|&(a, b)| if rate { a / b } else { b / a }).collect();
        Pairs {
            quantity: quantity.to_string(),
            unit: unit.to_string(),
            median_ours: median(&ours),
            median_peer: median(&peer),
            median_speedup: median(&speedups),
            ours,
            peer,
            speedups,
        }
    }

    /// `TD3 updates/s   hgym 231 | peer 140 | 1.65x (pairs 1.62 1.70 1.58)`.
    pub fn line(&self, peer: &str) -> String {
        let list: Vec<String> = self.speedups.iter().map(|r| format!("{r:.2}")).collect();
        format!(
            "{:<26} hgym {:>9} | {peer} {:>9} {:<9} hgym {:.2}x faster (medians; pairs: {})",
            self.quantity,
            significant(self.median_ours),
            significant(self.median_peer),
            self.unit,
            self.median_speedup,
            list.join(" ")
        )
    }
}

/// `v` with four significant digits, without an exponent for everyday magnitudes.
fn significant(v: f64) -> String {
    let decimals = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    format!("{v:.decimals$}")
}

/// A peer's answer to `ready` as one line: `stable-baselines3 2.9.2 (threads 2, torch 2.15.0)`.
pub fn describe(about: &serde_json::Value) -> String {
    let name = about.get("peer").and_then(|v| v.as_str()).unwrap_or("the peer");
    let rest: Vec<String> = about
        .as_object()
        .map(|m| m.iter().filter(|(k, _)| *k != "peer").map(|(k, v)| format!("{k} {v}")).collect())
        .unwrap_or_default();
    format!("{name} ({})", rest.join(", ").replace('"', ""))
}

pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_give_speedups_and_medians() {
        let p = Pairs::new("x", "1/s", &[(2.0, 1.0), (3.0, 1.0), (4.0, 1.0)], true);
        assert_eq!((p.median_ours, p.median_speedup), (3.0, 3.0));
        let t = Pairs::new("t", "us", &[(1.0, 4.0), (2.0, 4.0)], false);
        assert_eq!(t.speedups, vec![4.0, 2.0]);
        assert_eq!(t.median_speedup, 3.0);
    }

    #[test]
    fn a_missing_interpreter_says_how_to_install_it() {
        let e = Peer::start_with(Path::new("/nonexistent/python"), SB3_TD3, 1)
            .err()
            .expect("must fail");
        assert!(matches!(e, PeerError::Missing { .. }));
        assert!(e.to_string().contains("make peers"), "{e}");
    }
}
