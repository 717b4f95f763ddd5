//! Checkpoints: the learner's whole state (networks, optimisers, replay buffer, generators)
//! plus the run's options and learning curve, written atomically (temporary file, fsync,
//! rename), so a kill at any moment leaves either the previous or the new checkpoint intact.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::curve::CurveRow;
use crate::flow::Level;

/// 4: the worker thread count; 3: TD3/DDPG learners with `gradient_steps`, `action_l2` and the
/// warm start of a fine-tuned actor; 2: the algorithm by name and its learner's own bytes (1 held
/// an enum over the learners). Format 3 is still read (its thread count unknown).
pub const FORMAT: u32 = 5;
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
    /// Worker threads of the session that wrote it (`None` from format 3): a run is bitwise
    /// repeatable for the same seed and thread count, so a resume keeps this count. Stays the
    /// field before `cpu_s` (`load` reads format 3 by appending it).
    pub threads: Option<usize>,
    /// CPU time spent before this checkpoint, over all sessions of the run (`None` from format
    /// 4, or when a session could not measure it). Stays the last field (`load` reads formats 3
    /// and 4 by appending it).
    pub cpu_s: Option<f64>,
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
    #[error("{} has checkpoint format {found}, this hgym reads formats 3 to {FORMAT}", path.display())]
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
    // Every format starts with its number. bincode writes the fields in order, so format 4 is
    // format 5 without the trailing `cpu_s`, and format 3 also lacks `threads` before it: one byte
    // 0 (`None`) appended per missing field makes them format 5.
    let decoded = match bincode::deserialize::<u32>(&bytes) {
        Ok(FORMAT) => bincode::deserialize::<Checkpoint>(&bytes),
        Ok(4) => bincode::deserialize::<Checkpoint>(&[bytes.as_slice(), &[0]].concat()),
        Ok(3) => bincode::deserialize::<Checkpoint>(&[bytes.as_slice(), &[0, 0]].concat()),
        Ok(found) => return Err(CheckpointError::Format { path, found }),
        Err(source) => Err(source),
    };
    decoded.map_err(|source| CheckpointError::Decode { path, source })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(threads: Option<usize>) -> Checkpoint {
        Checkpoint {
            format: FORMAT,
            env_id: "Cylinder_2D_Re100".into(),
            algo: "td3".into(),
            seed: 7,
            level: Level::Coarse,
            config_toml: "[train]\nsteps = 10\n".into(),
            learner: vec![1, 2, 3],
            curve: vec![],
            reference: vec![1.5],
            wall_s: 2.5,
            resumed: 1,
            threads,
            cpu_s: None,
        }
    }

    #[test]
    fn round_trip_keeps_the_thread_count() {
        let dir = tempfile::tempdir().unwrap();
        save(dir.path(), &sample(Some(2))).unwrap();
        let ck = load(dir.path()).unwrap();
        assert_eq!(ck.threads, Some(2));
        assert_eq!(ck.cpu_s, None);
        let mut with_cpu = sample(Some(2));
        with_cpu.cpu_s = Some(12.5);
        save(dir.path(), &with_cpu).unwrap();
        assert_eq!(load(dir.path()).unwrap().cpu_s, Some(12.5));
        assert_eq!((ck.seed, ck.learner, ck.resumed), (7, vec![1, 2, 3], 1));
    }

    #[test]
    fn format_3_reads_with_the_thread_count_unknown() {
        let dir = tempfile::tempdir().unwrap();
        // bincode writes the fields in order: format 3 is format 5 without the trailing
        // `threads` and `cpu_s` (`None`, one byte each) and with another number in front.
        let mut bytes = bincode::serialize(&sample(None)).unwrap();
        assert_eq!((bytes.pop(), bytes.pop()), (Some(0), Some(0)));
        bytes[..4].copy_from_slice(&3u32.to_le_bytes());
        std::fs::write(dir.path().join(FILE), bytes).unwrap();
        let ck = load(dir.path()).unwrap();
        assert_eq!((ck.format, ck.threads, ck.cpu_s, ck.seed, ck.wall_s), (3, None, None, 7, 2.5));
    }

    #[test]
    fn format_4_reads_with_the_cpu_time_unknown() {
        let dir = tempfile::tempdir().unwrap();
        let mut bytes = bincode::serialize(&sample(Some(2))).unwrap();
        assert_eq!(bytes.pop(), Some(0));
        bytes[..4].copy_from_slice(&4u32.to_le_bytes());
        std::fs::write(dir.path().join(FILE), bytes).unwrap();
        let ck = load(dir.path()).unwrap();
        assert_eq!((ck.format, ck.threads, ck.cpu_s), (4, Some(2), None));
    }

    #[test]
    fn an_older_format_is_refused_by_number() {
        let dir = tempfile::tempdir().unwrap();
        let mut c = sample(Some(1));
        c.format = 2;
        save(dir.path(), &c).unwrap();
        match load(dir.path()) {
            Err(e @ CheckpointError::Format { found: 2, .. }) => assert!(e.to_string().contains("formats 3 to 5"), "{e}"),
            other => panic!("expected a format error, got {other:?}"),
        }
    }
}
