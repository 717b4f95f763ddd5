//! Helpers shared by the integration tests that read hgym's files with the Python tools people
//! use (the venv `make setup` builds in ~/.cache/hgym-venv, or `$HGYM_PYTHON`).

#![allow(dead_code)] // each test binary uses a part

use std::path::{Path, PathBuf};
use std::process::Command;

/// The checkout under test. Read at run time (cargo sets `CARGO_MANIFEST_DIR` when it runs a
/// test), not baked in with `env!`: cargo reuses a build from another clone of the same tree
/// that shares `CARGO_TARGET_DIR` (CI's fresh clone), and a baked path would point there.
pub fn repo() -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// The Python interpreter with `mcap`, pandas, pyarrow and `datasets` installed.
pub fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("HGYM_PYTHON") {
        return PathBuf::from(p);
    }
    let home = std::env::var_os("HOME").map(PathBuf::from).unwrap_or_default();
    let p = home.join(".cache/hgym-venv/bin/python");
    assert!(
        p.exists(),
        "{} is missing: run `make setup` (installs the Python mcap reader, pandas and datasets)",
        p.display()
    );
    p
}

/// The Python `mcap` reader's summary of a trajectory (tests/read_mcap.py), or its error text.
pub fn read_mcap(file: &Path) -> Result<serde_json::Value, String> {
    let script = repo().join("tests/read_mcap.py");
    let o = Command::new(python()).arg(script).arg(file).output().expect("run python");
    if !o.status.success() {
        return Err(String::from_utf8_lossy(&o.stderr).into_owned());
    }
    serde_json::from_slice(&o.stdout).map_err(|e| e.to_string())
}

/// Every file below `dir` (recursively, in directory order) whose path `keep` accepts.
pub fn files_under(dir: &Path, keep: &dyn Fn(&Path) -> bool) -> Vec<PathBuf> {
    let mut out = vec![];
    let Ok(entries) = std::fs::read_dir(dir) else { return out };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files_under(&p, keep));
        } else if keep(&p) {
            out.push(p);
        }
    }
    out
}
