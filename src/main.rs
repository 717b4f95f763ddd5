// `hgym`: the command line. Parses, hands each command to its file in `src/cli/` (its arguments
// and its `run`), and maps the outcome to an exit code in one place: 0 ok, 1 a check failed
// (validation out of tolerance, solver diverged, benchmark short of its target), 2 bad usage or
// bad input.

use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

/// `print!` through [`cli::out::write_out`]: a closed pipe ends the program with exit code 0.
macro_rules! print {
    ($($arg:tt)*) => { $crate::cli::out::write_out(format_args!($($arg)*)) };
}

/// `println!` through [`cli::out::write_out`]: a closed pipe ends the program with exit code 0.
macro_rules! println {
    () => { $crate::cli::out::write_out(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::cli::out::write_out(format_args!("{}\n", format_args!($($arg)*))) };
}

macro_rules! eprintln {
    () => { $crate::cli::out::write_err(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::cli::out::write_err(format_args!("{}\n", format_args!($($arg)*))) };
}

#[path = "cli/mod.rs"]
mod cli;
use hgym::validate::ValidateError;

#[derive(Parser)]
#[command(
    name = "hgym",
    version,
    about = "Reinforcement-learning flow control: validated CFD environments, benchmarks and reports",
    long_about = "hgym runs flow-control environments on fast in-process solvers.\n\n\
                  Start with `hgym validate cylinder` (checks the lattice-Boltzmann solver against the \
                  literature: Strouhal number, mean drag and lift amplitude at Re 100 and 200) and \
                  `hgym bench lbm` (solver speed against the machine's memory bandwidth); `hgym envs` lists \
                  the environments with how far each one's uncontrolled flow is from the literature."
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
    Bench(cli::bench::BenchCommand),
    /// List environments, print a spec, or calibrate observation statistics.
    ///
    /// `hgym envs` prints a table of every ID, with how far its uncontrolled flow is from the
    /// literature at the coarse and default levels (St and mean C_D deviations, measured by
    /// `hgym validate --env ID --level L --record`); `hgym envs show ID` prints its full spec as TOML;
    /// `hgym envs calibrate ID` runs it uncontrolled and records observation means and scales in
    /// benchmarks/envs/normalization.toml (rebuild to embed them).
    Envs(cli::envs::EnvsArgs),
    /// Run one episode of a fixed policy on an environment and write metrics, plots and a
    /// manifest (`<out>/<ID>-<policy>-seed<S>/`).
    Run(cli::run::RunArgs),
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
    /// Transfer a controller between flows (benchmarks/protocols/transfer/): over the same seeds,
    /// the source policy zero-shot on the target, fine-tuned from it, and trained from scratch;
    /// episodes and core-hours to 90 % of the from-scratch performance, the saving, a plot.
    ///
    /// `hgym transfer Cylinder_2D_Re200 Cylinder_2D_Re1000` (`--list` shows the pairs). Every arm
    /// is an ordinary run folder: Ctrl-C and the same command again continue where it stopped.
    Transfer(cli::transfer::TransferArgs),
    /// Trajectory files: `hgym data recover FILE` salvages every complete chunk of a truncated
    /// MCAP file (e.g. after a kill) into FILE.recovered.mcap.
    #[command(subcommand)]
    Data(cli::data::DataCommand),
    /// Turn trajectory files into a dataset: `hgym export --to hf results/runs OUT` writes
    /// Parquet shards (one row per control step, one config per env) and a dataset card.
    Export(cli::data::ExportArgs),
    /// Upload a dataset folder to the Hugging Face Hub (token from HF_TOKEN or the
    /// huggingface-cli token file; endpoint from HF_ENDPOINT).
    Push(cli::data::PushArgs),
    /// Learning curves of several training runs in one figure (evaluation return, or drag
    /// reduction with --drag), e.g. `hgym plot results/train/Cylinder_2D_Re100-*/seed0 -o cmp.png`.
    Plot(cli::plot::PlotArgs),
    /// Aggregate the result folders under results/ into results/leaderboard.json,
    /// results/LEADERBOARD.md and a bar chart per environment.
    Leaderboard(cli::plot::LeaderboardArgs),
}

/// Outcome of a command: 0 ok, 1 a check failed.
enum Outcome {
    Ok,
    CheckFailed,
}

fn main() -> ExitCode {
    // `hgym-mpi`: start MPI and learn this process's rank before anything prints (see `hgym::flow::ranks`).
    #[cfg(feature = "mpi")]
    let (_universe, ending) = {
        use mpi::traits::Communicator;
        // The solver is stepped from a worker thread, one call at a time.
        let Some((universe, provided)) = mpi::initialize_with_threading(mpi::Threading::Serialized) else {
            eprintln!("error: MPI was already initialised");
            return ExitCode::from(1);
        };
        if matches!(provided, mpi::Threading::Single | mpi::Threading::Funneled) {
            eprintln!(
                "error: this MPI library allows calls from the main thread only ({provided:?}); hgym-mpi needs MPI_THREAD_SERIALIZED"
            );
            return ExitCode::from(1);
        }
        let world = universe.world();
        hgym::flow::ranks::set(world.rank() as usize, world.size() as usize);
        let ending = cli::ranks::Ending::new(&world);
        (universe, ending)
    };
    #[cfg(not(feature = "mpi"))]
    let ending = cli::ranks::Ending;
    let mut cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    if let Some(refused) = refused_under_mpi(&cli.command) {
        if hgym::flow::ranks::leader() {
            eprintln!("error: {refused}");
        }
        return ExitCode::from(2);
    }
    let scratch = match cli::ranks::scatter_outputs(&mut cli.command) {
        Ok(s) => s,
        Err(e) => return failed(e, None, ending),
    };
    hgym::env::spin_up::observe_spin_ups(cli::progress::spin_up_progress);
    let result = match cli.command {
        Command::Validate(args) => cli::validate::run(args),
        Command::Bench(cmd) => cli::bench::run(cmd),
        Command::Envs(args) => cli::envs::run(args),
        Command::Run(args) => cli::run::run(args),
        Command::Train(args) => cli::train::run_train(args),
        Command::Eval(args) => cli::train::run_eval(args),
        Command::Compare(args) => cli::train::run_compare(args),
        Command::Transfer(args) => cli::transfer::run(args),
        Command::Export(args) => cli::data::run_export(args),
        Command::Push(args) => cli::data::run_push(args),
        Command::Data(cmd) => cli::data::run_data(cmd),
        Command::Plot(args) => cli::plot::plot(args),
        Command::Leaderboard(args) => cli::plot::leaderboard(args),
    };
    match result {
        Ok(Outcome::Ok) => ExitCode::SUCCESS,
        Ok(Outcome::CheckFailed) => ExitCode::from(1),
        Err(e) => failed(e, scratch, ending),
    }
}

/// Reports `e` and ends: exit code 2 for bad input, else 1. On several MPI ranks every rank
/// reports its own error and the job is aborted (see [`cli::ranks::Ending`]).
fn failed(e: anyhow::Error, scratch: Option<cli::ranks::Scratch>, ending: cli::ranks::Ending) -> ExitCode {
    let code = if is_bad_input(&e) { 2 } else { 1 };
    match hgym::flow::ranks::rank() {
        (0, 1) => std::eprintln!("error: {e:#}"),
        (r, _) => std::eprintln!("error (rank {r}): {e:#}"),
    }
    drop(scratch);
    ending.abort(code);
    ExitCode::from(code as u8)
}

/// The one place that decides the exit code of an error: 2 when anything in its chain is the
/// user's input (an unknown name, a malformed file, a spec that cannot run), else 1.
fn is_bad_input(e: &anyhow::Error) -> bool {
    use hgym_agents::EnvError;
    e.chain().any(|c| {
        c.downcast_ref::<UsageError>().is_some()
            || c.downcast_ref::<hgym::env::EnvInputError>().is_some()
            || c.downcast_ref::<hgym::train::config::ConfigError>().is_some()
            || c.downcast_ref::<hgym::train::curve::CurveFormatError>().is_some()
            || matches!(
                c.downcast_ref::<hgym::train::eval::PolicyError>(),
                Some(hgym::train::eval::PolicyError::Invalid(_))
            )
            || c.downcast_ref::<ValidateError>().is_some_and(|v| v.is_bad_input())
            || c.downcast_ref::<hgym::fidelity::FidelityError>().is_some_and(|v| v.is_bad_input())
            || c.downcast_ref::<hgym::train::TrainError>().is_some_and(|t| t.is_bad_input())
            || c.downcast_ref::<hgym::train::checkpoint::CheckpointError>()
                .is_some_and(|t| t.is_bad_input())
            || c.downcast_ref::<hgym::transfer::TransferError>().is_some_and(|t| t.is_bad_input())
            || c.downcast_ref::<hgym::train::compare::CompareError>()
                .is_some_and(|t| t.is_bad_input())
            || matches!(c.downcast_ref::<hgym::data::DataError>(), Some(hgym::data::DataError::Format(_)))
            || matches!(c.downcast_ref::<EnvError>(), Some(EnvError::InvalidSpec(_)))
            || c.downcast_ref::<hgym::data::hub::HubError>().is_some_and(|h| h.is_bad_input())
            || matches!(
                c.downcast_ref::<hgym::env::family::CalibrateError>(),
                Some(hgym::env::family::CalibrateError::NoActions)
            )
    })
}

/// Why a command cannot run on several MPI ranks, if it cannot: those that step flows (`validate`,
/// `train`, `eval`, `run`) can; the others gain nothing from ranks.
fn refused_under_mpi(command: &Command) -> Option<String> {
    let size = hgym::flow::ranks::rank().1;
    (size > 1
        && !matches!(
            command,
            Command::Validate(_) | Command::Train(_) | Command::Eval(_) | Command::Run(_)
        ))
    .then(|| format!("on {size} MPI ranks hgym-mpi runs validate, train, eval and run; run this command with `hgym` (one process)"))
}

/// A command-line mistake the CLI itself finds (exit code 2).
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
