//! Two-dimensional incompressible Navier-Stokes in vorticity form on the doubly periodic square
//! `(0, 2 pi)^2`,
//!
//! `d omega/dt + u . grad omega = nu lap omega + curl f`,  `omega = -lap psi`,  `u = (psi_y, -psi_x)`,
//!
//! with Kolmogorov forcing `f = sin(k_f y) e_x` (curl: `-k_f cos(k_f y)`), `nu = 1 / Re`, plus
//! control forcing `sum_i a_i sin(k_i y) e_x`. Pseudo-spectral with Orszag's 2/3 rule (modes with
//! `|k_x|` or `|k_y|` above `(n - 1) / 3` are zero, which also removes the Nyquist modes).
//!
//! Time stepping: integrating-factor ("Lawson") fourth-order Runge-Kutta. The viscous term is
//! integrated exactly by `E(h) = exp(-nu k^2 h)`, so the stable step is set by advection alone
//! (`|u| k_max h < ~2.8`), not by viscosity; the scheme is explicit, so its discrete adjoint is a
//! short, exact reverse sweep (no linear solves), which is why it was chosen over an IMEX
//! Crank-Nicolson scheme. Order 4 in time for the nonlinear dynamics (tested).
//!
//! Adjoint convention: every field, including a cotangent, is a real physical field, stored as
//! its half spectrum; the inner product is `sum_x f(x) g(x)`. The adjoint of a Fourier multiplier
//! with symbol `d(k)` is then the multiplier `conj(d(k))`, the adjoint of a pointwise product is
//! itself, so [`Kolmogorov::step_vjp`] mirrors [`Kolmogorov::step`] line by line (the nonlinear
//! term's adjoint folded into two products by `div u = 0`).

use realfft::num_complex::Complex64 as C;
use thiserror::Error;

use super::fft2::{inner, ky_of, Fft2};

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SpectralError {
    #[error("grid size {0} must be even and at least 8")]
    Grid(usize),
    #[error("Reynolds number {0} must be positive and finite")]
    Reynolds(f64),
    #[error("time step {0} must be positive and finite")]
    TimeStep(f64),
    #[error("forcing wavenumber {k} is not resolved on a {n}-point grid (at most {max} after dealiasing)")]
    Wavenumber { k: u32, n: usize, max: usize },
    #[error("{got} control amplitudes given, the solver has {expected} control wavenumbers")]
    Controls { expected: usize, got: usize },
    #[error("the flow diverged at step {step}: {reason}; reduce the time step (advective CFL {cfl:.2} > 2.8 for RK4) or the forcing")]
    Diverged { step: u64, reason: String, cfl: f64 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct KolmogorovConfig {
    pub n: usize,
    pub reynolds: f64,
    pub kf: u32,
    /// Amplitude `A` of the base forcing `A sin(k_f y) e_x` (1 in the paper; 0 for decay tests).
    pub forcing: f64,
    pub dt: f64,
    /// Wavenumbers of the control forcing `a_i sin(k_i y) e_x`.
    pub control_wavenumbers: Vec<u32>,
}

/// The physical fields of one right-hand-side evaluation (kept for the adjoint).
#[derive(Clone, Debug, Default)]
struct Fields {
    u: Vec<f64>,
    v: Vec<f64>,
    wx: Vec<f64>,
    wy: Vec<f64>,
}

/// Smallest grid whose transforms [`join`] runs on two threads.
const PARALLEL_MIN_N: usize = 256;

/// `rayon::join(a, b)` on grids of at least [`PARALLEL_MIN_N`] points a side in a pool of more
/// than one thread, else `a` then `b` on the calling thread: a join from outside the pool moves
/// both halves to a worker and back, which costs more than the two halves save on smaller grids
/// (`hgym bench kolmogorov --threads 1` is faster than `--threads 2` there). Either way each half
/// runs the same code on its own buffers, so the results are bitwise the same.
fn join(n: usize, a: impl FnOnce() + Send, b: impl FnOnce() + Send) {
    if n < PARALLEL_MIN_N || rayon::current_num_threads() == 1 {
        a();
        b();
    } else {
        rayon::join(a, b);
    }
}

impl Fields {
    fn new(m: usize) -> Self {
        Fields {
            u: vec![0.0; m],
            v: vec![0.0; m],
            wx: vec![0.0; m],
            wy: vec![0.0; m],
        }
    }
}

/// Reused work arrays: nothing is allocated by a step.
struct Work {
    spec: [Vec<C>; 4],
    k: [Vec<C>; 4],
    s: Vec<C>,
    forcing: Vec<C>,
    stage: [Fields; 4],
    bar: [Vec<C>; 5],
    fbar: Vec<C>,
    /// `grad mu` of a VJP's cotangent, physical.
    mu: [Vec<f64>; 2],
}

pub struct Kolmogorov {
    cfg: KolmogorovConfig,
    nu: f64,
    n: usize,
    len: usize,
    /// Coefficients of the dealiased columns `k_x <= k_max` (the rest are zero throughout).
    act: usize,
    fft: Fft2,
    /// A second transform with its own scratch, so independent transforms run on two threads.
    fft_b: Fft2,
    kx: Vec<f64>,
    ky: Vec<f64>,
    inv_k2: Vec<f64>,
    mask: Vec<f64>,
    e_half: Vec<f64>,
    e_full: Vec<f64>,
    /// Base forcing (curl of `sin(k_f y) e_x`) and one spectrum per control wavenumber.
    base: Vec<C>,
    controls: Vec<Vec<C>>,
    /// The state: vorticity half spectrum (dealiased).
    pub omega: Vec<C>,
    steps: u64,
    w: Work,
}

impl Kolmogorov {
    pub fn new(cfg: KolmogorovConfig) -> Result<Self, SpectralError> {
        let n = cfg.n;
        if n < 8 || !n.is_multiple_of(2) {
            return Err(SpectralError::Grid(n));
        }
        if !(cfg.reynolds > 0.0 && cfg.reynolds.is_finite()) {
            return Err(SpectralError::Reynolds(cfg.reynolds));
        }
        if !(cfg.dt > 0.0 && cfg.dt.is_finite()) {
            return Err(SpectralError::TimeStep(cfg.dt));
        }
        let kmax = (n - 1) / 3;
        for &k in std::iter::once(&cfg.kf).chain(&cfg.control_wavenumbers) {
            if k == 0 || k as usize > kmax {
                return Err(SpectralError::Wavenumber { k, n, max: kmax });
            }
        }
        let nh = n / 2 + 1;
        let len = nh * n;
        let nu = 1.0 / cfg.reynolds;
        let (mut kx, mut ky, mut inv_k2, mut mask) = (vec![0.0; len], vec![0.0; len], vec![0.0; len], vec![0.0; len]);
        for ix in 0..nh {
            for iy in 0..n {
                let i = ix * n + iy;
                let (a, b) = (ix as f64, ky_of(iy, n) as f64);
                kx[i] = a;
                ky[i] = b;
                let k2 = a * a + b * b;
                inv_k2[i] = if k2 > 0.0 { 1.0 / k2 } else { 0.0 };
                mask[i] = if ix <= kmax && ky_of(iy, n).unsigned_abs() as usize <= kmax {
                    1.0
                } else {
                    0.0
                };
            }
        }
        let k2 = |i: usize| kx[i] * kx[i] + ky[i] * ky[i];
        let e_half: Vec<f64> = (0..len).map(|i| (-nu * k2(i) * cfg.dt / 2.0).exp()).collect();
        let e_full: Vec<f64> = (0..len).map(|i| (-nu * k2(i) * cfg.dt).exp()).collect();
        // curl of sin(k y) e_x is -k cos(k y): half spectrum -k n^2 / 2 at (0, +-k).
        let shear = |k: u32| {
            let mut f = vec![C::default(); len];
            let amp = -(k as f64) * (n * n) as f64 / 2.0;
            f[k as usize].re = amp;
            f[n - k as usize].re = amp;
            f
        };
        let mut base = shear(cfg.kf);
        base.iter_mut().for_each(|c| *c *= cfg.forcing);
        let controls = cfg.control_wavenumbers.iter().map(|&k| shear(k)).collect();
        let m = n * n;
        let z = || vec![C::default(); len];
        Ok(Kolmogorov {
            fft: Fft2::new(n, kmax + 1),
            fft_b: Fft2::new(n, kmax + 1),
            nu,
            n,
            len,
            act: (kmax + 1) * n,
            kx,
            ky,
            inv_k2,
            mask,
            e_half,
            e_full,
            base,
            controls,
            omega: z(),
            steps: 0,
            w: Work {
                spec: [z(), z(), z(), z()],
                k: [z(), z(), z(), z()],
                s: z(),
                forcing: z(),
                stage: [Fields::new(m), Fields::new(m), Fields::new(m), Fields::new(m)],
                bar: [z(), z(), z(), z(), z()],
                fbar: z(),
                mu: [vec![0.0; m], vec![0.0; m]],
            },
            cfg,
        })
    }

    pub fn config(&self) -> &KolmogorovConfig {
        &self.cfg
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn nu(&self) -> f64 {
        self.nu
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn time(&self) -> f64 {
        self.steps as f64 * self.cfg.dt
    }

    /// Length of a half spectrum.
    pub fn spectral_len(&self) -> usize {
        self.len
    }

    /// The laminar state `omega = -(A Re / k_f) cos(k_f y)` (velocity `(A Re / k_f^2) sin(k_f y)`).
    pub fn laminar(&self) -> Vec<C> {
        let mut w = vec![C::default(); self.len];
        let (n, k) = (self.n, self.cfg.kf as usize);
        let amp = -(self.cfg.forcing * self.cfg.reynolds / self.cfg.kf as f64) * (n * n) as f64 / 2.0;
        w[k].re = amp;
        w[n - k].re = amp;
        w
    }

    /// Sets the state from a physical vorticity field (row-major `n x n`), projected onto the
    /// dealiased modes.
    pub fn set_vorticity(&mut self, phys: &[f64]) {
        let mut w = std::mem::take(&mut self.omega);
        self.fft.forward(phys, &mut w);
        w.iter_mut().zip(&self.mask).for_each(|(c, m)| *c *= *m);
        self.omega = w;
    }

    /// The physical vorticity field.
    pub fn vorticity(&mut self) -> Vec<f64> {
        let mut out = vec![0.0; self.n * self.n];
        self.fft.inverse(&self.omega, &mut out);
        out
    }

    /// Physical velocity fields `(u, v)` of the current state.
    pub fn velocity(&mut self) -> (Vec<f64>, Vec<f64>) {
        let m = self.n * self.n;
        let (mut u, mut v) = (vec![0.0; m], vec![0.0; m]);
        self.velocity_into(&mut u, &mut v);
        (u, v)
    }

    /// [`Kolmogorov::velocity`] into `u` and `v` (`n * n` each) from the stream function,
    /// `u_hat = i k_y omega_hat / k^2`, `v_hat = -i k_x omega_hat / k^2`; allocates nothing.
    pub fn velocity_into(&mut self, u: &mut [f64], v: &mut [f64]) {
        let s = &mut self.w.spec[0];
        for i in 0..self.len {
            s[i] = self.omega[i] * C::new(0.0, self.ky[i] * self.inv_k2[i]);
        }
        self.fft.inverse(s, u);
        for i in 0..self.len {
            s[i] = self.omega[i] * C::new(0.0, -self.kx[i] * self.inv_k2[i]);
        }
        self.fft.inverse(s, v);
    }

    /// Energy dissipation rate per unit area, `epsilon = 2 nu <S_ij S_ij> = nu <omega^2>` (equal on a
    /// periodic domain).
    pub fn dissipation_of(&self, w: &[C]) -> f64 {
        self.nu * inner(w, w, self.n) / (self.n * self.n) as f64
    }

    pub fn dissipation(&self) -> f64 {
        self.dissipation_of(&self.omega)
    }

    /// Gradient of [`Kolmogorov::dissipation_of`] (half spectrum of the physical gradient),
    /// `2 nu omega / n^2`, scaled by `scale` and added to `out`.
    pub fn add_dissipation_gradient(&self, w: &[C], scale: f64, out: &mut [C]) {
        let c = scale * 2.0 * self.nu / (self.n * self.n) as f64;
        out.iter_mut().zip(w).for_each(|(o, w)| *o += *w * c);
    }

    /// Turbulent kinetic energy per unit area, `<|u - U(y)|^2> / 2` with `U(y)` the x-average
    /// (the modes with `k_x != 0`): `sum_{k_x != 0} |omega_k|^2 / k^2` by Parseval.
    pub fn tke_of(&self, w: &[C]) -> f64 {
        let n = self.n;
        let mut s = 0.0;
        for kx in 1..=n / 2 {
            let wt = if kx == n / 2 { 1.0 } else { 2.0 };
            for i in kx * n..(kx + 1) * n {
                s += wt * w[i].norm_sqr() * self.inv_k2[i];
            }
        }
        0.5 * s / (n * n) as f64 / (n * n) as f64
    }

    pub fn tke(&self) -> f64 {
        self.tke_of(&self.omega)
    }

    /// Gradient of [`Kolmogorov::tke_of`]: `omega / (n^2 k^2)` on `k_x != 0`, scaled, added to `out`.
    pub fn add_tke_gradient(&self, w: &[C], scale: f64, out: &mut [C]) {
        let n = self.n;
        let c = scale / (n * n) as f64;
        for i in n..self.len {
            out[i] += w[i] * (c * self.inv_k2[i]);
        }
    }

    /// Largest advective CFL number `max(|u| + |v|) k_max dt` of the state `w` (uses stage 0's
    /// work arrays).
    pub fn cfl(&mut self) -> f64 {
        let w = self.omega.clone();
        self.fields(&w, 0);
        let f = &self.w.stage[0];
        let umax = f.u.iter().zip(&f.v).map(|(u, v)| u.abs() + v.abs()).fold(0.0, f64::max);
        umax * ((self.n - 1) / 3) as f64 * self.cfg.dt
    }

    /// `u, v, omega_x, omega_y` of `w` into stage slot `slot`.
    fn fields(&mut self, w: &[C], slot: usize) {
        let [s0, s1, s2, s3] = &mut self.w.spec;
        for i in 0..self.act {
            let (kx, ky, ik2) = (self.kx[i], self.ky[i], self.inv_k2[i]);
            // i a w for real a, written out (multiplying by C::new(0, a) wastes two products).
            let iw = C::new(-w[i].im, w[i].re);
            s0[i] = iw * (ky * ik2);
            s1[i] = iw * (-kx * ik2);
            s2[i] = iw * kx;
            s3[i] = iw * ky;
        }
        let Fields { u, v, wx, wy } = &mut self.w.stage[slot];
        let (fa, fb) = (&mut self.fft, &mut self.fft_b);
        // Two independent pairs of transforms, one per thread (each transform is computed the
        // same way on either, so results do not depend on the thread count).
        join(
            self.n,
            || {
                fa.inverse_destroying(s0, u);
                fa.inverse_destroying(s1, v);
            },
            || {
                fb.inverse_destroying(s2, wx);
                fb.inverse_destroying(s3, wy);
            },
        );
    }

    /// `out = -P FFT(u omega_x + v omega_y) + forcing` at `w`, keeping the fields in `slot`.
    fn rhs(&mut self, w: &[C], slot: usize, out_slot: usize) {
        self.fields(w, slot);
        let f = &self.w.stage[slot];
        let out = &mut self.w.k[out_slot];
        let n = self.n;
        self.fft.forward_rows(
            |y, row| {
                let r = y * n..(y + 1) * n;
                let (u, v, wx, wy) = (&f.u[r.clone()], &f.v[r.clone()], &f.wx[r.clone()], &f.wy[r]);
                for ((((p, u), v), wx), wy) in row.iter_mut().zip(u).zip(v).zip(wx).zip(wy) {
                    *p = u * wx + v * wy;
                }
            },
            out,
        );
        for ((o, m), fc) in out[..self.act].iter_mut().zip(&self.mask).zip(&self.w.forcing) {
            *o = -*o * *m + *fc;
        }
    }

    fn set_forcing(&mut self, a: &[f64]) -> Result<(), SpectralError> {
        if a.len() != self.controls.len() {
            return Err(SpectralError::Controls {
                expected: self.controls.len(),
                got: a.len(),
            });
        }
        self.w.forcing.copy_from_slice(&self.base);
        for (ai, phi) in a.iter().zip(&self.controls) {
            for (f, p) in self.w.forcing.iter_mut().zip(phi) {
                *f += *p * *ai;
            }
        }
        Ok(())
    }

    /// The four stages of Lawson RK4 from `w0` into `w1`; stage fields stay in the work arrays.
    /// Without `w1` (a VJP's recomputation, which needs only the stage fields) the last stage's
    /// transform back to spectral space and the update are skipped.
    fn stages(&mut self, w0: &[C], w1: Option<&mut [C]>) {
        let h = self.cfg.dt;
        self.rhs(w0, 0, 0);
        let mut s = std::mem::take(&mut self.w.s);
        let a = self.act;
        for i in 0..a {
            s[i] = self.e_half[i] * (w0[i] + self.w.k[0][i] * (h / 2.0));
        }
        self.rhs(&s, 1, 1);
        for i in 0..a {
            s[i] = self.e_half[i] * w0[i] + self.w.k[1][i] * (h / 2.0);
        }
        self.rhs(&s, 2, 2);
        for i in 0..a {
            s[i] = self.e_full[i] * w0[i] + self.e_half[i] * self.w.k[2][i] * h;
        }
        let Some(w1) = w1 else {
            self.fields(&s, 3);
            self.w.s = s;
            return;
        };
        self.rhs(&s, 3, 3);
        self.w.s = s;
        let k = &self.w.k;
        w1[a..].iter_mut().for_each(|c| *c = C::default());
        for i in 0..a {
            let (e, e2) = (self.e_full[i], self.e_half[i]);
            w1[i] = e * w0[i] + (e * k[0][i] + (k[1][i] + k[2][i]) * (2.0 * e2) + k[3][i]) * (h / 6.0);
        }
    }

    /// One step with control amplitudes `a` (one per control wavenumber).
    pub fn step(&mut self, a: &[f64]) -> Result<(), SpectralError> {
        self.set_forcing(a)?;
        let w0 = std::mem::take(&mut self.omega);
        let mut w1 = std::mem::take(&mut self.w.bar[0]);
        self.stages(&w0, Some(&mut w1));
        self.w.bar[0] = w0;
        self.omega = w1;
        self.steps += 1;
        if !self.omega.iter().all(|c| c.re.is_finite() && c.im.is_finite()) {
            let f = &self.w.stage[0];
            let umax = f.u.iter().zip(&f.v).map(|(u, v)| u.abs() + v.abs()).fold(0.0, f64::max);
            return Err(SpectralError::Diverged {
                step: self.steps,
                reason: "non-finite vorticity".into(),
                cfl: umax * ((self.n - 1) / 3) as f64 * self.cfg.dt,
            });
        }
        Ok(())
    }

    /// `out = J(w)^T lambda` for the nonlinear term `-P F(u omega_x + v omega_y)` at the stage
    /// whose fields sit in `slot`. Its conjugate symbols give, with `mu = P lambda`,
    /// `i [k_y/k^2 F(omega_x mu) - k_x/k^2 F(omega_y mu) + k_x F(u mu) + k_y F(v mu)]`; since
    /// `i k F(f) = F(grad f)` and `div u = 0`, the pairs fold into
    ///
    /// `out = F(omega_x mu_y - omega_y mu_x) / k^2 + F(u mu_x + v mu_y)`,
    ///
    /// two inverse and two forward transforms instead of one and four. The folding is exact on
    /// the dealiased modes: every field here is band-limited to `k_max` (the solver's states are),
    /// so the products' spectra up to `k_max` carry no aliases.
    fn nonlinear_vjp(&mut self, slot: usize, lambda: &[C], out: &mut [C]) {
        let [s0, s1, s2, s3] = &mut self.w.spec;
        for i in 0..self.act {
            let l = lambda[i] * self.mask[i];
            let il = C::new(-l.im, l.re);
            s0[i] = il * self.kx[i];
            s1[i] = il * self.ky[i];
        }
        let f = &self.w.stage[slot];
        let [mu_x, mu_y] = &mut self.w.mu;
        let (fa, fb) = (&mut self.fft, &mut self.fft_b);
        join(self.n, || fa.inverse_destroying(s0, mu_x), || fb.inverse_destroying(s1, mu_y));
        let (mu_x, mu_y, n) = (&*mu_x, &*mu_y, self.n);
        let rows = move |y: usize| y * n..(y + 1) * n;
        join(
            self.n,
            || {
                fa.forward_rows(
                    |y, row| {
                        let (wx, wy, mx, my) = (&f.wx[rows(y)], &f.wy[rows(y)], &mu_x[rows(y)], &mu_y[rows(y)]);
                        for ((((p, wx), wy), mx), my) in row.iter_mut().zip(wx).zip(wy).zip(mx).zip(my) {
                            *p = wx * my - wy * mx;
                        }
                    },
                    s2,
                )
            },
            || {
                fb.forward_rows(
                    |y, row| {
                        let (u, v, mx, my) = (&f.u[rows(y)], &f.v[rows(y)], &mu_x[rows(y)], &mu_y[rows(y)]);
                        for ((((p, u), v), mx), my) in row.iter_mut().zip(u).zip(v).zip(mx).zip(my) {
                            *p = u * mx + v * my;
                        }
                    },
                    s3,
                )
            },
        );
        for i in 0..self.act {
            out[i] = s2[i] * self.inv_k2[i] + s3[i];
        }
        out[self.act..].iter_mut().for_each(|c| *c = C::default());
    }

    /// Vector-Jacobian product of one step from `w0` with controls `a`: given the cotangent
    /// `bar1` of the new state, returns the cotangent of `w0` (projected on the dealiased modes)
    /// and adds the cotangent of the controls to `bar_a`. The forward stages are recomputed
    /// from `w0` (the solver's own state is not touched).
    pub fn step_vjp(&mut self, w0: &[C], a: &[f64], bar1: &[C], bar0: &mut [C], bar_a: &mut [f64]) -> Result<(), SpectralError> {
        self.set_forcing(a)?;
        self.stages(w0, None);
        let (h, act) = (self.cfg.dt, self.act);
        // Cotangents of k1..k4, of a stage state, and of the forcing, on the dealiased modes
        // (the only ones a step reads or writes).
        let mut kb: [Vec<C>; 4] = std::array::from_fn(|j| std::mem::take(&mut self.w.bar[j]));
        for v in kb.iter_mut() {
            v.resize(self.len, C::default());
        }
        let mut sb = std::mem::take(&mut self.w.bar[4]);
        sb.resize(self.len, C::default());
        let mut fbar = std::mem::take(&mut self.w.fbar);
        fbar.iter_mut().for_each(|c| *c = C::default());
        for i in 0..act {
            let (e, e2, g) = (self.e_full[i], self.e_half[i], bar1[i]);
            kb[0][i] = g * (e * h / 6.0);
            kb[1][i] = g * (e2 * h / 3.0);
            kb[2][i] = g * (e2 * h / 3.0);
            kb[3][i] = g * (h / 6.0);
            bar0[i] = g * e;
        }
        // k4 = N(s4) + F, s4 = E w0 + h E/2 k3
        self.nonlinear_vjp(3, &kb[3], &mut sb);
        for i in 0..act {
            fbar[i] += kb[3][i];
            bar0[i] += sb[i] * self.e_full[i];
            kb[2][i] += sb[i] * (h * self.e_half[i]);
        }
        // k3 = N(s3) + F, s3 = E/2 w0 + h/2 k2
        self.nonlinear_vjp(2, &kb[2], &mut sb);
        for i in 0..act {
            fbar[i] += kb[2][i];
            bar0[i] += sb[i] * self.e_half[i];
            kb[1][i] += sb[i] * (h / 2.0);
        }
        // k2 = N(s2) + F, s2 = E/2 (w0 + h/2 k1)
        self.nonlinear_vjp(1, &kb[1], &mut sb);
        for i in 0..act {
            fbar[i] += kb[1][i];
            bar0[i] += sb[i] * self.e_half[i];
            kb[0][i] += sb[i] * (h / 2.0 * self.e_half[i]);
        }
        // k1 = N(w0) + F
        self.nonlinear_vjp(0, &kb[0], &mut sb);
        for i in 0..act {
            fbar[i] += kb[0][i];
            bar0[i] = (bar0[i] + sb[i]) * self.mask[i];
        }
        bar0[act..].iter_mut().for_each(|c| *c = C::default());
        for (ba, phi) in bar_a.iter_mut().zip(&self.controls) {
            *ba += inner(phi, &fbar, self.n);
        }
        for (j, v) in kb.into_iter().enumerate() {
            self.w.bar[j] = v;
        }
        self.w.bar[4] = sb;
        self.w.fbar = fbar;
        Ok(())
    }

    /// Advances `w` by one step into `out` without touching the solver's state (for replaying a
    /// segment of a trajectory in a backward sweep).
    pub fn step_from(&mut self, w: &[C], a: &[f64], out: &mut [C]) -> Result<(), SpectralError> {
        self.set_forcing(a)?;
        self.stages(w, Some(out));
        Ok(())
    }
}
