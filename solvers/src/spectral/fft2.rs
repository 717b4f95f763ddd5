//! Two-dimensional real FFT on an `n x n` periodic grid: real-to-complex along x (`realfft`),
//! complex along y (`rustfft`). Physical fields are row-major `f[y * n + x]`; spectra are stored
//! column-major over the half plane, `F[kx * n + iy]` with `kx = 0..=n/2` and `iy = 0..n`
//! (`ky = iy` for `iy <= n/2`, else `iy - n`), so every y-transform is contiguous.
//!
//! Forward is unnormalised, `F(k) = sum_x f(x) e^{-i k.x}`; inverse divides by `n^2`. Only the
//! first `active` x-wavenumber columns are transformed along y (a dealiased field has no energy
//! beyond them): the others are left at zero on the way in and skipped on the way out.

use std::sync::Arc;

use realfft::num_complex::Complex64;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

pub struct Fft2 {
    n: usize,
    nh: usize,
    active: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
    row: Vec<f64>,
    row_spec: Vec<Complex64>,
    cols: Vec<Complex64>,
    scratch_r: Vec<Complex64>,
    scratch_c: Vec<Complex64>,
}

impl Fft2 {
    /// Plans for an `n x n` grid (`n` even); `active` x-wavenumber columns (at most `n/2 + 1`).
    pub fn new(n: usize, active: usize) -> Self {
        let nh = n / 2 + 1;
        let active = active.min(nh);
        let mut rp = RealFftPlanner::<f64>::new();
        let mut cp = FftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(n);
        let c2r = rp.plan_fft_inverse(n);
        let fwd = cp.plan_fft_forward(n);
        let inv = cp.plan_fft_inverse(n);
        let sr = r2c.get_scratch_len().max(c2r.get_scratch_len());
        let sc = fwd.get_inplace_scratch_len().max(inv.get_inplace_scratch_len());
        Fft2 {
            n,
            nh,
            active,
            r2c,
            c2r,
            fwd,
            inv,
            row: vec![0.0; n],
            row_spec: vec![Complex64::default(); nh],
            cols: vec![Complex64::default(); n * nh],
            scratch_r: vec![Complex64::default(); sr],
            scratch_c: vec![Complex64::default(); sc],
        }
    }

    pub fn n(&self) -> usize {
        self.n
    }

    /// Length of a spectrum: `(n/2 + 1) n`.
    pub fn spectral_len(&self) -> usize {
        self.nh * self.n
    }

    /// `out = FFT2(phys)`; columns beyond `active` are set to zero.
    pub fn forward(&mut self, phys: &[f64], out: &mut [Complex64]) {
        let n = self.n;
        assert_eq!(phys.len(), n * n);
        self.forward_rows(|y, row| row.copy_from_slice(&phys[y * n..(y + 1) * n]), out);
    }

    /// `out = FFT2(f)` of the field whose row `y` `fill(y, row)` writes (`row` has `n` values):
    /// a product of fields is transformed row by row as it is formed, with no `n x n` array
    /// written and read back in between.
    pub fn forward_rows(&mut self, mut fill: impl FnMut(usize, &mut [f64]), out: &mut [Complex64]) {
        let (n, nh) = (self.n, self.nh);
        assert_eq!(out.len(), n * nh);
        for y in 0..n {
            fill(y, &mut self.row);
            // Lengths match the plan, so the transform cannot fail.
            let _ = self
                .r2c
                .process_with_scratch(&mut self.row, &mut self.row_spec, &mut self.scratch_r);
            for kx in 0..self.active {
                out[kx * n + y] = self.row_spec[kx];
            }
        }
        out[self.active * n..].iter_mut().for_each(|c| *c = Complex64::default());
        self.fwd.process_with_scratch(&mut out[..self.active * n], &mut self.scratch_c);
    }

    /// `phys = IFFT2(spec) / n^2` (only the `active` columns of `spec` are read).
    pub fn inverse(&mut self, spec: &[Complex64], phys: &mut [f64]) {
        let m = self.active * self.n;
        let mut cols = std::mem::take(&mut self.cols);
        cols[..m].copy_from_slice(&spec[..m]);
        self.inverse_destroying(&mut cols, phys);
        self.cols = cols;
    }

    /// [`Fft2::inverse`] that uses `spec` as its work array (its content is destroyed): one copy
    /// less for spectra that are scratch anyway.
    pub fn inverse_destroying(&mut self, spec: &mut [Complex64], phys: &mut [f64]) {
        let (n, nh) = (self.n, self.nh);
        assert_eq!(spec.len(), n * nh);
        assert_eq!(phys.len(), n * n);
        let m = self.active * n;
        self.inv.process_with_scratch(&mut spec[..m], &mut self.scratch_c);
        let scale = 1.0 / (n * n) as f64;
        let r = &mut self.row_spec;
        for (y, out) in phys.chunks_exact_mut(n).enumerate() {
            for kx in 0..self.active {
                r[kx] = spec[kx * n + y] * scale;
            }
            r[self.active..].iter_mut().for_each(|c| *c = Complex64::default());
            // A real field has real x-mean and x-Nyquist coefficients; drop round-off there.
            r[0].im = 0.0;
            r[nh - 1].im = 0.0;
            let _ = self.c2r.process_with_scratch(r, out, &mut self.scratch_r);
        }
    }
}

/// Signed wavenumber of y-index `iy` on an `n`-point grid.
pub fn ky_of(iy: usize, n: usize) -> i64 {
    if iy <= n / 2 {
        iy as i64
    } else {
        iy as i64 - n as i64
    }
}

/// `sum_x f(x) g(x)` for real fields given by their half spectra (Parseval, with weight 2 for the
/// columns `0 < kx < n/2` that stand for their mirror images).
pub fn inner(f: &[Complex64], g: &[Complex64], n: usize) -> f64 {
    let nh = n / 2 + 1;
    let mut s = 0.0;
    for kx in 0..nh {
        let w = if kx == 0 || (kx == n / 2) { 1.0 } else { 2.0 };
        let col: f64 = f[kx * n..(kx + 1) * n]
            .iter()
            .zip(&g[kx * n..(kx + 1) * n])
            .map(|(a, b)| a.re * b.re + a.im * b.im)
            .sum();
        s += w * col;
    }
    s / (n * n) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_parseval() {
        let n = 16;
        let mut f = Fft2::new(n, n / 2 + 1);
        let phys: Vec<f64> = (0..n * n).map(|i| ((i * 37 % 23) as f64 - 11.0) / 7.0).collect();
        let mut spec = vec![Complex64::default(); f.spectral_len()];
        f.forward(&phys, &mut spec);
        let mut back = vec![0.0; n * n];
        f.inverse(&spec, &mut back);
        let err = phys.iter().zip(&back).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-13, "round trip error {err}");
        let direct: f64 = phys.iter().map(|v| v * v).sum();
        assert!((inner(&spec, &spec, n) - direct).abs() < 1e-10 * direct);
        // A single mode cos(3x + 2y) lands at (kx, ky) = (3, 2) with amplitude n^2 / 2.
        let two_pi = 2.0 * std::f64::consts::PI;
        let wave: Vec<f64> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 * two_pi / n as f64, (i / n) as f64 * two_pi / n as f64);
                (3.0 * x + 2.0 * y).cos()
            })
            .collect();
        f.forward(&wave, &mut spec);
        assert!((spec[3 * n + 2].re - (n * n) as f64 / 2.0).abs() < 1e-9);
        assert_eq!(ky_of(n - 2, n), -2);
    }

    #[test]
    fn forward_rows_is_bitwise_forward() {
        let (n, active) = (24, 9);
        let mut f = Fft2::new(n, active);
        let (a, b): (Vec<f64>, Vec<f64>) = (0..n * n).map(|i| ((i % 7) as f64 - 3.1, (i % 5) as f64 * 0.3 - 0.7)).unzip();
        let product: Vec<f64> = a.iter().zip(&b).map(|(a, b)| a * b).collect();
        let (mut one, mut two) = (
            vec![Complex64::default(); f.spectral_len()],
            vec![Complex64::default(); f.spectral_len()],
        );
        f.forward(&product, &mut one);
        f.forward_rows(
            |y, row| {
                for (x, r) in row.iter_mut().enumerate() {
                    *r = a[y * n + x] * b[y * n + x];
                }
            },
            &mut two,
        );
        assert!(one
            .iter()
            .zip(&two)
            .all(|(x, y)| x.re.to_bits() == y.re.to_bits() && x.im.to_bits() == y.im.to_bits()));
    }
}
