use hgym_solvers::spectral::{Complex64 as C, Kolmogorov, KolmogorovConfig};
fn main() {
    for n in [64usize, 128, 256] {
        let mut s = Kolmogorov::new(KolmogorovConfig {
            n,
            reynolds: 40.0,
            kf: 4,
            forcing: 1.0,
            dt: 1e-3,
            control_wavenumbers: vec![4, 5, 6, 7],
        })
        .unwrap();
        s.omega = s.laminar();
        let a = [0.0; 4];
        for _ in 0..20 {
            s.step(&a).unwrap();
        }
        let reps = 2000 * 64 * 64 / (n * n);
        let t = std::time::Instant::now();
        for _ in 0..reps {
            s.step(&a).unwrap();
        }
        let fwd = t.elapsed().as_secs_f64() / reps as f64;
        let w0 = s.omega.clone();
        let bar1 = w0.clone();
        let mut bar0 = vec![C::default(); w0.len()];
        let mut ba = vec![0.0; 4];
        let t = std::time::Instant::now();
        for _ in 0..reps / 2 {
            s.step_vjp(&w0, &a, &bar1, &mut bar0, &mut ba).unwrap();
        }
        let vjp = t.elapsed().as_secs_f64() / (reps / 2) as f64;
        println!("n {n}: {:.0} steps/s ({:.1} us), vjp {:.2}x", 1.0 / fwd, fwd * 1e6, vjp / fwd);
    }
}
