//! `hgym run`: one episode of a fixed policy on an environment of any family, written as
//! metrics, plots (the final flow's fields as images), a trajectory and a manifest.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::progress::Progress;
use crate::{thread_pool, Outcome, UsageError};
use hgym::flow::Level;

#[derive(Args)]
pub struct RunArgs {
    /// Environment ID (`hgym envs` lists them), e.g. Cylinder_2D_Re100.
    #[arg(long)]
    env: String,
    /// Open-loop policy.
    #[arg(long, value_enum, default_value = "zero")]
    policy: hgym::env::rollout::Policy,
    /// Number of actions (control intervals).
    #[arg(long, default_value_t = 200)]
    steps: usize,
    /// Resolution level.
    #[arg(long = "res", value_enum, default_value_t = Level::Default)]
    level: Level,
    /// Seed of the episode's reset (and of a random policy).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Parent folder of the result folder.
    #[arg(long, default_value = "results/runs")]
    out: PathBuf,
    /// TOML file whose [env] table overrides any field of the spec (as `hgym envs show ID` prints it).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Write flow-field snapshots (u, v, vorticity; foxglove.Grid on /field) into
    /// trajectory.mcap at reset and every K actions (0: none).
    #[arg(long, value_name = "K", default_value_t = 0)]
    fields_every: u64,
    /// Worker threads (default: all cores); results are bitwise repeatable for the same seed and thread count.
    #[arg(long)]
    threads: Option<usize>,
}

impl RunArgs {
    /// Under MPI, ranks other than 0 write here (see `cli::ranks`).
    pub fn write_into(&mut self, scratch: &super::ranks::Scratch) {
        self.out = scratch.output(&self.out);
    }
}

pub fn run(args: RunArgs) -> Result<Outcome> {
    let config = match &args.config {
        None => hgym::train::config::TrainConfig::default(),
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("cannot read the config file {}", p.display()))?;
            hgym::train::config::TrainConfig::parse(&text, &p.display().to_string())?
        }
    };
    let spec = super::train::resolved(&args.env, &config)?;
    if args.steps == 0 {
        return Err(UsageError("--steps must be at least 1".into()).into());
    }
    let (pool, _) = thread_pool(args.threads)?;
    let out = args.out.join(format!(
        "{}-{}-seed{}",
        spec.id(),
        format!("{:?}", args.policy).to_lowercase(),
        args.seed
    ));
    let opts = hgym::env::rollout::RolloutOptions {
        level: args.level,
        seed: args.seed,
        actions: args.steps,
        policy: args.policy,
        out: out.clone(),
        cache: hgym::env::default_cache_dir(),
        fields_every: args.fields_every,
    };
    eprintln!(
        "{}: starting from the developed flow (spun up once per ID and level, then cached)",
        spec.id()
    );
    let pb = Progress::new(args.steps as u64, spec.id());
    super::train::install_interrupt();
    let summary = pool
        .install(|| hgym::env::rollout::rollout(&spec, &opts, &mut |k, _| pb.set_position(k as u64), &super::train::interrupted))
        .with_context(|| format!("running {}", spec.id()))?;
    pb.finish_and_clear();
    println!(
        "{}: {} of {} actions, total reward {:.3}, mean C_D {:.4}{}",
        summary.env_id,
        summary.actions_run,
        summary.actions_planned,
        summary.total_reward,
        summary.mean_c_d,
        if summary.terminated { " (terminated: solver diverged)" } else { "" }
    );
    println!("  results: {}", out.display());
    if super::train::INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst) {
        eprintln!(
            "interrupted: the partial episode and its trajectory.mcap (complete and valid) are in {}",
            out.display()
        );
        std::process::exit(130);
    }
    Ok(if summary.terminated { Outcome::CheckFailed } else { Outcome::Ok })
}
