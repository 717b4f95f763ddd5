//! `hgym export --to hf DIR OUT`: trajectory files become a Hugging Face dataset folder.
//!
//! ```text
//! OUT/README.md                                  dataset card (YAML front matter the Hub reads)
//! OUT/data/<ENV>/train-00000-of-0000N.parquet    one row per control step (see super::table)
//! OUT/fields/<ENV>/train-...parquet              flow-field snapshots, if the files have any
//! OUT/hgym_export.json                           what was exported from where (schemas/hf-export.json)
//! ```
//! One Hub *config* per environment (`load_dataset(repo, "Cylinder_2D_Re100")`) and one per
//! environment's snapshots (`"<ENV>-fields"`). Files are read in path order, so the same input
//! gives the same shards.

use super::DataError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::read::{self, Trajectory};
use super::table::{self, Source};

/// Options of an export.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    /// Rows per Parquet shard of the step table.
    pub shard_rows: usize,
    /// Snapshots per Parquet shard of the field table.
    pub shard_fields: usize,
    /// SPDX licence identifier for the card (`license:` in the front matter).
    pub license: String,
    /// Dataset title.
    pub pretty_name: Option<String>,
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            shard_rows: 100_000,
            shard_fields: 200,
            license: "cc-by-4.0".into(),
            pretty_name: None,
        }
    }
}

/// One exported trajectory file.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ExportedRun {
    pub run: String,
    pub file: String,
    pub env_id: String,
    pub spec_hash: String,
    pub level: String,
    pub policy: String,
    pub seeds: String,
    pub code_version: String,
    pub git_commit: String,
    pub episodes: usize,
    pub rows: usize,
    pub snapshots: usize,
}

/// What `export` wrote (`OUT/hgym_export.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ExportReport {
    pub schema: String,
    pub out: String,
    pub configs: Vec<String>,
    pub files: Vec<String>,
    pub rows: usize,
    pub snapshots: usize,
    pub runs: Vec<ExportedRun>,
    pub code_version: String,
}

/// Every `*.mcap` under `dir` (or `dir` itself if it is one), sorted.
pub fn find_trajectories(dir: &Path) -> Result<Vec<PathBuf>, DataError> {
    if dir.is_file() {
        return Ok(vec![dir.to_path_buf()]);
    }
    if !dir.is_dir() {
        return Err(DataError::Format(format!("{} does not exist", dir.display())));
    }
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries = std::fs::read_dir(&d).map_err(DataError::io(&d))?;
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "mcap") {
                out.push(p);
            }
        }
    }
    out.sort();
    if out.is_empty() {
        return Err(DataError::Format(format!(
            "no .mcap trajectory under {}: write some with `hgym run`, `hgym eval --out DIR` or `hgym train`",
            dir.display()
        )));
    }
    Ok(out)
}

/// Shard `k` of `n` of a table.
fn shard_name(k: usize, n: usize) -> String {
    format!("train-{k:05}-of-{n:05}.parquet")
}

fn write_shards(df: &polars::prelude::DataFrame, per: usize, dir: &Path, out: &Path, files: &mut Vec<String>) -> Result<(), DataError> {
    std::fs::create_dir_all(dir).map_err(DataError::io(dir))?;
    let rows = df.height();
    let n = rows.div_ceil(per.max(1)).max(1);
    for k in 0..n {
        let path = dir.join(shard_name(k, n));
        table::write_parquet(df, k * per, per.min(rows - (k * per).min(rows)), &path)?;
        files.push(path.strip_prefix(out).unwrap_or(&path).to_string_lossy().replace('\\', "/"));
    }
    Ok(())
}

/// Refuses to overwrite a folder that is not an earlier export; clears an earlier export's data.
fn prepare(out: &Path) -> Result<(), DataError> {
    if out.exists() {
        let is_export = out.join("hgym_export.json").exists();
        let empty = std::fs::read_dir(out).map(|mut d| d.next().is_none()).unwrap_or(false);
        if !is_export && !empty {
            return Err(DataError::Format(format!(
                "{} exists and is not an hgym export (no hgym_export.json): choose an empty or new folder",
                out.display()
            )));
        }
        for sub in ["data", "fields"] {
            let p = out.join(sub);
            if p.exists() {
                std::fs::remove_dir_all(&p).map_err(DataError::io(&p))?;
            }
        }
    }
    std::fs::create_dir_all(out).map_err(DataError::io(out))
}

/// Exports every trajectory under `dir` to the dataset folder `out`.
pub fn export(dir: &Path, out: &Path, opts: &ExportOptions, progress: &mut dyn FnMut(usize, usize)) -> Result<ExportReport, DataError> {
    let paths = find_trajectories(dir)?;
    let mut trajectories: Vec<(String, String, Trajectory)> = vec![];
    for (k, p) in paths.iter().enumerate() {
        let tr = read::read(p)?;
        let base = if dir.is_file() { dir.parent().unwrap_or(dir) } else { dir };
        let rel = p.strip_prefix(base).unwrap_or(p);
        let run = rel.parent().map(|r| r.to_string_lossy().replace('\\', "/")).unwrap_or_default();
        let run = if run.is_empty() { ".".to_string() } else { run };
        trajectories.push((run, rel.to_string_lossy().replace('\\', "/"), tr));
        progress(k + 1, paths.len());
    }
    prepare(out)?;
    let mut by_env: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for (k, (_, _, tr)) in trajectories.iter().enumerate() {
        by_env.entry(tr.env_id().to_string()).or_default().push(k);
    }
    let mut files = vec![];
    let mut configs = vec![];
    let (mut rows, mut snapshots) = (0, 0);
    for (env, idx) in &by_env {
        let sources: Vec<Source> = idx
            .iter()
            .map(|&k| Source {
                run: trajectories[k].0.clone(),
                trajectory: &trajectories[k].2,
            })
            .collect();
        let df = table::steps(&sources)?;
        rows += df.height();
        write_shards(&df, opts.shard_rows, &out.join("data").join(env), out, &mut files)?;
        configs.push(env.clone());
        if let Some(f) = table::fields(&sources)? {
            snapshots += f.height();
            write_shards(&f, opts.shard_fields, &out.join("fields").join(env), out, &mut files)?;
            configs.push(format!("{env}-fields"));
        }
    }
    let get = |tr: &Trajectory, k: &str| tr.manifest.get(k).cloned().unwrap_or_default();
    let runs: Vec<ExportedRun> = trajectories
        .iter()
        .map(|(run, file, tr)| ExportedRun {
            run: run.clone(),
            file: file.clone(),
            env_id: tr.env_id().to_string(),
            spec_hash: get(tr, "spec_hash"),
            level: get(tr, "level"),
            policy: get(tr, "policy"),
            seeds: get(tr, "seeds"),
            code_version: get(tr, "code_version"),
            git_commit: get(tr, "git_commit"),
            episodes: tr.episodes(),
            rows: tr.rows.len(),
            snapshots: tr.fields.len(),
        })
        .collect();
    let report = ExportReport {
        schema: "hgym/hf-export/v1".into(),
        out: out.display().to_string(),
        configs,
        files,
        rows,
        snapshots,
        runs,
        code_version: crate::report::manifest::manifest(1, 0.0).code_version,
    };
    let card = super::card::card(&report, &trajectories.iter().map(|(_, _, t)| t).collect::<Vec<_>>(), opts);
    let w = |name: &str, text: String| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(DataError::io(&path))
    };
    w("README.md", card)?;
    w("hgym_export.json", serde_json::to_string_pretty(&report)? + "\n")?;
    Ok(report)
}
