//! Kolmogorov-flow solver: exact solutions, convergence orders, and the discrete adjoint
//! against central finite differences.

use hgym_solvers::spectral::fft2::inner;
use hgym_solvers::spectral::{Complex64 as C, Kolmogorov, KolmogorovConfig};

fn cfg(n: usize, re: f64, dt: f64) -> KolmogorovConfig {
    KolmogorovConfig {
        n,
        reynolds: re,
        kf: 4,
        forcing: 1.0,
        dt,
        control_wavenumbers: vec![4, 5, 6, 7],
    }
}

/// A smooth, non-band-limited field on an `n`-grid: `exp(sin x + 0.5 cos 2y) - 0.7 sin(x + y)`.
fn smooth(n: usize, phase: f64) -> Vec<f64> {
    let h = 2.0 * std::f64::consts::PI / n as f64;
    (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 * h, (i / n) as f64 * h);
            (x.sin() + 0.5 * (2.0 * y + phase).cos()).exp() - 0.7 * (x + y).sin() - 1.2
        })
        .collect()
}

/// Deterministic pseudo-random numbers (SplitMix64).
fn noise(len: usize, seed: u64) -> Vec<f64> {
    let mut z = seed;
    (0..len)
        .map(|_| {
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut x = z;
            x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect()
}

/// Laminar Kolmogorov flow: u = (Re/k_f^2) sin(k_f y) solves the steady equations because the
/// advection term vanishes (omega depends on y only, v = 0) and nu k_f^2 u = sin(k_f y). Its
/// dissipation is nu <|grad u|^2> = nu (Re/k_f)^2 / 2 = Re / (2 k_f^2) = 1.25 at Re 40, k_f 4.
#[test]
fn laminar_kolmogorov_is_steady_with_dissipation_re_over_2kf2() {
    let mut s = Kolmogorov::new(cfg(64, 40.0, 0.01)).unwrap();
    s.omega = s.laminar();
    let d0 = s.dissipation();
    println!("laminar dissipation {d0:.15} (exact 1.25)");
    assert!((d0 - 1.25).abs() < 1e-12);
    let start = s.omega.clone();
    for _ in 0..1000 {
        s.step(&[0.0; 4]).unwrap();
    }
    let drift =
        s.omega.iter().zip(&start).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max) / start.iter().map(|c| c.norm()).fold(0.0, f64::max);
    println!(
        "relative drift of the laminar state over 1000 steps: {drift:.2e}; dissipation {:.15}",
        s.dissipation()
    );
    // Lawson RK4 integrates the constant forcing with Simpson's rule: O((nu k_f^2 dt)^4) per step.
    assert!(drift < 1e-9, "drift {drift}");
    assert!((s.dissipation() - 1.25).abs() < 1e-9);
}

/// Taylor-Green vortex omega = 2 cos x cos y: advection vanishes identically, the viscous decay
/// exp(-2 nu t) is integrated exactly by the integrating factor, so only round-off remains.
#[test]
fn taylor_green_decays_exactly() {
    let mut c = cfg(32, 50.0, 0.05);
    c.forcing = 0.0;
    let mut s = Kolmogorov::new(c).unwrap();
    let n = 32;
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let tg: Vec<f64> = (0..n * n)
        .map(|i| 2.0 * ((i % n) as f64 * h).cos() * ((i / n) as f64 * h).cos())
        .collect();
    s.set_vorticity(&tg);
    for _ in 0..200 {
        s.step(&[0.0; 4]).unwrap();
    }
    let decay = (-2.0 * s.nu() * s.time()).exp();
    let w = s.vorticity();
    let err = w.iter().zip(&tg).map(|(a, b)| (a - b * decay).abs()).fold(0.0, f64::max);
    println!(
        "Taylor-Green after t = {}: max error {err:.2e} (amplitude {:.4})",
        s.time(),
        2.0 * decay
    );
    assert!(err < 1e-13, "error {err}");
}

/// Fourth order in time on a nonlinear, forced flow: errors at t = 1 against a dt/16 reference.
#[test]
fn lawson_rk4_is_fourth_order_in_time() {
    let run = |dt: f64| {
        let mut s = Kolmogorov::new(cfg(32, 40.0, dt)).unwrap();
        let w0: Vec<f64> = smooth(32, 0.3).iter().map(|v| 3.0 * v).collect();
        s.set_vorticity(&w0);
        let steps = (1.0 / dt).round() as usize;
        for _ in 0..steps {
            s.step(&[0.3, -0.2, 0.1, 0.05]).unwrap();
        }
        s.vorticity()
    };
    let reference = run(0.1 / 64.0);
    let mut errs = vec![];
    for dt in [0.1 / 2.0, 0.1 / 4.0, 0.1 / 8.0] {
        let w = run(dt);
        errs.push(w.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max));
    }
    let orders: Vec<f64> = errs.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
    println!("time errors {errs:?}, orders {orders:.2?}");
    assert!(orders.iter().all(|p| *p > 3.7 && *p < 4.5), "orders {orders:?}");
}

/// Spectral accuracy in space: a smooth flow at n = 16, 24, 32 against n = 96, compared on the
/// points the grids share after t = 0.5; the error falls faster than any power of n.
#[test]
fn spatial_convergence_is_spectral() {
    let run = |n: usize| {
        let mut c = cfg(n, 20.0, 0.005);
        c.kf = 2;
        c.control_wavenumbers.clear();
        let mut s = Kolmogorov::new(c).unwrap();
        s.set_vorticity(&smooth(n, 0.0));
        for _ in 0..100 {
            s.step(&[]).unwrap();
        }
        s.vorticity()
    };
    let nref = 96;
    let reference = run(nref);
    let mut errs = vec![];
    for n in [12, 24, 48] {
        let w = run(n);
        let r = nref / n;
        let e = (0..n * n)
            .map(|i| (w[i] - reference[(i / n) * r * nref + (i % n) * r]).abs())
            .fold(0.0, f64::max);
        errs.push(e);
    }
    println!("spatial errors at n = 12, 24, 48: {errs:?}");
    // Algebraic order p would give ratios 2^p; spectral convergence gives growing ratios.
    assert!(errs[0] / errs[1] > 30.0 && errs[1] / errs[2] > errs[0] / errs[1], "{errs:?}");
    assert!(errs[2] < 1e-6 * errs[0], "{errs:?}");
}

/// The scalar whose gradient the adjoint tests check: dissipation + TKE + a random linear
/// functional of the final state.
fn objective(s: &Kolmogorov, w: &[C], g: &[C]) -> f64 {
    s.dissipation_of(w) + s.tke_of(w) + inner(g, w, s.n())
}

fn adjoint_check(steps: usize) {
    let n = 32;
    let mut s = Kolmogorov::new(cfg(n, 40.0, 0.01)).unwrap();
    // A developed-looking state: laminar plus a smooth perturbation.
    let lam = s.laminar();
    s.set_vorticity(&smooth(n, 1.1));
    let w0: Vec<C> = s.omega.iter().zip(&lam).map(|(a, b)| *a + *b).collect();
    let a0 = [0.2, -0.1, 0.15, 0.05];
    let mut g = vec![C::default(); s.spectral_len()];
    s.set_vorticity(&noise(n * n, 3));
    g.copy_from_slice(&s.omega);
    // Direction of the perturbation: random, dealiased, and random controls.
    s.set_vorticity(&noise(n * n, 7));
    let dw = s.omega.clone();
    let da: Vec<f64> = noise(4, 11);

    let forward = |s: &mut Kolmogorov, w0: &[C], a: &[f64]| -> (Vec<Vec<C>>, f64) {
        let mut traj = vec![w0.to_vec()];
        let mut w1 = vec![C::default(); s.spectral_len()];
        for _ in 0..steps {
            let last = traj.last().unwrap().clone();
            s.step_from(&last, a, &mut w1).unwrap();
            traj.push(w1.clone());
        }
        let j = objective(s, traj.last().unwrap(), &g);
        (traj, j)
    };
    let (traj, _) = forward(&mut s, &w0, &a0);
    // Backward sweep.
    let wt = traj.last().unwrap();
    let mut bar = g.clone();
    s.add_dissipation_gradient(wt, 1.0, &mut bar);
    s.add_tke_gradient(wt, 1.0, &mut bar);
    let mut bar_a = vec![0.0; 4];
    let mut bar0 = vec![C::default(); s.spectral_len()];
    for k in (0..steps).rev() {
        s.step_vjp(&traj[k], &a0, &bar, &mut bar0, &mut bar_a).unwrap();
        std::mem::swap(&mut bar, &mut bar0);
    }
    let adjoint = inner(&bar, &dw, n) + bar_a.iter().zip(&da).map(|(x, y)| x * y).sum::<f64>();
    // Central differences along (dw, da).
    let eps = 1e-4 * (1.0 / inner(&dw, &dw, n).sqrt());
    let shifted = |sign: f64, s: &mut Kolmogorov| {
        let w: Vec<C> = w0.iter().zip(&dw).map(|(a, d)| *a + *d * (sign * eps)).collect();
        let a: Vec<f64> = a0.iter().zip(&da).map(|(a, d)| a + sign * eps * d).collect();
        forward(s, &w, &a).1
    };
    let fd = (shifted(1.0, &mut s) - shifted(-1.0, &mut s)) / (2.0 * eps);
    let rel = (adjoint - fd).abs() / fd.abs();
    println!("{steps} step(s): adjoint {adjoint:.12e}, central difference {fd:.12e}, relative error {rel:.2e}");
    assert!(rel < 1e-6, "relative error {rel}");
}

#[test]
fn adjoint_of_one_step_matches_finite_differences() {
    adjoint_check(1);
}

#[test]
fn adjoint_of_100_steps_matches_finite_differences() {
    adjoint_check(100);
}

/// Steps and a VJP on a grid large enough for the transforms to run on two threads give the same
/// bits as on one.
#[test]
fn bitwise_identical_across_thread_counts() {
    let n = 256;
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut s = Kolmogorov::new(cfg(n, 40.0, 0.01)).unwrap();
            let lam = s.laminar();
            s.set_vorticity(&smooth(n, 0.3));
            s.omega.iter_mut().zip(&lam).for_each(|(w, l)| *w += *l);
            let a = [0.1, -0.2, 0.05, 0.0];
            for _ in 0..3 {
                s.step(&a).unwrap();
            }
            let (w, bar1) = (s.omega.clone(), s.omega.clone());
            let (mut bar0, mut bar_a) = (vec![C::default(); w.len()], vec![0.0; 4]);
            s.step_vjp(&w, &a, &bar1, &mut bar0, &mut bar_a).unwrap();
            (w, bar0, bar_a)
        })
    };
    let bits = |r: (Vec<C>, Vec<C>, Vec<f64>)| -> Vec<u64> {
        let c = r.0.iter().chain(&r.1).flat_map(|c| [c.re.to_bits(), c.im.to_bits()]);
        c.chain(r.2.iter().map(|x| x.to_bits())).collect()
    };
    assert_eq!(bits(run(1)), bits(run(2)), "results depend on the thread count");
}
