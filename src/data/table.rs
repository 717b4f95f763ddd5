//! Trajectories as tables (polars): one row per control step, and one row per flow-field
//! snapshot. Columns of the step table: `run` (the trajectory's folder), `env_id`, `policy`,
//! `seed`, `episode`, `step`, `t`, `obs`, `action`, `action_physical` (lists; null at the
//! reset, step 0), `reward` (null at step 0), `terminated`, `truncated`, then every numeric info
//! value under its snake-case name (`c_d`, `c_l`, `abs_c_l`, `actuation_0`, ...).

use super::DataError;
use std::collections::BTreeSet;

use polars::prelude::*;

use super::read::Trajectory;

/// A trajectory with the name of the run it belongs to.
pub struct Source<'a> {
    pub run: String,
    pub trajectory: &'a Trajectory,
}

/// Info keys become column names: `C_D` -> `c_d`, `abs_C_L` -> `abs_c_l`.
pub fn column_name(key: &str) -> String {
    key.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' })
        .collect()
}

const FIXED: [&str; 13] = [
    "run",
    "env_id",
    "policy",
    "seed",
    "episode",
    "step",
    "t",
    "obs",
    "action",
    "action_physical",
    "reward",
    "terminated",
    "truncated",
];

fn list(name: &str, rows: Vec<Option<Vec<f64>>>) -> Column {
    let series: Vec<Option<Series>> = rows.into_iter().map(|r| r.map(|v| Series::new(PlSmallStr::EMPTY, v))).collect();
    let s = Series::new(name.into(), series);
    // An all-null column would have dtype Null: give it the list type readers expect.
    s.cast(&DataType::List(Box::new(DataType::Float64)))
        .unwrap_or_else(|_| Series::new_null(name.into(), 0))
        .into_column()
}

/// The step table of `sources` (in the given order, rows in (episode, step) order).
pub fn steps(sources: &[Source]) -> Result<DataFrame, DataError> {
    let info_keys: BTreeSet<String> = sources
        .iter()
        .flat_map(|s| s.trajectory.rows.iter().flat_map(|r| r.info.keys().cloned()))
        .filter(|k| k != "t")
        .collect();
    for k in &info_keys {
        if FIXED.contains(&column_name(k).as_str()) {
            return Err(DataError::Format(format!(
                "info value '{k}' would shadow the column '{}'",
                column_name(k)
            )));
        }
    }
    let n: usize = sources.iter().map(|s| s.trajectory.rows.len()).sum();
    let (mut run, mut env_id, mut policy) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    let (mut seed, mut episode, mut step, mut t) = (vec![], vec![], vec![], vec![]);
    let (mut obs, mut action, mut physical) = (vec![], vec![], vec![]);
    let (mut reward, mut terminated, mut truncated) = (vec![], vec![], vec![]);
    let mut info: Vec<Vec<Option<f64>>> = vec![Vec::with_capacity(n); info_keys.len()];
    for s in sources {
        let tr = s.trajectory;
        let pol = tr.manifest.get("policy").cloned().unwrap_or_default();
        for r in &tr.rows {
            run.push(s.run.clone());
            env_id.push(tr.env_id().to_string());
            policy.push(pol.clone());
            seed.push(tr.seed_of(r.episode).map(|v| v as i64));
            episode.push(r.episode as i64);
            step.push(r.step as i64);
            t.push(r.info.get("t").copied().flatten());
            obs.push(Some(r.obs.clone()));
            action.push(r.action.clone());
            physical.push(r.action_physical.clone());
            reward.push(r.reward);
            terminated.push(r.terminated);
            truncated.push(r.truncated);
            for (col, k) in info.iter_mut().zip(&info_keys) {
                col.push(r.info.get(k).copied().flatten());
            }
        }
    }
    let mut columns = vec![
        Column::new("run".into(), run),
        Column::new("env_id".into(), env_id),
        Column::new("policy".into(), policy),
        Column::new("seed".into(), seed),
        Column::new("episode".into(), episode),
        Column::new("step".into(), step),
        Column::new("t".into(), t),
        list("obs", obs),
        list("action", action),
        list("action_physical", physical),
        Column::new("reward".into(), reward),
        Column::new("terminated".into(), terminated),
        Column::new("truncated".into(), truncated),
    ];
    for (k, col) in info_keys.iter().zip(info) {
        columns.push(Column::new(column_name(k).into(), col));
    }
    Ok(DataFrame::new(n, columns)?)
}

/// The snapshot table: `run`, `env_id`, `episode`, `step`, `t`, `nx`, `ny`, `extent`
/// (x0, x1, y0, y1) and one float32 list column per field (`u`, `v`, `vorticity`), row-major
/// `f[y * nx + x]`.
pub fn fields(sources: &[Source]) -> Result<Option<DataFrame>, DataError> {
    let names: BTreeSet<String> = sources
        .iter()
        .flat_map(|s| s.trajectory.fields.iter().flat_map(|f| f.fields.iter().map(|(n, _)| n.clone())))
        .collect();
    let n: usize = sources.iter().map(|s| s.trajectory.fields.len()).sum();
    if n == 0 {
        return Ok(None);
    }
    let (mut run, mut env_id, mut episode, mut step, mut t) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut nx, mut ny, mut extent) = (vec![], vec![], vec![]);
    let mut values: Vec<Vec<Option<Series>>> = vec![vec![]; names.len()];
    for s in sources {
        for f in &s.trajectory.fields {
            run.push(s.run.clone());
            env_id.push(s.trajectory.env_id().to_string());
            episode.push(f.episode as i64);
            step.push(f.step as i64);
            t.push(f.t);
            nx.push(f.nx as i64);
            ny.push(f.ny as i64);
            extent.push(Some(f.extent.to_vec()));
            for (col, name) in values.iter_mut().zip(&names) {
                col.push(
                    f.fields
                        .iter()
                        .find(|(n, _)| n == name)
                        .map(|(_, v)| Series::new(PlSmallStr::EMPTY, v.as_slice())),
                );
            }
        }
    }
    let mut columns = vec![
        Column::new("run".into(), run),
        Column::new("env_id".into(), env_id),
        Column::new("episode".into(), episode),
        Column::new("step".into(), step),
        Column::new("t".into(), t),
        Column::new("nx".into(), nx),
        Column::new("ny".into(), ny),
        list("extent", extent),
    ];
    for (name, col) in names.iter().zip(values) {
        columns.push(Series::new(column_name(name).into(), col).into_column());
    }
    Ok(Some(DataFrame::new(n, columns)?))
}

/// Writes `df` rows `[start, start + len)` as a zstd-compressed Parquet file.
pub fn write_parquet(df: &DataFrame, start: usize, len: usize, path: &std::path::Path) -> Result<u64, DataError> {
    let mut part = df.slice(start as i64, len);
    let file = std::fs::File::create(path).map_err(DataError::io(path))?;
    Ok(ParquetWriter::new(file)
        .with_compression(ParquetCompression::Zstd(None))
        .finish(&mut part)?)
}
