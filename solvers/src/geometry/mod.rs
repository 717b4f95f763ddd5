//! Signed-distance geometry for immersed bodies.
//!
//! A [`Shape`] is a closed body in physical coordinates given by its signed distance
//! `phi(p)`: negative inside the body, positive in the fluid, zero on the wall. Everything the
//! lattice needs (which nodes are solid, where a lattice link crosses the wall, the wall normal)
//! follows from `phi`, so a new shape only has to say how far a point is from it. Circles,
//! rectangles (square cylinders), NACA 4-digit aerofoils, half-planes (channel walls), open
//! cavities and channel stenoses are here; in 3D ([`Solid`]) spheres, cuboids and any of those
//! sections extruded along the span.

mod cavity;
mod circle;
mod naca;
mod plane;
mod rectangle;
mod solid;
mod stenosis;

pub use cavity::OpenCavity;
pub use circle::Circle;
pub use naca::Naca4;
pub use plane::HalfPlane;
pub use rectangle::Rectangle;
pub use solid::{Cuboid, Extruded, Solid, Sphere};
pub use stenosis::{StenosedPipe, Stenosis};

/// A closed body described by a signed distance function (negative inside).
pub trait Shape: Send + Sync + std::fmt::Debug {
    /// Signed distance from `p` to the wall: `< 0` inside the body, `> 0` in the fluid.
    fn sdf(&self, p: [f64; 2]) -> f64;

    /// Axis-aligned bounding box `[xmin, ymin, xmax, ymax]` of the body (may be infinite for
    /// half-planes).
    fn bounding_box(&self) -> [f64; 4];

    /// Fraction `q` in `(0, 1]` of the segment from `a` (fluid) to `b` (solid) at which the wall
    /// lies. The default bisects `sdf` along the segment (52 halvings: exact to f64 round-off for
    /// any shape whose `sdf` changes sign once on the segment); shapes with a closed form override it.
    fn wall_fraction(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..52 {
            let mid = 0.5 * (lo + hi);
            let p = [a[0] + mid * (b[0] - a[0]), a[1] + mid * (b[1] - a[1])];
            if self.sdf(p) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Outward unit normal at (or near) the wall point `p`, from the gradient of `sdf`.
    fn normal(&self, p: [f64; 2]) -> [f64; 2] {
        let h = 1e-7;
        let gx = self.sdf([p[0] + h, p[1]]) - self.sdf([p[0] - h, p[1]]);
        let gy = self.sdf([p[0], p[1] + h]) - self.sdf([p[0], p[1] - h]);
        let n = (gx * gx + gy * gy).sqrt();
        if n > 0.0 {
            [gx / n, gy / n]
        } else {
            [0.0, 0.0]
        }
    }
}

/// A shared shape is the shape it points to (bodies are held as `Arc<dyn Shape>` and extruded
/// along a span as they are).
impl<S: Shape + ?Sized> Shape for std::sync::Arc<S> {
    fn sdf(&self, p: [f64; 2]) -> f64 {
        (**self).sdf(p)
    }
    fn bounding_box(&self) -> [f64; 4] {
        (**self).bounding_box()
    }
    fn wall_fraction(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        (**self).wall_fraction(a, b)
    }
    fn normal(&self, p: [f64; 2]) -> [f64; 2] {
        (**self).normal(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_bisection_matches_closed_form_for_a_circle() {
        #[derive(Debug)]
        struct Plain(Circle);
        impl Shape for Plain {
            fn sdf(&self, p: [f64; 2]) -> f64 {
                self.0.sdf(p)
            }
            fn bounding_box(&self) -> [f64; 4] {
                self.0.bounding_box()
            }
        }
        let c = Circle {
            center: [0.3, -0.2],
            radius: 0.5,
        };
        let plain = Plain(c.clone());
        for (a, b) in [([0.9, -0.2], [0.7, -0.2]), ([0.3, 0.4], [0.31, 0.25]), ([-0.3, 0.2], [-0.1, 0.1])] {
            let exact = c.wall_fraction(a, b);
            let bis = plain.wall_fraction(a, b);
            assert!((exact - bis).abs() < 1e-12, "{exact} vs {bis}");
        }
    }
}
