//! Axis-aligned rectangle (the square cylinder).

use super::Shape;

/// Rectangle of full extents `size = [width, height]` around `center`.
#[derive(Clone, Debug, PartialEq)]
pub struct Rectangle {
    pub center: [f64; 2],
    pub size: [f64; 2],
}

impl Shape for Rectangle {
    /// Exact box distance (Quilez): `|max(d, 0)| + min(max(d_x, d_y), 0)` with
    /// `d = |p - c| - size/2`.
    fn sdf(&self, p: [f64; 2]) -> f64 {
        let dx = (p[0] - self.center[0]).abs() - 0.5 * self.size[0];
        let dy = (p[1] - self.center[1]).abs() - 0.5 * self.size[1];
        let ox = dx.max(0.0);
        let oy = dy.max(0.0);
        (ox * ox + oy * oy).sqrt() + dx.max(dy).min(0.0)
    }

    fn bounding_box(&self) -> [f64; 4] {
        let [cx, cy] = self.center;
        let [hx, hy] = [0.5 * self.size[0], 0.5 * self.size[1]];
        [cx - hx, cy - hy, cx + hx, cy + hy]
    }
}
