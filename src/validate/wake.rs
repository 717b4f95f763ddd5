//! The mean wake on a bluff body's centreline and its recirculation length.
//!
//! The streamwise velocity is sampled on the line `y = y_c` behind the body's base (one point per
//! lattice cell, [`WAKE_LENGTH`] body lengths long), at every node plane of an extruded body's
//! span (a sphere's or a cube's line is the one through its centre), every [`SAMPLE_EVERY`] L/U
//! of the averaging window, and averaged over time and span. The recirculation length `L_r / L`
//! is the distance from the base to the first upward zero crossing of that mean (linear
//! interpolation between points): the end of the mean recirculation bubble.

use serde::Serialize;

use crate::flow::FlowSetup;

/// How far behind the base the line reaches (body lengths); recirculation bubbles of the
/// cylinder at Re 3900 measure 1.2-1.6 D.
pub const WAKE_LENGTH: f64 = 6.0;

/// Time between samples (L/U): some 20 per shedding period at St 0.2.
pub const SAMPLE_EVERY: f64 = 0.25;

/// The time- (and span-) averaged streamwise velocity on the wake's centreline.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Wake {
    /// Distance behind the body's base, in L.
    pub x: Vec<f64>,
    /// Mean `u / U` at each `x`.
    pub u: Vec<f64>,
    /// Samples averaged (in time).
    pub samples: usize,
}

/// Accumulates [`Wake`] from probes at fixed points.
#[derive(Clone, Debug)]
pub struct WakeSampler {
    base: f64,
    xs: Vec<f64>,
    /// The probe points: `xs.len()` points per span position, span position major.
    points: Vec<[f64; 3]>,
    sum: Vec<f64>,
    samples: usize,
}

impl WakeSampler {
    /// The sampler of `setup`'s first body at `cells_per_length`, or `None` if that body has no
    /// wake axis. `span_nodes` are the node positions along the span (empty in 2D).
    pub fn new(setup: &FlowSetup, cells_per_length: f64, span_nodes: &[f64]) -> Option<Self> {
        let (base, y, z) = setup.bodies.first()?.wake_axis()?;
        let l = setup.reference_length();
        let dx = l / cells_per_length;
        let end = (base + WAKE_LENGTH * l).min(setup.domain.x[1] - dx);
        let count = ((end - base) / dx).floor() as usize + 1;
        let xs: Vec<f64> = (0..count).map(|i| base + i as f64 * dx).collect();
        let zs: Vec<f64> = match (z, span_nodes.is_empty()) {
            (Some(z), _) => vec![z],
            (None, false) => span_nodes.to_vec(),
            (None, true) => vec![0.0],
        };
        let points = zs.iter().flat_map(|&z| xs.iter().map(move |&x| [x, y, z])).collect();
        Some(WakeSampler {
            base,
            sum: vec![0.0; xs.len()],
            xs,
            points,
            samples: 0,
        })
    }

    /// Where the flow is to be probed next.
    pub fn points(&self) -> &[[f64; 3]] {
        &self.points
    }

    /// Adds one sample: `u[k]` is the streamwise velocity over U at `points()[k]`.
    pub fn add(&mut self, u: impl IntoIterator<Item = f64>) {
        let n = self.xs.len();
        for (k, v) in u.into_iter().enumerate() {
            self.sum[k % n] += v;
        }
        self.samples += 1;
    }

    pub fn finish(&self) -> Wake {
        let per = (self.samples * (self.points.len() / self.xs.len().max(1))).max(1) as f64;
        Wake {
            x: self.xs.iter().map(|x| x - self.base).collect(),
            u: self.sum.iter().map(|s| s / per).collect(),
            samples: self.samples,
        }
    }
}

/// `L_r / L`: the first `x` where the mean `u` crosses zero upwards, after it has been negative;
/// `None` without a recirculation bubble, or when it reaches past the line's end. `x` is in L.
pub fn recirculation_length(w: &Wake) -> Option<f64> {
    let first_negative = w.u.iter().position(|&u| u < 0.0)?;
    (first_negative..w.u.len().saturating_sub(1)).find_map(|i| {
        let (u0, u1) = (w.u[i], w.u[i + 1]);
        (u0 < 0.0 && u1 >= 0.0).then(|| w.x[i] + (w.x[i + 1] - w.x[i]) * (-u0) / (u1 - u0))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wake(u: impl Fn(f64) -> f64) -> Wake {
        let x: Vec<f64> = (0..97).map(|i| i as f64 / 16.0).collect();
        Wake {
            u: x.iter().map(|&x| u(x)).collect(),
            x,
            samples: 1,
        }
    }

    #[test]
    fn the_bubble_ends_where_the_mean_velocity_turns_positive() {
        // A linear profile crossing zero at x = 1.3 between samples: interpolation is exact.
        let l = recirculation_length(&wake(|x| 0.4 * (x - 1.3))).unwrap();
        assert!((l - 1.3).abs() < 1e-12, "{l}");
        // The wall's no-slip zero at the base does not count: the crossing is upward after
        // a negative stretch.
        let l = recirculation_length(&wake(|x| if x == 0.0 { 0.0 } else { (x - 0.7) * (x + 0.1) })).unwrap();
        assert!((l - 0.7).abs() < 0.01, "{l}");
    }

    #[test]
    fn no_bubble_or_an_open_bubble_has_no_length() {
        assert_eq!(recirculation_length(&wake(|x| 0.1 + x)), None);
        assert_eq!(recirculation_length(&wake(|x| -0.1 - x)), None);
    }

    #[test]
    fn samples_are_averaged_over_time_and_span() {
        let setup: FlowSetup = toml::from_str(
            r#"
bodies = [{ shape = "circle", center = [0.0, 0.0], diameter = 1.0 }]
domain = { x = [-4.0, 12.0], y = [-4.0, 4.0] }
boundaries = { west = "inlet", east = "outlet", south = "periodic", north = "periodic" }
inlet = {}
reynolds = 100.0
lattice_velocity = 0.05
collision = "regularized"
smagorinsky = 0.0
resolution = { coarse = 4, default = 8, fine = 16 }
sponges = []
span = { z = [0.0, 3.0], boundary = "periodic" }
"#,
        )
        .unwrap();
        let mut s = WakeSampler::new(&setup, 8.0, &[0.0, 1.0, 2.0]).unwrap();
        assert_eq!(s.points()[0], [0.5, 0.0, 0.0]);
        let n = s.points().len() / 3;
        assert_eq!(s.points()[n][2], 1.0);
        // Span positions 0, 1, 2 carry 1, 2, 3 in the first sample and 3, 4, 5 in the second:
        // mean 3 at every x.
        s.add((0..3 * n).map(|k| (k / n) as f64 + 1.0));
        s.add((0..3 * n).map(|k| (k / n) as f64 + 3.0));
        let w = s.finish();
        assert_eq!(w.samples, 2);
        assert!(w.u.iter().all(|&u| (u - 3.0).abs() < 1e-12), "{:?}", &w.u[..3]);
        assert_eq!(w.x[0], 0.0);
        assert!((w.x[1] - 1.0 / 8.0).abs() < 1e-12);
    }
}
