//! `hgym train`: runs a learner from `hgym-agents` on a flow environment, in rounds (one episode
//! on each of the learner's parallel environments), with periodic deterministic evaluation,
//! atomic checkpoints, and a result folder:
//!
//! - `manifest.json`: env spec and hash, algorithm, configuration, seed, samples, code version,
//!   machine, wall time;
//! - `curve.csv`, `curve.png`, `drag_reduction.png`: the learning curve (the CSV also at every
//!   checkpoint, to follow a long run);
//! - `policy.json`: the final deterministic policy (`hgym eval --policy DIR` loads it);
//!   for a flow that declares agents (`hgym_agents::multi`: the channel flows), one actor shared
//!   by every agent, trained through one pseudo-environment per agent (`[train] multi_agent`);
//! - `metrics.json`: the final evaluation ([`eval::EvalReport`]); one image per snapshot field
//!   of the flow its last episode ends in (the 2D flows: `vorticity.png`, `u.png`, `v.png`);
//! - `init_from.json`: for a run started from another run's policy (`--init-from`), where it
//!   started and how the source was mapped (also in the manifest); such a run evaluates its
//!   starting policy before the first round (curve row 0), which is the source policy's
//!   zero-shot evaluation;
//! - `checkpoint.bin`: everything needed to continue (`--resume DIR`): a resumed run reaches the
//!   same policy and metrics as an uninterrupted one, bitwise, because rounds reset their
//!   environments from seeds derived from (seed, round) and the learner's state is complete.

pub mod checkpoint;
pub mod compare;
pub mod config;
pub mod curve;
pub mod eval;

use std::path::{Path, PathBuf};
use std::time::Instant;

use hgym_agents::learn::{algorithm, Learner, ParallelEnv};
use hgym_agents::multi::pseudo_envs;
use hgym_agents::policy::ActorPolicy;
use hgym_agents::EnvError;
use serde::{Deserialize, Serialize};

use self::checkpoint::Checkpoint;
use self::config::TrainConfig;
use self::curve::CurveRow;
use self::eval::{evaluate, uncontrolled, EvalReport, LiftDeviationStat, Stat, Uncontrolled};
use crate::env::{FlowEnv, Spec};
use crate::flow::Level;
use crate::report::manifest::{manifest, CpuClock, Manifest};

#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    /// Bad input: an unknown ID, an algorithm that does not fit the environment (exit code 2).
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error(transparent)]
    Learn(#[from] hgym_agents::learn::LearnError),
    #[error(transparent)]
    Config(#[from] config::ConfigError),
    #[error(transparent)]
    Checkpoint(#[from] checkpoint::CheckpointError),
    #[error("writing the trajectory")]
    Trajectory(#[from] crate::data::DataError),
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
    #[error("cannot write {}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl TrainError {
    /// Whether the error is the user's input (exit code 2), not a failure of the run.
    pub fn is_bad_input(&self) -> bool {
        match self {
            TrainError::Input(_) | TrainError::Config(_) => true,
            TrainError::Env(e) => matches!(e, EnvError::InvalidSpec(_)),
            TrainError::Learn(e) => !matches!(
                e,
                hgym_agents::learn::LearnError::Env(_) | hgym_agents::learn::LearnError::Encode(_)
            ),
            TrainError::Checkpoint(e) => e.is_bad_input(),
            TrainError::Trajectory(_) | TrainError::Report(_) | TrainError::Io { .. } => false,
        }
    }
}

/// What to train.
#[derive(Clone, Debug)]
pub struct TrainOptions {
    pub env_id: String,
    /// A registered algorithm's name (`hgym_agents::learn::ALGORITHMS`).
    pub algo: String,
    pub seed: u64,
    pub level: Level,
    pub config: TrainConfig,
    pub out: PathBuf,
    pub cache: Option<PathBuf>,
    /// Start from another run's policy (fresh runs only; a resumed run has it in its checkpoint).
    pub init: Option<Init>,
}

/// A starting point for `--init-from`: the source policy mapped onto this environment, and
/// optionally the source learner's critics and replay buffer.
#[derive(Clone, Debug)]
pub struct Init {
    pub policy: hgym_agents::policy::ActorPolicy,
    /// The source learner's checkpoint bytes and the map, when `parts` asks for more than the actor.
    pub learner: Option<(Vec<u8>, hgym_agents::transplant::SpaceMap)>,
    pub parts: hgym_agents::transplant::Parts,
    pub record: InitRecord,
}

/// What a fine-tuning run records about where it started (`init_from.json`, then its manifest).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct InitRecord {
    pub dir: PathBuf,
    pub env_id: String,
    pub spec_hash: String,
    pub algo: String,
    pub seed: u64,
    pub level: String,
    /// The `[mapping]` table the source was mapped with.
    pub mapping: serde_json::Value,
    /// Whether the map was the identity (same layouts).
    pub identity: bool,
    pub critics: bool,
    pub buffer: bool,
}

pub const INIT_FILE: &str = "init_from.json";

/// What the progress display sees after each round.
#[derive(Clone, Debug)]
pub struct Progress {
    pub samples: u64,
    pub total: u64,
    pub round: u64,
    pub train_return: f64,
    pub train_c_d: f64,
    pub last_eval: Option<(f64, f64)>,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Ending {
    Finished(Box<EvalReport>),
    /// Stopped by the user (Ctrl-C) after a round; the checkpoint is current.
    Interrupted {
        samples: u64,
    },
}

#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TrainManifest {
    pub schema: String,
    pub env_id: String,
    pub spec_hash: String,
    pub spec: Spec,
    pub level: String,
    pub algo: String,
    pub seed: u64,
    pub samples: u64,
    pub updates: u64,
    pub rounds: u64,
    pub resumed: u32,
    /// The effective training configuration (as `--print-config` prints it).
    pub config_toml: String,
    /// The run this one started from (`--init-from`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub init_from: Option<InitRecord>,
    pub manifest: Manifest,
}

/// The environment spec with the configuration's `[env]` overrides applied.
pub fn resolve_spec(env_id: &str, config: &TrainConfig) -> Result<Spec, TrainError> {
    let spec = crate::env::lookup(env_id).map_err(|e| TrainError::Input(e.to_string()))?;
    match &config.env {
        Some(over) => spec.with_overrides(over).map_err(|e| TrainError::Input(e.to_string())),
        None => Ok(spec),
    }
}

fn eval_seeds(config: &TrainConfig, n: usize) -> Vec<u64> {
    (0..n as u64).map(|k| config.train.eval_seed + k).collect()
}

/// Trains from scratch (or continues from `resume`), calling `progress` after every round and
/// stopping cleanly after the current round when `interrupted()` turns true.
pub fn train(
    opts: &TrainOptions,
    resume: Option<Checkpoint>,
    progress: &mut dyn FnMut(&Progress),
    interrupted: &dyn Fn() -> bool,
) -> Result<Ending, TrainError> {
    let started = Instant::now();
    let cpu = CpuClock::start();
    let config = &opts.config;
    let spec = resolve_spec(&opts.env_id, config)?;
    let algo = algorithm(&opts.algo).map_err(|e| TrainError::Input(e.to_string()))?;
    let n_envs = algo.n_envs(&config.algos)?;
    std::fs::create_dir_all(&opts.out).map_err(io(&opts.out))?;
    let make = || spec.make(opts.level, opts.cache.clone());
    let mut eval_env = make()?;
    // A flow that declares agents trains them as pseudo-environments sharing one policy: the
    // learner sees one agent's spaces, and the policy acts for all of them on the whole flow.
    let agents = if config.train.multi_agent { eval_env.agents() } else { None };
    let (obs_dim, act_dim) = match &agents {
        Some(a) => (a.local_obs_dim(), a.local_act_dim()),
        None => (spec.obs_dim(), spec.act_dim()),
    };
    let mut envs: Vec<Box<dyn ParallelEnv>> = vec![];
    for _ in 0..n_envs {
        let env = make()?;
        match agents {
            Some(_) => envs.extend(pseudo_envs(env)?.into_iter().map(|p| Box::new(p) as Box<dyn ParallelEnv>)),
            None => envs.push(Box::new(env)),
        }
    }
    let shared = |p: ActorPolicy| match &agents {
        Some(a) => p.with_agents(a.clone()),
        None => p,
    };
    let periodic_seeds = eval_seeds(config, config.train.eval_episodes.max(1));
    let hash = spec.hash();
    // The periodic evaluation of the learner's current policy: the curve's eval columns.
    let periodic_eval = |env: &mut Box<dyn FlowEnv>, learner: &dyn Learner, reference: &[f64]| {
        let reference: Vec<Uncontrolled> = reference.iter().map(|&c_d| Uncontrolled::drag(c_d)).collect();
        evaluate(
            env,
            &mut shared(learner.policy()),
            algo.name(),
            spec.id(),
            &hash,
            opts.level.name(),
            &periodic_seeds,
            &reference,
            None,
            &mut |_| {},
        )
    };

    let (mut learner, mut curve, reference, wall_before, cpu_before, resumed) = match resume {
        Some(ck) => {
            let learner = algo.decode(&ck.learner)?;
            (learner, ck.curve, ck.reference, ck.wall_s, ck.cpu_s, ck.resumed + 1)
        }
        None => {
            let mut learner = algo.learner(&config.algos, obs_dim, act_dim, opts.seed)?;
            let reference: Vec<f64> = uncontrolled(&mut eval_env, &periodic_seeds)?.iter().map(|u| u.c_d).collect();
            let mut curve = vec![];
            if let Some(init) = &opts.init {
                learner.init_actor(&init.policy)?;
                if let Some((bytes, map)) = &init.learner {
                    learner.init_critics(bytes, map, init.parts)?;
                }
                write_json(&opts.out.join(INIT_FILE), "the source run", &init.record)?;
                let r = periodic_eval(&mut eval_env, learner.as_ref(), &reference)?;
                let mut start = CurveRow {
                    round: 0,
                    samples: 0,
                    updates: 0,
                    wall_s: started.elapsed().as_secs_f64(),
                    train_return: f64::NAN,
                    train_c_d: f64::NAN,
                    eval_return: f64::NAN,
                    eval_c_d: f64::NAN,
                    eval_drag_reduction_pct: f64::NAN,
                };
                start.set_eval(&r);
                curve.push(start);
            }
            (learner, curve, reference, 0.0, Some(0.0), 0)
        }
    };
    let config_toml = config.to_toml();
    let checkpoint = |learner: &dyn Learner, curve: &[CurveRow]| {
        checkpoint::save(
            &opts.out,
            &Checkpoint {
                format: checkpoint::FORMAT,
                env_id: opts.env_id.clone(),
                algo: opts.algo.clone(),
                seed: opts.seed,
                level: opts.level,
                config_toml: config_toml.clone(),
                learner: learner.to_bytes()?,
                curve: curve.to_vec(),
                reference: reference.clone(),
                wall_s: wall_before + started.elapsed().as_secs_f64(),
                resumed,
                threads: Some(rayon::current_num_threads()),
                cpu_s: cpu.total(cpu_before),
            },
        )?;
        // The curve so far, to follow a long run from another terminal.
        let csv = opts.out.join("curve.csv");
        std::fs::write(&csv, curve::to_csv(curve)).map_err(io(&csv))
    };
    // A resumed run records itself at once (so `resumed` counts every resume, even one killed
    // before its first round); every run saves after its first round, then every
    // `checkpoint_seconds`, so a short run killed early can still resume.
    if resumed > 0 {
        checkpoint(&*learner, &curve)?;
    }
    let mut last_ckpt: Option<Instant> = None;
    let mut last_eval = curve
        .iter()
        .rev()
        .find(|r| r.eval_return.is_finite())
        .map(|r| (r.eval_return, r.eval_drag_reduction_pct));
    while learner.samples() < config.train.steps {
        if interrupted() {
            checkpoint(&*learner, &curve)?;
            return Ok(Ending::Interrupted {
                samples: learner.samples(),
            });
        }
        let stats = learner.round_on(&mut envs)?;
        let n = stats.len().max(1) as f64;
        let mut row = CurveRow {
            round: learner.rounds(),
            samples: learner.samples(),
            updates: learner.updates(),
            wall_s: wall_before + started.elapsed().as_secs_f64(),
            train_return: stats.iter().map(|s| s.ret).sum::<f64>() / n,
            train_c_d: stats
                .iter()
                .map(|s| s.info_means.get("C_D").copied().unwrap_or(f64::NAN))
                .sum::<f64>()
                / n,
            eval_return: f64::NAN,
            eval_c_d: f64::NAN,
            eval_drag_reduction_pct: f64::NAN,
        };
        let every = config.train.eval_every;
        if every > 0 && learner.rounds().is_multiple_of(every) {
            let r = periodic_eval(&mut eval_env, learner.as_ref(), &reference)?;
            row.set_eval(&r);
            last_eval = Some((r.ret.mean, r.drag_reduction_pct.mean));
        }
        progress(&Progress {
            samples: row.samples,
            total: config.train.steps,
            round: row.round,
            train_return: row.train_return,
            train_c_d: row.train_c_d,
            last_eval,
        });
        curve.push(row);
        if last_ckpt.is_none_or(|t| t.elapsed().as_secs_f64() >= config.train.checkpoint_seconds) {
            checkpoint(&*learner, &curve)?;
            last_ckpt = Some(Instant::now());
        }
    }
    let wall = wall_before + started.elapsed().as_secs_f64();
    checkpoint(&*learner, &curve)?;

    // Final evaluation on its own seeds, against the uncontrolled flow from the same states.
    let final_seeds = eval_seeds(config, config.train.final_eval_episodes.max(1));
    let final_ref = uncontrolled(&mut eval_env, &final_seeds)?;
    let mut policy = shared(learner.policy());
    let hash = spec.hash();
    let mut trajectory = crate::data::trajectory::TrajectoryWriter::create(
        &opts.out.join("trajectory.mcap"),
        spec.control_interval(),
        spec.trajectory_manifest(opts.level, algo.name(), &final_seeds)
            .map_err(|source| crate::report::ReportError::Json {
                what: "the spec".into(),
                source,
            })?,
    )?
    .with_fields(config.train.fields_every);
    let report = evaluate(
        &mut eval_env,
        &mut policy,
        algo.name(),
        spec.id(),
        &hash,
        opts.level.name(),
        &final_seeds,
        &final_ref,
        Some(&mut trajectory),
        &mut |_| {},
    )?;
    trajectory.finish()?;
    // The flow the learned policy leaves at the end of the last evaluation episode, as images.
    let what = format!(
        "{} under {} seed {}, end of the episode from seed {}",
        spec.id(),
        algo.name(),
        opts.seed,
        final_seeds[final_seeds.len() - 1]
    );
    crate::env::rollout::field_pngs(&opts.out, &eval_env.snapshot(), &what)?;
    write_json(&opts.out.join("policy.json"), "the policy", &policy)?;
    write_json(&opts.out.join("metrics.json"), "the evaluation", &report)?;
    let csv = opts.out.join("curve.csv");
    std::fs::write(&csv, curve::to_csv(&curve)).map_err(io(&csv))?;
    let title = format!("{} {} seed {} ({})", spec.id(), algo.name(), opts.seed, opts.level.name());
    curve::plot(&opts.out, &title, &curve).map_err(crate::report::ReportError::from)?;
    let m = TrainManifest {
        schema: "hgym/train/v1".into(),
        env_id: spec.id().to_string(),
        spec_hash: hash,
        spec: spec.clone(),
        level: opts.level.name().into(),
        algo: algo.name().into(),
        seed: opts.seed,
        samples: learner.samples(),
        updates: learner.updates(),
        rounds: learner.rounds(),
        resumed,
        config_toml,
        init_from: read_init(&opts.out)?,
        manifest: manifest(rayon::current_num_threads(), wall).with_cpu(cpu.total(cpu_before)),
    };
    write_json(&opts.out.join("manifest.json"), "the manifest", &m)?;
    Ok(Ending::Finished(Box::new(report)))
}

/// Options stored in a checkpoint, for `--resume DIR` (the step budget may be raised).
pub fn resume_options(dir: &Path, steps: Option<u64>, cache: Option<PathBuf>) -> Result<(TrainOptions, Checkpoint), TrainError> {
    let ck = checkpoint::load(dir)?;
    let mut config = TrainConfig::parse(&ck.config_toml, "checkpoint")?;
    if let Some(s) = steps {
        config.train.steps = s;
    }
    Ok((
        TrainOptions {
            env_id: ck.env_id.clone(),
            algo: ck.algo.clone(),
            seed: ck.seed,
            level: ck.level,
            config,
            out: dir.to_path_buf(),
            cache,
            init: None,
        },
        ck,
    ))
}

/// The run's `init_from.json`, if it started from another run.
fn read_init(dir: &Path) -> Result<Option<InitRecord>, TrainError> {
    let path = dir.join(INIT_FILE);
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).map_err(io(&path))?;
    serde_json::from_str(&text).map(Some).map_err(|source| {
        TrainError::Report(crate::report::ReportError::Json {
            what: path.display().to_string(),
            source,
        })
    })
}

/// Summary over the seeds of one (env, algorithm): mean and std over seeds of the per-seed
/// evaluation means.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SeedSummary {
    pub schema: String,
    pub env_id: String,
    pub algo: String,
    pub level: String,
    pub seeds: Vec<u64>,
    pub drag_reduction_pct: Stat,
    pub ret: Stat,
    pub mean_c_d: Stat,
    /// The gust flows' lift deviation reduction (see [`eval::LiftDeviation`]) over seeds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lift_deviation_reduction_pct: Option<Stat>,
    pub runs: Vec<PathBuf>,
}

pub fn summarize(env_id: &str, algo: &str, level: &str, runs: &[(u64, PathBuf, EvalReport)]) -> SeedSummary {
    let col = |f: fn(&EvalReport) -> f64| Stat::of(&runs.iter().map(|(_, _, r)| f(r)).collect::<Vec<_>>());
    SeedSummary {
        schema: "hgym/seeds/v1".into(),
        env_id: env_id.into(),
        algo: algo.into(),
        level: level.into(),
        seeds: runs.iter().map(|(s, _, _)| *s).collect(),
        drag_reduction_pct: col(|r| r.drag_reduction_pct.mean),
        ret: col(|r| r.ret.mean),
        mean_c_d: col(|r| r.mean_c_d.mean),
        lift_deviation_reduction_pct: LiftDeviationStat::reduction_over(runs.iter().map(|(_, _, r)| r)),
        runs: runs.iter().map(|(_, p, _)| p.clone()).collect(),
    }
}

/// An I/O error on `path`.
fn io(path: &Path) -> impl Fn(std::io::Error) -> TrainError + '_ {
    move |source| TrainError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// `value` as pretty JSON in `path` (NaN becomes null); `what` names it in an error.
fn write_json<T: Serialize>(path: &Path, what: &str, value: &T) -> Result<(), TrainError> {
    let text = serde_json::to_string_pretty(value).map_err(|source| crate::report::ReportError::Json {
        what: what.to_string(),
        source,
    })?;
    std::fs::write(path, text + "\n").map_err(io(path))
}
