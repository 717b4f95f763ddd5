//! `hgym train`, `hgym eval` and `hgym bench agents`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use anyhow::{Context, Result};
use clap::Args;
use hgym::flow::Level;
use hgym::train::checkpoint::Checkpoint;
use hgym::train::config::TrainConfig;
use hgym::train::eval::{evaluate, parse_policy, uncontrolled, EvalReport, LiftDeviationStat, NamedPolicy};
use hgym::train::{resolve_spec, resume_options, summarize, Ending, Init, TrainError, TrainOptions};
use hgym::transfer::mapping::MappingSpec;
use hgym::transfer::{load_mapping, SourceRun, TransferError};
use hgym_agents::baselines::BaselinePolicy;
use hgym_agents::learn::{algorithm, ALGORITHMS};
use hgym_agents::policy::Policy;
use hgym_agents::transplant::Parts;

use crate::cli::progress::progress_bar;
use crate::{thread_pool, Outcome, UsageError};

/// `--algo`: the registered algorithms, each with its one-line description.
fn algo_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        ALGORITHMS
            .iter()
            .map(|a| clap::builder::PossibleValue::new(a.name()).help(a.about())),
    )
}

#[derive(Args)]
pub struct TrainArgs {
    /// Environment ID (`hgym envs` lists them), e.g. Cylinder_2D_Re100.
    #[arg(long, required_unless_present_any = ["resume", "print_config"])]
    env: Option<String>,
    /// Learning algorithm [default: td3, or the --init-from run's].
    #[arg(long, value_parser = algo_names())]
    algo: Option<String>,
    /// Seed of the learner and of every episode's initial phase.
    #[arg(long, default_value_t = 0, conflicts_with = "seeds")]
    seed: u64,
    /// Several seeds, one run each, then a summary: `0..3` (0, 1, 2), `0..=4`, or `1,5,9`. A seed
    /// whose folder already holds a finished run of the same set-up is kept, not trained again, so
    /// seeds trained by separate commands (e.g. two at once) join one summary.
    #[arg(long)]
    seeds: Option<String>,
    /// Environment transitions to collect (default: the config's `train.steps`, 20000).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    steps: Option<u64>,
    /// Resolution level. Training defaults to coarse: the default level costs ~30x more per action.
    #[arg(long = "res", value_enum, default_value_t = Level::Coarse)]
    level: Level,
    /// TOML file overriding the defaults: [train], [ppo], [ddpg], [td3], [env] (see --print-config);
    /// or a training result folder, to train with the configuration it was made with.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Where result folders go: <out>/<ID>-<algo>-<level>/seed<S>/ (fine-tuning: <ID>-<algo>-<level>-from-<SOURCE>-seed<S>/).
    #[arg(long, default_value = "results/train")]
    out: PathBuf,
    /// Continue a run (killed or finished) from its folder's checkpoint; --steps may raise the budget.
    #[arg(long, conflicts_with_all = ["env", "seeds", "config", "init_from"])]
    resume: Option<PathBuf>,
    /// Fine-tune: start from the policy of a finished run folder (trained on --env or another
    /// flow: probes are matched by position, actuators by name, see --mapping). Its first
    /// evaluation (curve row 0) is the source policy's zero-shot evaluation.
    #[arg(long, value_name = "DIR")]
    init_from: Option<PathBuf>,
    /// A TOML file whose [mapping] table maps the source run's actuators onto --env's (e.g. a
    /// protocol in benchmarks/protocols/transfer/); needed when actuator names differ.
    #[arg(long, value_name = "FILE", requires = "init_from")]
    mapping: Option<PathBuf>,
    /// Also start from the source run's critics (td3, ddpg; needs its checkpoint.bin).
    #[arg(long, requires = "init_from")]
    init_critics: bool,
    /// Also start from the source run's replay buffer (td3, ddpg; same layouts only; implies --init-critics).
    #[arg(long, requires = "init_from")]
    init_buffer: bool,
    /// Print the effective configuration as TOML and exit.
    #[arg(long)]
    print_config: bool,
    /// Print the final metrics as JSON.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: all cores; with --resume, the count the run ran on); results are bitwise
    /// repeatable for the same seed and thread count.
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Args)]
pub struct EvalArgs {
    /// A training result folder (its policy.json), or a baseline: zero, random, sine[=period],
    /// constant=v[,v2,..] (one value for all actuators, or one each), opposition[=gain]
    /// (a = -gain C_L), wall-opposition[=gain] (channel flows: each actuator a = -gain v' at its
    /// sensing point), pd=SIGNAL,kp,kd (SIGNAL: obs:i or an info key).
    #[arg(long)]
    policy: String,
    /// Environment ID. A run folder trained on another flow is mapped onto it (zero-shot
    /// transfer): probes by position relative to the body, actuators by name or --mapping.
    #[arg(long)]
    env: String,
    /// A TOML file whose [mapping] table maps the run's actuators onto --env's (e.g. a protocol
    /// in benchmarks/protocols/transfer/).
    #[arg(long, value_name = "FILE")]
    mapping: Option<PathBuf>,
    /// Episodes to evaluate (1 to 100000).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    episodes: u64,
    /// Resolution level.
    #[arg(long = "res", value_enum, default_value_t = Level::Coarse)]
    level: Level,
    /// Episode k starts from reset(eval_seed + k); the default matches training's evaluation.
    #[arg(long, default_value_t = 1_000_000)]
    eval_seed: u64,
    /// TOML file whose [env] table overrides the environment spec.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Also write the report to <out>/<ID>-<policy>-<level>/metrics.json (+ manifest.json), the
    /// episodes to trajectory.mcap, and the flow the last episode ends in as images
    /// (vorticity.png, u.png, v.png).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Flow-field snapshots (u, v, vorticity) in trajectory.mcap at each reset and every K
    /// actions (0: none; needs --out).
    #[arg(long, value_name = "K", default_value_t = 0, requires = "out")]
    fields_every: u64,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: all cores); results are bitwise repeatable for the same seed and thread count.
    #[arg(long)]
    threads: Option<usize>,
}

impl TrainArgs {
    /// Under MPI, ranks other than 0 write here (see `cli::ranks`).
    pub fn write_into(&mut self, scratch: &super::ranks::Scratch) -> Result<()> {
        self.out = scratch.output(&self.out);
        if let Some(dir) = &self.resume {
            self.resume = Some(scratch.copy_of(dir)?);
        }
        Ok(())
    }
}

impl EvalArgs {
    /// Under MPI, ranks other than 0 write here (see `cli::ranks`).
    pub fn write_into(&mut self, scratch: &super::ranks::Scratch) {
        self.out = self.out.as_deref().map(|o| scratch.output(o));
    }
}

pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Whether Ctrl-C was pressed, on any rank under MPI (a collective there: the training loops
/// ask between rounds and actions, at the same points on every rank).
pub fn interrupted() -> bool {
    hgym::flow::ranks::any(INTERRUPTED.load(Ordering::SeqCst))
}
static SIGNALS: AtomicUsize = AtomicUsize::new(0);

/// First Ctrl-C: finish the current round, write the checkpoint, exit 130. Second: exit now
/// (the last checkpoint stays valid: checkpoints are replaced atomically).
pub fn install_interrupt() {
    let _ = ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        if SIGNALS.fetch_add(1, Ordering::SeqCst) >= 1 {
            eprintln!("\ninterrupted twice: exiting without a new checkpoint (the previous one is intact)");
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the current round, then writing the checkpoint (Ctrl-C again to quit now)");
    });
}

fn load_config(path: Option<&Path>) -> Result<TrainConfig> {
    Ok(path.map_or_else(|| Ok(TrainConfig::default()), TrainConfig::load)?)
}

/// Most seeds one `--seeds` may list (each is a whole training run).
const MAX_SEEDS: u64 = 1000;

/// `0..3`, `0..=4`, `1,5,9`: 1 to [`MAX_SEEDS`] seeds, counted before any list is made.
fn parse_seeds(text: &str) -> Result<Vec<u64>> {
    let bad = || {
        UsageError(format!(
            "--seeds {text}: expected a range like 0..3 or 0..=4, or a list like 1,5,9, of 1 to {MAX_SEEDS} seeds"
        ))
    };
    let num = |s: &str| s.trim().parse::<u64>().map_err(|_| bad());
    let range = |a: u64, end: Option<u64>| -> Result<Vec<u64>> {
        match end {
            Some(end) if end > a && end - a <= MAX_SEEDS => Ok((a..end).collect()),
            _ => Err(bad().into()),
        }
    };
    let seeds: Vec<u64> = if let Some((a, b)) = text.split_once("..=") {
        range(num(a)?, num(b)?.checked_add(1))?
    } else if let Some((a, b)) = text.split_once("..") {
        range(num(a)?, Some(num(b)?))?
    } else {
        text.split(',').map(num).collect::<Result<_, _>>()?
    };
    if seeds.is_empty() || seeds.len() as u64 > MAX_SEEDS {
        return Err(bad().into());
    }
    Ok(seeds)
}

fn transfer_error(e: TransferError) -> anyhow::Error {
    if e.is_bad_input() {
        UsageError(e.to_string()).into()
    } else {
        anyhow::Error::new(e)
    }
}

/// `--init-from`: the source run's policy mapped onto `spec` by `mapping`,
/// and with `critics`/`buffer` its learner's checkpoint. Warns when the source's spec is stale.
pub fn init_from(src: &SourceRun, spec: &hgym::env::Spec, mapping: &MappingSpec, critics: bool, buffer: bool) -> Result<Init> {
    if src.stale() {
        eprintln!(
            "warning: {} was trained on spec {} of {}, which is no longer the registered one ({}); its layout is read from today's",
            src.dir.display(),
            &src.spec_hash[..8.min(src.spec_hash.len())],
            src.env_id,
            &src.spec.hash()[..8]
        );
    }
    let (map, policy) = src.onto(spec, mapping).map_err(transfer_error)?;
    let parts = Parts {
        critics: critics || buffer,
        buffer,
    };
    let learner = if parts.critics {
        let ck = hgym::train::checkpoint::load(&src.dir).map_err(|e| {
            UsageError(format!(
                "--init-critics needs the source run's checkpoint: {} (checkpoints stay on the machine that trained; rerun the source or drop the flag)",
                hgym::report::chain(&e)
            ))
        })?;
        Some((ck.learner, map.clone()))
    } else {
        None
    };
    Ok(Init {
        record: src.record(mapping, &map, parts.critics, parts.buffer),
        policy,
        learner,
        parts,
    })
}

/// The `[mapping]` table of `--mapping FILE` (the default mapping without one).
fn mapping(file: Option<&Path>) -> Result<MappingSpec> {
    Ok(file.map(load_mapping).transpose().map_err(transfer_error)?.unwrap_or_default())
}

/// The spec of `env_id` with the configuration's `[env]` overrides; its warnings go to stderr.
pub fn resolved(env_id: &str, config: &hgym::train::config::TrainConfig) -> Result<hgym::env::Spec> {
    let spec = resolve_spec(env_id, config).map_err(train_error)?;
    for w in spec.warnings() {
        eprintln!("warning: {w}");
    }
    Ok(spec)
}

fn train_error(e: TrainError) -> anyhow::Error {
    match e {
        TrainError::Input(m) => UsageError(m).into(),
        other => anyhow::Error::new(other),
    }
}

/// Under MPI every split flow talks to the other ranks in the order its steps are taken, and
/// environments stepped on several threads at once would take them in a different order on each
/// rank: a learner with several environments runs on ranks only with one thread each.
fn refuse_parallel_envs_on_ranks(opts: &TrainOptions, threads: usize) -> Result<()> {
    let ranks = hgym::flow::ranks::rank().1;
    let algo = algorithm(&opts.algo).map_err(|e| UsageError(e.to_string()))?;
    let n_envs = algo.n_envs(&opts.config.algos).map_err(|e| UsageError(e.to_string()))?;
    if ranks > 1 && threads > 1 && n_envs > 1 {
        return Err(UsageError(format!(
            "on {ranks} MPI ranks the {n_envs} training environments of {} would step their split flows on {threads} threads \
             at once; run with --threads 1 (one rank per core) or set n_envs = 1 in the learner's section of --config \
             (e.g. [td3])",
            opts.algo
        ))
        .into());
    }
    Ok(())
}

pub fn run_train(args: TrainArgs) -> Result<Outcome> {
    let mut config = load_config(args.config.as_deref())?;
    if let Some(s) = args.steps {
        config.train.steps = s;
    }
    if args.print_config {
        print!("{}", config.to_toml());
        return Ok(Outcome::Ok);
    }
    let cache = hgym::env::default_cache_dir();
    let resumed = match &args.resume {
        Some(dir) => Some(resume_options(dir, args.steps, cache.clone()).map_err(train_error)?),
        None => None,
    };
    // A resumed run keeps the thread count it ran on, unless told otherwise.
    let (pool, threads) = thread_pool(args.threads.or(resumed.as_ref().and_then(|(_, ck)| ck.threads)))?;
    install_interrupt();
    let jobs: Vec<(TrainOptions, Option<Checkpoint>)> = if let Some((opts, ck)) = resumed {
        note_threads(&opts, &ck, threads);
        eprintln!(
            "resuming {} {} seed {} at {} samples (round {})",
            opts.env_id,
            opts.algo,
            opts.seed,
            ck.curve.last().map(|r| r.samples).unwrap_or(0),
            ck.curve.len()
        );
        vec![(opts, Some(ck))]
    } else {
        let env_id = args.env.clone().unwrap_or_default();
        let spec = resolved(&env_id, &config)?;
        let source = args.init_from.as_deref().map(SourceRun::load).transpose().map_err(transfer_error)?;
        let algo_name = args
            .algo
            .clone()
            .or_else(|| source.as_ref().map(|s| s.algo.clone()))
            .unwrap_or_else(|| "td3".into());
        let algo = algorithm(&algo_name).map_err(|e| UsageError(e.to_string()))?;
        let init = match &source {
            Some(src) => Some(init_from(
                src,
                &spec,
                &mapping(args.mapping.as_deref())?,
                args.init_critics,
                args.init_buffer,
            )?),
            None => None,
        };
        if algo.needs_gradients() && !spec.differentiable() {
            return Err(UsageError(format!(
                "{} needs a differentiable environment (the Kolmogorov flows, e.g. Kolmogorov_2D_Re40); \
                 {env_id} runs on the {} solver, which has no adjoint: use ppo, ddpg or td3",
                algo.name(),
                spec.solver()
            ))
            .into());
        }
        let seeds = match &args.seeds {
            Some(s) => parse_seeds(s)?,
            None => vec![args.seed],
        };
        let from = source
            .as_ref()
            .map(|s| format!("-from-{}-seed{}", s.env_id, s.seed))
            .unwrap_or_default();
        let root = args.out.join(format!("{env_id}-{}-{}{from}", algo.name(), args.level.name()));
        seeds
            .iter()
            .map(|s| {
                (
                    TrainOptions {
                        env_id: env_id.clone(),
                        algo: algo.name().to_string(),
                        seed: *s,
                        level: args.level,
                        config: config.clone(),
                        out: root.join(format!("seed{s}")),
                        cache: cache.clone(),
                        init: init.clone(),
                    },
                    None,
                )
            })
            .collect()
    };
    let mut finished = vec![];
    for (opts, ck) in jobs {
        refuse_parallel_envs_on_ranks(&opts, threads)?;
        if ck.is_none() {
            if let Some(report) = finished_run(&opts)? {
                eprintln!(
                    "{} seed {}: finished already in {} (same spec and configuration), kept; delete the folder to train it again",
                    opts.env_id,
                    opts.seed,
                    opts.out.display()
                );
                finished.push((opts.seed, opts.out.clone(), report, opts.clone()));
                continue;
            }
        }
        let label = format!("{} s{}", opts.algo, opts.seed);
        let pb = progress_bar(opts.config.train.steps, &label);
        if let Some(ck) = &ck {
            pb.set_position(ck.curve.last().map(|r| r.samples).unwrap_or(0));
        }
        let ending = pool
            .install(|| {
                hgym::train::train(
                    &opts,
                    ck,
                    &mut |p| {
                        pb.set_position(p.samples.min(p.total));
                        let eval = p
                            .last_eval
                            .map(|(r, dr)| {
                                if dr.is_finite() {
                                    format!(" | eval return {r:.1}, drag reduction {dr:+.1}%")
                                } else {
                                    format!(" | eval return {r:.2}")
                                }
                            })
                            .unwrap_or_default();
                        let c_d = if p.train_c_d.is_finite() {
                            format!(" C_D {:.3}", p.train_c_d)
                        } else {
                            String::new()
                        };
                        pb.set_message(format!("{label} return {:.1}{c_d}{eval}", p.train_return));
                        if !pb.is_hidden() {
                            return;
                        }
                        if p.round % 10 == 0 {
                            eprintln!(
                                "{label}: {} / {} samples, return {:.2}, C_D {:.4}{eval}",
                                p.samples, p.total, p.train_return, p.train_c_d
                            );
                        }
                    },
                    &interrupted,
                )
            })
            .map_err(train_error)
            .with_context(|| format!("training {} on {}", opts.algo, opts.env_id))?;
        pb.finish_and_clear();
        match ending {
            Ending::Interrupted { samples } => {
                eprintln!(
                    "stopped at {samples} samples; checkpoint written. Continue with: hgym train --resume {}",
                    opts.out.display()
                );
                std::process::exit(130);
            }
            Ending::Finished(report) => {
                if !args.json && !report.drag_reduction_pct.mean.is_finite() {
                    println!(
                        "{} {} seed {}: return {:.3} +- {:.3} over {} episodes\n  results: {}",
                        opts.env_id,
                        opts.algo,
                        opts.seed,
                        report.ret.mean,
                        report.ret.std,
                        report.episodes.len(),
                        opts.out.display()
                    );
                } else if !args.json {
                    println!(
                        "{} {} seed {}: drag reduction {:+.2} % +- {:.2} (C_D {:.4} vs {:.4} uncontrolled), return {:.2} +- {:.2} over {} episodes",
                        opts.env_id,
                        opts.algo,
                        opts.seed,
                        report.drag_reduction_pct.mean,
                        report.drag_reduction_pct.std,
                        report.mean_c_d.mean,
                        report.uncontrolled_c_d.mean,
                        report.ret.mean,
                        report.ret.std,
                        report.episodes.len()
                    );
                    if let Some(l) = &report.lift_deviation {
                        println!("{}", lift_line(l));
                    }
                    println!("  results: {}", opts.out.display());
                }
                finished.push((opts.seed, opts.out.clone(), *report, opts.clone()));
            }
        }
    }
    if finished.len() > 1 {
        let o = &finished[0].3;
        let runs: Vec<_> = finished.iter().map(|(s, p, r, _)| (*s, p.clone(), r.clone())).collect();
        let summary = summarize(&o.env_id, &o.algo, o.level.name(), &runs);
        let root = o.out.parent().unwrap_or(Path::new("."));
        std::fs::write(root.join("summary.json"), serde_json::to_string_pretty(&summary)? + "\n")
            .with_context(|| format!("cannot write {}", root.join("summary.json").display()))?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&summary)?);
        } else {
            println!(
                "{} {} over seeds {:?}: drag reduction {:+.2} % +- {:.2} (std over seeds), return {:.2} +- {:.2}\n  summary: {}",
                summary.env_id,
                summary.algo,
                summary.seeds,
                summary.drag_reduction_pct.mean,
                summary.drag_reduction_pct.std,
                summary.ret.mean,
                summary.ret.std,
                root.join("summary.json").display()
            );
            if let Some(l) = summary.lift_deviation_reduction_pct {
                println!(
                    "  lift deviation |C_L - C_L,ref| reduced by {:+.2} % +- {:.2} (std over seeds)",
                    l.mean, l.std
                );
            }
        }
    } else if args.json {
        if let Some((_, _, r, _)) = finished.first() {
            println!("{}", serde_json::to_string_pretty(r)?);
        }
    }
    Ok(Outcome::Ok)
}

/// What an `hgym eval` folder records besides its report: the flow, the policy and the seeds.
pub struct EvalRun<'a> {
    pub spec: &'a hgym::env::Spec,
    pub level: Level,
    pub policy: &'a str,
    pub eval_seed: u64,
    pub episodes: u64,
    /// The `--config` the flow was overridden with, as TOML (`None`: the registered spec).
    pub config_toml: Option<String>,
}

impl EvalRun<'_> {
    /// Writes `dir/metrics.json` (the report) and `dir/manifest.json` (hgym/eval-manifest/v1).
    /// `cpu_s`: the CPU time of the evaluation ([`hgym::report::manifest::CpuClock`]).
    pub fn write(&self, dir: &Path, report: &EvalReport, threads: usize, wall_s: f64, cpu_s: Option<f64>) -> Result<()> {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        std::fs::write(dir.join("metrics.json"), serde_json::to_string_pretty(report)? + "\n")?;
        let mut manifest = serde_json::json!({
            "schema": "hgym/eval-manifest/v1",
            "env_id": self.spec.id(),
            "spec_hash": self.spec.hash(),
            "spec": self.spec,
            "level": self.level.name(),
            "policy": self.policy,
            "eval_seed": self.eval_seed,
            "episodes": self.episodes,
            "manifest": hgym::report::manifest::manifest(threads, wall_s).with_cpu(cpu_s),
        });
        if let (Some(toml), Some(m)) = (&self.config_toml, manifest.as_object_mut()) {
            m.insert("config_toml".into(), toml.clone().into());
        }
        std::fs::write(dir.join("manifest.json"), serde_json::to_string_pretty(&manifest)? + "\n")?;
        Ok(())
    }
}

pub fn run_eval(args: EvalArgs) -> Result<Outcome> {
    let config = load_config(args.config.as_deref())?;
    let spec = resolved(&args.env, &config)?;
    let named = parse_policy(&args.policy)?;
    let (mut policy, name): (Box<dyn Policy + Send>, String) = match named {
        NamedPolicy::Trained(_) if Path::new(&args.policy).join("manifest.json").exists() => {
            // A run folder: its environment's layout maps the policy onto this one.
            let src = SourceRun::load(Path::new(&args.policy)).map_err(transfer_error)?;
            let init = init_from(&src, &spec, &mapping(args.mapping.as_deref())?, false, false)?;
            let name = format!("{} ({})", src.algo, args.policy);
            (Box::new(init.policy), name)
        }
        NamedPolicy::Trained(p) => {
            if p.obs_dim() != spec.obs_dim() || p.act_dim() != spec.act_dim() {
                return Err(UsageError(format!(
                    "the policy in {} maps {} observations to {} actions, but {} has {} observations and {} actions: \
                     transfer between flows needs matching sizes (same probe count and actuators)",
                    args.policy,
                    p.obs_dim(),
                    p.act_dim(),
                    spec.id(),
                    spec.obs_dim(),
                    spec.act_dim()
                ))
                .into());
            }
            let name = format!("{} ({})", p.algo, args.policy);
            (p, name)
        }
        NamedPolicy::Baseline(b) => (Box::new(BaselinePolicy::new(b, args.eval_seed)), args.policy.clone()),
    };
    let (pool, threads) = thread_pool(args.threads)?;
    let started = std::time::Instant::now();
    let cpu = hgym::report::manifest::CpuClock::start();
    if args.eval_seed.checked_add(args.episodes).is_none() {
        return Err(UsageError(format!(
            "--eval-seed {} + --episodes {} passes the largest seed ({}): give a smaller --eval-seed",
            args.eval_seed,
            args.episodes,
            u64::MAX
        ))
        .into());
    }
    let seeds: Vec<u64> = (0..args.episodes).map(|k| args.eval_seed + k).collect();
    let pb = progress_bar(2 * args.episodes, spec.id());
    let slug: String = args
        .policy
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '_' })
        .collect();
    let out_dir = args
        .out
        .as_ref()
        .map(|o| o.join(format!("{}-{}-{}", spec.id(), slug, args.level.name())));
    let mut trajectory = match &out_dir {
        Some(dir) => {
            std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
            Some(
                hgym::data::trajectory::TrajectoryWriter::create(
                    &dir.join("trajectory.mcap"),
                    spec.control_interval(),
                    spec.trajectory_manifest(args.level, &args.policy, &seeds)?,
                )
                .map_err(anyhow::Error::from)?
                .with_fields(args.fields_every),
            )
        }
        None => None,
    };
    let report: EvalReport = pool
        .install(|| -> Result<EvalReport> {
            let mut env = spec.make(args.level, hgym::env::default_cache_dir())?;
            // The first step's info: forces appear there, not at the reset.
            env.reset(seeds[0])?;
            let first = env.step(&vec![0.0; spec.act_dim()])?;
            policy
                .check(&first.obs, &first.info, spec.act_dim())
                .map_err(|m| UsageError(format!("--policy {} on {}: {m}", args.policy, spec.id())))?;
            let reference = uncontrolled(&mut env, &seeds)?;
            pb.set_position(args.episodes);
            let hash = spec.hash();
            let report = evaluate(
                &mut env,
                policy.as_mut(),
                &name,
                spec.id(),
                &hash,
                args.level.name(),
                &seeds,
                &reference,
                trajectory.as_mut(),
                &mut |k| pb.set_position(args.episodes + k as u64),
            )?;
            if let Some(dir) = &out_dir {
                // The controlled flow as the last episode leaves it, beside the numbers.
                let last = seeds[seeds.len() - 1];
                let what = format!("{} under {}, end of the episode from seed {last}", spec.id(), args.policy);
                hgym::env::rollout::field_pngs(dir, &env.snapshot(), &what)?;
            }
            Ok(report)
        })
        .with_context(|| format!("evaluating {} on {}", args.policy, spec.id()))?;
    pb.finish_and_clear();
    if let Some(dir) = &out_dir {
        let run = EvalRun {
            spec: &spec,
            level: args.level,
            policy: &args.policy,
            eval_seed: args.eval_seed,
            episodes: args.episodes,
            config_toml: args.config.is_some().then(|| config.to_toml()),
        };
        run.write(dir, &report, threads, started.elapsed().as_secs_f64(), cpu.total(Some(0.0)))?;
        eprintln!("results: {}", dir.display());
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !report.mean_c_d.mean.is_finite() {
        println!(
            "{} on {} ({}, {} episodes)\n  return          {:10.3} +- {:.3}\n  actuation cost  {:10.4} +- {:.4}   (mean sum of squared actions)",
            report.policy,
            report.env_id,
            report.level,
            report.episodes.len(),
            report.ret.mean,
            report.ret.std,
            report.actuation_cost.mean,
            report.actuation_cost.std
        );
    } else {
        println!(
            "{} on {} ({}, {} episodes)\n  return          {:10.3} +- {:.3}\n  mean C_D        {:10.4} +- {:.4}   (uncontrolled {:.4})\n  drag reduction  {:+9.2} % +- {:.2}\n  mean |C_L|      {:10.4} +- {:.4}\n  actuation cost  {:10.4} +- {:.4}   (mean sum of squared actions)",
            report.policy,
            report.env_id,
            report.level,
            report.episodes.len(),
            report.ret.mean,
            report.ret.std,
            report.mean_c_d.mean,
            report.mean_c_d.std,
            report.uncontrolled_c_d.mean,
            report.drag_reduction_pct.mean,
            report.drag_reduction_pct.std,
            report.mean_abs_c_l.mean,
            report.mean_abs_c_l.std,
            report.actuation_cost.mean,
            report.actuation_cost.std
        );
        if let Some(l) = &report.lift_deviation {
            println!("{}", lift_line(l));
        }
    }
    Ok(if report.episodes.iter().any(|e| e.terminated) {
        Outcome::CheckFailed
    } else {
        Outcome::Ok
    })
}

/// The gust flows' load figure as `hgym eval` and `hgym train` print it.
fn lift_line(l: &LiftDeviationStat) -> String {
    format!(
        "  |C_L - C_L,ref| {:10.4} +- {:.4}   (uncontrolled {:.4}; the lift's deviation from the undisturbed mean)\n  lift deviation reduction {:+.2} % +- {:.2}",
        l.mean_abs_dc_l.mean, l.mean_abs_dc_l.std, l.uncontrolled_abs_dc_l.mean, l.reduction_pct.mean, l.reduction_pct.std
    )
}

#[derive(Args)]
pub struct CompareArgs {
    /// A protocol file, e.g. benchmarks/protocols/kolmogorov_gppo.toml.
    protocol: PathBuf,
    /// Where the runs and the comparison go: <out>/<name>/<algo>/seed<S>/, comparison.json, learning_curves.png.
    #[arg(long, default_value = "results/compare")]
    out: PathBuf,
    /// Only recompute the comparison from finished runs.
    #[arg(long)]
    analyse_only: bool,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: all cores); results are bitwise repeatable for the same seed and thread count.
    #[arg(long)]
    threads: Option<usize>,
}

/// The final evaluation of a run that `opts` would start afresh but that is finished already in
/// `opts.out` (a `--seeds` command or a protocol given again continues with the runs still to
/// do, and its summary covers them all); `None` if the folder holds no finished run. A finished
/// run of another set-up (spec, algorithm, seed, level, configuration, source run) is refused
/// rather than overwritten.
pub fn finished_run(opts: &TrainOptions) -> Result<Option<EvalReport>> {
    let metrics = opts.out.join("metrics.json");
    if !metrics.exists() {
        return Ok(None);
    }
    let read = |path: &Path| -> Result<serde_json::Value> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))
    };
    let manifest_path = opts.out.join("manifest.json");
    let manifest = read(&manifest_path)?;
    let spec = resolve_spec(&opts.env_id, &opts.config).map_err(train_error)?;
    let expected = [
        ("spec_hash", serde_json::json!(spec.hash())),
        ("algo", serde_json::json!(opts.algo)),
        ("seed", serde_json::json!(opts.seed)),
        ("level", serde_json::json!(opts.level.name())),
    ];
    let mut differ: Vec<String> = expected
        .iter()
        .filter(|(key, value)| manifest.get(*key) != Some(value))
        .map(|(key, _)| key.to_string())
        .collect();
    // Compared as parsed, so a field added since the run (at its default) or another order of
    // the text is the same set-up.
    let origin = format!("{} (config_toml)", manifest_path.display());
    match manifest["config_toml"].as_str().map(|text| TrainConfig::parse(text, &origin)) {
        Some(Ok(config)) if config == opts.config => {}
        Some(Ok(_)) => differ.push("config_toml".into()),
        Some(Err(e)) => differ.push(format!("config_toml, which no longer parses: {e}")),
        None => differ.push(format!("config_toml, which {} lacks", manifest_path.display())),
    }
    if manifest.get("init_from").is_some() != opts.init.is_some() {
        differ.push("init_from".into());
    }
    if !differ.is_empty() {
        return Err(UsageError(format!(
            "{} holds a finished run of another set-up ({} differ): give another --out, or delete the folder to train it again",
            opts.out.display(),
            differ.join(", ")
        ))
        .into());
    }
    let report: EvalReport = serde_json::from_value(read(&metrics)?)
        .with_context(|| format!("{} is not a training run's final evaluation", metrics.display()))?;
    Ok(Some(report))
}

/// Says when a run continues on another thread count than its checkpoint was written on: the
/// result stays valid but is no longer bitwise the one an uninterrupted run gives.
fn note_threads(opts: &TrainOptions, ck: &Checkpoint, threads: usize) {
    if let Some(t) = ck.threads.filter(|&t| t != threads) {
        eprintln!(
            "note: {} ran on {t} threads and continues on {threads}; the result will not be bitwise the uninterrupted run's \
             (give --threads {t} to keep it so)",
            opts.out.display()
        );
    }
}

/// One run of a protocol (`hgym compare`, `hgym transfer`) in `opts.out`, with a progress bar:
/// resumed from its checkpoint when one is there (then without `opts.init`: the checkpoint holds
/// the networks), else started. Ctrl-C keeps the checkpoint and exits 130; the same command
/// continues.
pub fn protocol_run(pool: &rayon::ThreadPool, mut opts: TrainOptions, label: &str) -> Result<()> {
    let resume = if opts.out.join(hgym::train::checkpoint::FILE).exists() {
        opts.init = None;
        let ck = hgym::train::checkpoint::load(&opts.out)?;
        note_threads(&opts, &ck, pool.current_num_threads());
        Some(ck)
    } else {
        None
    };
    let pb = progress_bar(opts.config.train.steps, label);
    let ending = pool
        .install(|| {
            hgym::train::train(
                &opts,
                resume,
                &mut |pr| {
                    pb.set_position(pr.samples.min(pr.total));
                    if pb.is_hidden() && pr.round % 20 == 0 {
                        eprintln!("{label}: {} / {} samples, return {:.2}", pr.samples, pr.total, pr.train_return);
                    }
                },
                &interrupted,
            )
        })
        .map_err(train_error)
        .with_context(|| format!("{label} on {}", opts.env_id))?;
    pb.finish_and_clear();
    if let Ending::Interrupted { .. } = ending {
        eprintln!("stopped; run the same command again to continue where it stopped");
        std::process::exit(130);
    }
    Ok(())
}

/// `hgym compare`: every (algorithm, seed) of a protocol, then samples-to-threshold.
pub fn run_compare(args: CompareArgs) -> Result<Outcome> {
    use hgym::train::compare::{analyse, uncontrolled_return, Protocol};
    let p = Protocol::load(&args.protocol)?;
    let spec = resolve_spec(&p.env, &p.config).map_err(train_error)?;
    for name in &p.algos {
        if algorithm(name).is_ok_and(|a| a.needs_gradients()) && !spec.differentiable() {
            return Err(UsageError(format!(
                "{}: {name} needs a differentiable environment, {} is not",
                args.protocol.display(),
                p.env
            ))
            .into());
        }
    }
    let root = args.out.join(&p.name);
    let (pool, _) = thread_pool(args.threads)?;
    install_interrupt();
    if !args.analyse_only {
        for algo in &p.algos {
            for seed in &p.seeds {
                let dir = root.join(algo).join(format!("seed{seed}"));
                let opts = TrainOptions {
                    env_id: p.env.clone(),
                    algo: algo.clone(),
                    seed: *seed,
                    level: p.level,
                    config: p.config.clone(),
                    out: dir.clone(),
                    cache: hgym::env::default_cache_dir(),
                    init: None,
                };
                if finished_run(&opts)?.is_some() {
                    eprintln!("{algo} s{seed}: done already ({})", dir.display());
                    continue;
                }
                protocol_run(&pool, opts, &format!("{algo} s{seed}"))?;
                eprintln!("{algo} s{seed}: finished ({})", dir.display());
            }
        }
    }
    let r0 = pool.install(|| uncontrolled_return(&p.env, p.level, &p.config))?;
    let cmp = analyse(&p, &root, r0)?;
    std::fs::create_dir_all(&root)?;
    std::fs::write(root.join("comparison.json"), serde_json::to_string_pretty(&cmp)? + "\n")?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&cmp)?);
    } else {
        println!(
            "{} on {} ({}), seeds {:?}: uncontrolled return {:.3}, {} final {:.3}, threshold {:.3}",
            p.name,
            p.env,
            p.level.name(),
            p.seeds,
            cmp.uncontrolled_return,
            p.reference,
            cmp.reference_final_return,
            cmp.threshold
        );
        for s in &cmp.summary {
            println!(
                "  {:<5} final return {:8.3} +- {:.3}   samples to threshold {:8.0} +- {:.0} ({} of {} seeds reach it)   wall {:.0} s",
                s.algo,
                s.final_return.mean,
                s.final_return.std,
                s.samples_to_threshold.mean,
                s.samples_to_threshold.std,
                s.seeds_reaching,
                p.seeds.len(),
                s.wall_s.mean
            );
        }
        for (a, r) in &cmp.sample_reduction_vs_reference {
            println!("  {a} needs {:+.1} % samples vs {}", -100.0 * r, p.reference);
        }
        println!("  results: {}", root.display());
    }
    Ok(Outcome::Ok)
}
