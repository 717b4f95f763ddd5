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

use super::Shape;

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
}
