//! `hgym run`: one episode of a fixed policy (zero, random, sine) on an environment, with its
//! metrics, plots and manifest written to a result folder.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hgym_agents::{Env, EnvError};
use serde::{Deserialize, Serialize};

use super::spec::EnvSpec;
use super::LbmEnv;
use crate::data::DataError;
use crate::env::fields::FlowFields;
use crate::flow::vorticity_field;
use crate::flow::Level;
use crate::report::manifest::{manifest, Manifest};
use crate::report::{plots, ReportError};

/// Open-loop policies for smoke runs and baselines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Policy {
    /// No actuation.
    Zero,
    /// Uniform in [-1, 1], from a generator seeded by the run's seed.
    Random,
    /// `sin(2 pi k / 20)` for action k: one period per 20 actions (about one shedding period).
    Sine,
}

#[derive(Clone, Debug)]
pub struct RolloutOptions {
    pub level: Level,
    pub seed: u64,
    pub actions: usize,
    pub policy: Policy,
    pub out: PathBuf,
    pub cache: Option<PathBuf>,
    /// Flow-field snapshots in the trajectory at reset and every this many actions (0: none).
    pub fields_every: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Metrics {
    pub t: Vec<f64>,
    pub reward: Vec<f64>,
    pub c_d: Vec<f64>,
    pub c_l: Vec<f64>,
    /// Physical actuation per action, one list per actuator.
    pub actuation: Vec<Vec<f64>>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RolloutManifest {
    pub schema: String,
    pub env_id: String,
    pub spec_hash: String,
    pub spec: EnvSpec,
    pub level: String,
    pub seed: u64,
    pub policy: Policy,
    pub actions_planned: usize,
    pub actions_run: usize,
    pub terminated: bool,
    pub truncated: bool,
    pub message: Option<String>,
    pub total_reward: f64,
    pub mean_c_d: f64,
    pub manifest: Manifest,
}

/// xorshift64* (Vigna 2016) for the random policy.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (v >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Runs one episode (at most `actions` actions) and writes `<out>/manifest.json`,
/// `metrics.json`, `rollout.png` and `vorticity.png`.
pub fn rollout(
    spec: &EnvSpec,
    opts: &RolloutOptions,
    progress: &mut dyn FnMut(usize, usize),
    stop: &dyn Fn() -> bool,
) -> Result<RolloutManifest, RolloutError> {
    let started = Instant::now();
    let mut spec_run = spec.clone();
    spec_run.episode_actions = opts.actions.max(1);
    let mut env = LbmEnv::new(spec_run, opts.level, opts.cache.clone())?;
    let (obs0, info0) = env.reset(opts.seed)?;
    std::fs::create_dir_all(&opts.out).map_err(|e| EnvError::Backend(format!("cannot create {}: {e}", opts.out.display())))?;
    let policy_name = format!("{:?}", opts.policy).to_lowercase();
    let metadata = crate::env::Spec::new(spec.clone())
        .trajectory_manifest(opts.level, &policy_name, &[opts.seed])
        .map_err(|e| EnvError::Backend(format!("cannot describe the spec: {e}")))?;
    let trajectory = crate::data::trajectory::TrajectoryWriter::create(&opts.out.join("trajectory.mcap"), spec.control_interval, metadata)
        .map_err(RolloutError::from)?;
    let mut trajectory = trajectory.with_fields(opts.fields_every);
    trajectory.reset(&obs0, &info0).map_err(RolloutError::from)?;
    if trajectory.wants_field() {
        trajectory.field(env.snapshot()).map_err(RolloutError::from)?;
    }
    let dim = spec.act_dim();
    let mut rng = Rng(opts.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut m = Metrics {
        t: vec![],
        reward: vec![],
        c_d: vec![],
        c_l: vec![],
        actuation: vec![vec![]; dim],
    };
    let (mut terminated, mut truncated, mut message) = (false, false, None);
    for k in 0..opts.actions.max(1) {
        let a: Vec<f64> = match opts.policy {
            Policy::Zero => vec![0.0; dim],
            Policy::Random => (0..dim).map(|_| 2.0 * rng.next_f64() - 1.0).collect(),
            Policy::Sine => vec![(2.0 * std::f64::consts::PI * k as f64 / 20.0).sin(); dim],
        };
        let r = env.step(&a)?;
        trajectory
            .step_with_field(&a, &r, Some(|| env.snapshot()))
            .map_err(RolloutError::from)?;
        m.t.push(super::info_value(&r.info, "t")?);
        m.reward.push(r.reward);
        // A diverged step has no forces: NaN marks it in the series.
        let force = |key: &str| {
            if r.terminated {
                Ok(r.info.get(key).unwrap_or(f64::NAN))
            } else {
                super::info_value(&r.info, key)
            }
        };
        m.c_d.push(force("C_D")?);
        m.c_l.push(force("C_L")?);
        for (j, col) in m.actuation.iter_mut().enumerate() {
            col.push(super::info_value(&r.info, &format!("actuation_{j}"))?);
        }
        progress(k + 1, opts.actions);
        if r.terminated {
            terminated = true;
            message = r.info.text("reason").map(|s| s.to_string());
            break;
        }
        if r.truncated {
            truncated = true;
            break;
        }
        if stop() {
            message = Some(format!("interrupted after {} actions", k + 1));
            break;
        }
    }
    trajectory.finish().map_err(RolloutError::from)?;
    let n = m.reward.len();
    let summary = RolloutManifest {
        schema: "hgym/rollout/v1".into(),
        env_id: spec.id.clone(),
        spec_hash: spec.hash(),
        spec: spec.clone(),
        level: opts.level.name().into(),
        seed: opts.seed,
        policy: opts.policy,
        actions_planned: opts.actions,
        actions_run: n,
        terminated,
        truncated,
        message,
        total_reward: m.reward.iter().sum(),
        mean_c_d: m.c_d.iter().filter(|v| v.is_finite()).sum::<f64>() / n.max(1) as f64,
        manifest: manifest(rayon::current_num_threads(), started.elapsed().as_secs_f64()),
    };
    write(&opts.out, &summary, &m, &env)?;
    Ok(summary)
}

/// Why a rollout stopped short of its files.
#[derive(Debug, thiserror::Error)]
pub enum RolloutError {
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error("writing the trajectory")]
    Trajectory(#[from] DataError),
    #[error(transparent)]
    Report(#[from] ReportError),
}

fn write(dir: &Path, summary: &RolloutManifest, m: &Metrics, env: &LbmEnv) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(ReportError::io(dir))?;
    let json = |what: &str, text: serde_json::Result<String>| {
        text.map_err(|source| ReportError::Json {
            what: what.to_string(),
            source,
        })
    };
    let put = |name: &str, text: String| {
        let path = dir.join(name);
        std::fs::write(&path, text + "\n").map_err(ReportError::io(&path))
    };
    put("manifest.json", json("the manifest", serde_json::to_string_pretty(summary))?)?;
    put("metrics.json", json("the metrics", serde_json::to_string_pretty(m))?)?;
    let mut panels = vec![
        plots::Series {
            label: "reward",
            values: &m.reward,
        },
        plots::Series {
            label: "C_D",
            values: &m.c_d,
        },
        plots::Series {
            label: "C_L",
            values: &m.c_l,
        },
    ];
    let labels: Vec<String> = (0..m.actuation.len()).map(|j| format!("actuation {j}")).collect();
    for (j, col) in m.actuation.iter().enumerate() {
        panels.push(plots::Series {
            label: &labels[j],
            values: col,
        });
    }
    let title = format!(
        "{} ({}, {:?} policy, seed {})",
        summary.env_id, summary.level, summary.policy, summary.seed
    );
    plots::time_series(&dir.join("rollout.png"), &title, &m.t, &panels, None)?;
    let d = &summary.spec.domain;
    let v = vorticity_field(env.solver(), env.units(), [d.x[0], d.x[1], d.y[0], d.y[1]]);
    crate::report::plots::field_png(
        &v,
        &dir.join("vorticity.png"),
        &format!("{}: vorticity w L/U at the end", summary.env_id),
    )?;
    Ok(())
}
