//! A boundary-layer trip: the random wall-normal volume force of Schlatter & Orlu (J. Fluid Mech.
//! 710, 2012), which makes streaks that break down to turbulence a short way downstream.
//!
//! `F_y = exp(-((x - x0) / lx)^2 - (y / ly)^2) f(z, t)`,
//! `f(z, t) = A_s g(z) + A_t [(1 - b(p)) h_i(z) + b(p) h_{i+1}(z)]`, `i = floor(t / t_s)`,
//! `p = t / t_s - i`, `b(p) = 3 p^2 - 2 p^3`. `g` and the `h_i` are random Fourier series in z
//! with the modes of wavelength down to `z_s` (uniform amplitudes and phases), drawn from the seed
//! and the index `i` alone, so a run restarted at any time sees the same force.

use super::error::ChannelError;

/// Where the trip sits, its shape and strength.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TripSpec {
    pub x0: f64,
    /// Gaussian widths in x and y.
    pub lx: f64,
    pub ly: f64,
    /// Shortest spanwise wavelength of the random series.
    pub z_s: f64,
    /// Time between independent time-dependent patterns.
    pub t_s: f64,
    /// Amplitudes of the steady and the time-dependent parts (force per unit mass).
    pub a_steady: f64,
    pub a_time: f64,
    pub seed: u64,
}

/// The trip with its spanwise patterns for the current interval.
#[derive(Clone, Debug)]
pub struct Trip {
    spec: TripSpec,
    lz: f64,
    /// `exp(-((x - x0)/lx)^2)` at the cell centres in x.
    shape_x: Vec<f64>,
    steady: Vec<f64>,
    /// `h_i` and `h_{i+1}` and the `i` they belong to.
    patterns: [Vec<f64>; 2],
    interval: Option<i64>,
    /// `f(z, t)` of the current stage, one value per z-cell.
    now: Vec<f64>,
}

fn splitmix64(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// A random Fourier series in z of the modes `1..=modes` on `nz` cells (values at the centres),
/// normalised so its largest value is 1, from the stream `key`.
fn series(key: u64, modes: usize, nz: usize, out: &mut [f64]) {
    let mut state = key;
    let mut uniform = || {
        state = splitmix64(state);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    out.fill(0.0);
    let two_pi = 2.0 * std::f64::consts::PI;
    for m in 1..=modes {
        let (a, phase) = (2.0 * uniform() - 1.0, two_pi * uniform());
        for (k, o) in out.iter_mut().enumerate() {
            *o += a * (two_pi * m as f64 * (k as f64 + 0.5) / nz as f64 + phase).cos();
        }
    }
    let max = out.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if max > 0.0 {
        out.iter_mut().for_each(|v| *v /= max);
    }
}

impl Trip {
    /// The trip on a grid of `nx` cells of width `dx` in x and `nz` cells over `lz` in z.
    pub fn new(spec: TripSpec, nx: usize, dx: f64, nz: usize, lz: f64) -> Result<Self, ChannelError> {
        let positive = [spec.lx, spec.ly, spec.z_s, spec.t_s].iter().all(|v| *v > 0.0 && v.is_finite());
        if !positive {
            return Err(ChannelError::config("trip", "lx, ly, z_s and t_s must be positive"));
        }
        if !(spec.a_steady.is_finite() && spec.a_time.is_finite()) {
            return Err(ChannelError::config("trip", "the amplitudes must be finite"));
        }
        let shape_x = (0..nx)
            .map(|i| (-(((i as f64 + 0.5) * dx - spec.x0) / spec.lx).powi(2)).exp())
            .collect();
        let mut steady = vec![0.0; nz];
        series(splitmix64(spec.seed), modes(lz, spec.z_s), nz, &mut steady);
        Ok(Trip {
            spec,
            lz,
            shape_x,
            steady,
            patterns: [vec![0.0; nz], vec![0.0; nz]],
            interval: None,
            now: vec![0.0; nz],
        })
    }

    pub fn spec(&self) -> &TripSpec {
        &self.spec
    }

    /// Sets `f(z, t)` for time `t` (draws new patterns only when the interval changes).
    pub fn at_time(&mut self, t: f64) {
        let x = t / self.spec.t_s;
        let i = x.floor() as i64;
        let nz = self.now.len();
        let m = modes(self.lz, self.spec.z_s);
        let key = |i: i64| splitmix64(self.spec.seed ^ splitmix64(i as u64 ^ 0x5851_f42d_4c95_7f2d));
        match self.interval {
            Some(j) if j == i => {}
            Some(j) if j + 1 == i => {
                self.patterns.swap(0, 1);
                series(key(i + 1), m, nz, &mut self.patterns[1]);
            }
            _ => {
                series(key(i), m, nz, &mut self.patterns[0]);
                series(key(i + 1), m, nz, &mut self.patterns[1]);
            }
        }
        self.interval = Some(i);
        let p = x - i as f64;
        let b = p * p * (3.0 - 2.0 * p);
        for k in 0..nz {
            let h = (1.0 - b) * self.patterns[0][k] + b * self.patterns[1][k];
            self.now[k] = self.spec.a_steady * self.steady[k] + self.spec.a_time * h;
        }
    }

    /// Adds the force to the right-hand side of `v` on face row `(y, k)` at height `y`.
    pub fn force_v_row(&self, y: f64, k: usize, rv: &mut [f64]) {
        let fy = (-(y / self.spec.ly).powi(2)).exp() * self.now[k];
        for (r, s) in rv.iter_mut().zip(&self.shape_x) {
            *r += fy * s;
        }
    }
}

/// Modes of wavelength at least `z_s` that fit in `lz` (at least one).
fn modes(lz: f64, z_s: f64) -> usize {
    ((lz / z_s).floor() as usize).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> TripSpec {
        TripSpec {
            x0: 2.0,
            lx: 0.5,
            ly: 0.2,
            z_s: 0.5,
            t_s: 1.0,
            a_steady: 0.0,
            a_time: 1.0,
            seed: 7,
        }
    }

    #[test]
    fn the_force_is_continuous_in_time_and_repeats_from_any_start() {
        let mut a = Trip::new(spec(), 16, 0.25, 24, 3.0).unwrap();
        let mut b = a.clone();
        let mut last: Option<Vec<f64>> = None;
        for n in 0..400 {
            a.at_time(n as f64 * 0.01);
            if let Some(prev) = &last {
                let jump = prev.iter().zip(&a.now).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
                assert!(jump < 0.05, "jump {jump} at step {n}");
            }
            last = Some(a.now.clone());
        }
        // A trip that starts late sees the same force.
        b.at_time(3.99);
        assert_eq!(a.now, b.now);
        assert!(a.now.iter().any(|v| v.abs() > 0.1));
    }

    #[test]
    fn bad_shapes_are_refused() {
        let bad = Trip::new(TripSpec { ly: 0.0, ..spec() }, 16, 0.25, 24, 3.0);
        assert!(matches!(bad, Err(ChannelError::Config { field: "trip", .. })));
    }
}
