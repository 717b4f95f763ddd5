//! Evaluation of any policy (trained actor or classical baseline) on an environment:
//! return, mean C_D, drag reduction against the uncontrolled flow on the same episodes, mean
//! |C_L| and actuation cost (and on the gusts the lift's deviation from the undisturbed mean), as
//! mean and standard deviation over episodes.

use std::path::Path;

use hgym_agents::baselines::{Baseline, BaselinePolicy, Signal};
use hgym_agents::policy::{ActorPolicy, Policy};
use hgym_agents::rollout::{episode, EpisodeAccumulator, EpisodeStats};

use crate::data::trajectory::TrajectoryWriter;
use hgym_agents::{Env, EnvError, StepResult};

pub use crate::report::eval::{nan_if_null, EvalEpisode, EvalReport, LiftDeviation, LiftDeviationStat, Stat};

/// What the uncontrolled flow does on one evaluation episode: the reference of the reductions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uncontrolled {
    /// Mean C_D.
    pub c_d: f64,
    /// Mean |C_L - C_L,ref| (info `dC_L`) on the flows whose reward has a reference lift.
    pub abs_dc_l: Option<f64>,
}

impl Uncontrolled {
    /// A reference with the drag only (the periodic evaluations' checkpointed one).
    pub fn drag(c_d: f64) -> Self {
        Uncontrolled { c_d, abs_dc_l: None }
    }
}

/// The uncontrolled flow of each episode from `reset(seed)` for `seeds`.
pub fn uncontrolled<E: Env + ?Sized>(env: &mut E, seeds: &[u64]) -> Result<Vec<Uncontrolled>, EnvError> {
    let mut zero = BaselinePolicy::new(Baseline::Zero, 0);
    seeds
        .iter()
        .map(|s| {
            let means = episode(env, &mut zero, *s, &mut |_, _| {})?.info_means;
            Ok(Uncontrolled {
                c_d: means.get("C_D").copied().unwrap_or(f64::NAN),
                abs_dc_l: means.get("abs_dC_L").copied(),
            })
        })
        .collect()
}

/// Runs `policy` for one episode per seed; `reference` is the uncontrolled flow per seed.
#[allow(clippy::too_many_arguments)]
pub fn evaluate<E: Env + crate::env::fields::FlowFields + ?Sized>(
    env: &mut E,
    policy: &mut dyn Policy,
    policy_name: &str,
    env_id: &str,
    spec_hash: &str,
    level: &str,
    seeds: &[u64],
    reference: &[Uncontrolled],
    mut trajectory: Option<&mut TrajectoryWriter>,
    progress: &mut dyn FnMut(usize),
) -> Result<EvalReport, EnvError> {
    let mut episodes = vec![];
    for (k, (seed, uncontrolled)) in seeds.iter().zip(reference).enumerate() {
        let (e, _) = eval_episode(env, policy, *seed, uncontrolled, trajectory.as_deref_mut(), &mut |_, _| {})?;
        episodes.push(e);
        progress(k + 1);
    }
    Ok(EvalReport::of(episodes, policy_name, env_id, spec_hash, level))
}

/// One evaluation episode from `reset(seed)` against the uncontrolled flow from the same state;
/// `on_step` sees the environment and the step's result after every step (to accumulate fields
/// or figures of its own). Also returns the episode's statistics (the means of every info key).
pub fn eval_episode<E: Env + crate::env::fields::FlowFields + ?Sized>(
    env: &mut E,
    policy: &mut dyn Policy,
    seed: u64,
    uncontrolled: &Uncontrolled,
    mut trajectory: Option<&mut TrajectoryWriter>,
    on_step: &mut dyn FnMut(&mut E, &StepResult),
) -> Result<(EvalEpisode, EpisodeStats), EnvError> {
    let io = |e: crate::data::DataError| EnvError::Backend(crate::report::chain(&e));
    let mut cost = 0.0;
    let (mut obs, mut info) = env.reset(seed)?;
    if let Some(t) = trajectory.as_deref_mut() {
        t.reset(&obs, &info).map_err(io)?;
        if t.wants_field() {
            t.field(env.snapshot()).map_err(io)?;
        }
    }
    policy.reset();
    let mut action = vec![0.0; env.action_space().dim()];
    let mut acc = EpisodeAccumulator::default();
    loop {
        policy.act(&obs, &info, &mut action);
        let r = env.step(&action)?;
        cost += action.iter().map(|v| v * v).sum::<f64>();
        if let Some(t) = trajectory.as_deref_mut() {
            t.step_with_field(&action, &r, Some(|| env.snapshot())).map_err(io)?;
        }
        on_step(env, &r);
        acc.add(&r);
        let done = r.terminated || r.truncated;
        obs = r.obs;
        info = r.info;
        if done {
            break;
        }
    }
    let stats: EpisodeStats = acc.finish();
    let mean_c_d = stats.info_means.get("C_D").copied().unwrap_or(f64::NAN);
    let c_d0 = uncontrolled.c_d;
    let lift_deviation = stats
        .info_means
        .get("abs_dC_L")
        .zip(uncontrolled.abs_dc_l)
        .map(|(&d, d0)| LiftDeviation {
            mean_abs_dc_l: d,
            uncontrolled_abs_dc_l: d0,
            reduction_pct: 100.0 * (1.0 - d / d0),
        });
    let episode = EvalEpisode {
        seed,
        ret: stats.ret,
        length: stats.length,
        terminated: stats.terminated,
        mean_c_d,
        uncontrolled_c_d: c_d0,
        drag_reduction_pct: 100.0 * (1.0 - mean_c_d / c_d0),
        mean_abs_c_l: stats.info_means.get("abs_C_L").copied().unwrap_or(f64::NAN),
        actuation_cost: cost / stats.length.max(1) as f64,
        lift_deviation,
    };
    Ok((episode, stats))
}

/// A policy named on the command line: a trained-run folder (its `policy.json`), or a
/// classical baseline: `zero`, `random`, `sine[=period]`, `constant=v[,v2,..]` (one
/// value for all actuators or one each), `opposition[=gain]`
/// (proportional feedback against the lift, `a = -gain C_L`), `wall-opposition[=gain]` (each
/// wall actuator against the wall-normal velocity at its sensing point, the channel flows'
/// opposition control), `pd=SIGNAL,kp,kd` with SIGNAL `obs:i` or an info key such as `C_L`.
pub enum NamedPolicy {
    Trained(Box<ActorPolicy>),
    Baseline(Baseline),
}

/// A `--policy` that names no baseline and no readable policy file.
#[derive(Debug, thiserror::Error)]
pub enum PolicyError {
    /// Always the user's input (exit code 2).
    #[error("{0}")]
    Invalid(String),
    #[error("cannot read {}", path.display())]
    Read {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
}

pub fn parse_policy(text: &str) -> Result<NamedPolicy, PolicyError> {
    let (name, arg) = text.split_once('=').map(|(a, b)| (a, Some(b))).unwrap_or((text, None));
    let num = |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(PolicyError::Invalid(format!("'{s}' in --policy {text} is not a finite number"))),
    };
    let b = match (name, arg) {
        ("zero", None) => Baseline::Zero,
        ("random", None) => Baseline::Random,
        ("sine", p) => match p.map(num).transpose()?.unwrap_or(20.0) {
            period if period > 0.0 => Baseline::Sine { amplitude: 1.0, period },
            period => {
                return Err(PolicyError::Invalid(format!(
                    "--policy {text}: the period {period} must be positive (in actions)"
                )))
            }
        },
        ("constant", Some(v)) => {
            let values = v.split(',').map(num).collect::<Result<Vec<f64>, _>>()?;
            if let Some(value) = values.iter().find(|x| !(-1.0..=1.0).contains(*x)) {
                return Err(PolicyError::Invalid(format!(
                    "--policy {text}: {value} is outside the normalised action range [-1, 1]"
                )));
            }
            Baseline::Constant { values }
        }
        ("opposition", g) => Baseline::Pd {
            signal: Signal::Info("C_L".into()),
            kp: g.map(num).transpose()?.unwrap_or(1.0),
            kd: 0.0,
            target: 0.0,
            signs: vec![],
        },
        ("wall-opposition", g) => Baseline::Local {
            stride: 2,
            offset: 1,
            gain: g.map(num).transpose()?.unwrap_or(1.0),
        },
        ("pd", Some(spec)) => {
            let parts: Vec<&str> = spec.split(',').collect();
            if parts.len() != 3 {
                return Err(PolicyError::Invalid(format!(
                    "--policy {text}: expected pd=SIGNAL,kp,kd (e.g. pd=C_L,1.0,0.5 or pd=obs:3,0.5,0)"
                )));
            }
            let signal = match parts[0].strip_prefix("obs:") {
                Some(i) => Signal::Obs(
                    i.parse()
                        .map_err(|_| PolicyError::Invalid(format!("--policy {text}: '{i}' is not an observation index")))?,
                ),
                None => Signal::Info(parts[0].to_string()),
            };
            Baseline::Pd {
                signal,
                kp: num(parts[1])?,
                kd: num(parts[2])?,
                target: 0.0,
                signs: vec![],
            }
        }
        _ => {
            let dir = Path::new(text);
            let file = if dir.is_dir() { dir.join("policy.json") } else { dir.to_path_buf() };
            if !file.exists() {
                return Err(PolicyError::Invalid(format!(
                    "--policy {text}: neither a result folder with policy.json nor a baseline \
                     (zero, random, sine[=period], constant=v[,v2,..], opposition[=gain], wall-opposition[=gain], pd=SIGNAL,kp,kd)"
                )));
            }
            let body = std::fs::read_to_string(&file).map_err(|source| PolicyError::Read {
                path: file.clone(),
                source,
            })?;
            let p: ActorPolicy =
                serde_json::from_str(&body).map_err(|e| PolicyError::Invalid(format!("{} is not a policy file: {e}", file.display())))?;
            p.validate()
                .map_err(|e| PolicyError::Invalid(format!("{} is not a whole policy: {e}", file.display())))?;
            return Ok(NamedPolicy::Trained(Box::new(p)));
        }
    };
    Ok(NamedPolicy::Baseline(b))
}
