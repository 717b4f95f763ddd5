//! Pseudo-spectral solvers on periodic domains and their discrete adjoints.
//!
//! - [`fft2`]: the 2D real FFT and Parseval inner products on half spectra;
//! - [`kolmogorov`]: 2D Navier-Stokes in vorticity form with Kolmogorov forcing, Lawson RK4,
//!   and the vector-Jacobian product of a step.

// Index loops over spectral coefficients read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod fft2;
pub mod kolmogorov;

pub use fft2::Fft2;
pub use kolmogorov::{Kolmogorov, KolmogorovConfig, SpectralError};
pub use realfft::num_complex::Complex64;
