//! Absorbing layers of the 3D box: the 2D solver's (`crate::lbm::sponge`, Israeli & Orszag 1981)
//! on any of the six faces. After every collision the populations of a fluid node at depth `d`
//! into the layer (`d = 0` at its inner end, `1` at the face) relax towards the equilibrium of
//! the target state, `g_i <- g_i - sigma(d) (g_i - g_i^eq(rho_0, u_0))`,
//! `sigma(d) = sigma_max d^2`.

use std::ops::Range;

use super::collision::{equilibrium, CHUNK};
use super::lattice::Lattice3;
use crate::lbm::part::Part;

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

/// A layer ready for the step on one rank's box: its target equilibrium, the local indices it
/// covers along its axis and `sigma` at each of them, computed once.
#[derive(Clone, Debug)]
pub(crate) struct Sponge3Plan {
    face: usize,
    width: usize,
    strength: f32,
    g_eq: Vec<f32>,
    /// The layer's axis, `face / 2`.
    axis: usize,
    /// The local indices along `axis` the layer covers (all of them along the other axes).
    /// Unwrapped: a ghost layer may be left out, the exchange overwrites it.
    range: Range<usize>,
    /// `sigma` at each local index along `axis` (zero outside `range`).
    sigma: Vec<f32>,
}

impl Sponge3Plan {
    /// Layer `s` on the box of rank slab `part`.
    pub fn new<const Q: usize, L: Lattice3<Q>>(s: &Sponge3, part: &Part) -> Self {
        let (a, n, ng) = (s.face / 2, part.local_n(), part.n_global);
        let (lo, hi) = if s.face.is_multiple_of(2) {
            (0, s.width.min(ng[a]))
        } else {
            (ng[a].saturating_sub(s.width), ng[a])
        };
        let offset = if a == part.axis { part.offset } else { 0 };
        let local = |g: usize| (g as isize - offset).clamp(0, n[a] as isize) as usize;
        let mut plan = Sponge3Plan {
            face: s.face,
            width: s.width,
            strength: s.strength as f32,
            g_eq: equilibrium::<Q, L>((s.rho - 1.0) as f32, s.u.map(|v| v as f32)).to_vec(),
            axis: a,
            range: local(lo)..local(hi),
            sigma: vec![0.0; n[a]],
        };
        for v in plan.range.clone() {
            plan.sigma[v] = plan.sigma_at(part.global_index_along(a, v), ng[a]);
        }
        plan
    }

    /// `sigma` at node `p` of a box of `n` nodes, zero outside the layer.
    pub fn sigma(&self, p: [usize; 3], n: [usize; 3]) -> f32 {
        self.sigma_at(p[self.axis], n[self.axis])
    }

    /// `sigma` at index `v` along the layer's axis of `n` nodes.
    fn sigma_at(&self, v: usize, n: usize) -> f32 {
        let depth = if self.face.is_multiple_of(2) {
            self.width as isize - v as isize
        } else {
            v as isize + self.width as isize + 1 - n as isize
        };
        if depth <= 0 {
            return 0.0;
        }
        let d = depth as f32 / self.width as f32;
        self.strength * d * d
    }

    /// The local indices along axis `a` of a box of `n` nodes that the layer covers.
    fn local_range(&self, a: usize, n: [usize; 3]) -> Range<usize> {
        if a == self.axis {
            self.range.clone()
        } else {
            0..n[a]
        }
    }
}

/// The absorbing layers as the step's kernel applies them: to each chunk of a row's bulk loop
/// before it is stored ([`Self::chunk`]) and to each special fluid node after its collision
/// ([`Self::node`]), so that the layers cost no extra pass over memory (applied after a
/// non-temporal store they read it all back: half the time of the cylinder's 3D step went there).
/// Both give bitwise what [`apply_plane`] gives.
#[derive(Clone, Copy)]
pub(crate) struct Layers<'a>(pub &'a [Sponge3Plan]);

impl Layers<'_> {
    /// Applies every layer to nodes `x0 .. x0 + m` of row `(y, z)` held in `buf[i][x - x0]`.
    /// Solid and ghost nodes get values too; the specials overwrite them. (Inside its range a
    /// layer's sigma is never zero, so no test: the loops vectorise.)
    #[inline]
    pub fn chunk<const Q: usize>(&self, buf: &mut [[f32; CHUNK]; Q], x0: usize, m: usize, y: usize, z: usize) {
        for p in self.0 {
            if p.axis == 0 {
                let (lo, hi) = (p.range.start.max(x0), p.range.end.min(x0 + m));
                if lo >= hi {
                    continue;
                }
                for (row, e) in buf.iter_mut().zip(&p.g_eq) {
                    for (g, s) in row[lo - x0..hi - x0].iter_mut().zip(&p.sigma[lo..hi]) {
                        *g -= s * (*g - e);
                    }
                }
            } else {
                let v = if p.axis == 1 { y } else { z };
                if !p.range.contains(&v) {
                    continue;
                }
                let s = p.sigma[v];
                for (row, e) in buf.iter_mut().zip(&p.g_eq) {
                    for g in &mut row[..m] {
                        *g -= s * (*g - e);
                    }
                }
            }
        }
    }

    /// Applies every layer to the populations `g` of fluid node `q`.
    #[inline]
    pub fn node(&self, g: &mut [f32], q: [usize; 3]) {
        for p in self.0.iter().filter(|p| p.range.contains(&q[p.axis])) {
            let s = p.sigma[q[p.axis]];
            for (gi, e) in g.iter_mut().zip(&p.g_eq) {
                *gi -= s * (*gi - e);
            }
        }
    }
}

/// Applies every layer to the post-collision populations of plane `z` (`plane[(i ny + y) nx + x]`)
/// of this rank's box of `n` nodes (its slab of the global box, `part`) in a pass of its own,
/// with `sigma` from its formula: the oracle's way ([`Layers`] is the step's). Solid nodes are
/// left alone. Allocates nothing.
pub(crate) fn apply_plane(plans: &[Sponge3Plan], plane: &mut [f32], z: usize, n: [usize; 3], part: &Part, solid: &[bool]) {
    let [nx, ny, _] = n;
    for p in plans {
        if !p.local_range(2, n).contains(&z) {
            continue;
        }
        for y in p.local_range(1, n) {
            for x in p.local_range(0, n) {
                let s = p.sigma(part.global([x, y, z]), part.n_global);
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
            let s = Sponge3 {
                face,
                width: 4,
                strength: 0.5,
                rho: 1.0,
                u: [0.0; 3],
            };
            let p = Sponge3Plan::new::<19, D3q19>(&s, &Part::whole(n));
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
