//! Half-plane: the solid side of a straight wall (channel walls placed anywhere between nodes).

use super::Shape;

/// Solid half-plane `{p : (p - point) . normal < 0}`; `normal` points into the fluid.
#[derive(Clone, Debug, PartialEq)]
pub struct HalfPlane {
    pub point: [f64; 2],
    /// Unit normal pointing into the fluid.
    pub normal: [f64; 2],
}

impl Shape for HalfPlane {
    /// `phi(p) = (p - p0) . n`.
    fn sdf(&self, p: [f64; 2]) -> f64 {
        (p[0] - self.point[0]) * self.normal[0] + (p[1] - self.point[1]) * self.normal[1]
    }

    fn bounding_box(&self) -> [f64; 4] {
        let inf = f64::INFINITY;
        [-inf, -inf, inf, inf]
    }

    /// Closed form: `t = phi(a) / (phi(a) - phi(b))`.
    fn wall_fraction(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let pa = self.sdf(a);
        let pb = self.sdf(b);
        (pa / (pa - pb)).clamp(0.0, 1.0)
    }

    fn normal(&self, _p: [f64; 2]) -> [f64; 2] {
        self.normal
    }
}
