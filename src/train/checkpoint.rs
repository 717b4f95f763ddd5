//! Checkpoints: the learner's whole state (networks, optimisers, replay buffer, generators)
//! plus the run's options and learning curve, written atomically (temporary file, fsync,
//! rename), so a kill at any moment leaves either the previous or the new checkpoint intact.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::curve::CurveRow;
use crate::flow::Level;

/// 3: TD3/DDPG learners with `gradient_steps`, `action_l2` and the warm start of a fine-tuned
/// actor; 2: the algorithm by name and its learner's own bytes (1 held an enum over the learners).
pub const FORMAT: u32 = 3;
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

/// Why a checkpoint could not be written or read back.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read {} (is this a training result folder?)", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{} is damaged or from another hgym version", path.display())]
    Decode {
        path: PathBuf,
        #[source]
        source: bincode::Error,
    },
    #[error("cannot encode the checkpoint")]
    Encode(#[source] bincode::Error),
    #[error("{} has checkpoint format {found}, this hgym reads {FORMAT}", path.display())]
    Format { path: PathBuf, found: u32 },
}

impl CheckpointError {
    /// Whether the error is the user's input (a folder that holds no readable checkpoint).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            CheckpointError::Read { .. } | CheckpointError::Decode { .. } | CheckpointError::Format { .. }
        )
    }
}

pub fn save(dir: &Path, ck: &Checkpoint) -> Result<(), CheckpointError> {
    let bytes = bincode::serialize(ck).map_err(CheckpointError::Encode)?;
    let path = dir.join(FILE);
    let tmp = dir.join(format!("{FILE}.tmp"));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(&bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, &path)
    };
    write().map_err(|source| CheckpointError::Write { path, source })
}

pub fn load(dir: &Path) -> Result<Checkpoint, CheckpointError> {
    let path = dir.join(FILE);
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(source) => return Err(CheckpointError::Read { path, source }),
    };
    let ck: Checkpoint = match bincode::deserialize(&bytes) {
        Ok(ck) => ck,
        Err(source) => return Err(CheckpointError::Decode { path, source }),
    };
    if ck.format != FORMAT {
        return Err(CheckpointError::Format { path, found: ck.format });
    }
    Ok(ck)
}
