//! `hgym bench python`: what reaching hgym from Python costs. hgym's Python package runs in a
//! Python process (`scripts/bench/hgym_python.py`, spoken to as a [`super::peer::Peer`]) while
//! this process steps the same environments (same spec, overrides, level and seed) in Rust,
//! alternating Rust and Python so both see the same minute of the machine.
//!
//! - **Boundary overhead**: seconds per `HgymEnv.step` minus the seconds spent inside the Rust
//!   `FlowEnv::step` in the same calls (the package times it: `_hgym.Env.step_seconds`), so
//!   the machine's minute-to-minute noise, which is larger than the overhead, cancels. The
//!   overhead does not depend on the flow's cost (numpy in, float32 numpy and a dict out, the
//!   GIL released and taken back), so it is judged on the cheapest step there is, the Kolmogorov
//!   flow at N 24 with one solver step per action; a cylinder row shows it on a real step.
//!   Beside it, the Python step against the same env stepped by this process in a Rust loop
//!   (alternating), which also shows what the Python process's threads cost the solver.
//! - **Vector throughput**: environment steps per second of `hgym.make_vec(id, n)` against the
//!   Rust loop it wraps (the n environments stepped with rayon on a pool of as many threads),
//!   with 1 and 2 threads.
//! - **HydroGym** (`--peer`): one control action of HydroGym's JAX Kolmogorov environment
//!   through gymnax's Gymnasium wrapper, against one action of hgym's through its Gymnasium
//!   class at the same set-up (N 64, Re 40, dt 1e-3, 10 time units per action, float64).

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::peer::{median, Pairs, Peer, PeerError};
use crate::env::{EnvInputError, FlowEnv, Spec};
use crate::flow::Level;
use hgym_agents::EnvError;

/// hgym's Python package, timed by [`bench_python`].
pub const HGYM_PYTHON: (&str, &str) = ("hgym_python.py", include_str!("../../scripts/bench/hgym_python.py"));

/// Targets: the boundary's overhead per step, and the vector env's throughput against Rust's.
pub const MAX_OVERHEAD_US: f64 = 5.0;
pub const MIN_VECTOR_RATIO: f64 = 0.95;

#[derive(Debug, thiserror::Error)]
pub enum PythonBenchError {
    #[error(transparent)]
    Peer(#[from] PeerError),
    #[error(transparent)]
    Input(#[from] EnvInputError),
    #[error("the Rust environment failed")]
    Env(#[from] EnvError),
    #[error("cannot start the worker threads")]
    Threads(#[from] rayon::ThreadPoolBuildError),
}

/// One environment the benchmark steps in both languages.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Case {
    /// What the row is, for the table.
    pub name: String,
    pub id: String,
    pub level: Level,
    /// Spec fields overridden (the Python keywords), as JSON.
    pub overrides: serde_json::Value,
}

impl Case {
    fn new(name: &str, id: &str, level: Level, overrides: serde_json::Value) -> Case {
        Case {
            name: name.to_string(),
            id: id.to_string(),
            level,
            overrides,
        }
    }

    fn spec(&self) -> Result<Spec, EnvInputError> {
        let spec = crate::env::lookup(&self.id)?;
        let table: toml::Table = serde_json::from_value(self.overrides.clone()).map_err(|e| EnvInputError::Override {
            id: self.id.clone(),
            message: e.to_string(),
        })?;
        spec.with_overrides(&table)
    }

    fn make(&self, seed: u64) -> Result<Box<dyn FlowEnv>, PythonBenchError> {
        let mut env = self.spec()?.make(self.level, crate::env::default_cache_dir())?;
        env.reset(seed)?;
        Ok(env)
    }

    /// `ID LEVEL SEED OVERRIDES` as the script reads them.
    fn words(&self, seed: u64) -> String {
        format!("{} {} {seed} {}", self.id, self.level.name(), self.overrides)
    }
}

/// Per-step time of one environment through Python and in Rust.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BoundaryRow {
    pub case: Case,
    pub threads: usize,
    pub steps: usize,
    /// Seconds per step of the Rust loop in this process and of `HgymEnv.step`, pair by pair.
    pub pairs: Pairs,
    /// The boundary per round, microseconds: `HgymEnv.step` minus the time inside the Rust step
    /// in the same calls; and its median (the judged figure).
    pub overhead_us: Vec<f64>,
    pub median_overhead_us: f64,
    /// `HgymEnv.step` minus this process's Rust loop per pair, microseconds, median.
    pub median_loop_gap_us: f64,
    /// The boundary through `gymnasium.make`'s wrappers (Gymnasium's order and passive checks), median.
    pub median_gym_overhead_us: f64,
}

/// Environment steps per second of the vector environment and of the Rust loop.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct VectorRow {
    pub case: Case,
    pub num_envs: usize,
    pub threads: usize,
    /// Rust's and Python's environment steps per second, pair by pair.
    pub pairs: Pairs,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PythonBench {
    /// The Python side's versions (hgym wheel, Gymnasium, numpy, Python).
    pub about: serde_json::Value,
    pub boundary: Vec<BoundaryRow>,
    pub vector: Vec<VectorRow>,
    /// HydroGym's Kolmogorov env through its Gymnasium wrapper, with `--peer`.
    pub peer: Option<HydrogymRow>,
    /// Overhead under [`MAX_OVERHEAD_US`] on the judged case's rows and every vector ratio at least
    /// [`MIN_VECTOR_RATIO`].
    pub pass: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct HydrogymRow {
    pub about: serde_json::Value,
    pub case: Case,
    /// Seconds per control action, hgym (through its Gymnasium class) and HydroGym (through
    /// gymnax's Gymnasium wrapper, whose `step` also computes the auto-reset state), pair by pair.
    pub pairs: Pairs,
    /// The same hgym actions against HydroGym's jitted `step_env` alone (no wrapper, no reset).
    pub step_env: Pairs,
}

/// The boundary's cases; the first is judged: one Kolmogorov solver step (N 24, the smallest grid that resolves its forcing) per action.
fn boundary_cases() -> Vec<Case> {
    let long = 1_000_000;
    vec![
        Case::new(
            "Kolmogorov N 24, 1 solver step",
            "Kolmogorov_2D_Re40",
            Level::Coarse,
            serde_json::json!({"resolution": {"coarse": 24, "default": 64, "fine": 128}, "dt_at_64": 0.0375,
                "control_interval": 0.1, "spin_up": 10.0, "episode_actions": long}),
        ),
        Case::new(
            "Cylinder_2D_Re100 coarse",
            "Cylinder_2D_Re100",
            Level::Coarse,
            serde_json::json!({"episode_actions": long}),
        ),
    ]
}

fn vector_case() -> Case {
    Case::new(
        "Cylinder_2D_Re100 coarse",
        "Cylinder_2D_Re100",
        Level::Coarse,
        serde_json::json!({"episode_actions": 1_000_000}),
    )
}

/// HydroGym's set-up (`scripts/peers/hydrogym_kolmogorov.py`) in hgym's spec fields.
fn hydrogym_case() -> Case {
    Case::new(
        "Kolmogorov N 64, dt 1e-3, 10 time units",
        "Kolmogorov_2D_Re40",
        Level::Default,
        serde_json::json!({"dt_at_64": 1e-3, "control_interval": 10.0, "spin_up": 10.0, "episode_actions": 1_000_000}),
    )
}

/// Runs the benchmark with hgym's package in `python` (with 1 and 2 threads) and, if given,
/// HydroGym's Kolmogorov env as the peer.
pub fn bench_python(
    python: &Path,
    quick: bool,
    peer: Option<&mut Peer>,
    progress: &mut dyn FnMut(&str),
) -> Result<PythonBench, PythonBenchError> {
    let rounds = if quick { 2 } else { 7 };
    let seed = 0;
    let mut boundary = vec![];
    let mut vector = vec![];
    let mut about = serde_json::Value::Null;
    for threads in [1, 2] {
        progress(&format!("starting {} with {threads} thread(s) ...", python.display()));
        let mut py = Peer::start_with(python, HGYM_PYTHON, threads)?;
        about = py.about.clone();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        for case in boundary_cases() {
            progress(&format!("boundary: {}, {threads} thread(s)", case.name));
            boundary.push(pool.install(|| boundary_row(&mut py, &case, threads, seed, rounds, quick))?);
        }
        let case = vector_case();
        progress(&format!("vector env: 4 x {}, {threads} thread(s)", case.name));
        vector.push(pool.install(|| vector_row(&mut py, &case, 4, threads, seed, rounds, quick))?);
    }
    let peer = match peer {
        None => None,
        Some(p) => {
            progress("HydroGym's Kolmogorov env through Gymnasium, against hgym's ...");
            Some(hydrogym_row(p, python, rounds.min(3))?)
        }
    };
    let judged = boundary_cases()[0].clone();
    let pass = boundary
        .iter()
        .filter(|b| b.case == judged)
        .all(|b| b.median_overhead_us < MAX_OVERHEAD_US)
        && vector.iter().all(|v| v.pairs.median_speedup >= MIN_VECTOR_RATIO);
    Ok(PythonBench {
        about,
        boundary,
        vector,
        peer,
        pass,
    })
}

fn boundary_row(
    py: &mut Peer,
    case: &Case,
    threads: usize,
    seed: u64,
    rounds: usize,
    quick: bool,
) -> Result<BoundaryRow, PythonBenchError> {
    let mut env = case.make(seed)?;
    py.ask(&format!("env {}", case.words(seed)))?;
    let zero = vec![0.0; env.action_space().low.len()];
    // About a quarter of a second per measurement.
    let t = Instant::now();
    env.step(&zero)?;
    let steps = ((if quick { 0.05 } else { 0.25 }) / t.elapsed().as_secs_f64()).clamp(5.0, 20_000.0) as usize;
    let (mut pairs, mut overhead_us, mut gym) = (vec![], vec![], vec![]);
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..steps {
            env.step(&zero)?;
        }
        let rust = t.elapsed().as_secs_f64() / steps as f64;
        let [python, inside, through_gym, inside_gym] = py.numbers(
            &format!("steps {steps}"),
            ["s_per_step", "s_in_rust", "s_per_step_gym", "s_in_rust_gym"],
        )?;
        pairs.push((rust, python));
        overhead_us.push((python - inside) * 1e6);
        gym.push((through_gym - inside_gym) * 1e6);
    }
    let gap: Vec<f64> = pairs.iter().map(|(r, p)| (p - r) * 1e6).collect();
    Ok(BoundaryRow {
        case: case.clone(),
        threads,
        steps,
        pairs: Pairs::new("s per step", "s", &pairs, false),
        median_overhead_us: median(&overhead_us),
        median_loop_gap_us: median(&gap),
        median_gym_overhead_us: median(&gym),
        overhead_us,
    })
}

fn vector_row(
    py: &mut Peer,
    case: &Case,
    n: usize,
    threads: usize,
    seed: u64,
    rounds: usize,
    quick: bool,
) -> Result<VectorRow, PythonBenchError> {
    // Instance i gets seed + i, as the vector env's reset(seed) gives it.
    let mut envs = (0..n).map(|i| case.make(seed + i as u64)).collect::<Result<Vec<_>, _>>()?;
    py.ask(&format!("vec {n} {}", case.words(seed)))?;
    let zero = vec![0.0; envs[0].action_space().low.len()];
    let mut step_all = || envs.par_iter_mut().try_for_each(|e| e.step(&zero).map(|_| ()));
    let t = Instant::now();
    step_all()?;
    let k = ((if quick { 0.1 } else { 0.25 }) / t.elapsed().as_secs_f64()).clamp(2.0, 10_000.0) as usize;
    let mut pairs = vec![];
    // The machine's speed moves by tens of percent within seconds, so the ratio needs many short
    // pairs, and each pair's order alternates (Rust first, then Python first) so that a drift
    // within a pair does not favour either side.
    for round in 0..3 * rounds {
        let mut rust_loop = || -> Result<f64, PythonBenchError> {
            let t = Instant::now();
            for _ in 0..k {
                step_all()?;
            }
            Ok((k * n) as f64 / t.elapsed().as_secs_f64())
        };
        let python_loop = |py: &mut Peer| py.numbers(&format!("vsteps {k}"), ["env_steps_per_s"]).map(|[p]| p);
        let (rust, python) = if round % 2 == 0 {
            let rust = rust_loop()?;
            (rust, python_loop(py)?)
        } else {
            let python = python_loop(py)?;
            (rust_loop()?, python)
        };
        // Python over Rust: the vector env's share of the Rust loop's throughput.
        pairs.push((python, rust));
    }
    Ok(VectorRow {
        case: case.clone(),
        num_envs: n,
        threads,
        pairs: Pairs::new("env steps/s", "1/s", &pairs, true),
    })
}

fn hydrogym_row(peer: &mut Peer, python: &Path, rounds: usize) -> Result<HydrogymRow, PythonBenchError> {
    let case = hydrogym_case();
    let threads = peer.about.get("threads").and_then(|t| t.as_u64()).unwrap_or(1) as usize;
    let mut ours = Peer::start_with(python, HGYM_PYTHON, threads)?;
    ours.ask(&format!("env {}", case.words(0)))?;
    let (mut gym, mut jitted) = (vec![], vec![]);
    for _ in 0..rounds {
        let [hgym] = ours.numbers("action", ["s_per_action"])?;
        let [through_gym] = peer.numbers("gym_action", ["s_per_action"])?;
        let [step_env] = peer.numbers("action", ["s_per_action"])?;
        gym.push((hgym, through_gym));
        jitted.push((hgym, step_env));
    }
    Ok(HydrogymRow {
        about: peer.about.clone(),
        case,
        pairs: Pairs::new("s/action, Gymnasium", "s", &gym, false),
        step_env: Pairs::new("s/action, its step_env", "s", &jitted, false),
    })
}

/// The report as text.
pub fn table(b: &PythonBench) -> String {
    let mut s = format!("hgym from Python {}\n", super::peer::describe(&b.about).replace("the peer (", "("));
    s += &format!(
        "boundary overhead per step (HgymEnv.step minus the Rust FlowEnv::step inside the same calls; target < {MAX_OVERHEAD_US} us on the Kolmogorov N 24 rows), and the Python step against a Rust loop of the same env in this process:\n"
    );
    for r in &b.boundary {
        s += &format!(
            "  {:<30} {} thread(s): overhead {:>6.2} us (rounds: {}); through gymnasium.make {:.2} us; Rust loop {:.1} us, Python {:.1} us ({:+.1} us)\n",
            r.case.name,
            r.threads,
            r.median_overhead_us,
            r.overhead_us.iter().map(|o| format!("{o:.2}")).collect::<Vec<_>>().join(" "),
            r.median_gym_overhead_us,
            r.pairs.median_ours * 1e6,
            r.pairs.median_peer * 1e6,
            r.median_loop_gap_us,
        );
    }
    s += &format!("vector env against the Rust loop (target >= {:.0} %):\n", MIN_VECTOR_RATIO * 100.0);
    for v in &b.vector {
        s += &format!(
            "  {} x {}, {} thread(s): Python {:.1}, Rust {:.1} env steps/s: {:.1} % (pairs: {})\n",
            v.num_envs,
            v.case.name,
            v.threads,
            v.pairs.median_ours,
            v.pairs.median_peer,
            v.pairs.median_speedup * 100.0,
            v.pairs.speedups.iter().map(|r| format!("{:.3}", r)).collect::<Vec<_>>().join(" "),
        );
    }
    match &b.peer {
        None => s += "HydroGym: not measured in this run (--peer runs its Kolmogorov env through Gymnasium beside ours)\n",
        Some(p) => {
            s += &format!(
                "one control action, Kolmogorov Re 40, N 64, dt 1e-3, 10 time units, float64, hgym through its Gymnasium class against {}:\n  {}\n  {}\n",
                super::peer::describe(&p.about),
                p.pairs.line("HydroGym"),
                p.step_env.line("HydroGym"),
            );
        }
    }
    s += if b.pass { "PASS\n" } else { "FAIL (a target above is missed)\n" };
    s
}
