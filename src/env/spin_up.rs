//! Telling someone how a spin-up is going, and keeping its result: the developed-flow state on
//! disk ([`load_state`], [`store_state`]), or in the process and on disk ([`developed`]).
//!
//! The first reset of an ID runs the flow from rest onto its attractor before it is cached, which
//! takes from seconds to about ten minutes (the cavity at its default level). The library draws
//! nothing itself; a program installs one observer for the whole process (the `hgym` binary a
//! progress bar), and every spin-up reports to it in up to [`REPORTS`] chunks.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use hgym_agents::EnvError;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// One report: which spin-up (a serial number, distinct for spin-ups running at the same time),
/// the environment ID, solver steps done, solver steps in all. `done == 0` opens a spin-up and
/// `done == total` closes it; a spin-up stopped by an error closes with `total == 0`.
pub type SpinUpObserver = fn(serial: u64, id: &str, done: u64, total: u64);

/// How many reports a spin-up makes after its opening one, at most.
pub const REPORTS: u64 = 100;

static OBSERVER: OnceLock<SpinUpObserver> = OnceLock::new();
static SERIAL: AtomicU64 = AtomicU64::new(0);

/// Installs the process's observer; only the first call has an effect.
pub fn observe_spin_ups(observer: SpinUpObserver) {
    let _ = OBSERVER.set(observer);
}

/// Runs `total` solver steps through `advance(n)` in up to [`REPORTS`] chunks, reporting after
/// each; stops at the first error. The chunks change nothing in the result: the solver is
/// stepped `total` times either way.
pub(crate) fn run_reported<E>(id: &str, total: u64, mut advance: impl FnMut(u64) -> Result<(), E>) -> Result<(), E> {
    let observer = OBSERVER.get();
    let serial = SERIAL.fetch_add(1, Ordering::Relaxed);
    let Some(observer) = observer else {
        return advance(total);
    };
    observer(serial, id, 0, total);
    let chunk = total.div_ceil(REPORTS).max(1);
    let mut done = 0;
    while done < total {
        let n = chunk.min(total - done);
        if let Err(e) = advance(n) {
            observer(serial, id, done, 0);
            return Err(e);
        }
        done += n;
        observer(serial, id, done, total);
    }
    Ok(())
}

/// A developed-flow state cached at `path` (little-endian f32), if there is one of `len` values.
pub fn load_state(path: &std::path::Path, len: usize) -> Option<Vec<f32>> {
    let bytes = std::fs::read(path).ok()?;
    (bytes.len() == 4 * len).then(|| {
        bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    })
}

/// Caches `state` at `path`: written to a temporary file, then renamed, so a crash never leaves
/// a truncated cache file. A cache that cannot be written is skipped (the next run spins up again).
pub fn store_state(path: &std::path::Path, state: &[f32]) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    let bytes: Vec<u8> = state.iter().flat_map(|v| v.to_le_bytes()).collect();
    let tmp = path.with_extension("tmp");
    if std::fs::write(&tmp, bytes).is_ok() {
        let _ = std::fs::rename(&tmp, path);
    }
}

/// A developed state shared by the process's environments through `memo` (under `key`) and kept
/// on disk at `file` (bincode): the memo's, else the file's if it `fits`, else `spin_up()`'s,
/// which then goes to both. A cache that cannot be written only costs the next process its
/// spin-up.
pub(crate) fn developed<T: Serialize + DeserializeOwned>(
    memo: &Mutex<HashMap<String, Arc<T>>>,
    key: String,
    file: Option<PathBuf>,
    fits: impl Fn(&T) -> bool,
    spin_up: impl FnOnce() -> Result<T, EnvError>,
) -> Result<Arc<T>, EnvError> {
    if let Some(s) = memo.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return Ok(s);
    }
    let from_disk = file
        .as_ref()
        .and_then(|p| std::fs::read(p).ok())
        .and_then(|b| bincode::deserialize::<T>(&b).ok())
        .filter(&fits);
    let state = match from_disk {
        Some(s) => s,
        None => {
            let s = spin_up()?;
            if let Some(p) = &file {
                if let Some(dir) = p.parent() {
                    let _ = std::fs::create_dir_all(dir);
                }
                if let Ok(bytes) = bincode::serialize(&s) {
                    let _ = std::fs::write(p, bytes);
                }
            }
            s
        }
    };
    let state = Arc::new(state);
    if let Ok(mut m) = memo.lock() {
        m.insert(key, state.clone());
    }
    Ok(state)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    static SEEN: Mutex<Vec<(u64, u64)>> = Mutex::new(Vec::new());

    fn record(_: u64, id: &str, done: u64, total: u64) {
        if id.starts_with("test-") {
            SEEN.lock().unwrap().push((done, total));
        }
    }

    #[test]
    fn every_step_is_run_once_and_reported_in_order() {
        observe_spin_ups(record);
        let mut stepped = 0u64;
        run_reported::<()>("test-id", 1234, |n| {
            stepped += n;
            Ok(())
        })
        .unwrap();
        assert_eq!(stepped, 1234);
        let seen = SEEN.lock().unwrap().clone();
        assert_eq!(seen.first(), Some(&(0, 1234)));
        assert_eq!(seen.last(), Some(&(1234, 1234)));
        assert!(seen.len() <= REPORTS as usize + 1);
        assert!(seen.windows(2).all(|w| w[0].0 < w[1].0), "{seen:?}");
        // An error stops the run, is passed on, and closes the spin-up with total 0.
        SEEN.lock().unwrap().clear();
        let mut calls = 0;
        let r = run_reported("test-error", 500, |_| {
            calls += 1;
            if calls == 3 {
                Err("diverged")
            } else {
                Ok(())
            }
        });
        assert_eq!((r, calls), (Err("diverged"), 3));
        assert_eq!(SEEN.lock().unwrap().last(), Some(&(10, 0)), "5 steps a chunk, 2 chunks done");
    }
}
