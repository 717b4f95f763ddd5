//! Circle (the cylinder of every bluff-body family).

use super::Shape;

/// Circle of `radius` around `center`.
#[derive(Clone, Debug, PartialEq)]
pub struct Circle {
    pub center: [f64; 2],
    pub radius: f64,
}

impl Shape for Circle {
    /// `phi(p) = |p - c| - r`.
    fn sdf(&self, p: [f64; 2]) -> f64 {
        let dx = p[0] - self.center[0];
        let dy = p[1] - self.center[1];
        (dx * dx + dy * dy).sqrt() - self.radius
    }

    fn bounding_box(&self) -> [f64; 4] {
        let [cx, cy] = self.center;
        let r = self.radius;
        [cx - r, cy - r, cx + r, cy + r]
    }

    /// Closed form: smallest root `t` of `|a + t (b - a) - c|^2 = r^2`.
    fn wall_fraction(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let d = [b[0] - a[0], b[1] - a[1]];
        let m = [a[0] - self.center[0], a[1] - self.center[1]];
        let aa = d[0] * d[0] + d[1] * d[1];
        let bb = 2.0 * (m[0] * d[0] + m[1] * d[1]);
        let cc = m[0] * m[0] + m[1] * m[1] - self.radius * self.radius;
        let disc = (bb * bb - 4.0 * aa * cc).max(0.0);
        // `cc >= 0` (a outside), so the nearer root is the one with the minus sign.
        let t = (-bb - disc.sqrt()) / (2.0 * aa);
        t.clamp(0.0, 1.0)
    }

    fn normal(&self, p: [f64; 2]) -> [f64; 2] {
        let dx = p[0] - self.center[0];
        let dy = p[1] - self.center[1];
        let n = (dx * dx + dy * dy).sqrt();
        if n > 0.0 {
            [dx / n, dy / n]
        } else {
            [1.0, 0.0]
        }
    }
}
