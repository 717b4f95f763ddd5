//! Speed benchmarks, reported against the machine's limit measured in the same run.
//!
//! `hgym bench lbm [--lattice d2q9|d3q19|d3q27]`: million lattice updates per second (MLUPS) of
//! the step at three sizes
//! (L2-resident, L3-resident, at least four times the last-level cache), with 1 and 2 threads,
//! next to the machine's copy bandwidth with the same thread count (the faster of STREAM's loop
//! and memcpy; `stream.rs`). The roofline is
//! `bandwidth / bytes per cell update`; the FP32 kernel moves `2 Q 4` bytes per update (72 for
//! D2Q9, 152 for D3Q19, 216 for D3Q27: Q 4-byte populations read, Q written; no flag field), the
//! same read+write convention STREAM's copy uses. Each size first passes a correctness check (Taylor-Green decay) before it is timed.
//! The target (D2Q9: 85 % of the roofline with all threads and 75 % with one; 3D: 80 % with all
//! threads) is judged at the memory-bound size.
//!
//! `hgym bench channel`: the channel DNS's simulated time per wall-clock second
//! ([`channel`]), and with `--peer` against HydroGym's JAX channel.
//!
//! `hgym bench refine`: the cost of 2:1 grid refinement's coupling, as the ratio of a refined
//! grid's node updates per second to the uniform kernel's on the same coarse grid, same run.

pub mod agents;
pub mod channel;
pub mod envs;
pub mod kolmogorov;
mod lbm;
pub mod peer;
pub mod python;
mod refine;
mod stream;

/// Why a speed benchmark could not report.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Solver(#[from] hgym_solvers::lbm::LbmError),
    /// The kernel gave a wrong answer on the correctness check that precedes every timing.
    #[error("correctness check failed: {0}")]
    Check(String),
    #[error("{0}")]
    Input(String),
    #[error("cannot start the worker threads")]
    Threads(#[from] rayon::ThreadPoolBuildError),
}

pub use lbm::{bench_lbm, BenchLattice, BenchReport, BenchRow, LbmBenchOptions};
pub use refine::{bench_refine, RefineBenchOptions, RefineBenchReport, RefineBenchRow};
pub use stream::{default_copy_values, last_level_cache_bytes, stream_copy_gbs, CopyBandwidth, CopyMethod};
