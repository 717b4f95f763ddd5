//! `hgym bench kolmogorov`: the spectral solver's speed and accuracy, and with a peer
//! (HydroGym's JAX env, [`super::peer`]) the same quantities of the peer measured in the same
//! run, alternating with ours: steps per second at N 64 and 128 and dt 1e-3 (at the thread count
//! of the run, `--threads`; the peer gets the same), and wall time per control
//! action of 10 time units with each solver at its own step (ours the largest within tolerance,
//! the peer's its default 1e-3), each step's accuracy stated against a quarter-step reference.
//!
//! Reports (1) Lawson-RK4 steps per second at N = 64, 128, 256 (dt = 1e-3, Re 40, from a developed
//! state) and the cost of one step's VJP relative to a forward step; (2) accuracy against step
//! size: the relative L2 error of the vorticity after one control action of 10 time units, for
//! steps from 1e-3 up, against a dt = 2.5e-4 reference from the same developed state, and the wall
//! time per control action at the largest step whose error stays below 1e-3 (and below the error
//! the dt = 1e-3 run itself has against the reference, if that is larger).
//! Judged here: a step's VJP costs at most [`VJP_TARGET`] forward steps, and with the peer, our
//! steps/s at N 64 and 128 are at least [`speedup_target`] times its (both in f64).

use std::time::Instant;

use hgym_solvers::spectral::{Complex64 as C, Kolmogorov, KolmogorovConfig};
use serde::{Deserialize, Serialize};

use super::peer::{Pairs, Peer, PeerError};

/// Largest cost of a step's VJP, in forward steps.
pub const VJP_TARGET: f64 = 2.0;

/// Smallest speed-up over the peer per solver step: 3x on 2 or more threads, 1.5x on one.
pub fn speedup_target(threads: usize) -> f64 {
    if threads > 1 {
        3.0
    } else {
        1.5
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SizeRow {
    pub n: usize,
    pub steps_per_s: f64,
    pub vjp_over_step: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AccuracyRow {
    pub dt: f64,
    pub relative_error: f64,
    pub s_per_action: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct KolmogorovBench {
    pub sizes: Vec<SizeRow>,
    pub accuracy: Vec<AccuracyRow>,
    pub tolerance: f64,
    pub chosen_dt: f64,
    pub s_per_action: f64,
    /// The peer measured in the same run (`--peer`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peer: Option<KolmogorovPeer>,
    /// Threads of our side (the peer's are in its description).
    #[serde(default)]
    pub threads: usize,
    pub pass: bool,
}

/// HydroGym's figures beside ours.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct KolmogorovPeer {
    /// The peer's own description (versions, dt, precision, threads).
    pub about: serde_json::Value,
    /// Steps/s at dt 1e-3, and seconds per control action each at its own step.
    pub pairs: Vec<Pairs>,
    /// The peer's step and its relative L2 error after one action against a quarter of it.
    pub dt: f64,
    pub reference_dt: f64,
    pub relative_error: f64,
}

fn solver(n: usize, dt: f64) -> Kolmogorov {
    let cfg = KolmogorovConfig {
        n,
        reynolds: 40.0,
        kf: 4,
        forcing: 1.0,
        dt,
        control_wavenumbers: vec![4, 5, 6, 7],
    };
    // Valid by construction (even n >= 64, k <= 7, positive Re and dt).
    Kolmogorov::new(cfg).unwrap_or_else(|e| panic!("{e}"))
}

/// A developed state: the laminar flow plus a large-scale kick, run for `t` time units at dt 0.01.
fn developed(n: usize, t: f64) -> Vec<C> {
    let mut s = solver(n, 0.01);
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let kick: Vec<f64> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 * h, (i / n) as f64 * h);
            0.5 * (x.cos() + (x + 2.0 * y).sin())
        })
        .collect();
    let lam = s.laminar();
    s.set_vorticity(&kick);
    let w: Vec<C> = s.omega.iter().zip(&lam).map(|(a, b)| *a + *b).collect();
    s.omega = w;
    for _ in 0..(t / 0.01) as usize {
        let _ = s.step(&[0.0; 4]);
    }
    s.omega
}

fn run_to(n: usize, dt: f64, w0: &[C], t: f64) -> (Vec<C>, f64) {
    let mut s = solver(n, dt);
    s.omega = w0.to_vec();
    let steps = (t / dt).round() as usize;
    let start = Instant::now();
    for _ in 0..steps {
        let _ = s.step(&[0.0; 4]);
    }
    (s.omega.clone(), start.elapsed().as_secs_f64())
}

pub fn bench_kolmogorov(quick: bool, peer: Option<&mut Peer>) -> Result<KolmogorovBench, PeerError> {
    let mut sizes = vec![];
    let ns: &[usize] = if quick { &[64] } else { &[64, 128, 256] };
    for &n in ns {
        let w0 = developed(n, if quick { 5.0 } else { 50.0 });
        let mut s = solver(n, 1e-3);
        s.omega = w0.clone();
        let reps = ((if quick { 400 } else { 4000 }) * 64 * 64 / (n * n)).max(20);
        let a = [0.0; 4];
        for _ in 0..10 {
            let _ = s.step(&a);
        }
        let best = |f: &mut dyn FnMut() -> f64| (0..3).map(|_| f()).fold(f64::INFINITY, f64::min);
        let fwd = best(&mut || {
            let t = Instant::now();
            for _ in 0..reps {
                let _ = s.step(&a);
            }
            t.elapsed().as_secs_f64() / reps as f64
        });
        let w = s.omega.clone();
        let mut bar0 = vec![C::default(); w.len()];
        let mut ba = vec![0.0; 4];
        let vjp = best(&mut || {
            let t = Instant::now();
            for _ in 0..reps / 2 {
                let _ = s.step_vjp(&w, &a, &w, &mut bar0, &mut ba);
            }
            t.elapsed().as_secs_f64() / (reps / 2) as f64
        });
        sizes.push(SizeRow {
            n,
            steps_per_s: 1.0 / fwd,
            vjp_over_step: vjp / fwd,
        });
    }
    // Accuracy over one control action of 10 time units at N = 64.
    let action_t = if quick { 1.0 } else { 10.0 };
    let w0 = developed(64, if quick { 5.0 } else { 50.0 });
    let (reference, _) = run_to(64, 2.5e-4, &w0, action_t);
    let norm = reference.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
    let dts: &[f64] = if quick {
        &[1e-3, 0.01]
    } else {
        &[1e-3, 0.005, 0.01, 0.02, 0.025, 0.04]
    };
    let mut accuracy = vec![];
    for &dt in dts {
        let (w, secs) = run_to(64, dt, &w0, action_t);
        let err = w.iter().zip(&reference).map(|(a, b)| (a - b).norm_sqr()).sum::<f64>().sqrt() / norm;
        accuracy.push(AccuracyRow {
            dt,
            relative_error: if err.is_finite() { err } else { f64::INFINITY },
            s_per_action: secs * 10.0 / action_t,
        });
    }
    let tolerance = accuracy.first().map(|a| a.relative_error).unwrap_or(0.0).max(1e-3);
    let chosen = accuracy
        .iter()
        .filter(|a| a.relative_error <= tolerance)
        .max_by(|a, b| a.dt.total_cmp(&b.dt))
        .cloned()
        .unwrap_or(AccuracyRow {
            dt: 1e-3,
            relative_error: f64::NAN,
            s_per_action: f64::NAN,
        });
    let peer = match peer {
        None => None,
        Some(p) => Some(with_peer(p, quick, &w0, chosen.dt)?),
    };
    let threads = rayon::current_num_threads();
    let fast_enough = peer.as_ref().is_none_or(|p| p.fast_enough(threads));
    Ok(KolmogorovBench {
        pass: vjp_within_target(&sizes) && fast_enough,
        threads,
        sizes,
        accuracy,
        tolerance,
        chosen_dt: chosen.dt,
        s_per_action: chosen.s_per_action,
        peer,
    })
}

/// Alternating pairs of one control action (10 time units) by us and by the peer: our steps/s
/// at dt 1e-3 against its steps/s at its dt (1e-3), at N 64 and 128 (64 only with `quick`), and
/// at N 64 our seconds per action at `our_dt` against its at its dt; then the peer's accuracy at
/// its dt.
fn with_peer(p: &mut Peer, quick: bool, w0: &[C], our_dt: f64) -> Result<KolmogorovPeer, PeerError> {
    let runs = if quick { 1 } else { 3 };
    let (mut rates, mut actions) = (vec![], vec![]);
    for _ in 0..runs {
        let (_, at_1e3) = run_to(64, 1e-3, w0, 10.0);
        let (_, at_ours) = run_to(64, our_dt, w0, 10.0);
        let [steps_per_s, s_per_action] = p.numbers("action", ["steps_per_s", "s_per_action"])?;
        rates.push((10.0 / 1e-3 / at_1e3, steps_per_s));
        actions.push((at_ours, s_per_action));
    }
    let mut pairs = vec![Pairs::new("steps/s, N 64, dt 1e-3", "steps/s", &rates, true)];
    if !quick {
        let w128 = developed(128, 50.0);
        let mut rates = vec![];
        for _ in 0..runs {
            let (_, at_1e3) = run_to(128, 1e-3, &w128, 10.0);
            let [steps_per_s] = p.numbers("action 128", ["steps_per_s"])?;
            rates.push((10.0 / 1e-3 / at_1e3, steps_per_s));
        }
        pairs.push(Pairs::new("steps/s, N 128, dt 1e-3", "steps/s", &rates, true));
    }
    pairs.push(Pairs::new("s per action, own dt", "s", &actions, false));
    let [dt, reference_dt, relative_error] = p.numbers("accuracy", ["dt", "reference_dt", "relative_error"])?;
    Ok(KolmogorovPeer {
        about: p.about.clone(),
        pairs,
        dt,
        reference_dt,
        relative_error,
    })
}

/// Whether a step's VJP costs at most [`VJP_TARGET`] forward steps at every size.
fn vjp_within_target(sizes: &[SizeRow]) -> bool {
    sizes.iter().all(|s| s.vjp_over_step <= VJP_TARGET)
}

impl KolmogorovPeer {
    /// Whether our steps/s are at least [`speedup_target`] times the peer's on every grid.
    pub fn fast_enough(&self, threads: usize) -> bool {
        self.pairs
            .iter()
            .filter(|q| q.unit == "steps/s")
            .all(|q| q.median_speedup >= speedup_target(threads))
    }
}

pub fn table(b: &KolmogorovBench) -> String {
    let mut s = String::from(match b.peer {
        None => "Kolmogorov flow, Re 40, Lawson RK4 (no peer measured in this run, so no ratio to HydroGym's JAX env; --peer runs it)\n",
        Some(_) => "Kolmogorov flow, Re 40, Lawson RK4 (the peer's pairs below)\n",
    });
    s += "     N   steps/s (dt 1e-3)   VJP / step\n";
    for r in &b.sizes {
        s += &format!("{:6} {:16.0} {:12.2}\n", r.n, r.steps_per_s, r.vjp_over_step);
    }
    s += "accuracy after one control action (10 time units, N 64) against dt 2.5e-4:\n      dt   rel. L2 error   s per action\n";
    for a in &b.accuracy {
        s += &format!("{:8.4} {:15.2e} {:14.4}\n", a.dt, a.relative_error, a.s_per_action);
    }
    let vjp_ok = vjp_within_target(&b.sizes);
    s += &format!(
        "largest dt within {:.1e}: {} -> {:.4} s per action\nVJP within {VJP_TARGET}x a step: {}\n",
        b.tolerance,
        b.chosen_dt,
        b.s_per_action,
        if vjp_ok { "PASS" } else { "SHORT of target" }
    );
    if let Some(p) = &b.peer {
        let ours_err = b
            .accuracy
            .iter()
            .find(|a| a.dt == b.chosen_dt)
            .map_or(f64::NAN, |a| a.relative_error);
        s += &format!("against {} (same run, alternating pairs):\n", super::peer::describe(&p.about));
        for pair in &p.pairs {
            s += &format!("  {}\n", pair.line("HydroGym"));
        }
        s += &format!(
            "  steps per action: hgym dt {} (error {:.1e} against dt 2.5e-4), HydroGym dt {} (error {:.1e} against dt {})\n",
            b.chosen_dt, ours_err, p.dt, p.relative_error, p.reference_dt
        );
        s += &format!(
            "steps/s at least {}x HydroGym's with {} thread(s), every N: {}\n",
            speedup_target(b.threads),
            b.threads,
            if p.fast_enough(b.threads) { "PASS" } else { "SHORT of target" }
        );
    }
    s
}
