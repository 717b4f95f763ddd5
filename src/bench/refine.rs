//! The grid-refinement benchmark: what the 2:1 coupling costs.
//!
//! A refined run steps every node of every level (level `l` twice per step of level `l - 1`)
//! with the same kernel as a uniform grid, and adds the coupling: reading the parent's edge
//! moments, rebuilding the patch's outer ring, and restricting the patch onto the parent's nodes
//! under it. So the peer is the uniform D2Q9 kernel on the coarse grid, timed in the same run with
//! the same threads: the ratio `refined node updates per second / uniform MLUPS` is 1 for free
//! coupling, and `1 - ratio` is the coupling's share of the time.

use std::f64::consts::PI;
use std::time::Instant;

use hgym_solvers::lbm::d3::{D3Config, D3q19, D3q27, Lattice3, Lbm3, Patch3, Refined3};
use hgym_solvers::lbm::{Collision, D2q9, D2q9Config, Patch, Refined, Sides};
use serde::{Deserialize, Serialize};

use super::{BenchError, BenchLattice};

fn d2q9() -> String {
    "d2q9".into()
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RefineBenchRow {
    pub threads: usize,
    /// Coarse grid side (periodic, `n x n` or `n x n x n`).
    pub n: usize,
    /// Nodes per coarse step: the coarse grid's plus twice the patch's.
    pub node_updates_per_step: usize,
    pub uniform_mlups: f64,
    /// Refined node updates per second, in millions.
    pub refined_mlups: f64,
    /// `refined_mlups / uniform_mlups`.
    pub ratio: f64,
    /// Largest relative velocity error (coarse grid, patch) of the Taylor-Green vortex against its
    /// exact decay after the timed steps.
    pub check_error: [f64; 2],
}

impl RefineBenchRow {
    fn new(threads: usize, n: usize, updates: usize, uniform_mlups: f64, refined_mlups: f64, check_error: [f64; 2]) -> Self {
        RefineBenchRow {
            threads,
            n,
            node_updates_per_step: updates,
            uniform_mlups,
            refined_mlups,
            ratio: refined_mlups / uniform_mlups,
            check_error,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RefineBenchReport {
    pub schema: String,
    /// `d2q9`, `d3q19` or `d3q27`.
    #[serde(default = "d2q9")]
    pub lattice: String,
    pub collision: String,
    pub rows: Vec<RefineBenchRow>,
    /// Smallest ratio accepted with all threads.
    pub target_ratio: f64,
    pub pass: bool,
    pub manifest: crate::report::manifest::Manifest,
}

#[derive(Clone, Debug)]
pub struct RefineBenchOptions {
    /// D2Q9 (a square grid) or a 3D set (a cube).
    pub lattice: BenchLattice,
    /// Coarse grid side; the patch covers the middle half of each direction (a quarter of the
    /// area, an eighth of the volume, so the patch has about as many nodes as the coarse grid).
    pub n: usize,
    pub threads: Vec<usize>,
    /// Seconds of timed stepping per measurement.
    pub seconds: f64,
}

impl RefineBenchOptions {
    /// The defaults for `lattice`: a 3D cube of 96^3 coarse nodes (134 MB for the D3Q19 A-B
    /// pair, far beyond the last-level cache) and its 97^3-node patch.
    pub fn for_lattice(lattice: BenchLattice) -> Self {
        let n = if lattice == BenchLattice::D2q9 { 1008 } else { 96 };
        RefineBenchOptions {
            lattice,
            n,
            ..Default::default()
        }
    }
}

impl Default for RefineBenchOptions {
    fn default() -> Self {
        // 1008^2 coarse nodes (73 MB for the A-B pair) and about as many on the patch: far beyond the
        // last-level cache, like the validation runs. Not 1024: rows of 1024-1026 floats per
        // population put the kernel's load and store streams 4 KiB apart (4K aliasing; measured
        // plain-store rates at 1 thread: 82, 85, 96 MLUPS at nx 1024, 1025, 1026 against 118-139
        // at 1027-1049), so a 1024 grid's 1025-wide patch would time the aliasing, not the coupling.
        RefineBenchOptions {
            lattice: BenchLattice::D2q9,
            n: 1008,
            threads: vec![1, 2],
            seconds: 1.5,
        }
    }
}

const TAU: f64 = 0.6;
const U0: f64 = 0.02;

/// Taylor-Green vortex of wavelength `n / 4` coarse cells at coarse time `t`: `(rho, u, v)`, the
/// density carrying the pressure `p = -u0^2 / 4 (cos 2kx + cos 2ky) e^{-4 nu k^2 t}` (`rho = 1 + 3 p`).
fn vortex(n: usize, t: f64, x: f64, y: f64) -> (f64, f64, f64) {
    let k = 8.0 * PI / n as f64;
    let nu = (TAU - 0.5) / 3.0;
    let d = (-2.0 * nu * k * k * t).exp();
    let p = -0.25 * U0 * U0 * ((2.0 * k * x).cos() + (2.0 * k * y).cos()) * d * d;
    (
        1.0 + 3.0 * p,
        -U0 * (k * x).cos() * (k * y).sin() * d,
        U0 * (k * x).sin() * (k * y).cos() * d,
    )
}

/// Largest velocity error of `grid` (positions `origin + i dx` in coarse units) on a 32 x 32
/// sample, as a fraction of the initial amplitude.
fn check(grid: &D2q9, origin: f64, dx: f64, n: usize, t: f64) -> f64 {
    let mut err = 0.0f64;
    for y in (0..grid.ny()).step_by((grid.ny() / 32).max(1)) {
        for x in (0..grid.nx()).step_by((grid.nx() / 32).max(1)) {
            let (_, u, v) = grid.node(x, y);
            let (_, ue, ve) = vortex(n, t, origin + x as f64 * dx, origin + y as f64 * dx);
            err = err.max((u as f64 - ue).abs().max((v as f64 - ve).abs()) / U0);
        }
    }
    err
}

/// [`check`] on a 3D grid's mid-plane. The 3D vortex is uniform along z and twice as long as
/// the 2D one (wavelength `n / 2`: the boxes are smaller), so it is `vortex(2 n, ..)`.
fn check3<const Q: usize, L: Lattice3<Q>>(grid: &Lbm3<Q, L>, n: usize, t: f64) -> f64 {
    let c = grid.config();
    let z = c.n[2] / 2;
    let mut err = 0.0f64;
    for y in (0..c.n[1]).step_by((c.n[1] / 32).max(1)) {
        for x in (0..c.n[0]).step_by((c.n[0] / 32).max(1)) {
            let (_, u) = grid.rho_u([x, y, z]);
            let p = c.grid.position([x, y, z]);
            let (_, ue, ve) = vortex(2 * n, t, p[0], p[1]);
            err = err.max((u[0] - ue).abs().max((u[1] - ve).abs()) / U0);
        }
    }
    err
}

/// One row of the 3D benchmark: the uniform box and the box with a patch over its middle
/// eighth, timed alike.
fn row3<const Q: usize, L: Lattice3<Q>>(n: usize, threads: usize, seconds: f64) -> Result<RefineBenchRow, BenchError> {
    let cfg = || {
        let mut c = D3Config::new([n; 3], TAU);
        c.collision = Collision::Regularized;
        c.check_interval = 0;
        c
    };
    let at = |x: usize, y: usize, _z: usize| {
        let (rho, u, v) = vortex(2 * n, 0.0, x as f64, y as f64);
        (rho, [u, v, 0.0])
    };
    let mut uniform = Lbm3::<Q, L>::new(cfg(), &[])?;
    uniform.set_equilibrium(at);
    let uniform_rate = time_steps(seconds, |k| (0..k).try_for_each(|_| uniform.step()))?;
    let uniform_mlups = uniform_rate * (n * n * n) as f64 / 1e6;
    drop(uniform);

    let patch = Patch3 {
        lo: [n / 4; 3],
        hi: [3 * n / 4; 3],
    };
    let mut refined = Refined3::<Q, L>::new(cfg(), &[patch], &[])?;
    refined.init_with(|p| {
        let (rho, u, v) = vortex(2 * n, 0.0, p[0], p[1]);
        (rho, [u, v, 0.0])
    });
    let rate = time_steps(seconds, |k| (0..k).try_for_each(|_| refined.step()))?;
    let updates = refined.node_updates_per_step();
    let refined_mlups = rate * updates as f64 / 1e6;
    refined.sync();
    let t = refined.time() as f64;
    let check_error = [check3(refined.coarse(), n, t), check3(&refined.levels()[1], n, t)];
    Ok(RefineBenchRow::new(threads, n, updates, uniform_mlups, refined_mlups, check_error))
}

/// Steps `step` for about `seconds` (best of three timings after a calibration); returns steps
/// per second.
fn time_steps(seconds: f64, mut step: impl FnMut(u64) -> Result<(), hgym_solvers::lbm::LbmError>) -> Result<f64, BenchError> {
    step(2)?;
    let t = Instant::now();
    step(2)?;
    let per_step = t.elapsed().as_secs_f64() / 2.0;
    let steps = ((seconds / 3.0 / per_step.max(1e-9)) as u64).max(2);
    let mut dt = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        step(steps)?;
        dt = dt.min(t.elapsed().as_secs_f64());
    }
    Ok(steps as f64 / dt)
}

/// Runs the benchmark (regularised collision, the validation cases' operator).
pub fn bench_refine(opts: &RefineBenchOptions, progress: &mut dyn FnMut(&str)) -> Result<RefineBenchReport, BenchError> {
    let n = opts.n;
    let smallest = if opts.lattice == BenchLattice::D2q9 { 64 } else { 32 };
    if n < smallest || !n.is_multiple_of(16) {
        return Err(BenchError::Input(format!(
            "grid side {n}: use a multiple of 16, at least {smallest}"
        )));
    }
    let cfg = || {
        let mut c = D2q9Config::new(n, n, TAU, Sides::periodic());
        c.collision = Collision::Regularized;
        c.check_interval = 0;
        c
    };
    let patch = Patch {
        x: [n / 4, 3 * n / 4],
        y: [n / 4, 3 * n / 4],
    };
    let mut rows = Vec::new();
    for &threads in &opts.threads {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        let row = pool.install(|| -> Result<RefineBenchRow, BenchError> {
            match opts.lattice {
                BenchLattice::D3q19 => return row3::<19, D3q19>(n, threads, opts.seconds),
                BenchLattice::D3q27 => return row3::<27, D3q27>(n, threads, opts.seconds),
                BenchLattice::D2q9 => {}
            }
            let mut uniform = D2q9::new(cfg(), vec![])?;
            uniform.init_with(|x, y| vortex(n, 0.0, x, y));
            let uniform_rate = time_steps(opts.seconds, |k| uniform.advance(k))?;
            let uniform_mlups = uniform_rate * (n * n) as f64 / 1e6;
            drop(uniform);

            let mut refined = Refined::new(cfg(), &[patch], vec![])?;
            refined.init_with(|x, y| vortex(n, 0.0, x, y));
            let rate = time_steps(opts.seconds, |k| refined.advance(k))?;
            let updates = refined.node_updates_per_step();
            let refined_mlups = rate * updates as f64 / 1e6;
            refined.sync();
            let t = refined.time() as f64;
            let check_error = [
                check(refined.coarse(), 0.0, 1.0, n, t),
                check(refined.fine(), patch.x[0] as f64, 0.5, n, t),
            ];
            Ok(RefineBenchRow::new(threads, n, updates, uniform_mlups, refined_mlups, check_error))
        })?;
        if row.check_error.iter().any(|e| *e > 0.01) {
            return Err(BenchError::Check(format!(
                "Taylor-Green velocity off by {:.2e} (coarse) / {:.2e} (patch) of its amplitude",
                row.check_error[0], row.check_error[1]
            )));
        }
        progress(&format!(
            "{threads} thread(s): uniform {:.0} MLUPS, refined {:.0} MLUPS ({:.0} %)",
            row.uniform_mlups,
            row.refined_mlups,
            100.0 * row.ratio
        ));
        rows.push(row);
    }
    let target = 0.8;
    let max_threads = rows.iter().map(|r| r.threads).max().unwrap_or(1);
    let pass = rows.iter().filter(|r| r.threads == max_threads).all(|r| r.ratio >= target);
    Ok(RefineBenchReport {
        schema: "hgym/bench-refine/v1".into(),
        lattice: opts.lattice.name().into(),
        collision: Collision::Regularized.name().into(),
        rows,
        target_ratio: target,
        pass,
        manifest: crate::report::manifest::manifest(max_threads, 0.0),
    })
}

impl RefineBenchReport {
    pub fn table(&self) -> String {
        let (set, part) = if self.lattice == "d2q9" {
            ("D2Q9", "quarter")
        } else {
            (&self.lattice[..], "eighth")
        };
        let mut s = format!(
            "{} with a 2:1 patch over the middle {part} ({} collision); peer: the uniform coarse grid, same run, same threads\n",
            set.to_uppercase(),
            self.collision
        );
        s += &format!(
            "  {:>7} {:>11} {:>13} {:>14} {:>14} {:>7}  {}\n",
            "threads", "coarse", "updates/step", "uniform MLUPS", "refined MLUPS", "ratio", "check"
        );
        for r in &self.rows {
            s += &format!(
                "  {:>7} {:>11} {:>13} {:>14.1} {:>14.1} {:>6.0}%  TG err {:.1e} / {:.1e}\n",
                r.threads,
                if self.lattice == "d2q9" {
                    format!("{}x{}", r.n, r.n)
                } else {
                    format!("{0}x{0}x{0}", r.n)
                },
                r.node_updates_per_step,
                r.uniform_mlups,
                r.refined_mlups,
                100.0 * r.ratio,
                r.check_error[0],
                r.check_error[1]
            );
        }
        s += &format!(
            "  target: refined >= {:.0}% of the uniform rate with all threads: {}\n",
            100.0 * self.target_ratio,
            if self.pass { "met" } else { "NOT met" }
        );
        s
    }
}
