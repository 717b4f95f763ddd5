//! Absorbing layers of the 3D box: the 2D solver's (`crate::lbm::sponge`, Israeli & Orszag 1981)
//! on any of the six faces. After every collision the populations of a fluid node at depth `d`
//! into the layer (`d = 0` at its inner end, `1` at the face) relax towards the equilibrium of
//! the target state, `g_i <- g_i - sigma(d) (g_i - g_i^eq(rho_0, u_0))`,
//! `sigma(d) = sigma_max d^2`.

use super::collision::equilibrium;
use super::lattice::Lattice3;
use super::part::Part;

/// One absorbing layer.
#[derive(Clone, Debug, PartialEq)]
pub struct Sponge3 {
    /// The face it lines: `2 a` the low end of axis `a`, `2 a + 1` the high end (as [`super::Faces`]).
    pub face: usize,
    /// Thickness in nodes.
    pub width: usize,
    /// `sigma_max`, the relaxation per step at the face, in (0, 1].
    pub strength: f64,
    /// Target density and velocity (lattice units).
    pub rho: f64,
    pub u: [f64; 3],
}

/// A layer ready for the step: its target equilibrium computed once.
#[derive(Clone, Debug)]
pub(crate) struct Sponge3Plan {
    face: usize,
    width: usize,
    strength: f32,
    g_eq: Vec<f32>,
}

impl Sponge3Plan {
    pub fn new<const Q: usize, L: Lattice3<Q>>(s: &Sponge3) -> Self {
        Sponge3Plan {
            face: s.face,
            width: s.width,
            strength: s.strength as f32,
            g_eq: equilibrium::<Q, L>((s.rho - 1.0) as f32, s.u.map(|v| v as f32)).to_vec(),
        }
    }

    /// `sigma` at node `p` of a box of `n` nodes, zero outside the layer.
    pub fn sigma(&self, p: [usize; 3], n: [usize; 3]) -> f32 {
        let a = self.face / 2;
        let depth = if self.face.is_multiple_of(2) {
            self.width as isize - p[a] as isize
        } else {
            p[a] as isize + self.width as isize + 1 - n[a] as isize
        };
        if depth <= 0 {
            return 0.0;
        }
        let d = depth as f32 / self.width as f32;
        self.strength * d * d
    }
}

/// Applies every layer to the post-collision populations of plane `z` (`plane[(i ny + y) nx + x]`)
/// of this rank's box of `n` nodes (its slab of the global box, `part`). Solid nodes are left
/// alone. Allocates nothing.
pub(crate) fn apply_plane(plans: &[Sponge3Plan], plane: &mut [f32], z: usize, n: [usize; 3], part: &Part, solid: &[bool]) {
    let [nx, ny, _] = n;
    let ng = part.n_global;
    // Local index along each axis of global index `g` (unwrapped: a ghost layer may be left
    // out, the exchange overwrites it).
    let offset = |a: usize| if a == part.axis { part.offset } else { 0 };
    for p in plans {
        // The local nodes of the layer along its axis, all of them along the others.
        let range = |a: usize| {
            let (lo, hi) = if a != p.face / 2 {
                return 0..n[a];
            } else if p.face.is_multiple_of(2) {
                (0, p.width.min(ng[a]))
            } else {
                (ng[a].saturating_sub(p.width), ng[a])
            };
            let local = |g: usize| (g as isize - offset(a)).clamp(0, n[a] as isize) as usize;
            local(lo)..local(hi)
        };
        if !range(2).contains(&z) {
            continue;
        }
        for y in range(1) {
            for x in range(0) {
                let s = p.sigma(part.global([x, y, z]), ng);
                if s == 0.0 || solid[(z * ny + y) * nx + x] {
                    continue;
                }
                for (i, e) in p.g_eq.iter().enumerate() {
                    let g = &mut plane[(i * ny + y) * nx + x];
                    *g -= s * (*g - e);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::lattice::D3q19;
    use super::*;

    #[test]
    fn sigma_ramps_quadratically_to_each_face() {
        let n = [10, 8, 6];
        for face in 0..6 {
            let p = Sponge3Plan::new::<19, D3q19>(&Sponge3 {
                face,
                width: 4,
                strength: 0.5,
                rho: 1.0,
                u: [0.0; 3],
            });
            let a = face / 2;
            let along = |k: usize| {
                let mut q = [1, 1, 1];
                q[a] = if face % 2 == 0 { k } else { n[a] - 1 - k };
                p.sigma(q, n)
            };
            assert_eq!(
                [along(0), along(1), along(2), along(3), along(4)],
                [0.5, 0.5 * 9.0 / 16.0, 0.5 * 4.0 / 16.0, 0.5 / 16.0, 0.0],
                "face {face}"
            );
        }
    }
}
