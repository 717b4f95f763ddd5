//! Reading `trajectory.mcap` files back into control steps: the inverse of
//! [`super::trajectory::TrajectoryWriter`]. One [`StepRow`] per (episode, step), joining the
//! `/obs`, `/action`, `/reward` and `/info` messages of that step; the `manifest` metadata
//! record; the flow-field snapshots of `/field` (see [`super::field`]).

use super::DataError;
use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value;

/// One control step of one episode. Step 0 is the reset: it has an observation and info but no
/// action or reward.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepRow {
    pub episode: u64,
    pub step: u64,
    pub obs: Vec<f64>,
    pub action: Option<Vec<f64>>,
    pub action_physical: Option<Vec<f64>>,
    pub reward: Option<f64>,
    pub terminated: bool,
    pub truncated: bool,
    /// Numeric info values (`t`, `C_D`, `C_L`, ...); `None` where the writer stored null (NaN).
    pub info: BTreeMap<String, Option<f64>>,
}

/// Everything one trajectory file holds.
#[derive(Clone, Debug, Default)]
pub struct Trajectory {
    pub manifest: BTreeMap<String, String>,
    pub rows: Vec<StepRow>,
    pub fields: Vec<super::field::Snapshot>,
}

/// The registry's ID syntax (`Cylinder_2D_Re100`): an ASCII letter, then letters, digits and
/// '_', at most 64 in all. IDs from files are checked against it before they name a folder.
pub fn is_env_id(s: &str) -> bool {
    let mut c = s.chars();
    s.len() <= 64 && c.next().is_some_and(|c| c.is_ascii_alphabetic()) && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

impl Trajectory {
    /// The manifest's environment ID ([`read`] checks it has the registry's syntax).
    pub fn env_id(&self) -> &str {
        self.manifest.get("env_id").map_or("", |s| s.as_str())
    }

    /// The seed of episode `e`, when the manifest lists one seed per episode.
    pub fn seed_of(&self, e: u64) -> Option<u64> {
        let seeds = self.manifest.get("seeds")?;
        let seeds: Vec<u64> = serde_json::from_str(seeds).ok()?;
        seeds.get(e as usize).copied()
    }

    pub fn episodes(&self) -> usize {
        self.rows.iter().map(|r| r.episode + 1).max().unwrap_or(0) as usize
    }
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
        .unwrap_or_default()
}

/// Longest record a reader accepts (1 GiB; hgym's writer closes chunks at 768 KiB plus one
/// message).
pub const MAX_RECORD: usize = 1 << 30;

/// The messages of an MCAP file in `buf`, in file order, through a reader that bounds every
/// record's declared length, inside chunks too (by 64 times the file's size, at most
/// [`MAX_RECORD`]): `mcap::MessageStream` does not bound the records of a decompressed chunk, so a
/// damaged length there is allocated whole and aborts the process.
pub fn messages(buf: &[u8], skip_end_magic: bool) -> mcap::io::MessageReader<std::io::Cursor<&[u8]>> {
    let limit = buf.len().saturating_mul(64).saturating_add(1 << 20).min(MAX_RECORD);
    mcap::io::MessageReader::new_with_options(
        std::io::Cursor::new(buf),
        mcap::sans_io::LinearReaderOptions::default()
            .with_record_length_limit(limit)
            .with_skip_end_magic(skip_end_magic),
    )
}

/// Reads a complete (or `hgym data recover`-ed) trajectory file.
pub fn read(path: &Path) -> Result<Trajectory, DataError> {
    let buf = std::fs::read(path).map_err(DataError::io(path))?;
    let bad = |e: &dyn std::fmt::Display| {
        DataError::Format(format!(
            "{} is not a readable MCAP file ({e}); if a run was killed, `hgym data recover {}` salvages it",
            path.display(),
            path.display()
        ))
    };
    let mut manifest = BTreeMap::new();
    let summary = mcap::Summary::read(&buf).map_err(|e| bad(&e))?;
    if let Some(summary) = summary {
        for index in &summary.metadata_indexes {
            if index.name == "manifest" {
                let m = mcap::read::metadata(&buf, index).map_err(|e| bad(&e))?;
                manifest = m.metadata;
            }
        }
    } else {
        return Err(bad(&"no summary section: the file was not finished"));
    }
    match manifest.get("env_id") {
        Some(id) if is_env_id(id) => {}
        Some(id) => {
            return Err(DataError::Format(format!(
                "{}: the manifest's env_id {:?} is not an environment ID (a letter, then letters, digits and '_', at most 64); refused, since it would name a folder",
                path.display(),
                id.chars().take(80).collect::<String>()
            )))
        }
        None => {
            return Err(DataError::Format(format!(
                "{}: its manifest has no env_id, so it is not a trajectory hgym wrote",
                path.display()
            )))
        }
    }
    let mut rows: BTreeMap<(u64, u64), StepRow> = BTreeMap::new();
    let mut fields = vec![];
    for m in messages(&buf, false) {
        let m = m.map_err(|e| bad(&e))?;
        if m.channel.topic == "/field" {
            fields.push(super::field::Snapshot::decode(&m.data).map_err(|e| bad(&e))?);
            continue;
        }
        let v: Value = serde_json::from_slice(&m.data).map_err(|e| bad(&e))?;
        let key = (v["episode"].as_u64().unwrap_or(0), v["step"].as_u64().unwrap_or(0));
        let row = rows.entry(key).or_insert_with(|| StepRow {
            episode: key.0,
            step: key.1,
            ..StepRow::default()
        });
        match m.channel.topic.as_str() {
            "/obs" => row.obs = numbers(&v["obs"]),
            "/action" => {
                row.action = Some(numbers(&v["normalised"]));
                row.action_physical = Some(numbers(&v["physical"]));
            }
            "/reward" => {
                row.reward = v["reward"].as_f64();
                row.terminated = v["terminated"].as_bool().unwrap_or(false);
                row.truncated = v["truncated"].as_bool().unwrap_or(false);
            }
            "/info" => {
                if let Some(values) = v["values"].as_object() {
                    row.info = values.iter().map(|(k, x)| (k.clone(), x.as_f64())).collect();
                }
            }
            _ => {}
        }
    }
    Ok(Trajectory {
        manifest,
        rows: rows.into_values().collect(),
        fields,
    })
}
