//! Absorbing ("sponge") layers along domain edges.
//!
//! A lattice Boltzmann fluid is weakly compressible: pressure waves travel at `c_s = 1/sqrt 3`
//! lattice units and reflect off walls, free-slip sides and velocity inlets. In a closed-off
//! direction (a cavity floor under a free-slip top) they form an undamped standing wave. The
//! layer damps them before they reach the edge: after every collision, the post-collision
//! populations of a node at depth `d` into the layer (`d = 0` at its inner end, `1` at the edge)
//! relax towards the equilibrium of a target state,
//!
//! `g_i <- g_i - sigma(d) (g_i - g_i^eq(rho_0, u_0))`,  `sigma(d) = sigma_max d^2`,
//!
//! the absorbing-layer technique of Israeli & Orszag (J. Comput. Phys. 41, 1981), used for LBM
//! by e.g. Xu & Sagaut (J. Comput. Phys. 245, 2013). The quadratic ramp keeps the layer's own
//! reflection small; the target is the far-field state the edge stands for (free stream).

use super::collision::equilibrium;
use super::domain::Edge;
use super::lattice::Q;

/// One absorbing layer.
#[derive(Clone, Debug, PartialEq)]
pub struct Sponge {
    /// The edge the layer lines.
    pub edge: Edge,
    /// Thickness in nodes.
    pub width: usize,
    /// `sigma_max`, the relaxation per step at the edge, in (0, 1].
    pub strength: f64,
    /// Target density and velocity (lattice units).
    pub rho: f64,
    pub u: [f64; 2],
}

/// A layer ready for the step: the target equilibrium computed once.
#[derive(Clone, Debug)]
pub(crate) struct SpongePlan {
    pub edge: Edge,
    pub width: usize,
    pub strength: f32,
    pub g_eq: [f32; Q],
}

impl SpongePlan {
    pub fn new(s: &Sponge) -> Self {
        SpongePlan {
            edge: s.edge,
            width: s.width,
            strength: s.strength as f32,
            g_eq: equilibrium((s.rho - 1.0) as f32, s.u[0] as f32, s.u[1] as f32),
        }
    }

    /// `sigma` at node `(x, y)`, zero outside the layer.
    fn sigma(&self, x: usize, y: usize, nx: usize, ny: usize) -> f32 {
        let depth = match self.edge {
            Edge::West => self.width as isize - x as isize,
            Edge::East => x as isize + self.width as isize + 1 - nx as isize,
            Edge::South => self.width as isize - y as isize,
            Edge::North => y as isize + self.width as isize + 1 - ny as isize,
        };
        if depth <= 0 {
            return 0.0;
        }
        let d = depth as f32 / self.width as f32;
        self.strength * d * d
    }

    /// Whether row `y` has any node in the layer.
    fn touches_row(&self, y: usize, ny: usize) -> bool {
        match self.edge {
            Edge::West | Edge::East => true,
            Edge::South => y < self.width,
            Edge::North => y + self.width >= ny,
        }
    }
}

/// Applies every layer to one row of post-collision populations (row-blocked SoA:
/// `row[i * nx + x]`) at row `y` of a grid `nx` by `ny` (the whole grid's, when this is a
/// rank's slab); `solid_row[x]` marks the row's solid nodes, which are left alone. Allocates
/// nothing.
pub(crate) fn apply_row(plans: &[SpongePlan], row: &mut [f32], y: usize, nx: usize, ny: usize, solid_row: &[bool]) {
    apply_span(plans, row, nx, 0..nx, y, nx, ny, solid_row);
}

/// [`apply_row`] on the nodes `span` of row `y` only, node `x`'s population `i` at
/// `values[i * stride + x - span.start]`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn apply_span(
    plans: &[SpongePlan],
    values: &mut [f32],
    stride: usize,
    span: std::ops::Range<usize>,
    y: usize,
    nx: usize,
    ny: usize,
    solid_row: &[bool],
) {
    for p in plans.iter().filter(|p| p.touches_row(y, ny)) {
        let xs = match p.edge {
            Edge::West => 0..p.width.min(nx),
            Edge::East => nx.saturating_sub(p.width)..nx,
            Edge::South | Edge::North => 0..nx,
        };
        for x in xs.start.max(span.start)..xs.end.min(span.end) {
            let s = p.sigma(x, y, nx, ny);
            if s == 0.0 || solid_row[x] {
                continue;
            }
            for (i, e) in p.g_eq.iter().enumerate() {
                let g = &mut values[i * stride + x - span.start];
                *g -= s * (*g - e);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(edge: Edge) -> SpongePlan {
        SpongePlan::new(&Sponge {
            edge,
            width: 4,
            strength: 0.5,
            rho: 1.0,
            u: [0.0, 0.0],
        })
    }

    #[test]
    fn sigma_ramps_quadratically_to_the_edge_on_every_side() {
        let (nx, ny) = (20, 10);
        let north = plan(Edge::North);
        let depths: Vec<f32> = (0..ny).map(|y| north.sigma(3, y, nx, ny)).collect();
        assert_eq!(&depths[..6], &[0.0; 6]);
        assert_eq!(&depths[6..], &[0.5 / 16.0, 0.5 * 4.0 / 16.0, 0.5 * 9.0 / 16.0, 0.5]);
        // Mirror images: the south layer at y equals the north layer at ny - 1 - y.
        let south = plan(Edge::South);
        let west = plan(Edge::West);
        let east = plan(Edge::East);
        for y in 0..ny {
            assert_eq!(south.sigma(3, y, nx, ny), north.sigma(3, ny - 1 - y, nx, ny));
        }
        for x in 0..nx {
            assert_eq!(west.sigma(x, 2, nx, ny), east.sigma(nx - 1 - x, 2, nx, ny));
        }
        assert_eq!(west.sigma(0, 2, nx, ny), 0.5);
    }

    #[test]
    fn a_node_at_the_target_state_is_left_unchanged_and_others_move_towards_it() {
        let (nx, ny) = (6, 6);
        let p = plan(Edge::North);
        let mut row = vec![0.0f32; Q * nx];
        for x in 0..nx {
            for i in 0..Q {
                row[i * nx + x] = if x == 0 { p.g_eq[i] } else { p.g_eq[i] + 0.01 };
            }
        }
        apply_row(std::slice::from_ref(&p), &mut row, ny - 1, nx, ny, &[false; 6]);
        for i in 0..Q {
            assert_eq!(row[i * nx], p.g_eq[i]);
            assert!((row[i * nx + 1] - p.g_eq[i] - 0.005).abs() < 1e-7);
        }
    }
}
