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
pub mod deploy;
pub mod mapping;
pub mod protocol;
pub mod summary;

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
    /// The training configuration the run was made with (its manifest's `config_toml`).
    pub config_toml: String,
    /// SHA-256 of its `policy.json`.
    pub policy_sha256: String,
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
        let policy_file = dir.join("policy.json");
        let bytes = std::fs::read(&policy_file).map_err(|source| TransferError::Read {
            path: policy_file.clone(),
            source,
        })?;
        let policy_sha256 = format!("{:x}", <sha2::Sha256 as sha2::Digest>::digest(&bytes));
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
            config_toml: m.config_toml,
            policy_sha256,
        })
    }

    /// Whether today's registry gives the run's environment another spec than it was trained on.
    pub fn stale(&self) -> bool {
        self.spec.hash() != self.spec_hash
    }

    /// The map onto `target` and the policy rewritten for it.
    ///
    /// A shared multi-agent actor reads one agent's neighbourhood: it moves onto a target whose
    /// spec splits it into agents of the same local sizes (the channel's patches onto the wing's:
    /// both see `u'` and `v'` at `y+ = 15` of 3 x 3 patches in local viscous units and set one
    /// patch), acting for every target agent; the map is then the identity on one agent's spaces.
    pub fn onto(&self, target: &Spec, mapping: &MappingSpec) -> Result<(SpaceMap, ActorPolicy), TransferError> {
        let p = &self.policy;
        if let (Some(ours), Some(theirs)) = (&p.agents, target.decomposition()) {
            let local = |a: &hgym_agents::multi::Agents| (a.local_obs_dim(), a.local_act_dim());
            if self.env_id != target.id() && local(ours) == local(&theirs) {
                let (obs, act) = local(ours);
                return Ok((SpaceMap::identity(obs, act), p.clone().with_agents(theirs)));
            }
        }
        let map = resolve((&self.env_id, &self.spec.layout()), (target.id(), &target.layout()), mapping)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::registry::lookup;
    use hgym_agents::nn::{Activation, Init, Mlp};
    use hgym_agents::policy::Policy;
    use hgym_agents::rng::Rng;
    use hgym_agents::Info;

    /// A run of `env_id` holding `policy` (the folder is never read).
    fn run(env_id: &str, policy: ActorPolicy) -> SourceRun {
        let spec = lookup(env_id).unwrap();
        SourceRun {
            dir: PathBuf::from("source"),
            policy,
            env_id: env_id.into(),
            spec_hash: spec.hash(),
            algo: "td3".into(),
            seed: 0,
            level: "default".into(),
            spec,
            config_toml: String::new(),
            policy_sha256: String::new(),
        }
    }

    fn actor(obs: usize, act: usize) -> ActorPolicy {
        let net = Mlp::new(
            &[obs, 8, act],
            Activation::Relu,
            Activation::Tanh,
            Init::FanIn,
            Init::FanIn,
            &mut Rng::seed(1),
        );
        ActorPolicy::new("td3", net, None, 10.0)
    }

    #[test]
    fn a_channel_agents_actor_acts_for_every_patch_of_the_wing() {
        let channel = lookup("TCFOpen_3D_Retau206").unwrap();
        let agents = channel.decomposition().unwrap();
        let src = run(
            "TCFOpen_3D_Retau206",
            actor(agents.local_obs_dim(), agents.local_act_dim()).with_agents(agents),
        );
        let wing = lookup("WingTBL_3D_Rec200000").unwrap();
        let (map, mut p) = src.onto(&wing, &MappingSpec::default()).unwrap();
        assert!(map.is_identity());
        assert_eq!((p.obs_dim(), p.act_dim()), (wing.obs_dim(), wing.act_dim()));
        // Each patch's action is the shared actor on that patch's neighbourhood.
        let obs: Vec<f64> = (0..wing.obs_dim()).map(|k| ((k * 7919) % 13) as f64 / 13.0 - 0.5).collect();
        let mut act = vec![0.0; wing.act_dim()];
        p.act(&obs, &Info::default(), &mut act);
        let theirs = wing.decomposition().unwrap();
        let mut one = actor(18, 1);
        let (mut local, mut a) = (vec![], vec![0.0]);
        for agent in [0, 7, theirs.len() - 1] {
            theirs.gather(agent, &obs, &mut local);
            one.act(&local, &Info::default(), &mut a);
            assert_eq!(act[theirs.act[agent][0]], a[0], "agent {agent}");
        }
    }

    #[test]
    fn a_single_agent_policy_does_not_move_onto_the_wing() {
        let channel = lookup("TCFOpen_3D_Retau206").unwrap();
        let src = run("TCFOpen_3D_Retau206", actor(channel.obs_dim(), channel.act_dim()));
        let wing = lookup("WingTBL_3D_Rec200000").unwrap();
        assert!(src.onto(&wing, &MappingSpec::default()).is_err());
    }
}
