//! A two-dimensional stenosis: a smooth constriction of a straight channel of width `width`
//! between walls at `y = center_y -+ width / 2`, after the cosine profile of Varghese, Frankel &
//! Fischer (J. Fluid Mech. 582, 2007), taken as a channel's half-width:
//!
//! `h(x) = (width / 2) (1 - s0 (1 + cos(2 pi (x - x0) / length)))` for `|x - x0| <= length / 2`,
//! `h = width / 2` elsewhere,
//!
//! with `s0 = severity`: `s0 = 0.25` halves the width at the throat `x0` (Varghese et al.: 75 %
//! area reduction of a pipe). The body is the wall material between `|y - center_y| = h(x)` and
//! the channel walls; the walls themselves are the domain's sides.
//!
//! [`StenosedPipe`] is the original 3D geometry: a round pipe along x whose radius is `h(x)`.

use super::{Shape, Solid};

#[derive(Clone, Debug, PartialEq)]
pub struct Stenosis {
    /// Throat position `x0` and channel axis `y`.
    pub center: [f64; 2],
    pub width: f64,
    pub length: f64,
    pub severity: f64,
}

impl Stenosis {
    /// Half-width of the open channel at `x`.
    pub fn half_width(&self, x: f64) -> f64 {
        let s = x - self.center[0];
        let h0 = 0.5 * self.width;
        if s.abs() >= 0.5 * self.length {
            return h0;
        }
        h0 * (1.0 - self.severity * (1.0 + (2.0 * std::f64::consts::PI * s / self.length).cos()))
    }
}

impl Shape for Stenosis {
    /// Vertical distance `h(x) - |y - y_c|` (not the Euclidean one; its sign and zero set are
    /// exact, which is all the lattice uses: solid nodes by sign, wall crossings by bisection).
    fn sdf(&self, p: [f64; 2]) -> f64 {
        self.half_width(p[0]) - (p[1] - self.center[1]).abs()
    }

    fn bounding_box(&self) -> [f64; 4] {
        let [x0, y0] = self.center;
        let (l, h) = (0.5 * self.length, 0.5 * self.width);
        [x0 - l, y0 - h, x0 + l, y0 + h]
    }
}

/// A round pipe of diameter `width` along x through `(center[1], center[2])`, its radius `h(x)`
/// of the cosine stenosis (throat at `x = center[0]`); solid outside that radius.
#[derive(Clone, Debug, PartialEq)]
pub struct StenosedPipe {
    pub center: [f64; 3],
    pub width: f64,
    pub length: f64,
    pub severity: f64,
}

impl StenosedPipe {
    /// The axial section's profile: the radius is its half-width.
    pub fn section(&self) -> Stenosis {
        Stenosis {
            center: [self.center[0], 0.0],
            width: self.width,
            length: self.length,
            severity: self.severity,
        }
    }

    /// Distance from the pipe's axis.
    pub fn radius_of(&self, p: [f64; 3]) -> f64 {
        (p[1] - self.center[1]).hypot(p[2] - self.center[2])
    }
}

impl Solid for StenosedPipe {
    /// Radial distance `h(x) - r` (not the Euclidean one; its sign and zero set are exact, which
    /// is all the lattice uses).
    fn sdf(&self, p: [f64; 3]) -> f64 {
        self.section().half_width(p[0]) - self.radius_of(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn severity_a_quarter_halves_the_width_at_the_throat() {
        let s = Stenosis {
            center: [0.0, 0.0],
            width: 1.0,
            length: 2.0,
            severity: 0.25,
        };
        assert!((s.half_width(0.0) - 0.25).abs() < 1e-15);
        assert_eq!(s.half_width(1.0), 0.5);
        assert_eq!(s.half_width(-3.0), 0.5);
        assert!(s.sdf([0.0, 0.3]) < 0.0 && s.sdf([0.0, 0.2]) > 0.0 && s.sdf([0.0, -0.3]) < 0.0);
        // Smooth and symmetric.
        assert!((s.half_width(0.4) - s.half_width(-0.4)).abs() < 1e-15);
    }

    #[test]
    fn the_pipe_is_round_and_narrows_to_its_throat() {
        let p = StenosedPipe {
            center: [0.0, 0.5, 0.5],
            width: 1.0,
            length: 2.0,
            severity: 0.25,
        };
        // Radius 1/4 at the throat in every direction, 1/2 away from it.
        for (dy, dz) in [(0.24, 0.0), (0.0, -0.24), (0.17, 0.17)] {
            assert!(p.sdf([0.0, 0.5 + dy, 0.5 + dz]) > 0.0);
        }
        assert!(p.sdf([0.0, 0.5 + 0.18, 0.5 + 0.18]) < 0.0);
        assert!(p.sdf([3.0, 0.5 + 0.35, 0.5 + 0.35]) > 0.0 && p.sdf([3.0, 0.5 + 0.36, 0.5 + 0.36]) < 0.0);
    }
}
