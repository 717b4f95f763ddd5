//! `hgym`: the command line. Parses, calls the library, prints text or `--json`, and maps the
//! outcome to an exit code: 0 ok, 1 a check failed (validation out of tolerance, solver
//! diverged, benchmark short of its target), 2 bad usage or bad input.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use hgym::bench::{bench_lbm, bench_refine, LbmBenchOptions, RefineBenchOptions};

/// `print!` through [`cli::out::write_out`]: a closed pipe ends the program with exit code 0.
macro_rules! print {
    ($($arg:tt)*) => { $crate::cli::out::write_out(format_args!($($arg)*)) };
}

/// `println!` through [`cli::out::write_out`]: a closed pipe ends the program with exit code 0.
macro_rules! println {
    () => { $crate::cli::out::write_out(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::cli::out::write_out(format_args!("{}\n", format_args!($($arg)*))) };
}

mod cli;
use cli::progress::Progress;
use hgym::validate::{Level, ValidateError};

#[derive(Parser)]
#[command(
    name = "hgym",
    version,
    about = "Reinforcement-learning flow control: validated CFD environments, benchmarks and reports",
    long_about = "hgym runs flow-control environments on fast in-process solvers.\n\n\
                  Start with `hgym validate cylinder` (checks the lattice-Boltzmann solver against the \
                  literature: Strouhal number, mean drag and lift amplitude at Re 100 and 200) and \
                  `hgym bench lbm` (solver speed against the machine's memory bandwidth)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run validation cases against published numbers and write JSON reports and plots.
    ///
    /// `hgym validate cylinder` runs the bundled cylinder cases; `hgym validate --case FILE`
    /// runs any case file (see benchmarks/validation/*.toml for the format). Exit code 0 when
    /// every quantity is within its tolerance, 1 when one is not or the solver diverged, 2 for
    /// bad input (unknown family, malformed file, parameters that cannot run).
    Validate(cli::validate::ValidateArgs),
    /// Measure solver speed against the machine's limits.
    #[command(subcommand)]
    Bench(BenchCommand),
    /// List environments, print a spec, or calibrate observation statistics.
    ///
    /// `hgym envs` prints a table of every ID, with how far its uncontrolled flow is from the
    /// literature at the coarse and default levels (St and mean C_D deviations, measured by
    /// `hgym validate --env ID --level L --record`); `hgym envs show ID` prints its full spec as TOML;
    /// `hgym envs calibrate ID` runs it uncontrolled and records observation means and scales in
    /// benchmarks/envs/normalization.toml (rebuild to embed them).
    Envs(EnvsArgs),
    /// Run one episode of a fixed policy on an environment and write metrics, plots and a
    /// manifest (`<out>/<ID>-<policy>-seed<S>/`).
    Run(RunArgs),
    /// Train an agent (PPO, DDPG, TD3) on an environment, with periodic evaluation, checkpoints
    /// and a result folder (manifest, learning curve CSV + PNG, policy, metrics).
    ///
    /// `hgym train --env Cylinder_2D_Re100 --algo td3 --seeds 0..3` trains three seeds and writes a
    /// summary; Ctrl-C stops after the current round with a checkpoint, `--resume DIR` continues
    /// it (bitwise the same result as an uninterrupted run with the same thread count).
    Train(cli::train::TrainArgs),
    /// Evaluate a trained policy or a classical baseline: return, C_D, drag reduction against the
    /// uncontrolled flow from the same initial states, |C_L|, actuation cost (mean +- std).
    Eval(cli::train::EvalArgs),
    /// Run a comparison protocol (benchmarks/protocols/*.toml): several algorithms over the same
    /// seeds, and the samples each needs to reach a fraction of the reference's final return.
    Compare(cli::train::CompareArgs),
    /// Trajectory files: `hgym data recover FILE` salvages every complete chunk of a truncated
    /// MCAP file (e.g. after a kill) into FILE.recovered.mcap.
    #[command(subcommand)]
    Data(DataCommand),
    /// Turn trajectory files into a dataset: `hgym export --to hf results/runs OUT` writes
    /// Parquet shards (one row per control step, one config per env) and a dataset card.
    Export(cli::data::ExportArgs),
    /// Upload a dataset folder to the Hugging Face Hub (token from HF_TOKEN or the
    /// huggingface-cli token file; endpoint from HF_ENDPOINT).
    Push(cli::data::PushArgs),
    /// Learning curves of several training runs in one figure (evaluation return, or drag
    /// reduction with --drag), e.g. `hgym plot results/train/Cylinder_2D_Re100-*/seed0 -o cmp.png`.
    Plot {
        /// Training result folders (each with curve.csv).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Output PNG.
        #[arg(short, long, default_value = "learning_curves.png")]
        out: PathBuf,
        /// Plot the evaluation drag reduction instead of the return.
        #[arg(long)]
        drag: bool,
        /// Plot the training return (with exploration) instead of the evaluation return.
        #[arg(long)]
        train: bool,
    },
    /// Aggregate the result folders under results/ into results/leaderboard.json,
    /// results/LEADERBOARD.md and a bar chart per environment.
    Leaderboard {
        /// Only this environment.
        #[arg(long)]
        env: Option<String>,
        /// The results folder.
        #[arg(long, default_value = "results")]
        results: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args)]
struct EnvsArgs {
    #[command(subcommand)]
    command: Option<EnvsCommand>,
    /// Print the table as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Subcommand)]
enum EnvsCommand {
    /// Print the full spec of an ID as TOML.
    Show { id: String },
    /// Compute observation statistics from an uncontrolled run and record them.
    Calibrate {
        id: String,
        #[arg(long, value_enum, default_value_t = Level::Default)]
        level: Level,
        /// Control intervals to average over.
        #[arg(long, default_value_t = 100)]
        actions: usize,
        /// The table to update.
        #[arg(long, default_value = "benchmarks/envs/normalization.toml")]
        table: PathBuf,
        #[arg(long)]
        threads: Option<usize>,
    },
}

#[derive(Args)]
struct RunArgs {
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
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Subcommand)]
enum BenchCommand {
    /// D2Q9 lattice-Boltzmann step: MLUPS at three sizes, 1 and 2 threads, against a STREAM copy
    /// measured in the same run. Exit 1 if the memory-bound size reaches less than 70 % of the
    /// roofline.
    Lbm {
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// A fast smoke run (small sizes, short timings; the target is not judged).
        #[arg(long)]
        quick: bool,
        /// Collision operator to time.
        #[arg(long, value_enum, default_value = "regularized")]
        collision: CollisionArg,
    },
    /// 2:1 grid refinement: node updates per second of a grid with a patch over its middle
    /// quarter against the uniform kernel on the same grid, 1 and 2 threads. Exit 1 if the refined
    /// rate is below 80 % of the uniform one with all threads.
    Refine {
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// A fast smoke run (a small grid, short timings; the target is not judged).
        #[arg(long)]
        quick: bool,
    },
    /// Learner speed: TD3 updates/s (256x256, batch 256), PPO epochs/s (64x64), batch-1 policy
    /// latency, against SB3 measured on this machine. Exit 1 if short of the targets.
    Agents {
        #[arg(long)]
        json: bool,
        /// Short timings (targets not judged).
        #[arg(long)]
        quick: bool,
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Spectral Kolmogorov solver: steps/s at N 64-256, VJP cost, accuracy against step size,
    /// against HydroGym's JAX env measured on this machine. Exit 1 if short of the targets.
    Kolmogorov {
        #[arg(long)]
        json: bool,
        /// Short timings and a 1-time-unit action (targets not judged).
        #[arg(long)]
        quick: bool,
    },
    /// Control steps (actions) per second of each environment family at coarse and default.
    Envs {
        /// Print the rows as JSON.
        #[arg(long)]
        json: bool,
        /// Actions timed per family and level.
        #[arg(long, default_value_t = 20)]
        actions: usize,
        /// Only the coarse level (fast smoke run).
        #[arg(long)]
        quick: bool,
        /// Only this family (repeatable), e.g. `--family stenotic_pipe`; an unknown name lists the families.
        #[arg(long)]
        family: Vec<String>,
    },
}

#[derive(Subcommand)]
enum DataCommand {
    /// Copy every complete chunk (and the metadata) of a damaged MCAP file into a valid one.
    Recover {
        file: PathBuf,
        /// Output file (default: <file>.recovered.mcap).
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum CollisionArg {
    /// Single-relaxation-time BGK.
    Bgk,
    /// Regularised BGK (Latt & Chopard 2006), the default of every case and environment.
    Regularized,
    /// Recursive regularised BGK (Malaspinas 2015; Coreixas et al. 2017).
    Recursive,
}

/// Outcome of a command: 0 ok, 1 a check failed.
enum Outcome {
    Ok,
    CheckFailed,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    hgym::env::spin_up::observe_spin_ups(cli::progress::spin_up_progress);
    let result = match cli.command {
        Command::Validate(args) => cli::validate::run(args),
        Command::Bench(BenchCommand::Lbm { json, quick, collision }) => run_bench(json, quick, collision),
        Command::Bench(BenchCommand::Refine { json, quick }) => run_bench_refine(json, quick),
        Command::Bench(BenchCommand::Envs {
            json,
            actions,
            quick,
            family,
        }) => run_bench_envs(json, actions, quick, &family),
        Command::Envs(args) => run_envs(args),
        Command::Run(args) => run_rollout(args),
        Command::Train(args) => cli::train::run_train(args),
        Command::Eval(args) => cli::train::run_eval(args),
        Command::Compare(args) => cli::train::run_compare(args),
        Command::Export(args) => cli::data::run_export(args),
        Command::Push(args) => cli::data::run_push(args),
        Command::Data(DataCommand::Recover { file, out, json }) => {
            let out = out.unwrap_or_else(|| file.with_extension("recovered.mcap"));
            match hgym::data::trajectory::recover(&file, &out) {
                Ok(r) => {
                    if json {
                        println!("{}", serde_json::to_string_pretty(&r).unwrap_or_default());
                    } else {
                        println!(
                            "recovered {} messages and {} metadata records from {} into {}{}",
                            r.messages,
                            r.metadata,
                            file.display(),
                            out.display(),
                            r.stopped_at
                                .as_ref()
                                .map(|e| format!("\n  lost: everything after the last complete chunk (reading stopped: {e})"))
                                .unwrap_or_else(|| "\n  nothing lost: the file was complete".into())
                        );
                    }
                    Ok(Outcome::Ok)
                }
                Err(e) => Err(UsageError(e).into()),
            }
        }
        Command::Plot { runs, out, drag, train } => run_plot(&runs, &out, drag, train),
        Command::Leaderboard { env, results, json } => {
            let lb = hgym::report::leaderboard::build(&results, env.as_deref());
            hgym::report::leaderboard::write(&results, &lb)
                .map_err(anyhow::Error::msg)
                .and_then(|_| {
                    if json {
                        println!("{}", serde_json::to_string_pretty(&lb)?);
                    } else {
                        print!("{}", hgym::report::leaderboard::markdown(&lb));
                    }
                    Ok(Outcome::Ok)
                })
        }
        Command::Bench(BenchCommand::Agents { json, quick, threads }) => cli::train::run_bench_agents(json, quick, threads),
        Command::Bench(BenchCommand::Kolmogorov { json, quick }) => {
            let b = hgym::bench::kolmogorov::bench_kolmogorov(quick);
            if json {
                serde_json::to_string_pretty(&b)
                    .map(|t| println!("{t}"))
                    .map_err(anyhow::Error::from)
                    .map(|_| ())
            } else {
                print!("{}", hgym::bench::kolmogorov::table(&b));
                Ok(())
            }
            .map(|_| if b.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
        }
    };
    match result {
        Ok(Outcome::Ok) => ExitCode::SUCCESS,
        Ok(Outcome::CheckFailed) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e:#}");
            let bad_input = e.chain().any(|c| {
                c.downcast_ref::<ValidateError>().is_some_and(|v| v.is_bad_input())
                    || c.downcast_ref::<hgym::fidelity::FidelityError>().is_some_and(|v| v.is_bad_input())
                    || c.downcast_ref::<UsageError>().is_some()
                    || c.downcast_ref::<hgym::env::EnvInputError>().is_some()
            });
            ExitCode::from(if bad_input { 2 } else { 1 })
        }
    }
}

#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct UsageError(String);

fn thread_pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let n = threads.unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
    if n == 0 {
        return Err(UsageError("--threads must be at least 1".into()).into());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("cannot start the worker threads")?;
    Ok((pool, n))
}

fn run_bench(json: bool, quick: bool, collision: CollisionArg) -> Result<Outcome> {
    let mut opts = LbmBenchOptions {
        collision: match collision {
            CollisionArg::Bgk => hgym_solvers::lbm::Collision::Bgk,
            CollisionArg::Regularized => hgym_solvers::lbm::Collision::Regularized,
            CollisionArg::Recursive => hgym_solvers::lbm::Collision::Recursive,
        },
        ..LbmBenchOptions::default()
    };
    if quick {
        opts.sizes = vec![(32, 32), (128, 64), (256, 256)];
        opts.seconds = 0.05;
        opts.stream_values = 1 << 22;
    }
    let quiet = json;
    let report = bench_lbm(&opts, &mut |msg| {
        if !quiet {
            eprintln!("{msg}");
        }
    })
    .map_err(anyhow::Error::msg)
    .context("LBM benchmark")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
    }
    Ok(if report.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}

fn run_bench_refine(json: bool, quick: bool) -> Result<Outcome> {
    let mut opts = RefineBenchOptions::default();
    if quick {
        opts.n = 128;
        opts.seconds = 0.05;
    }
    let report = bench_refine(&opts, &mut |msg| {
        if !json {
            eprintln!("{msg}");
        }
    })
    .map_err(anyhow::Error::msg)
    .context("refinement benchmark")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", report.table());
    }
    Ok(if report.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}

/// The committed deviations of `s`'s uncontrolled flow at `level` from the literature
/// (`hgym validate --env ID --level L --record`), if measured on the flow registered now.
fn fidelity_entry(s: &hgym::env::any::AnySpec, level: Level) -> Option<&'static hgym::fidelity::Entry> {
    match s {
        hgym::env::any::AnySpec::Lbm(spec) => hgym::fidelity::committed(spec, level),
        hgym::env::any::AnySpec::Kolmogorov(_) => None,
    }
}

/// `St -2.7% C_D +13.7%`; `-` without references (the Kolmogorov flows' check is `hgym validate
/// kolmogorov`); `not measured`.
fn fidelity(s: &hgym::env::any::AnySpec, level: Level) -> String {
    match (s, fidelity_entry(s, level)) {
        (_, Some(e)) => e.summary(),
        (hgym::env::any::AnySpec::Lbm(spec), None) if hgym::fidelity::has_reference(spec) => "not measured".into(),
        _ => "-".into(),
    }
}

fn run_envs(args: EnvsArgs) -> Result<Outcome> {
    match args.command {
        None => {
            let specs = hgym::env::any::all();
            let calibrated = |s: &hgym::env::any::AnySpec| match s {
                hgym::env::any::AnySpec::Lbm(s) => !s.normalization.mean.is_empty(),
                hgym::env::any::AnySpec::Kolmogorov(s) => s.statistics.u_rms > 0.0,
            };
            if args.json {
                let rows: Vec<serde_json::Value> = specs
                    .iter()
                    .map(|s| {
                        serde_json::json!({
                            "id": s.id(), "family": s.family(), "dimension": 2, "reynolds": s.reynolds(),
                            "observations": s.obs_dim(), "actions": s.act_dim(), "solver": s.solver(),
                            "differentiable": s.differentiable(),
                            "calibrated": calibrated(s), "spec_hash": s.hash(),
                            "fidelity": {
                                "coarse": fidelity_entry(s, Level::Coarse),
                                "default": fidelity_entry(s, Level::Default),
                            },
                        })
                    })
                    .collect();
                println!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                println!(
                    "{:<30} {:>3} {:>7} {:>5} {:>5} {:<11} {:<10} {:<22} {}",
                    "ID", "dim", "Re", "obs", "act", "solver", "calibrated", "vs literature: coarse", "default"
                );
                for s in &specs {
                    println!(
                        "{:<30} {:>3} {:>7} {:>5} {:>5} {:<11} {:<10} {:<22} {}",
                        s.id(),
                        "2D",
                        s.reynolds(),
                        s.obs_dim(),
                        s.act_dim(),
                        s.solver(),
                        if calibrated(s) { "yes" } else { "no" },
                        fidelity(s, Level::Coarse),
                        fidelity(s, Level::Default)
                    );
                }
            }
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Show { id }) => {
            let spec = hgym::env::any::lookup(&id)?;
            println!("# {} (spec hash {})", spec.id(), spec.hash());
            print!("{}", spec.to_toml());
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Calibrate {
            id,
            level,
            actions,
            table: _,
            threads: _,
        }) if id.starts_with("Kolmogorov") => {
            let hgym::env::any::AnySpec::Kolmogorov(spec) = hgym::env::any::lookup(&id)? else {
                return Err(UsageError(format!("{id} is not a Kolmogorov flow")).into());
            };
            let table = PathBuf::from("benchmarks/envs/kolmogorov.toml");
            let text = std::fs::read_to_string(&table)
                .with_context(|| format!("cannot read {} (run from the repository root)", table.display()))?;
            let mut entries: std::collections::BTreeMap<String, hgym::env::kolmogorov::FlowStatistics> =
                toml::from_str(&text).with_context(|| format!("{} is malformed", table.display()))?;
            let pb = Progress::new(actions as u64, &id);
            let st = hgym::env::kolmogorov::calibrate(&spec, level, actions, &mut |k| pb.set_position(k as u64))
                .with_context(|| format!("calibrating {id}"))?;
            pb.finish_and_clear();
            println!(
                "{id}: u_rms {:.4}, dissipation {:.4} +- {:.4} (laminar {:.4}), TKE {:.4} over {} time units",
                st.u_rms,
                st.dissipation_mean,
                st.dissipation_std,
                spec.dissipation_laminar(),
                st.tke_mean,
                st.time
            );
            entries.insert(id.clone(), st);
            let header: String = text.lines().take_while(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
            let body = toml::to_string_pretty(&entries).context("cannot format the table")?;
            std::fs::write(&table, format!("{header}\n{body}")).with_context(|| format!("cannot write {}", table.display()))?;
            println!("wrote {} (rebuild to embed)", table.display());
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Calibrate {
            id,
            level,
            actions,
            table,
            threads,
        }) => {
            let spec = hgym::env::spec(&id)?;
            if actions == 0 {
                return Err(UsageError("--actions must be at least 1".into()).into());
            }
            let text = std::fs::read_to_string(&table)
                .with_context(|| format!("cannot read {} (run from the repository root or pass --table)", table.display()))?;
            // Parsed now to fail fast on a broken table; read again before writing (below).
            hgym::env::calibrate::parse_table(&text).map_err(anyhow::Error::msg)?;
            let (pool, _) = thread_pool(threads)?;
            let pb = Progress::new(actions as u64, &id);
            let entry = pool
                .install(|| {
                    hgym::env::calibrate::calibrate(&spec, level, actions, hgym::env::default_cache_dir(), &mut |k, _| {
                        pb.set_position(k as u64)
                    })
                })
                .with_context(|| format!("calibrating {id}"))?;
            pb.finish_and_clear();
            if let Some([c_d, c_l]) = entry.mean_forces {
                println!("{id}: uncontrolled mean C_D {c_d:.4}, mean C_L {c_l:.4}");
            }
            // Re-read the table: other calibrations may have written their entries while this one
            // ran (several IDs are often calibrated at once); then write atomically.
            let text = std::fs::read_to_string(&table).with_context(|| format!("cannot read {}", table.display()))?;
            let mut entries = hgym::env::calibrate::parse_table(&text).map_err(anyhow::Error::msg)?;
            entries.insert(hgym::env::calibrate::table_key(&id, level), entry);
            let header: String = text.lines().take_while(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
            let body = toml::to_string_pretty(&entries).context("cannot format the table")?;
            let tmp = table.with_extension(format!("tmp.{}", std::process::id()));
            std::fs::write(&tmp, format!("{header}\n{body}")).with_context(|| format!("cannot write {}", tmp.display()))?;
            std::fs::rename(&tmp, &table).with_context(|| format!("cannot replace {}", table.display()))?;
            println!(
                "calibrated {id} at the {} level over {actions} actions; wrote {} (rebuild to embed)",
                level.name(),
                table.display()
            );
            Ok(Outcome::Ok)
        }
    }
}

fn run_rollout(args: RunArgs) -> Result<Outcome> {
    let config = match &args.config {
        None => hgym::train::config::TrainConfig::default(),
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| format!("cannot read the config file {}", p.display()))?;
            hgym::train::config::TrainConfig::parse(&text, &p.display().to_string()).map_err(UsageError)?
        }
    };
    let spec = match hgym::train::resolve_spec(&args.env, &config) {
        Ok(hgym::env::any::AnySpec::Lbm(s)) => s,
        Ok(other) => {
            return Err(UsageError(format!(
                "`hgym run` draws lattice-Boltzmann flows; for {} use `hgym eval --policy zero|random|sine --env {}`",
                other.id(),
                other.id()
            ))
            .into())
        }
        Err(hgym::train::TrainError::Input(m)) => return Err(UsageError(m).into()),
        Err(e) => return Err(e.into()),
    };
    if args.steps == 0 {
        return Err(UsageError("--steps must be at least 1".into()).into());
    }
    let (pool, _) = thread_pool(args.threads)?;
    let out = args.out.join(format!(
        "{}-{}-seed{}",
        spec.id,
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
        spec.id
    );
    let pb = Progress::new(args.steps as u64, &spec.id);
    cli::train::install_interrupt();
    let summary = pool
        .install(|| {
            hgym::env::rollout::rollout(&spec, &opts, &mut |k, _| pb.set_position(k as u64), &|| {
                cli::train::INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst)
            })
        })
        .with_context(|| format!("running {}", spec.id))?;
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
    if cli::train::INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst) {
        eprintln!(
            "interrupted: the partial episode and its trajectory.mcap (complete and valid) are in {}",
            out.display()
        );
        std::process::exit(130);
    }
    Ok(if summary.terminated { Outcome::CheckFailed } else { Outcome::Ok })
}

fn run_bench_envs(json: bool, actions: usize, quick: bool, families: &[String]) -> Result<Outcome> {
    if actions == 0 {
        return Err(UsageError("--actions must be at least 1".into()).into());
    }
    let known = hgym::bench::envs::families();
    if let Some(f) = families.iter().find(|f| !known.contains(f)) {
        return Err(UsageError(format!("unknown family '{f}'; the families are: {}", known.join(", "))).into());
    }
    let levels: &[Level] = if quick {
        &[Level::Coarse]
    } else {
        &[Level::Coarse, Level::Default]
    };
    let rows = hgym::bench::envs::bench_envs(levels, actions, families, hgym::env::default_cache_dir(), &mut |m| {
        if !json {
            eprintln!("{m}");
        }
    })
    .map_err(anyhow::Error::msg)
    .context("environment benchmark")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print!("{}", hgym::bench::envs::table(&rows));
    }
    Ok(Outcome::Ok)
}

fn run_plot(runs: &[PathBuf], out: &std::path::Path, drag: bool, train: bool) -> Result<Outcome> {
    use hgym::report::plots::{lines, Line};
    let mut series: Vec<(String, Vec<f64>, Vec<f64>)> = vec![];
    for dir in runs {
        let file = dir.join("curve.csv");
        let text = std::fs::read_to_string(&file).map_err(|e| {
            UsageError(format!(
                "{}: {e} (give training result folders, each with curve.csv)",
                file.display()
            ))
        })?;
        let rows = hgym::train::curve::from_csv(&text).map_err(|e| UsageError(format!("{}: {e}", file.display())))?;
        let (x, y): (Vec<f64>, Vec<f64>) = rows
            .iter()
            .map(|r| {
                let y = if drag {
                    r.eval_drag_reduction_pct
                } else if train {
                    r.train_return
                } else {
                    r.eval_return
                };
                (r.samples as f64, y)
            })
            .filter(|(_, y)| y.is_finite())
            .unzip();
        let label = dir
            .components()
            .rev()
            .take(2)
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<Vec<_>>()
            .join("/");
        series.push((label, x, y));
    }
    let lines_: Vec<Line> = series
        .iter()
        .map(|(l, x, y)| Line {
            label: l,
            x,
            y,
            band: None,
        })
        .collect();
    let what = if drag {
        "evaluation drag reduction (%)"
    } else if train {
        "training return"
    } else {
        "evaluation return"
    };
    lines(out, "learning curves", "environment samples", what, &lines_).map_err(anyhow::Error::msg)?;
    println!("wrote {} ({} runs)", out.display(), series.len());
    Ok(Outcome::Ok)
}
