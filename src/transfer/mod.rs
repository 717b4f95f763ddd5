//! Transfer between environments: a policy trained on one flow, evaluated zero-shot on another
//! (`hgym eval --policy DIR --env TARGET`) or fine-tuned there (`hgym train --init-from DIR`),
//! and the protocols that compare both with training from scratch (`hgym transfer`).
//!
//! - [`mapping`]: which target observation each source observation reads and which source
//!   action drives each target actuator, from the environments' layouts
//!   ([`crate::env::layout`]) and a protocol's `[mapping]` table;
//! - [`protocol`]: the protocol files (`benchmarks/protocols/transfer/*.toml`) and their arms;
//! - [`compare`]: the comparison of the arms (`comparison.json`, the learning-curve plot).
//!
//! The network itself is rewritten by `hgym_agents::transplant` (first-layer columns and
//! last-layer rows), so a zero-shot evaluation and the first evaluation of a fine-tuning run
//! act through the same network.

pub mod compare;
pub mod mapping;
pub mod protocol;

use std::path::{Path, PathBuf};

use hgym_agents::policy::ActorPolicy;
use hgym_agents::transplant::SpaceMap;
use serde::Deserialize;

use self::mapping::{resolve, MappingError, MappingSpec};
use crate::env::Spec;
use crate::train::config::TrainConfig;
use crate::train::eval::{parse_policy, NamedPolicy};
use crate::train::InitRecord;

/// Why a source run cannot be moved to a target.
#[derive(Debug, thiserror::Error)]
pub enum TransferError {
    /// A folder without a finished run, a policy file that does not load (bad input).
    #[error("{0}")]
    Source(String),
    #[error(transparent)]
    Mapping(#[from] MappingError),
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl TransferError {
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, TransferError::Read { .. })
    }
}

/// The fields of a run's `manifest.json` a transfer reads.
#[derive(Clone, Debug, Deserialize)]
struct RunManifest {
    env_id: String,
    spec_hash: String,
    algo: String,
    seed: u64,
    level: String,
    config_toml: String,
}

/// A finished training run used as a source: its policy and its environment.
#[derive(Clone, Debug)]
pub struct SourceRun {
    pub dir: PathBuf,
    pub policy: ActorPolicy,
    pub env_id: String,
    /// The spec hash the run was trained on.
    pub spec_hash: String,
    pub algo: String,
    pub seed: u64,
    pub level: String,
    /// Today's registered spec with the run's `[env]` overrides (its layout is read from here).
    pub spec: Spec,
}

impl SourceRun {
    /// The finished run in `dir` (its `policy.json` and `manifest.json`).
    pub fn load(dir: &Path) -> Result<SourceRun, TransferError> {
        let bad = |m: String| TransferError::Source(m);
        let manifest = dir.join("manifest.json");
        if !dir.join("policy.json").exists() || !manifest.exists() {
            return Err(bad(format!(
                "{} holds no finished training run (policy.json and manifest.json); train one with `hgym train --env ID --out DIR`",
                dir.display()
            )));
        }
        let policy = match parse_policy(&dir.display().to_string()) {
            Ok(NamedPolicy::Trained(p)) => *p,
            Ok(NamedPolicy::Baseline(_)) => return Err(bad(format!("{} names a baseline, not a run folder", dir.display()))),
            Err(e) => return Err(bad(e.to_string())),
        };
        let text = std::fs::read_to_string(&manifest).map_err(|source| TransferError::Read {
            path: manifest.clone(),
            source,
        })?;
        let m: RunManifest =
            serde_json::from_str(&text).map_err(|e| bad(format!("{} is not a training manifest: {e}", manifest.display())))?;
        let config = TrainConfig::parse(&m.config_toml, &manifest.display().to_string()).map_err(|e| bad(e.to_string()))?;
        let spec = crate::train::resolve_spec(&m.env_id, &config).map_err(|e| bad(e.to_string()))?;
        Ok(SourceRun {
            dir: dir.to_path_buf(),
            policy,
            env_id: m.env_id,
            spec_hash: m.spec_hash,
            algo: m.algo,
            seed: m.seed,
            level: m.level,
            spec,
        })
    }

    /// Whether today's registry gives the run's environment another spec than it was trained on.
    pub fn stale(&self) -> bool {
        self.spec.hash() != self.spec_hash
    }

    /// The map onto `target` and the policy rewritten for it.
    pub fn onto(&self, target: &Spec, mapping: &MappingSpec) -> Result<(SpaceMap, ActorPolicy), TransferError> {
        let map = resolve((&self.env_id, &self.spec.layout()), (target.id(), &target.layout()), mapping)?;
        let p = &self.policy;
        if p.agents.is_some() {
            // A shared actor reads one agent's neighbourhood, not the whole flow: it moves only
            // onto the flow it was trained on.
            return match map.is_identity() {
                true => Ok((map, p.clone())),
                false => Err(TransferError::Source(format!(
                    "{} holds a multi-agent policy (one actor per actuator patch); moving it to {} \
                     through a map of whole observations is not supported",
                    self.dir.display(),
                    target.id()
                ))),
            };
        }
        let policy = ActorPolicy::new(
            &p.algo,
            map.actor(&p.net),
            p.obs_norm.as_ref().map(|n| map.obs_stats(n)),
            p.obs_clip,
        );
        Ok((map, policy))
    }

    pub fn record(&self, mapping: &MappingSpec, map: &SpaceMap, critics: bool, buffer: bool) -> InitRecord {
        InitRecord {
            dir: self.dir.clone(),
            env_id: self.env_id.clone(),
            spec_hash: self.spec_hash.clone(),
            algo: self.algo.clone(),
            seed: self.seed,
            level: self.level.clone(),
            mapping: serde_json::json!({ "tolerance": mapping.tolerance, "actions": mapping.actions }),
            identity: map.is_identity(),
            critics,
            buffer,
        }
    }
}

/// The `[mapping]` table of a TOML file (a protocol file or a file of its own); the defaults
/// when the file has none.
pub fn load_mapping(path: &Path) -> Result<MappingSpec, TransferError> {
    let text = std::fs::read_to_string(path).map_err(|source| TransferError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    #[derive(Deserialize)]
    struct File {
        #[serde(default)]
        mapping: MappingSpec,
    }
    let f: toml::Table = toml::from_str(&text).map_err(|e| TransferError::Source(format!("{}: {e}", path.display())))?;
    let file: File = toml::Value::Table(f)
        .try_into()
        .map_err(|e: toml::de::Error| TransferError::Source(format!("{} [mapping]: {e}", path.display())))?;
    Ok(file.mapping)
}
