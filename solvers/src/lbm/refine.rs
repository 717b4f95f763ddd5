//! Two-level local grid refinement (2:1) of the D2Q9 solver: a fine patch around the bodies,
//! embedded in the coarse grid that covers the whole domain.
//!
//! The scheme is the vertex-centred coupling of Lagrava, Malaspinas, Latt & Chopard (J. Comput.
//! Phys. 231, 4808, 2012) with the regularised populations of Latt & Chopard (2006) at the
//! interface. Both grids carry the same physical viscosity in convective scaling
//! (`dx_f = dx_c / 2`, `dt_f = dt_c / 2`, lattice velocities equal), so
//! `tau_f - 1/2 = 2 (tau_c - 1/2)`, and the non-equilibrium stress, `Pi^neq = -2 rho c_s^2 tau S dt`,
//! scales between the grids as `Pi_f = Pi_c tau_f / (2 tau_c)`.
//!
//! One coarse step `t -> t + 1`:
//! 1. the coarse grid steps everywhere (its nodes under the patch hold the fine solution, see 4);
//! 2. on the patch's four edge lines (coarse nodes) the density, velocity and post-collision
//!    stress are read before and after the step;
//! 3. the fine grid steps twice; after each sub-step its outermost ring of nodes (which lie on
//!    the coarse edge lines: every other one on a coarse node, the rest half-way between two) is
//!    overwritten with populations rebuilt from the coarse moments, interpolated in space
//!    (cubic along the line, linear at its ends) and in time (linear, `t + 1/2`);
//! 4. every coarse node strictly inside the patch takes the moments of the fine node on top of
//!    it (restriction).
//!
//! Both grids store post-collision populations. After a regularised collision these are
//! `g^eq + (1 - omega) Pi^neq` projected on the Hermite polynomials ([`hermite_stress`] reads the
//! stress back, [`hermite_populations`] rebuilds them), so a post-collision stress converts as
//! `Pi*_f = Pi*_c (tau_f - 1) / (2 (tau_c - 1))`. That is singular where either relaxation time
//! is 1 (the post-collision stress vanishes there), so such set-ups are refused; the flows that
//! need refinement run at `tau` close to 1/2. BGK runs too: the interface keeps only the Hermite
//! part of its non-equilibrium populations.
//!
//! Bodies live on the fine grid (forces come from there); the coarse grid marks them solid too,
//! but its nodes near them are overwritten each step. Sponges and domain edges stay on the coarse
//! grid; the patch must stay clear of them. The coupling conserves mass only to the truncation
//! error of the interpolation (no flux correction), as in Lagrava et al.

use std::sync::Arc;

use super::collision::{hermite_populations, hermite_stress};
use super::domain::{Edge, Grid, Sides};
use super::error::LbmError;
use super::solver::{D2q9, D2q9Config};
use crate::geometry::Shape;

/// The refined rectangle in coarse node indices, both ends included.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Patch {
    pub x: [usize; 2],
    pub y: [usize; 2],
}

/// Density deviation, velocity and post-collision Hermite stress `[xx, yy, xy]` of one node.
type Moments = [f32; 6];

/// Nodes the patch keeps between a body and its edge, and between its edge and the domain's.
const BODY_MARGIN_FINE: usize = 4;
const EDGE_MARGIN_COARSE: usize = 2;

/// A coarse D2Q9 grid with one fine patch (see the module docs).
pub struct Refined {
    coarse: D2q9,
    fine: D2q9,
    patch: Patch,
    /// Post-collision stress factors coarse -> fine and fine -> coarse.
    c2f: f32,
    f2c: f32,
    /// Coarse moments on the patch's edge lines (south, north: along x; west, east: along y) at
    /// the start (`old`) and the end (`new`) of the current coarse step.
    old: [Vec<Moments>; 4],
    new: [Vec<Moments>; 4],
    /// Mean force of the two fine sub-steps, in coarse lattice units.
    forces: Vec<[f64; 2]>,
}

impl std::fmt::Debug for Refined {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Refined")
            .field("coarse", &self.coarse)
            .field("fine", &self.fine)
            .field("patch", &self.patch)
            .finish()
    }
}

fn config_error(message: impl Into<String>) -> LbmError {
    LbmError::Config {
        field: "refinement",
        message: message.into(),
    }
}

impl Refined {
    /// Plans both grids: `cfg` is the coarse grid over the whole domain, `patch` the refined
    /// rectangle (which must contain every body with a margin and stay clear of the domain's
    /// edges and absorbing layers).
    pub fn new(cfg: D2q9Config, patch: Patch, bodies: Vec<Arc<dyn Shape>>) -> Result<Self, LbmError> {
        let (nx, ny) = (cfg.nx, cfg.ny);
        let [x0, x1] = patch.x;
        let [y0, y1] = patch.y;
        if x1 < x0 + 4 || y1 < y0 + 4 {
            return Err(config_error(format!(
                "the patch x {x0}..={x1}, y {y0}..={y1} (coarse nodes) must span at least 4 coarse cells each way"
            )));
        }
        let m = EDGE_MARGIN_COARSE;
        if x0 < m || y0 < m || x1 + m >= nx || y1 + m >= ny {
            return Err(config_error(format!(
                "the patch x {x0}..={x1}, y {y0}..={y1} must keep {m} coarse nodes from the domain's edges (0..{nx} x 0..{ny})"
            )));
        }
        for sp in &cfg.sponges {
            let clear = match sp.edge {
                Edge::West => x0 > sp.width + m,
                Edge::East => x1 + sp.width + m < nx,
                Edge::South => y0 > sp.width + m,
                Edge::North => y1 + sp.width + m < ny,
            };
            if !clear {
                return Err(config_error(format!(
                    "the patch overlaps the {} absorbing layer ({} nodes); move it or thin the layer",
                    sp.edge.name(),
                    sp.width
                )));
            }
        }
        if cfg.smagorinsky != 0.0 {
            return Err(config_error(
                "the subgrid model is not coupled across the interface yet; refine without smagorinsky",
            ));
        }
        if cfg.body_force != [0.0, 0.0] {
            return Err(config_error("a body force is not coupled across the interface yet"));
        }
        let tau_c = cfg.tau;
        let tau_f = 0.5 + 2.0 * (tau_c - 0.5);
        if (tau_c - 1.0).abs() < 0.05 || (tau_f - 1.0).abs() < 0.05 {
            return Err(config_error(format!(
                "tau = {tau_c:.4} (fine grid {tau_f:.4}): the coupling rebuilds the stress from post-collision \
                 populations, which carry none at tau = 1; keep both relaxation times 0.05 away from 1 \
                 (change the lattice velocity)"
            )));
        }
        let mut fine_cfg = D2q9Config::new(2 * (x1 - x0) + 1, 2 * (y1 - y0) + 1, tau_f, Sides::periodic());
        fine_cfg.collision = cfg.collision;
        fine_cfg.grid = Grid {
            origin: cfg.grid.position(x0 as f64, y0 as f64),
            dx: 0.5 * cfg.grid.dx,
        };
        fine_cfg.check_interval = 2 * cfg.check_interval;
        fine_cfg.rho_bounds = cfg.rho_bounds;
        fine_cfg.u_max = cfg.u_max;
        fine_cfg.stream_stores = cfg.stream_stores;
        let fine = D2q9::new(fine_cfg, bodies.clone())?;
        let coarse = D2q9::new(cfg, bodies)?;

        let (fx, fy) = (fine.nx(), fine.ny());
        for y in 0..fy {
            for x in 0..fx {
                let near_edge = x < BODY_MARGIN_FINE || y < BODY_MARGIN_FINE || x + BODY_MARGIN_FINE >= fx || y + BODY_MARGIN_FINE >= fy;
                if near_edge && fine.is_solid(x, y) {
                    return Err(config_error(format!(
                        "a body reaches within {BODY_MARGIN_FINE} fine nodes of the patch's edge; enlarge the patch"
                    )));
                }
            }
        }
        for y in 0..ny {
            for x in 0..nx {
                let inside = x > x0 + 1 && x + 1 < x1 && y > y0 + 1 && y + 1 < y1;
                if coarse.is_solid(x, y) && !inside {
                    return Err(config_error(format!(
                        "coarse node ({x}, {y}) is inside a body but outside the patch; every body must lie in the patch"
                    )));
                }
            }
        }

        let n_bodies = coarse.bodies().len();
        let lines = [x1 - x0 + 1, x1 - x0 + 1, y1 - y0 + 1, y1 - y0 + 1];
        let mut r = Refined {
            coarse,
            fine,
            patch,
            c2f: ((tau_f - 1.0) / (2.0 * (tau_c - 1.0))) as f32,
            f2c: ((2.0 * (tau_c - 1.0)) / (tau_f - 1.0)) as f32,
            old: lines.map(|n| vec![[0.0; 6]; n]),
            new: lines.map(|n| vec![[0.0; 6]; n]),
            forces: vec![[0.0; 2]; n_bodies],
        };
        r.init_with(|_, _| (1.0, 0.0, 0.0));
        Ok(r)
    }

    /// Sets both grids to the equilibrium of `(rho, ux, uy) = field(x, y)` (physical position,
    /// lattice density and velocity, the same on both grids); resets the time.
    pub fn init_with(&mut self, mut field: impl FnMut(f64, f64) -> (f64, f64, f64)) {
        self.coarse.init_with(&mut field);
        self.fine.init_with(&mut field);
        self.read_edges();
        self.old.clone_from(&self.new);
    }

    /// One coarse step (two fine sub-steps). Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        std::mem::swap(&mut self.old, &mut self.new);
        self.coarse.step()?;
        self.read_edges();
        for f in self.forces.iter_mut() {
            *f = [0.0; 2];
        }
        for theta in [0.5f32, 1.0] {
            if let Err(e) = self.fine.step() {
                return Err(self.on_fine(e));
            }
            for (acc, f) in self.forces.iter_mut().zip(self.fine.body_forces()) {
                // Mean of the two sub-steps, and a fine-lattice force is half the coarse-lattice
                // force with the same coefficient (the reference length doubles).
                acc[0] += 0.25 * f[0];
                acc[1] += 0.25 * f[1];
            }
            self.write_ring(theta);
        }
        self.restrict();
        Ok(())
    }

    /// Advances `n` coarse steps.
    pub fn advance(&mut self, n: u64) -> Result<(), LbmError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// A fine-grid divergence, located on the coarse grid.
    fn on_fine(&self, e: LbmError) -> LbmError {
        match e {
            LbmError::Diverged { reason, x, y, .. } => LbmError::Diverged {
                step: self.coarse.time(),
                reason: format!("{reason} (fine patch)"),
                x: self.patch.x[0] + x / 2,
                y: self.patch.y[0] + y / 2,
            },
            other => other,
        }
    }

    /// Reads the coarse moments on the four edge lines into `new`.
    fn read_edges(&mut self) {
        let [x0, x1] = self.patch.x;
        let [y0, y1] = self.patch.y;
        let c = &self.coarse;
        let read = |x: usize, y: usize| -> Moments {
            let (d, ux, uy, q) = hermite_stress(&c.node_populations(x, y));
            [d, ux, uy, q[0], q[1], q[2]]
        };
        let [south, north, west, east] = &mut self.new;
        for (k, x) in (x0..=x1).enumerate() {
            south[k] = read(x, y0);
            north[k] = read(x, y1);
        }
        for (k, y) in (y0..=y1).enumerate() {
            west[k] = read(x0, y);
            east[k] = read(x1, y);
        }
    }

    /// Overwrites the fine grid's outer ring with populations rebuilt from the coarse edge
    /// moments at time `t + theta` (coarse steps).
    fn write_ring(&mut self, theta: f32) {
        let (fx, fy) = (self.fine.nx(), self.fine.ny());
        let c2f = self.c2f;
        let (old, new) = (&self.old, &self.new);
        let at = |line: usize, i: usize| -> [f32; super::lattice::Q] {
            let a = interp(&old[line], i);
            let b = interp(&new[line], i);
            let m: Moments = std::array::from_fn(|k| (1.0 - theta) * a[k] + theta * b[k]);
            hermite_populations(m[0], m[1], m[2], [c2f * m[3], c2f * m[4], c2f * m[5]])
        };
        for i in 0..fx {
            let s = at(0, i);
            let n = at(1, i);
            self.fine.set_node_populations(i, 0, &s);
            self.fine.set_node_populations(i, fy - 1, &n);
        }
        for j in 1..fy - 1 {
            let w = at(2, j);
            let e = at(3, j);
            self.fine.set_node_populations(0, j, &w);
            self.fine.set_node_populations(fx - 1, j, &e);
        }
    }

    /// Gives every coarse node strictly inside the patch the moments of the fine node on it.
    fn restrict(&mut self) {
        let [x0, x1] = self.patch.x;
        let [y0, y1] = self.patch.y;
        let f2c = self.f2c;
        for y in y0 + 1..y1 {
            for x in x0 + 1..x1 {
                let (xf, yf) = (2 * (x - x0), 2 * (y - y0));
                if self.fine.is_solid(xf, yf) || self.coarse.is_solid(x, y) {
                    continue;
                }
                let (d, ux, uy, q) = hermite_stress(&self.fine.node_populations(xf, yf));
                let g = hermite_populations(d, ux, uy, [f2c * q[0], f2c * q[1], f2c * q[2]]);
                self.coarse.set_node_populations(x, y, &g);
            }
        }
    }

    /// Hydrodynamic force on each body (from the fine grid), averaged over the last coarse step
    /// and expressed in coarse lattice units, so coefficients use the coarse reference length.
    pub fn body_forces(&self) -> &[[f64; 2]] {
        &self.forces
    }

    /// Multiplies the coarse grid's velocity sides by `scale` (inlet ramps).
    pub fn set_boundary_velocity_scale(&mut self, scale: f64) {
        self.coarse.set_boundary_velocity_scale(scale);
    }

    pub fn coarse(&self) -> &D2q9 {
        &self.coarse
    }

    pub fn fine(&self) -> &D2q9 {
        &self.fine
    }

    pub fn patch(&self) -> Patch {
        self.patch
    }

    /// Coarse steps since the last initialisation.
    pub fn time(&self) -> u64 {
        self.coarse.time()
    }

    /// Node updates per coarse step (coarse fluid nodes plus twice the fine ones), for MLUPS.
    pub fn node_updates_per_step(&self) -> usize {
        self.coarse.fluid_nodes() + 2 * self.fine.fluid_nodes()
    }
}

/// Moments at fine index `i` along a coarse line (`i / 2` in coarse nodes): the node itself at
/// even `i`, else the 4-point cubic `(-1, 9, 9, -1) / 16` between nodes, linear at the ends.
#[inline]
fn interp(line: &[Moments], i: usize) -> Moments {
    let k = i / 2;
    if i.is_multiple_of(2) {
        return line[k];
    }
    if k >= 1 && k + 2 < line.len() {
        let (a, b, c, d) = (line[k - 1], line[k], line[k + 1], line[k + 2]);
        std::array::from_fn(|n| (9.0 * (b[n] + c[n]) - (a[n] + d[n])) * (1.0 / 16.0))
    } else {
        let (b, c) = (line[k], line[k + 1]);
        std::array::from_fn(|n| 0.5 * (b[n] + c[n]))
    }
}
