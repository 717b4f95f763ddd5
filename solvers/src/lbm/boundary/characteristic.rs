//! Non-reflecting ("characteristic") velocity inlets.
//!
//! A lattice Boltzmann fluid is weakly compressible, and a [`Side::Velocity`] edge that imposes
//! a fixed velocity reflects every pressure wave that reaches it (it is acoustically a rigid
//! wall). Between such an inlet and a pressure outlet (`rho = 1`, a pressure-release end) the
//! domain is a quarter-wave resonator of length `L`: its modes sit at `St = (2m + 1) c_s D /
//! (4 L U)`, i.e. 0.072, 0.22, ... for a 40 D domain at `U = 0.05` (Mach 0.087), right where
//! bluff-body wakes shed, and a wake can lock onto them.
//!
//! The characteristic inlet lets the waves leave. In linear acoustics a plane wave leaving
//! through the inlet carries `u_n' = -c_s rho'` (inward normal `n`), so the inlet imposes
//!
//! `u_n = U_n - c_s (rho - rho_ref)`,  tangential `u_t = U_t`,
//!
//! with `rho` the density of the edge node: the incoming characteristic is fixed, the outgoing
//! one passes (Thompson, J. Comput. Phys. 68, 1987; for LBM e.g. Izquierdo & Fueyo, Phys. Rev.
//! E 78, 2008, and Heubes et al., J. Comput. Appl. Math. 262, 2014). `rho_ref` is the edge's
//! mean density averaged over a time constant `T` (an exponential moving average, one update per
//! step): the steady pressure rise at the inlet (the pressure drop the body's drag sustains)
//! then does not slow the inflow, while waves with periods well below `T` are absorbed (the
//! amplitude reflection falls like `1 / (2 pi f T)`).

use super::super::collision::moments;
use super::super::domain::{Edge, Side, Sides};
use super::super::post::Post;

/// `c_s`, the lattice speed of sound.
const CS: f32 = 0.577_350_3;

/// The reference densities of the characteristic inlets, one per edge (unused entries stay 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InletReference {
    /// `rho_ref` per edge, in [`edge_index`] order.
    pub rho: [f32; 4],
    /// `1 / T` in steps: the weight of the newest edge mean.
    pub weight: f32,
}

/// Position of `edge` in [`InletReference::rho`].
pub(crate) fn edge_index(edge: Edge) -> usize {
    match edge {
        Edge::West => 0,
        Edge::East => 1,
        Edge::South => 2,
        Edge::North => 3,
    }
}

impl InletReference {
    /// References at the rest density, averaging over `time_constant` steps (at least 1).
    pub fn new(time_constant: f64) -> Self {
        InletReference {
            rho: [1.0; 4],
            weight: (1.0 / time_constant.max(1.0)) as f32,
        }
    }

    /// The velocity to impose at a node of `edge` with density `rho`, given the profile's
    /// `(ux, uy)`: the normal component follows the outgoing wave.
    #[inline]
    pub(crate) fn velocity(&self, edge: Edge, rho: f32, ux: f32, uy: f32) -> (f32, f32) {
        let du = CS * (rho - self.rho[edge_index(edge)]);
        match edge {
            Edge::West => (ux - du, uy),
            Edge::East => (ux + du, uy),
            Edge::South => (ux, uy - du),
            Edge::North => (ux, uy + du),
        }
    }

    /// Sets each velocity edge's reference to its current mean density (after an initialisation).
    pub(crate) fn reset(&mut self, sides: &Sides, f: &Post, solid: &[bool], nx: usize, ny: usize) {
        for edge in [Edge::West, Edge::East, Edge::South, Edge::North] {
            if let Some(mean) = edge_mean_density(sides, edge, f, solid, nx, ny) {
                self.rho[edge_index(edge)] = mean;
            }
        }
    }

    /// One step of the moving average: `rho_ref += (mean - rho_ref) / T` on each velocity edge.
    /// Serial and in a fixed order, so bitwise the same for any thread count. Allocates nothing.
    pub(crate) fn update(&mut self, sides: &Sides, f: &Post, solid: &[bool], nx: usize, ny: usize) {
        for edge in [Edge::West, Edge::East, Edge::South, Edge::North] {
            if let Some(mean) = edge_mean_density(sides, edge, f, solid, nx, ny) {
                let r = &mut self.rho[edge_index(edge)];
                *r += self.weight * (mean - *r);
            }
        }
    }
}

/// Mean density of the fluid nodes along `edge` if it is a velocity edge (shifted populations).
fn edge_mean_density(sides: &Sides, edge: Edge, f: &Post, solid: &[bool], nx: usize, ny: usize) -> Option<f32> {
    if !matches!(sides.get(edge), Side::Velocity { .. }) {
        return None;
    }
    let len = match edge {
        Edge::West | Edge::East => ny,
        Edge::South | Edge::North => nx,
    };
    let (mut sum, mut n) = (0.0f64, 0usize);
    for i in 0..len {
        let (x, y) = match edge {
            Edge::West => (0, i),
            Edge::East => (nx - 1, i),
            Edge::South => (i, 0),
            Edge::North => (i, ny - 1),
        };
        if solid[y * nx + x] {
            continue;
        }
        sum += 1.0 + moments(&f.node(x, y)).0 as f64;
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64) as f32)
}
