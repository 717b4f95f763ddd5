//! `hgym run`: one episode of a fixed policy (zero, random, sine) on an environment of any
//! family, with its metrics, plots (time series, and an image of each field of the final flow
//! snapshot: vorticity, or a channel's wall shear stress) and manifest written to a result folder.

use std::path::{Path, PathBuf};
use std::time::Instant;

use hgym_agents::{Env, EnvError};
use serde::{Deserialize, Serialize};

use super::family::{FlowEnv, Spec};
use crate::data::DataError;
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
    /// Physical actuation per action, one list per actuator the environment reports
    /// (`actuation_j` in its info: every one in 2D, the first patch of a channel).
    pub actuation: Vec<Vec<f64>>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RolloutManifest {
    pub schema: String,
    pub env_id: String,
    pub spec_hash: String,
    /// The spec as `hgym envs show ID --json` prints it.
    pub spec: serde_json::Value,
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
/// `metrics.json`, `rollout.png` and `<field>.png` for each field of the final snapshot.
pub fn rollout(
    spec: &Spec,
    opts: &RolloutOptions,
    progress: &mut dyn FnMut(usize, usize),
    stop: &dyn Fn() -> bool,
) -> Result<RolloutManifest, RolloutError> {
    let started = Instant::now();
    let mut length = toml::Table::new();
    length.insert("episode_actions".into(), toml::Value::Integer(opts.actions.max(1) as i64));
    let spec_run = spec.with_overrides(&length).map_err(|e| EnvError::InvalidSpec(e.to_string()))?;
    let mut env = spec_run.make(opts.level, opts.cache.clone())?;
    let (obs0, info0) = env.reset(opts.seed)?;
    std::fs::create_dir_all(&opts.out).map_err(|e| EnvError::Backend(format!("cannot create {}: {e}", opts.out.display())))?;
    let policy_name = format!("{:?}", opts.policy).to_lowercase();
    let metadata = spec
        .trajectory_manifest(opts.level, &policy_name, &[opts.seed])
        .map_err(|e| EnvError::Backend(format!("cannot describe the spec: {e}")))?;
    let trajectory =
        crate::data::trajectory::TrajectoryWriter::create(&opts.out.join("trajectory.mcap"), spec.control_interval(), metadata)
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
        actuation: vec![],
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
        // A flow without lift (the channel) has NaN here.
        m.c_l.push(r.info.get("C_L").unwrap_or(f64::NAN));
        if k == 0 {
            let reported = (0..dim).take_while(|j| r.info.get(&format!("actuation_{j}")).is_some()).count();
            m.actuation = vec![vec![]; reported];
        }
        for (j, col) in m.actuation.iter_mut().enumerate() {
            col.push(r.info.get(&format!("actuation_{j}")).unwrap_or(f64::NAN));
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
        env_id: spec.id().to_string(),
        spec_hash: spec.hash(),
        spec: spec.to_json().map_err(|source| ReportError::Json {
            what: "the spec".into(),
            source,
        })?,
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
    write(&opts.out, &summary, &m, &mut env)?;
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

fn write(dir: &Path, summary: &RolloutManifest, m: &Metrics, env: &mut Box<dyn FlowEnv>) -> Result<(), ReportError> {
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
    field_pngs(dir, &env.snapshot(), &format!("{} at the end", summary.env_id))
}

/// Each field of `snapshot` (u, v, vorticity, ...) as `<dir>/<name>.png`, titled
/// `<what>: <name>`.
pub fn field_pngs(dir: &Path, snapshot: &crate::data::field::Snapshot, what: &str) -> Result<(), ReportError> {
    for (name, values) in &snapshot.fields {
        let field = crate::flow::Field {
            nx: snapshot.nx,
            ny: snapshot.ny,
            extent: snapshot.extent,
            values: values.clone(),
        };
        plots::field_png(&field, &dir.join(format!("{name}.png")), &format!("{what}: {name}"))?;
    }
    Ok(())
}
