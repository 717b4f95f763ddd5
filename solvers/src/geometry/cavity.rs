//! Open cavity: a flat wall at `y = y_top` with a rectangular cut of `length x depth` whose
//! upstream (leading) edge is at `x = x0` (Sipp & Lebedev 2007; Barbagallo, Sipp & Schmid 2009).

use super::{Rectangle, Shape};

/// Solid region `{y < y_top} \ {x0 < x < x0 + length, y > y_top - depth}`: the plate upstream
/// and downstream of the cavity, and the cavity's front wall, floor and aft wall.
#[derive(Clone, Debug, PartialEq)]
pub struct OpenCavity {
    /// Leading edge (upstream lip) of the cavity, `(x0, y_top)`.
    pub leading_edge: [f64; 2],
    pub length: f64,
    pub depth: f64,
}

impl OpenCavity {
    /// The cut-out box `[x0, x0 + L] x [y_top - D, y_top + H]` (H large, so that the box's top
    /// never reaches the fluid of interest).
    fn cut(&self) -> Rectangle {
        let h = 1e3 * (self.length + self.depth);
        let [x0, yt] = self.leading_edge;
        Rectangle {
            center: [x0 + 0.5 * self.length, yt - self.depth + 0.5 * h],
            size: [self.length, h],
        }
    }
}

impl Shape for OpenCavity {
    /// `phi = max(y - y_top, -phi_box)`: the intersection of the half-plane below the wall with
    /// the outside of the cut. Exact away from the two lips' convex corners, where it is a lower
    /// bound of the distance with the right zero set (all the lattice needs).
    fn sdf(&self, p: [f64; 2]) -> f64 {
        (p[1] - self.leading_edge[1]).max(-self.cut().sdf(p))
    }

    fn bounding_box(&self) -> [f64; 4] {
        let inf = f64::INFINITY;
        [-inf, -inf, inf, self.leading_edge[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sdf_signs_and_distances() {
        let c = OpenCavity {
            leading_edge: [0.27, 1.0],
            length: 1.0,
            depth: 1.0,
        };
        // Fluid above the plate and inside the cavity; solid in the plate and below the floor.
        assert!((c.sdf([0.1, 1.2]) - 0.2).abs() < 1e-12);
        assert!((c.sdf([0.77, 0.5]) - 0.5).abs() < 1e-12); // centre of the cavity: 0.5 from all walls
        assert!((c.sdf([0.37, 0.5]) - 0.1).abs() < 1e-12); // 0.1 from the front wall
        assert!((c.sdf([0.77, 0.05]) - 0.05).abs() < 1e-12); // 0.05 above the floor
        assert!((c.sdf([0.1, 0.9]) + 0.1).abs() < 1e-12); // in the upstream plate
        assert!((c.sdf([1.5, 0.9]) + 0.1).abs() < 1e-12); // in the downstream plate
        assert!(c.sdf([0.77, -0.1]) < 0.0); // below the floor
                                            // The wall fraction along a horizontal link from the cavity into its front wall.
        let q = c.wall_fraction([0.3, 0.95], [0.25, 0.95]);
        assert!((q - 0.6).abs() < 1e-9, "q = {q}");
    }
}
