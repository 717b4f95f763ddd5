//! `hgym bench kolmogorov`: the spectral solver's speed and accuracy. Ratios to HydroGym's JAX
//! env need that peer measured in the same run, which is not built yet.
//!
//! Reports (1) Lawson-RK4 steps per second at N = 64, 128, 256 (dt = 1e-3, Re 40, from a developed
//! state) and the cost of one step's VJP relative to a forward step; (2) accuracy against step
//! size: the relative L2 error of the vorticity after one control action of 10 time units, for
//! steps from 1e-3 up, against a dt = 2.5e-4 reference from the same developed state, and the wall
//! time per control action at the largest step whose error stays below 1e-3 (and below the error
//! the dt = 1e-3 run itself has against the reference, if that is larger).
//! Judged here: a step's VJP costs at most 3 forward steps.

use std::time::Instant;

use hgym_solvers::spectral::{Complex64 as C, Kolmogorov, KolmogorovConfig};
use serde::{Deserialize, Serialize};

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
    pub pass: bool,
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

pub fn bench_kolmogorov(quick: bool) -> KolmogorovBench {
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
    // Ratios to HydroGym's JAX env need that peer measured in the same run (not built yet): only
    // the peer-free target is judged here.
    KolmogorovBench {
        pass: sizes.iter().all(|s| s.vjp_over_step <= 3.0),
        sizes,
        accuracy,
        tolerance,
        chosen_dt: chosen.dt,
        s_per_action: chosen.s_per_action,
    }
}

pub fn table(b: &KolmogorovBench) -> String {
    let mut s = String::from("Kolmogorov flow, Re 40, Lawson RK4 (no peer measured in this run, so no ratio to HydroGym's JAX env)\n");
    s += "     N   steps/s (dt 1e-3)   VJP / step\n";
    for r in &b.sizes {
        s += &format!("{:6} {:16.0} {:12.2}\n", r.n, r.steps_per_s, r.vjp_over_step);
    }
    s += "accuracy after one control action (10 time units, N 64) against dt 2.5e-4:\n      dt   rel. L2 error   s per action\n";
    for a in &b.accuracy {
        s += &format!("{:8.4} {:15.2e} {:14.4}\n", a.dt, a.relative_error, a.s_per_action);
    }
    s += &format!(
        "largest dt within {:.1e}: {} -> {:.4} s per action\nVJP within 3x a step: {}\n",
        b.tolerance,
        b.chosen_dt,
        b.s_per_action,
        if b.pass { "PASS" } else { "SHORT of target" }
    );
    s
}
