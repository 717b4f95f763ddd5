//! Committed tables keyed by ID (observation statistics, flow statistics, deviations from the
//! literature): read, merge new rows, write atomically (temporary file, then rename) with the
//! file's leading `#` comment kept, so a kill at any moment leaves the old or the new table, and
//! several commands recording at once lose no row (each re-reads the table just before writing).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::Serialize;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum TableError {
    #[error("{path} is malformed: {message}")]
    Malformed { path: PathBuf, message: String },
    #[error("cannot read or write {path}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The committed row of `id` in the table `text`, if it was measured on the physics `hash` names
/// (`hash_of` reads a row's; a row of other physics is stale and ignored, as is a table that does
/// not parse).
pub fn committed<T: DeserializeOwned>(text: &str, id: &str, hash: &str, hash_of: impl Fn(&T) -> &str) -> Option<T> {
    let mut rows: BTreeMap<String, T> = toml::from_str(text).ok()?;
    rows.remove(id).filter(|row| hash_of(row) == hash)
}

/// The rows of the TOML table `text` (read from `path`, for the error).
pub fn parse<T: DeserializeOwned>(text: &str, path: &Path) -> Result<BTreeMap<String, T>, TableError> {
    toml::from_str(text).map_err(|e| TableError::Malformed {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Fails when the table at `path` exists but cannot be read back as rows of `T` (checked before
/// a long run that will record into it).
pub fn check<T: DeserializeOwned>(path: &Path) -> Result<(), TableError> {
    match std::fs::read_to_string(path) {
        Ok(text) => parse::<T>(&text, path).map(|_| ()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(source) => Err(TableError::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// Inserts `rows` into the table at `path` (created when missing), replacing rows of the same key.
pub fn record<T: Serialize + DeserializeOwned + Clone>(path: &Path, rows: &[(String, T)]) -> Result<(), TableError> {
    let io = |source| TableError::Io {
        path: path.to_path_buf(),
        source,
    };
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(io(e)),
    };
    let mut entries: BTreeMap<String, T> = parse(&text, path)?;
    entries.extend(rows.iter().cloned());
    let header: String = text.lines().take_while(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
    let body = toml::to_string_pretty(&entries).map_err(|e| TableError::Malformed {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let tmp = path.with_extension(format!("tmp.{}", std::process::id()));
    std::fs::write(&tmp, format!("{header}\n{body}")).map_err(io)?;
    std::fs::rename(&tmp, path).map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_merged_and_the_header_kept() {
        let dir = std::env::temp_dir().join(format!("hgym-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.toml");
        std::fs::write(&path, "# header line\n\n[a]\nx = 1.0\n").unwrap();
        record(&path, &[("b".to_string(), BTreeMap::from([("x".to_string(), 2.0)]))]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("# header line\n"), "{text}");
        let rows: BTreeMap<String, BTreeMap<String, f64>> = parse(&text, &path).unwrap();
        assert_eq!((rows["a"]["x"], rows["b"]["x"]), (1.0, 2.0));
        std::fs::write(&path, "[a\n").unwrap();
        let e = record(&path, &[("b".to_string(), BTreeMap::from([("x".to_string(), 2.0)]))]).unwrap_err();
        assert!(matches!(e, TableError::Malformed { .. }), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
