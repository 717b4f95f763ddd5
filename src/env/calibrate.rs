//! Observation statistics from an uncontrolled run (`hgym envs calibrate ID`), and the embedded
//! table of committed statistics (`benchmarks/envs/normalization.toml`).

use std::collections::BTreeMap;

use hgym_agents::{Env, EnvError};
use serde::{Deserialize, Serialize};

use super::spec::{EnvSpec, Normalization};
use super::LbmEnv;
use crate::flow::Level;

/// The committed table, as text (embedded at build time).
pub const TABLE: &str = include_str!("../../benchmarks/envs/normalization.toml");

/// Where [`TABLE`] lives, from the repository root.
pub const TABLE_PATH: &str = "benchmarks/envs/normalization.toml";

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    pub spec_hash: String,
    pub level: String,
    pub actions: usize,
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
    /// Mean total (C_D, C_L) of the uncontrolled run: the reference of force-deviation rewards
    /// (the gust environments take theirs from the undisturbed flow's entry).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_forces: Option<[f64; 2]>,
}

impl Entry {
    /// One line for people: the uncontrolled mean forces of `id`.
    pub fn summary(&self, id: &str) -> String {
        match self.mean_forces {
            Some([c_d, c_l]) => format!("{id}: uncontrolled mean C_D {c_d:.4}, mean C_L {c_l:.4}"),
            None => format!("{id}: calibrated"),
        }
    }
}

/// Hash of the spec with its normalisation removed (what the statistics depend on).
pub fn physics_hash(spec: &EnvSpec) -> String {
    let mut s = spec.clone();
    s.normalization = Normalization::default();
    // The uncontrolled statistics do not depend on the reward or the episode length.
    s.reward = super::spec::RewardSpec::DragLift { lift_weight: 0.0 };
    s.episode_actions = 0;
    s.hash()
}

/// The committed table, parsed once (empty if broken: a test checks that it parses).
pub fn table() -> &'static BTreeMap<String, Entry> {
    static PARSED: std::sync::OnceLock<BTreeMap<String, Entry>> = std::sync::OnceLock::new();
    PARSED.get_or_init(|| parse_table(TABLE).unwrap_or_default())
}

/// Parses a table; a malformed one yields an error naming the problem.
pub fn parse_table(text: &str) -> Result<BTreeMap<String, Entry>, crate::report::table::TableError> {
    crate::report::table::parse(text, std::path::Path::new(TABLE_PATH))
}

/// The table key of `id`'s statistics at `level`: the ID itself for the default level (the
/// statistics a spec carries), `ID@level` for another level whose flow differs too much from the
/// default one for those to hold (the open cavity at coarse: its 40-cells-per-depth flow is a
/// different recirculation, observations up to 16 default-scales away).
pub fn table_key(id: &str, level: Level) -> String {
    match level {
        Level::Default => id.to_string(),
        other => format!("{id}@{}", other.name()),
    }
}

/// The committed statistics of `spec` at `level` when there is a level-specific entry (see
/// [`table_key`]); `None` means the spec's own (default-level) normalisation applies.
pub fn level_normalization(spec: &EnvSpec, level: Level) -> Option<Normalization> {
    if level == Level::Default {
        return None;
    }
    let table = table();
    let mut probe = spec.clone();
    probe.normalization = Normalization::default();
    attach_entry(&mut probe, table.get(&table_key(&spec.id, level)), &physics_hash(spec));
    (!probe.normalization.mean.is_empty()).then_some(probe.normalization)
}

/// Attaches the committed statistics to `spec` when they were computed for the same physics.
pub fn attach(spec: &mut EnvSpec, table: &BTreeMap<String, Entry>) {
    let hash = physics_hash(spec);
    attach_entry(spec, table.get(&spec.id), &hash);
}

fn attach_entry(spec: &mut EnvSpec, entry: Option<&Entry>, hash: &str) {
    if let Some(n) = matching(entry, hash, spec.obs_dim()) {
        spec.normalization = n;
    }
}

/// The statistics of `entry` if they were computed for the physics hashed `hash` and have
/// `obs_dim` values.
pub(crate) fn matching(entry: Option<&Entry>, hash: &str, obs_dim: usize) -> Option<Normalization> {
    entry
        .filter(|e| e.spec_hash == hash && e.mean.len() == obs_dim && e.scale.len() == obs_dim)
        .map(|e| Normalization {
            mean: e.mean.clone(),
            scale: e.scale.clone(),
        })
}

/// Smallest normalisation scale (units of U, rho U^2 or T_wall): 1 % of the free stream. A probe
/// that hardly moves in the uncontrolled flow (a steady region; the open cavity at Re 4200, whose
/// 2D flow is nearly steady) would otherwise get a scale near zero, and any actuation would give
/// huge normalised observations and probe-deviation rewards. (Entries calibrated before this
/// floor, up to 2026-11-23, used 1e-6.)
pub const MIN_SCALE: f64 = 0.01;

/// Runs `actions` uncontrolled control intervals from `reset(0)` and returns mean and
/// 3-standard-deviation scale of every raw observation, floored at [`MIN_SCALE`].
pub fn calibrate(
    spec: &EnvSpec,
    level: Level,
    actions: usize,
    cache: Option<std::path::PathBuf>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Entry, EnvError> {
    let mut raw_spec = spec.clone();
    raw_spec.normalization = Normalization::default();
    raw_spec.episode_actions = actions.max(1);
    let mut env = LbmEnv::new(raw_spec, level, cache)?;
    let entry = statistics(&mut env, &spec.id, actions, LbmEnv::raw_observation, progress)?;
    Ok(Entry {
        spec_hash: physics_hash(spec),
        level: level.name().into(),
        ..entry
    })
}

/// `FamilySpec::calibrate` of the lattice-Boltzmann families: checks the table first, then
/// `measure`s, records the entry for `id` at `level` and returns what it recorded, and where.
pub(crate) fn measure_and_record(
    id: &str,
    level: Level,
    actions: usize,
    table: Option<&std::path::Path>,
    measure: impl FnOnce() -> Result<Entry, EnvError>,
) -> Result<(String, std::path::PathBuf), super::family::CalibrateError> {
    let table = super::family::calibration_table::<Entry>(actions, table, TABLE_PATH)?;
    let entry = measure()?;
    let summary = entry.summary(id);
    crate::report::table::record(&table, &[(table_key(id, level), entry)])?;
    Ok((summary, table))
}

/// The statistics of an [`Entry`] (hash and level left empty) from `actions` uncontrolled
/// intervals of `env` after `reset(0)`: the raw observation `raw(env)` at the end of each, and
/// the mean total `C_D`, `C_L` of `info`.
pub(crate) fn statistics<E: Env>(
    env: &mut E,
    id: &str,
    actions: usize,
    raw: impl Fn(&E) -> Result<Vec<f64>, EnvError>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Entry, EnvError> {
    env.reset(0)?;
    let dim = env.observation_space().dim();
    let (mut sum, mut sq) = (vec![0.0f64; dim], vec![0.0f64; dim]);
    let zero = vec![0.0; env.action_space().dim()];
    let mut forces = [0.0f64; 2];
    for k in 0..actions {
        let r = super::family::uncontrolled_step(env, id, &zero)?;
        for (sum, key) in forces.iter_mut().zip(["C_D", "C_L"]) {
            *sum += super::info_value(&r.info, key)?;
        }
        let raw = raw(env)?;
        for i in 0..dim {
            sum[i] += raw[i];
            sq[i] += raw[i] * raw[i];
        }
        progress(k + 1, actions);
    }
    let n = actions.max(1) as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
    let scale = sq
        .iter()
        .zip(&mean)
        .map(|(q, m)| (3.0 * (q / n - m * m).max(0.0).sqrt()).max(MIN_SCALE))
        .collect();
    Ok(Entry {
        spec_hash: String::new(),
        level: String::new(),
        actions,
        mean,
        scale,
        mean_forces: Some([forces[0] / n, forces[1] / n]),
    })
}
