//! Bodies in three dimensions: spheres, cuboids (the cube, channel walls) and any 2D [`Shape`]
//! extruded along z (the spanwise axis: circle, square, NACA 4-digit, each pinball cylinder).
//!
//! Same contract as [`Shape`]: a signed distance `phi(p)`, negative inside, from which the
//! lattice takes its solid nodes and the wall fraction of every link that crosses the wall.

use super::Shape;

/// A closed body in 3D described by a signed distance function (negative inside).
pub trait Solid: Send + Sync + std::fmt::Debug {
    /// Signed distance from `p` to the wall: `< 0` inside the body, `> 0` in the fluid.
    fn sdf(&self, p: [f64; 3]) -> f64;

    /// Fraction `q` in `[0, 1]` of the segment from `a` (fluid) to `b` (solid) at which the wall
    /// lies, by bisection of `sdf` along the segment (52 halvings: f64 round-off).
    fn wall_fraction(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..52 {
            let mid = 0.5 * (lo + hi);
            let p = [0, 1, 2].map(|d| a[d] + mid * (b[d] - a[d]));
            if self.sdf(p) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Whether `sdf` is the same at every z (a section extruded along the span), so that one
    /// plane of a grid describes them all.
    fn z_invariant(&self) -> bool {
        false
    }
}

/// Sphere of `radius` around `center`: `phi(p) = |p - c| - r`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sphere {
    pub center: [f64; 3],
    pub radius: f64,
}

impl Solid for Sphere {
    fn sdf(&self, p: [f64; 3]) -> f64 {
        let d2: f64 = (0..3).map(|d| (p[d] - self.center[d]).powi(2)).sum();
        d2.sqrt() - self.radius
    }
}

/// Axis-aligned box of edge lengths `size` around `center` (the cube; with infinite sizes, a
/// wall slab). Exact box distance `|max(d, 0)| + min(max_k d_k, 0)`, `d = |p - c| - size/2`.
#[derive(Clone, Debug, PartialEq)]
pub struct Cuboid {
    pub center: [f64; 3],
    pub size: [f64; 3],
}

impl Solid for Cuboid {
    fn sdf(&self, p: [f64; 3]) -> f64 {
        let d = [0, 1, 2].map(|k| (p[k] - self.center[k]).abs() - 0.5 * self.size[k]);
        let outside: f64 = d.iter().map(|v| v.max(0.0).powi(2)).sum::<f64>().sqrt();
        outside + d[0].max(d[1]).max(d[2]).min(0.0)
    }
}

/// A 2D section in the (x, y) plane extruded along the whole span (z): `phi(x, y, z) =
/// phi_2D(x, y)`. On a periodic span this is the infinite-span body of the paper's 3D cylinder,
/// square, aerofoil and pinball flows.
#[derive(Debug)]
pub struct Extruded<S: Shape>(pub S);

impl<S: Shape> Solid for Extruded<S> {
    fn sdf(&self, p: [f64; 3]) -> f64 {
        self.0.sdf([p[0], p[1]])
    }

    fn wall_fraction(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        self.0.wall_fraction([a[0], a[1]], [b[0], b[1]])
    }

    fn z_invariant(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::Circle;
    use super::*;

    #[test]
    fn distances_and_wall_fractions() {
        let s = Sphere {
            center: [1.0, 2.0, 3.0],
            radius: 0.5,
        };
        assert!((s.sdf([1.0, 2.0, 4.0]) - 0.5).abs() < 1e-15);
        // Along z from 1 above the centre to the centre: the wall is half-way.
        assert!((s.wall_fraction([1.0, 2.0, 4.0], [1.0, 2.0, 3.0]) - 0.5).abs() < 1e-12);
        let c = Cuboid {
            center: [0.0; 3],
            size: [2.0, 2.0, 2.0],
        };
        assert!((c.sdf([2.0, 0.0, 0.0]) - 1.0).abs() < 1e-15);
        assert!((c.sdf([2.0, 2.0, 1.0]) - 2f64.sqrt()).abs() < 1e-15);
        assert!((c.sdf([0.5, 0.0, 0.0]) + 0.5).abs() < 1e-15);
        assert!((c.wall_fraction([1.25, 0.0, 0.0], [0.25, 0.0, 0.0]) - 0.25).abs() < 1e-12);
        let e = Extruded(Circle {
            center: [0.0, 0.0],
            radius: 1.0,
        });
        for z in [-10.0, 0.0, 7.5] {
            assert!((e.sdf([2.0, 0.0, z]) - 1.0).abs() < 1e-15);
        }
    }
}
