//! The pressure Poisson equation of the staggered channel, solved directly: real FFT along x,
//! complex FFT along z, then one tridiagonal (Thomas) solve in y per wavenumber pair (the method of
//! CaNS, Costa 2018). The operator is the discrete `div grad` of the grid itself, with the
//! x and z second differences diagonalised by their modified wavenumbers
//! `-(2 - 2 cos(2 pi m / n)) / d^2`, so the corrected velocity is divergence-free to round-off.
//! The gradient is not applied through the walls (the wall-normal velocity there is prescribed),
//! which makes the y operator Neumann; the singular mean mode is fixed by `phi = 0` in the first
//! cell.
//!
//! Spectra: after the x transform `hat[(k ny + j) nh + m]`; after the z transform, per x
//! wavenumber `m`, `spec[(m nz + kz) ny + j]`, so each tridiagonal system is contiguous. Every
//! stage runs over independent blocks of rows or wavenumbers with its own preallocated scratch,
//! so the result does not depend on the thread count and a solve allocates nothing.

use std::f64::consts::PI;
use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex64;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::grid::Grid;

struct RowScratch {
    row: Vec<f64>,
    spec: Vec<Complex64>,
    fft: Vec<Complex64>,
}

struct ColScratch {
    col: Vec<Complex64>,
    fft: Vec<Complex64>,
    /// Thomas sweep coefficients `c'_j`.
    cp: Vec<f64>,
}

pub struct Poisson {
    nx: usize,
    ny: usize,
    nz: usize,
    nh: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fwd: Arc<dyn Fft<f64>>,
    inv: Arc<dyn Fft<f64>>,
    /// Eigenvalues of the x and z second differences.
    lam_x: Vec<f64>,
    lam_z: Vec<f64>,
    /// Off-diagonals of the y operator: row j reads `a[j] phi[j-1] + (lam - a[j] - c[j]) phi[j] + c[j] phi[j+1]`.
    a: Vec<f64>,
    c: Vec<f64>,
    hat: Vec<Complex64>,
    spec: Vec<Complex64>,
    /// Grid rows per block of x transforms; one scratch per block.
    block: usize,
    rows: Vec<RowScratch>,
    cols: Vec<ColScratch>,
}

impl Poisson {
    pub fn new(g: &Grid) -> Self {
        let (nx, ny, nz) = (g.nx, g.ny, g.nz);
        let nh = nx / 2 + 1;
        let mut rp = RealFftPlanner::<f64>::new();
        let mut cp = FftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(nx);
        let c2r = rp.plan_fft_inverse(nx);
        let fwd = cp.plan_fft_forward(nz);
        let inv = cp.plan_fft_inverse(nz);
        let sr = r2c.get_scratch_len().max(c2r.get_scratch_len());
        let sc = fwd.get_inplace_scratch_len().max(inv.get_inplace_scratch_len());
        let eig = |n: usize, d: f64, m: usize| -(2.0 - 2.0 * (2.0 * PI * m as f64 / n as f64).cos()) / (d * d);
        let a = (0..ny).map(|j| if j == 0 { 0.0 } else { 1.0 / (g.dyf[j] * g.dyc[j]) }).collect();
        let c = (0..ny)
            .map(|j| if j + 1 == ny { 0.0 } else { 1.0 / (g.dyf[j] * g.dyc[j + 1]) })
            .collect();
        let block = (nz * ny).div_ceil(64);
        Poisson {
            block,
            nx,
            ny,
            nz,
            nh,
            lam_x: (0..nh).map(|m| eig(nx, g.dx, m)).collect(),
            lam_z: (0..nz).map(|m| eig(nz, g.dz, m)).collect(),
            a,
            c,
            hat: vec![Complex64::default(); nz * ny * nh],
            spec: vec![Complex64::default(); nh * nz * ny],
            rows: (0..(nz * ny).div_ceil(block))
                .map(|_| RowScratch {
                    row: vec![0.0; nx],
                    spec: vec![Complex64::default(); nh],
                    fft: vec![Complex64::default(); sr],
                })
                .collect(),
            cols: (0..nh)
                .map(|_| ColScratch {
                    col: vec![Complex64::default(); nz],
                    fft: vec![Complex64::default(); sc],
                    cp: vec![0.0; ny],
                })
                .collect(),
            r2c,
            c2r,
            fwd,
            inv,
        }
    }

    /// Overwrites `field` (cell values, the right-hand side) with the solution `phi` of
    /// `div grad phi = field`.
    pub fn solve(&mut self, field: &mut [f64]) {
        let (nx, ny, nz, nh) = (self.nx, self.ny, self.nz, self.nh);
        assert_eq!(field.len(), nx * ny * nz);
        let (r2c, block) = (&self.r2c, self.block);
        self.hat
            .par_chunks_mut(block * nh)
            .zip(field.par_chunks(block * nx))
            .zip(self.rows.par_iter_mut())
            .for_each(|((hat, rows), s)| {
                for (hat, row) in hat.chunks_exact_mut(nh).zip(rows.chunks_exact(nx)) {
                    s.row.copy_from_slice(row);
                    // Lengths match the plan, so the transform cannot fail.
                    let _ = r2c.process_with_scratch(&mut s.row, hat, &mut s.fft);
                }
            });

        let (hat, lam_x, lam_z, a, c) = (&self.hat, &self.lam_x, &self.lam_z, &self.a, &self.c);
        let (fwd, inv) = (&self.fwd, &self.inv);
        self.spec
            .par_chunks_mut(nz * ny)
            .zip(self.cols.par_iter_mut())
            .enumerate()
            .for_each(|(m, (spec, s))| {
                for j in 0..ny {
                    for kz in 0..nz {
                        s.col[kz] = hat[(kz * ny + j) * nh + m];
                    }
                    if nz > 1 {
                        fwd.process_with_scratch(&mut s.col, &mut s.fft);
                    }
                    for kz in 0..nz {
                        spec[kz * ny + j] = s.col[kz];
                    }
                }
                for kz in 0..nz {
                    let lam = lam_x[m] + lam_z[kz];
                    thomas(&mut spec[kz * ny..(kz + 1) * ny], a, c, lam, m == 0 && kz == 0, &mut s.cp);
                }
                if nz > 1 {
                    for j in 0..ny {
                        for k in 0..nz {
                            s.col[k] = spec[k * ny + j];
                        }
                        inv.process_with_scratch(&mut s.col, &mut s.fft);
                        for k in 0..nz {
                            spec[k * ny + j] = s.col[k];
                        }
                    }
                }
            });

        let (spec, c2r) = (&self.spec, &self.c2r);
        let scale = 1.0 / (nx * nz) as f64;
        field
            .par_chunks_mut(block * nx)
            .zip(self.rows.par_iter_mut())
            .enumerate()
            .for_each(|(b, (rows, s))| {
                for (r, out) in rows.chunks_exact_mut(nx).enumerate() {
                    let (k, j) = ((b * block + r) / ny, (b * block + r) % ny);
                    for m in 0..nh {
                        s.spec[m] = spec[(m * nz + k) * ny + j];
                    }
                    // A real field's mean and Nyquist coefficients are real; drop the round-off.
                    s.spec[0].im = 0.0;
                    if nx % 2 == 0 {
                        s.spec[nh - 1].im = 0.0;
                    }
                    let _ = c2r.process_with_scratch(&mut s.spec, &mut s.row, &mut s.fft);
                    for (p, r) in out.iter_mut().zip(&s.row) {
                        *p = r * scale;
                    }
                }
            });
    }
}

/// Thomas algorithm for `a[j] x[j-1] + (lam - a[j] - c[j]) x[j] + c[j] x[j+1] = d[j]`, in place
/// on `d`. The operator is diagonally dominant for `lam < 0`; for the mean mode (`lam = 0`,
/// singular) the first row is replaced by `x[0] = 0`.
fn thomas(d: &mut [Complex64], a: &[f64], c: &[f64], lam: f64, pin: bool, cp: &mut [f64]) {
    let n = d.len();
    let (b0, c0, d0) = if pin {
        (1.0, 0.0, Complex64::default())
    } else {
        (lam - c[0], c[0], d[0])
    };
    cp[0] = c0 / b0;
    d[0] = d0 / b0;
    for j in 1..n {
        let b = lam - a[j] - c[j];
        let den = b - a[j] * cp[j - 1];
        cp[j] = c[j] / den;
        d[j] = (d[j] - d[j - 1] * a[j]) / den;
    }
    for j in (0..n - 1).rev() {
        d[j] -= d[j + 1] * cp[j];
    }
}
