//! Checkpoints: the learner's whole state (networks, optimisers, replay buffer, generators)
//! plus the run's options and learning curve, written atomically (temporary file, fsync,
//! rename), so a kill at any moment leaves either the previous or the new checkpoint intact.

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::curve::CurveRow;
use crate::flow::Level;

/// 2: the algorithm by name and its learner's own bytes (1 held an enum over the learners).
pub const FORMAT: u32 = 2;
pub const FILE: &str = "checkpoint.bin";

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    pub format: u32,
    pub env_id: String,
    /// The algorithm's registered name.
    pub algo: String,
    pub seed: u64,
    pub level: Level,
    /// The effective training configuration (TOML text).
    pub config_toml: String,
    /// `Learner::to_bytes()` of that algorithm's learner.
    pub learner: Vec<u8>,
    pub curve: Vec<CurveRow>,
    /// Uncontrolled mean C_D of the periodic evaluation episodes.
    pub reference: Vec<f64>,
    /// Wall time spent before this checkpoint, over all sessions of the run.
    pub wall_s: f64,
    /// How many times the run was resumed.
    pub resumed: u32,
}

pub fn save(dir: &Path, ck: &Checkpoint) -> Result<(), String> {
    let bytes = bincode::serialize(ck).map_err(|e| format!("cannot encode the checkpoint: {e}"))?;
    let path = dir.join(FILE);
    let tmp = dir.join(format!("{FILE}.tmp"));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, &path)
    };
    write().map_err(|e| format!("cannot write {}: {e}", path.display()))
}

pub fn load(dir: &Path) -> Result<Checkpoint, String> {
    let path = dir.join(FILE);
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {} ({e}): is this a training result folder?", path.display()))?;
    let ck: Checkpoint =
        bincode::deserialize(&bytes).map_err(|e| format!("{} is damaged or from another hgym version: {e}", path.display()))?;
    if ck.format != FORMAT {
        return Err(format!(
            "{} has checkpoint format {}, this hgym reads {FORMAT}",
            path.display(),
            ck.format
        ));
    }
    Ok(ck)
}
