//! Environment families behind one trait. A family is one file (`cylinder.rs`, `kolmogorov.rs`,
//! ...) with a unit struct implementing [`Family`], plus one line in [`super::registry::FAMILIES`].
//! Its specs implement [`FamilySpec`]: the 2D lattice-Boltzmann families share
//! [`super::EnvSpec`] (implemented in `lbm_env.rs`), the spectral Kolmogorov flows have their own.
//! Training, evaluation, listings and the data commands see only [`Spec`] and [`FlowEnv`].

use std::any::Any;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use hgym_agents::{DifferentiableEnv, EnvError};
use serde::de::DeserializeOwned;
use serde::Serialize;

use super::clock::SolverTime;
use super::fields::FlowFields;
use super::EnvInputError;
use crate::flow::Level;

/// A family of environment IDs.
pub trait Family: Sync {
    /// Its registered specs, in listing order, with their committed statistics attached.
    fn specs(&self) -> Vec<Spec>;
}

/// What a running environment of any family offers: the Gymnasium contract, the reward
/// gradient where the family is differentiable (an error naming the alternatives elsewhere),
/// flow-field snapshots for trajectories, and the time its solver has stepped.
pub trait FlowEnv: DifferentiableEnv + FlowFields + SolverTime + Send {}

impl<T: DifferentiableEnv + FlowFields + SolverTime + Send> FlowEnv for T {}

/// A family's spec: the description of one ID that builds its environment.
pub trait FamilySpec: Any + Send + Sync + std::fmt::Debug {
    fn id(&self) -> &str;
    fn family(&self) -> &str;
    fn reynolds(&self) -> f64;
    /// The solver that runs it (`lbm-d2q9`, `spectral`, ...).
    fn solver(&self) -> &'static str;
    fn dimension(&self) -> u8 {
        2
    }
    fn obs_dim(&self) -> usize;
    fn act_dim(&self) -> usize;
    /// Physical time between actions.
    fn control_interval(&self) -> f64;
    /// What each observation and action means (for transfer between environments); by default
    /// they are known by index.
    fn layout(&self) -> super::layout::Layout {
        super::layout::Layout::indexed(self.obs_dim(), self.act_dim())
    }
    /// Whether [`DifferentiableEnv::reward_action_gradients`] works on its environments.
    fn differentiable(&self) -> bool {
        false
    }
    /// How its environments split into agents (`Env::agents`), where the spec alone tells (the
    /// wall-actuated flows: one agent per patch). Transfer reads it to move a shared actor onto
    /// another flow's agents.
    fn decomposition(&self) -> Option<hgym_agents::multi::Agents> {
        None
    }
    /// Whether committed observation statistics are attached.
    fn calibrated(&self) -> bool;
    /// Things that run but may not give what the user wants (the commands print them).
    fn warnings(&self) -> Vec<String> {
        vec![]
    }
    /// SHA-256 of the spec's JSON form (keys caches and results).
    fn hash(&self) -> String;
    /// The spec as JSON (as written into manifests).
    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error>;
    /// The spec as TOML (`hgym envs show ID`).
    fn to_toml(&self) -> String;
    /// The spec with TOML overrides deep-merged (unknown fields and wrong types are errors that
    /// name the field).
    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError>;
    /// A running environment at `level` (`cache`: where developed-flow states are kept).
    fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError>;
    /// Measures the uncontrolled flow's statistics at `level` over `actions` control intervals
    /// and records them in `table` (the family's committed table when `None`), atomically.
    /// Returns a one-line summary and the table written.
    fn calibrate(
        &self,
        level: Level,
        actions: usize,
        cache: Option<PathBuf>,
        table: Option<&Path>,
        progress: &mut dyn FnMut(usize),
    ) -> Result<(String, PathBuf), CalibrateError>;
    fn as_any(&self) -> &dyn Any;
}

/// The episode fields every family shares, checked: a control interval in (0, 1000] time units,
/// 1 to 10^7 actions per episode, a spin-up in [0, 10^5].
pub(crate) fn check_episode(control_interval: f64, episode_actions: usize, spin_up: f64) -> Result<(), String> {
    if !(control_interval.is_finite() && control_interval > 0.0 && control_interval <= 1e3) {
        return Err(format!("control_interval must be a time in (0, 1000], got {control_interval}"));
    }
    if !(1..=10_000_000).contains(&episode_actions) {
        return Err(format!("episode_actions must be 1 to 10000000, got {episode_actions}"));
    }
    if !(spin_up.is_finite() && (0.0..=1e5).contains(&spin_up)) {
        return Err(format!("spin_up must be a time in [0, 100000], got {spin_up}"));
    }
    Ok(())
}

/// One uncontrolled control interval of a calibration run; a diverged flow is an error naming
/// the ID and the solver's reason.
pub(crate) fn uncontrolled_step<E: hgym_agents::Env + ?Sized>(
    env: &mut E,
    id: &str,
    zero: &[f64],
) -> Result<hgym_agents::StepResult, EnvError> {
    let r = env.step(zero)?;
    if r.terminated {
        return Err(EnvError::Backend(format!(
            "{id}: uncontrolled run diverged: {}",
            r.info.text("reason").unwrap_or("?")
        )));
    }
    Ok(r)
}

/// What every calibration checks before it runs: at least one action, and a table (`table`, else
/// the family's `committed` one) that reads as a table of `T` (or does not exist yet).
pub(crate) fn calibration_table<T: DeserializeOwned>(
    actions: usize,
    table: Option<&Path>,
    committed: &str,
) -> Result<PathBuf, CalibrateError> {
    if actions == 0 {
        return Err(CalibrateError::NoActions);
    }
    let table = table.map_or_else(|| PathBuf::from(committed), Path::to_path_buf);
    crate::report::table::check::<T>(&table)?;
    Ok(table)
}

/// Why a calibration did not record its statistics.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    #[error("--actions must be at least 1")]
    NoActions,
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error(transparent)]
    Table(#[from] crate::report::table::TableError),
}

/// A spec of any family (cheap to clone; serialises as the family's own spec).
#[derive(Clone, Debug)]
pub struct Spec(Arc<dyn FamilySpec>);

impl Spec {
    pub fn new(spec: impl FamilySpec) -> Self {
        Spec(Arc::new(spec))
    }

    /// The family's own spec type, if it is `T`.
    pub fn downcast<T: FamilySpec>(&self) -> Option<&T> {
        self.0.as_any().downcast_ref::<T>()
    }

    /// The metadata record of a trajectory file: spec, hash, level, policy, seeds, code version.
    pub fn trajectory_manifest(
        &self,
        level: Level,
        policy: &str,
        seeds: &[u64],
    ) -> Result<std::collections::BTreeMap<String, String>, serde_json::Error> {
        let m = crate::report::manifest::manifest(rayon::current_num_threads(), 0.0);
        Ok([
            ("env_id", self.id().to_string()),
            ("spec_hash", self.hash()),
            ("spec", serde_json::to_string(&self.to_json()?)?),
            ("level", level.name().to_string()),
            ("policy", policy.to_string()),
            ("seeds", format!("{seeds:?}")),
            ("code_version", m.code_version),
            ("git_commit", m.git_commit.unwrap_or_default()),
            ("control_interval", self.control_interval().to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect())
    }
}

impl std::ops::Deref for Spec {
    type Target = dyn FamilySpec;
    fn deref(&self) -> &Self::Target {
        &*self.0
    }
}

impl Serialize for Spec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_json().map_err(serde::ser::Error::custom)?.serialize(s)
    }
}

impl PartialEq for Spec {
    fn eq(&self, other: &Self) -> bool {
        self.hash() == other.hash()
    }
}

/// `value` with `over`'s fields replaced (tables merged key by key), read back as a `T` and
/// checked by `check`, for `FamilySpec::with_overrides`; errors name the ID.
pub fn merged<T: FamilySpec + Serialize + DeserializeOwned>(
    value: &T,
    over: &toml::Table,
    id: &str,
    check: impl Fn(&T) -> Result<(), String>,
) -> Result<Spec, EnvInputError> {
    let bad = |message: String| EnvInputError::Override {
        id: id.to_string(),
        message,
    };
    let mut base = toml::Table::try_from(value).map_err(|e| bad(format!("the spec cannot be represented as TOML: {e}")))?;
    merge(&mut base, over);
    let spec: T = toml::Value::Table(base)
        .try_into()
        .map_err(|e: toml::de::Error| bad(e.to_string()))?;
    check(&spec).map_err(bad)?;
    Ok(Spec::new(spec))
}

fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}
