//! `hgym bench`: speed against the machine's limits (LBM kernel, refinement, environments,
//! learners, the spectral solver).

use anyhow::{Context, Result};
use clap::Subcommand;
use hgym::bench::peer::{Peer, PeerError};

use crate::{thread_pool, Outcome, UsageError};
use hgym::bench::{bench_lbm, bench_refine, BenchLattice, LbmBenchOptions, RefineBenchOptions};
use hgym::flow::Level;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// Lattice-Boltzmann step: MLUPS at three sizes (cache-resident to memory-bound), 1 and 2
    /// threads, against a STREAM copy measured in the same run. Exit 1 if the memory-bound size
    /// reaches less than the target fraction of the roofline (D2Q9: 85 % with all threads and
    /// 75 % with one; 3D: 80 % with all threads).
    Lbm {
        /// Velocity set: d2q9 (2D), d3q19 or d3q27 (3D).
        #[arg(long, value_enum, default_value = "d2q9")]
        lattice: LatticeArg,
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// A fast smoke run (small sizes, short timings; the target is not judged).
        #[arg(long)]
        quick: bool,
        /// Collision operator to time.
        #[arg(long, value_enum, default_value = "regularized")]
        collision: CollisionArg,
        /// The memory-bound size, NXxNY (2D) or NXxNYxNZ (3D), instead of the default: the
        /// smallest of 2048^2 or 160^3 and up whose two population arrays hold four times the
        /// last-level cache (e.g. 4096x4096, 1.2 GB, for a 260 MB cache).
        #[arg(long, value_parser = parse_size)]
        size: Option<[usize; 3]>,
    },
    /// 2:1 grid refinement: node updates per second of a grid with a patch over its middle
    /// quarter (an eighth of a 3D box) against the uniform kernel on the same grid, 1 and 2
    /// threads. Exit 1 if the refined rate is below 80 % of the uniform one with all threads.
    Refine {
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// Velocity set: d2q9 (a 1008^2 grid), d3q19 or d3q27 (a 96^3 box).
        #[arg(long, value_enum, default_value = "d2q9")]
        lattice: LatticeArg,
        /// A fast smoke run (a small grid, short timings; the target is not judged).
        #[arg(long)]
        quick: bool,
    },
    /// The copy bandwidth `hgym bench lbm` takes as the machine's limit (GB/s, read + write; the
    /// faster of STREAM's ordinary loop and memcpy), alone: `make roofline` runs it beside
    /// STREAM's C copy to check it is at least as fast.
    Copy {
        /// Print one JSON line.
        #[arg(long)]
        json: bool,
        /// Threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// f32 values per array (default: each at least twice the last-level cache, and at least
        /// 2^26 values, 256 MB).
        #[arg(long)]
        values: Option<usize>,
    },
    /// Learner speed: TD3 updates/s (256x256, batch 256), PPO epochs/s (64x64), batch-1 policy
    /// latency. With --peer, Stable-Baselines3's TD3 at the same shapes is timed in the same run,
    /// alternating with ours, and the ratios printed; without it, no ratio. Exit 1 if a policy
    /// evaluation takes 10 us or more; 2 if --peer is given and the peers are not installed.
    Agents(#[command(flatten)] PeerBenchArgs),
    /// Spectral Kolmogorov solver: steps/s at N 64-256, VJP cost, accuracy against step size.
    /// With --peer, HydroGym's JAX Kolmogorov env (N 64 and 128, Re 40, float64) is timed in the
    /// same run with the same threads, alternating with ours, with each one's step size and
    /// accuracy per control action. Exit 1 if a VJP costs more than 2 steps, or with --peer if
    /// ours is less than 3x its steps/s (1.5x with --threads 1); 2 if --peer is given and the
    /// peers are not installed.
    Kolmogorov(#[command(flatten)] PeerBenchArgs),
    /// Channel DNS: steps/s and simulated t+ per second at the minimal and the full box (default
    /// grids), 1 and 2 threads. With --peer, HydroGym's JAX channel (72^3, its box) is timed in
    /// the same run, alternating with ours on its grid, per simulated time unit with each one's
    /// step stated. Exit 1 if that ratio is below 5x; 2 if --peer is given and the peers are not
    /// installed.
    Channel(#[command(flatten)] PeerBenchArgs),
    /// hgym from Python: the boundary's overhead per step (HgymEnv.step minus the Rust step inside
    /// the same calls; beside it the same env stepped in a Rust loop, alternating) and the vector
    /// env's throughput against the Rust loop, 1 and 2 threads. Needs the package (`make python`; the interpreter is $HGYM_PYTHON, else
    /// ~/.cache/hgym-venv/bin/python). With --peer, HydroGym's JAX Kolmogorov env through its
    /// Gymnasium wrapper beside hgym's, per control action. Exit 1 if the overhead is 5 us or more
    /// or the vector env reaches less than 95 % of the Rust loop.
    Python {
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// Short timings (targets not judged).
        #[arg(long)]
        quick: bool,
        /// Time HydroGym's Kolmogorov env beside ours (`make peers` installs it).
        #[arg(long)]
        peer: bool,
    },
    /// Control steps (actions) per second of each environment family at coarse and default, and
    /// the share of an action's time outside the solver's steps (actuation, probes, forces,
    /// observation, reward, info). Exit 1 if a 2D ID at coarse spends 5 % or more there (not
    /// judged with --quick)
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
        /// Only the 2D or only the 3D IDs.
        #[arg(long, value_parser = clap::value_parser!(u8).range(2..=3))]
        dimension: Option<u8>,
    },
}

/// The options of a benchmark that can time a peer beside ours.
#[derive(clap::Args)]
pub struct PeerBenchArgs {
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Short timings (targets not judged).
    #[arg(long)]
    quick: bool,
    /// Threads for our side (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Time the peer beside ours in the same run, alternating (`make peers` installs it).
    #[arg(long)]
    peer: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum LatticeArg {
    D2q9,
    D3q19,
    D3q27,
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum CollisionArg {
    /// Single-relaxation-time BGK.
    Bgk,
    /// Regularised BGK (Latt & Chopard 2006), the default of every case and environment.
    Regularized,
    /// Recursive regularised BGK (Malaspinas 2015; Coreixas et al. 2017).
    Recursive,
}

fn bench_lattice(lattice: LatticeArg) -> BenchLattice {
    match lattice {
        LatticeArg::D2q9 => BenchLattice::D2q9,
        LatticeArg::D3q19 => BenchLattice::D3q19,
        LatticeArg::D3q27 => BenchLattice::D3q27,
    }
}

/// Runs one benchmark.
pub fn run(cmd: BenchCommand) -> Result<Outcome> {
    match cmd {
        BenchCommand::Lbm {
            json,
            quick,
            collision,
            lattice,
            size,
        } => run_bench(json, quick, collision, lattice, size),
        BenchCommand::Refine { json, quick, lattice } => run_bench_refine(json, quick, lattice),
        BenchCommand::Copy { json, threads, values } => {
            let values = values.unwrap_or_else(hgym::bench::default_copy_values);
            if values < 1 << 20 {
                return Err(UsageError("--values must be at least 1048576 (arrays far beyond the caches)".into()).into());
            }
            let (pool, n) = thread_pool(threads)?;
            let c = pool.install(|| hgym::bench::stream_copy_gbs(values, 10));
            if json {
                println!(
                    "{}",
                    serde_json::json!({"threads": n, "values": values, "copy_gbs": c.gbs, "method": c.method, "stream_gbs": c.stream_gbs, "memcpy_gbs": c.memcpy_gbs})
                );
            } else {
                println!(
                    "copy, {n} thread(s), 2 x {} MB: {:.2} GB/s ({}; STREAM's loop {:.2}, memcpy {:.2})",
                    (values * 4) >> 20,
                    c.gbs,
                    c.method.name(),
                    c.stream_gbs,
                    c.memcpy_gbs
                );
            }
            Ok(Outcome::Ok)
        }
        BenchCommand::Envs {
            json,
            actions,
            quick,
            family,
            dimension,
        } => run_bench_envs(json, actions, quick, family, dimension),
        BenchCommand::Agents(args) => run_bench_agents(args),
        BenchCommand::Python { json, quick, peer } => run_bench_python(json, quick, peer),
        BenchCommand::Kolmogorov(args) => run_peer_bench(args, hgym::bench::peer::HYDROGYM_KOLMOGOROV, |quick, _, peer| {
            let b = hgym::bench::kolmogorov::bench_kolmogorov(quick, peer)?;
            Ok((hgym::bench::kolmogorov::table(&b), b.pass, serde_json::to_value(b)?))
        }),
        BenchCommand::Channel(args) => run_peer_bench(args, hgym::bench::peer::HYDROGYM_CHANNEL, |quick, threads, peer| {
            let b = hgym::bench::channel::bench_channel(quick, threads, peer)?;
            Ok((hgym::bench::channel::table(&b), b.pass, serde_json::to_value(b)?))
        }),
    }
}

/// A benchmark with an optional peer: `bench(quick, threads, peer)` gives its table, whether it
/// passed and its JSON report. Exit 1 when it falls short (not judged with --quick).
fn run_peer_bench(
    args: PeerBenchArgs,
    script: (&str, &str),
    bench: impl FnOnce(bool, usize, Option<&mut Peer>) -> Result<(String, bool, serde_json::Value)> + Send,
) -> Result<Outcome> {
    let (pool, n) = thread_pool(args.threads)?;
    let mut peer = start_peer(args.peer, script, n)?;
    let (table, pass, report) = pool.install(|| bench(args.quick, n, peer.as_mut()))?;
    print_report(args.json, &report, &table)?;
    Ok(if pass || args.quick { Outcome::Ok } else { Outcome::CheckFailed })
}

/// A benchmark's report as pretty JSON (`--json`) or as its table.
fn print_report(json: bool, report: &impl serde::Serialize, table: &str) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        print!("{table}");
    }
    Ok(())
}

/// `NXxNY` or `NXxNYxNZ`, each at least 8.
fn parse_size(s: &str) -> Result<[usize; 3], String> {
    let bad = || format!("{s:?}: give the size as NXxNY (2D) or NXxNYxNZ (3D), each at least 8, e.g. 4096x4096");
    let n: Vec<usize> = s
        .split('x')
        .map(|v| v.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match n[..] {
        [nx, ny] if nx.min(ny) >= 8 => Ok([nx, ny, 1]),
        [nx, ny, nz] if nx.min(ny).min(nz) >= 8 => Ok([nx, ny, nz]),
        _ => Err(bad()),
    }
}

fn run_bench(json: bool, quick: bool, collision: CollisionArg, lattice: LatticeArg, size: Option<[usize; 3]>) -> Result<Outcome> {
    let lattice = bench_lattice(lattice);
    if lattice != BenchLattice::D2q9 && matches!(collision, CollisionArg::Recursive) {
        return Err(UsageError("--collision recursive is 2D only; use bgk or regularized with a 3D lattice".into()).into());
    }
    let mut opts = LbmBenchOptions {
        lattice,
        sizes: lattice.default_sizes(hgym::bench::last_level_cache_bytes()),
        collision: match collision {
            CollisionArg::Bgk => hgym_solvers::lbm::Collision::Bgk,
            CollisionArg::Regularized => hgym_solvers::lbm::Collision::Regularized,
            CollisionArg::Recursive => hgym_solvers::lbm::Collision::Recursive,
        },
        ..LbmBenchOptions::default()
    };
    if quick {
        opts.sizes = match lattice {
            BenchLattice::D2q9 => vec![[32, 32, 1], [128, 64, 1], [256, 256, 1]],
            _ => vec![[12, 12, 12], [24, 24, 24], [48, 48, 48]],
        };
        opts.seconds = 0.05;
        opts.stream_values = 1 << 22;
    }
    if let Some(n) = size {
        if (n[2] > 1) != (lattice != BenchLattice::D2q9) {
            return Err(UsageError(format!(
                "--size {}x{}x{} does not fit --lattice {}: give NXxNY in 2D, NXxNYxNZ in 3D",
                n[0],
                n[1],
                n[2],
                lattice.name()
            ))
            .into());
        }
        if let Some(last) = opts.sizes.last_mut() {
            *last = n;
        }
    }
    let quiet = json;
    let report = bench_lbm(&opts, &mut |msg| {
        if !quiet {
            eprintln!("{msg}");
        }
    })
    .map_err(anyhow::Error::from)
    .context("LBM benchmark")?;
    print_report(json, &report, &report.table())?;
    Ok(if report.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}

fn run_bench_refine(json: bool, quick: bool, lattice: LatticeArg) -> Result<Outcome> {
    let lattice = bench_lattice(lattice);
    let mut opts = RefineBenchOptions::for_lattice(lattice);
    if quick {
        opts.n = if lattice == BenchLattice::D2q9 { 128 } else { 64 };
        opts.seconds = 0.05;
    }
    let report = bench_refine(&opts, &mut |msg| {
        if !json {
            eprintln!("{msg}");
        }
    })
    .map_err(anyhow::Error::from)
    .context("refinement benchmark")?;
    print_report(json, &report, &report.table())?;
    Ok(if report.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}

fn run_bench_envs(json: bool, actions: usize, quick: bool, families: Vec<String>, dimension: Option<u8>) -> Result<Outcome> {
    if actions == 0 {
        return Err(UsageError("--actions must be at least 1".into()).into());
    }
    let known = hgym::bench::envs::families();
    if let Some(f) = families.iter().find(|f| !known.contains(f)) {
        return Err(UsageError(format!("unknown family '{f}'; the families are: {}", known.join(", "))).into());
    }
    let opts = hgym::bench::envs::EnvBenchOptions {
        levels: if quick {
            vec![Level::Coarse]
        } else {
            vec![Level::Coarse, Level::Default]
        },
        actions,
        families,
        dimension,
        cache: hgym::env::default_cache_dir(),
    };
    let rows = hgym::bench::envs::bench_envs(&opts, &mut |m| {
        if !json {
            eprintln!("{m}");
        }
    })
    .map_err(anyhow::Error::from)
    .context("environment benchmark")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print!("{}", hgym::bench::envs::table(&rows));
    }
    let over = rows.iter().any(|r| r.over_target());
    Ok(if over && !quick { Outcome::CheckFailed } else { Outcome::Ok })
}

/// The peer, if asked for; missing peers are bad input (exit 2) with the install command.
fn start_peer(wanted: bool, script: (&str, &str), threads: usize) -> Result<Option<Peer>> {
    if !wanted {
        return Ok(None);
    }
    eprintln!("starting the peer {} with {threads} thread(s) ...", script.0);
    match Peer::start(script, threads) {
        Ok(p) => Ok(Some(p)),
        Err(e @ PeerError::Missing { .. }) => Err(UsageError(e.to_string()).into()),
        Err(e) => Err(e.into()),
    }
}

fn run_bench_agents(
    PeerBenchArgs {
        json,
        quick,
        threads,
        peer,
    }: PeerBenchArgs,
) -> Result<Outcome> {
    let (pool, n) = thread_pool(threads)?;
    let mut peer = start_peer(peer, hgym::bench::peer::SB3_TD3, n)?;
    let b = pool.install(|| hgym::bench::agents::bench_agents(quick, peer.as_mut()))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&b)?);
    } else {
        print!("{}", hgym::bench::agents::table(&b));
    }
    Ok(if b.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}

fn run_bench_python(json: bool, quick: bool, peer: bool) -> Result<Outcome> {
    // The interpreter with hgym's package: `$HGYM_PYTHON`, else the test venv `make python` fills.
    let python = hgym::bench::peer::interpreter("HGYM_PYTHON", "hgym-venv");
    if !python.exists() {
        return Err(UsageError(format!(
            "{} not found: run `make python` (builds the package into ~/.cache/hgym-venv), or set HGYM_PYTHON to an interpreter that has it",
            python.display()
        ))
        .into());
    }
    let mut peer = start_peer(peer, hgym::bench::peer::HYDROGYM_KOLMOGOROV, 2)?;
    let b = hgym::bench::python::bench_python(&python, quick, peer.as_mut(), &mut |m| {
        if !json {
            eprintln!("{m}");
        }
    })?;
    print_report(json, &b, &hgym::bench::python::table(&b))?;
    Ok(if b.pass || quick { Outcome::Ok } else { Outcome::CheckFailed })
}
