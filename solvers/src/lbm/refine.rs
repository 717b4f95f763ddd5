//! Local grid refinement (2:1 per level) of the D2Q9 solver: nested fine patches around the
//! bodies, embedded in the coarse grid that covers the whole domain.
//!
//! The scheme is the vertex-centred coupling of Lagrava, Malaspinas, Latt & Chopard (J. Comput.
//! Phys. 231, 4808, 2012) with the regularised populations of Latt & Chopard (2006) at the
//! interface. Both grids carry the same physical viscosity in convective scaling
//! (`dx_f = dx_c / 2`, `dt_f = dt_c / 2`, lattice velocities equal), so
//! `tau_f - 1/2 = 2 (tau_c - 1/2)`, and the non-equilibrium stress, `Pi^neq = -2 rho c_s^2 tau S dt`,
//! scales between the grids as `Pi_f = Pi_c tau_f / (2 tau_c)`.
//!
//! One step `t -> t + 1` of a grid with a patch (applied recursively through the levels):
//! 1. the coarse grid steps everywhere (its nodes under the patch hold the fine solution, see 4);
//! 2. on the patch's four edge lines (coarse nodes) the density, velocity and post-collision
//!    stress are read before and after the step;
//! 3. the fine grid steps twice; after each sub-step its outermost ring of nodes (which lie on
//!    the coarse edge lines: every other one on a coarse node, the rest half-way between two) is
//!    overwritten with populations rebuilt from the coarse moments, interpolated in space
//!    (cubic along the line, linear at its ends) and in time (linear, `t + 1/2`);
//! 4. the coarse nodes strictly inside the patch take the moments of the fine node on top of
//!    them (restriction): the ring next to the edge lines every step, the whole interior every
//!    [`FULL_RESTRICTION_EVERY`] steps and on [`Refined::sync`] (only the ring feeds the
//!    coupling; see the constant).
//!
//! Both grids store post-collision populations. After a regularised collision these are
//! `g^eq + (1 - omega) Pi^neq` projected on the Hermite polynomials ([`hermite_stress`] reads the
//! stress back, [`hermite_populations`] rebuilds them), so a post-collision stress converts as
//! `Pi*_f = Pi*_c (tau_f - 1) / (2 (tau_c - 1))`, with the local relaxation times of the
//! Smagorinsky model when it is on ([`StressMap`]). That is singular where a relaxation time is 1
//! (the post-collision stress vanishes there), so such set-ups are refused; the flows that need
//! refinement run at `tau` close to 1/2. BGK runs too: the interface keeps only the Hermite part
//! of its non-equilibrium populations. With the recursive-regularised operator the rebuilt
//! populations also get the third- and fourth-order terms that operator's collision writes,
//! computed from the converted stress, so they are what a collision on that grid would produce.
//!
//! Bodies live on the finest grid (forces come from there); the coarser grids mark them solid
//! too, but their nodes near them are overwritten each step. Sponges and domain edges stay on the coarse
//! grid; the patch must stay clear of them. The coupling conserves mass only to the truncation
//! error of the interpolation (no flux correction), as in Lagrava et al.

use std::sync::Arc;

use super::aa::Propagation;
use super::collision::{add_third_and_fourth_order, hermite_populations, hermite_stress, Collision};
use super::domain::{Edge, Grid, Sides};
use super::error::LbmError;
use super::lattice::Q;
use super::solver::{D2q9, D2q9Config};
use crate::geometry::Shape;

/// A refined rectangle in the node indices of the grid it refines, both ends included.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Patch {
    pub x: [usize; 2],
    pub y: [usize; 2],
}

/// Density deviation, velocity and post-collision Hermite stress `[xx, yy, xy]` of one node.
type Moments = [f32; 6];

/// Nodes a patch keeps between a body and its edge, and between its edge and the edge of the
/// grid it refines.
const BODY_MARGIN_FINE: usize = 4;
const EDGE_MARGIN_COARSE: usize = 2;

/// The coupling between grid `l` and the patch `l + 1` inside it.
struct Coupling {
    /// The patch in grid `l`'s node indices.
    patch: Patch,
    /// Stress conversion between the two grids' post-collision states.
    convert: StressMap,
    /// Whether the grids run the recursive-regularised operator, whose post-collision
    /// populations also carry third- and fourth-order Hermite terms (rebuilt from the same
    /// moments, see [`rebuild`]).
    recursive: bool,
    /// Grid `l`'s moments on the patch's edge lines (south, north: along x; west, east: along
    /// y) at the start (`old`) and the end (`new`) of grid `l`'s current step.
    old: [Vec<Moments>; 4],
    new: [Vec<Moments>; 4],
}

/// A D2Q9 grid over the whole domain with nested 2:1 patches around the bodies (see the module
/// docs): level 0 is the coarse grid, each further level refines a rectangle of the one before.
pub struct Refined {
    levels: Vec<D2q9>,
    couplings: Vec<Coupling>,
    /// Mean force over the last coarse step, from the finest level, in coarse lattice units.
    forces: Vec<[f64; 2]>,
}

impl std::fmt::Debug for Refined {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Refined")
            .field("levels", &self.levels)
            .field("patches", &self.couplings.iter().map(|c| c.patch).collect::<Vec<_>>())
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
    /// Plans every grid: `cfg` is the coarse grid over the whole domain; `patches[0]` refines a
    /// rectangle of it (coarse node indices), `patches[1]` a rectangle of that patch (its node
    /// indices), and so on. The finest patch must contain every body with a margin; each patch
    /// stays clear of the edges of the grid it refines and of the absorbing layers.
    pub fn new(cfg: D2q9Config, patches: &[Patch], bodies: Vec<Arc<dyn Shape>>) -> Result<Self, LbmError> {
        if patches.is_empty() {
            return Err(config_error("at least one patch is needed (use D2q9 for a uniform grid)"));
        }
        if cfg.body_force != [0.0, 0.0] {
            return Err(config_error("a body force is not coupled across the interface yet"));
        }
        for sp in &cfg.sponges {
            let p = patches[0];
            let (nx, ny, m) = (cfg.nx, cfg.ny, EDGE_MARGIN_COARSE);
            let clear = match sp.edge {
                Edge::West => p.x[0] > sp.width + m,
                Edge::East => p.x[1] + sp.width + m < nx,
                Edge::South => p.y[0] > sp.width + m,
                Edge::North => p.y[1] + sp.width + m < ny,
            };
            if !clear {
                return Err(config_error(format!(
                    "the patch overlaps the {} absorbing layer ({} nodes); move it or thin the layer",
                    sp.edge.name(),
                    sp.width
                )));
            }
        }
        let mut cfgs = vec![cfg];
        for (l, p) in patches.iter().enumerate() {
            let parent = &cfgs[l];
            let (nx, ny) = (parent.nx, parent.ny);
            let ([x0, x1], [y0, y1]) = (p.x, p.y);
            if x1 < x0 + 4 || y1 < y0 + 4 {
                return Err(config_error(format!(
                    "patch {} (x {x0}..={x1}, y {y0}..={y1} in level {l}'s nodes) must span at least 4 cells each way",
                    l + 1
                )));
            }
            let m = EDGE_MARGIN_COARSE;
            if x0 < m || y0 < m || x1 + m >= nx || y1 + m >= ny {
                return Err(config_error(format!(
                    "patch {} (x {x0}..={x1}, y {y0}..={y1}) must keep {m} nodes from the edges of level {l} (0..{nx} x 0..{ny})",
                    l + 1
                )));
            }
            let tau_c = parent.tau;
            let tau_f = 0.5 + 2.0 * (tau_c - 0.5);
            if (tau_c - 1.0).abs() < 0.05 || (tau_f - 1.0).abs() < 0.05 {
                return Err(config_error(format!(
                    "tau = {tau_c:.4} on level {l}, {tau_f:.4} on level {}: the coupling rebuilds the stress from \
                     post-collision populations, which carry none at tau = 1; keep every level's relaxation time 0.05 \
                     away from 1 (change the lattice velocity or the number of levels)",
                    l + 1
                )));
            }
            let mut fine = D2q9Config::new(2 * (x1 - x0) + 1, 2 * (y1 - y0) + 1, tau_f, Sides::periodic());
            fine.collision = parent.collision;
            fine.smagorinsky = parent.smagorinsky;
            fine.grid = Grid {
                origin: parent.grid.position(x0 as f64, y0 as f64),
                dx: 0.5 * parent.grid.dx,
            };
            fine.check_interval = 2 * parent.check_interval;
            fine.rho_bounds = parent.rho_bounds;
            fine.u_max = parent.u_max;
            fine.stream_stores = parent.stream_stores;
            cfgs.push(fine);
        }
        // The coupling reads and rewrites canonical rows (`D2q9::row`, `rewrite_rows`).
        let levels = cfgs
            .into_iter()
            .map(|c| {
                D2q9::new(
                    D2q9Config {
                        propagation: Some(Propagation::Pull),
                        ..c
                    },
                    bodies.clone(),
                )
            })
            .collect::<Result<Vec<_>, _>>()?;

        let finest = &levels[levels.len() - 1];
        let (fx, fy) = (finest.nx(), finest.ny());
        let k = BODY_MARGIN_FINE;
        for y in 0..fy {
            for x in 0..fx {
                if (x < k || y < k || x + k >= fx || y + k >= fy) && finest.is_solid(x, y) {
                    return Err(config_error(format!(
                        "a body reaches within {k} nodes of the finest patch's edge; enlarge the patch"
                    )));
                }
            }
        }
        for (l, p) in patches.iter().enumerate() {
            let grid = &levels[l];
            for y in 0..grid.ny() {
                for x in 0..grid.nx() {
                    let inside = x > p.x[0] + 1 && x + 1 < p.x[1] && y > p.y[0] + 1 && y + 1 < p.y[1];
                    if grid.is_solid(x, y) && !inside {
                        return Err(config_error(format!(
                            "node ({x}, {y}) of level {l} is inside a body but outside patch {}; every body must lie in \
                             every patch",
                            l + 1
                        )));
                    }
                }
            }
        }

        let couplings = patches
            .iter()
            .zip(&levels)
            .map(|(p, coarse)| {
                let tau_c = coarse.config().tau;
                let tau_f = 0.5 + 2.0 * (tau_c - 0.5);
                let lines = [p.x[1] - p.x[0] + 1, p.x[1] - p.x[0] + 1, p.y[1] - p.y[0] + 1, p.y[1] - p.y[0] + 1];
                Coupling {
                    patch: *p,
                    convert: StressMap::new(tau_c, tau_f, coarse.config().smagorinsky),
                    recursive: coarse.config().collision == Collision::Recursive,
                    old: lines.map(|n| vec![[0.0; 6]; n]),
                    new: lines.map(|n| vec![[0.0; 6]; n]),
                }
            })
            .collect();
        let n_bodies = levels[0].bodies().len();
        let mut r = Refined {
            levels,
            couplings,
            forces: vec![[0.0; 2]; n_bodies],
        };
        r.init_with(|_, _| (1.0, 0.0, 0.0));
        Ok(r)
    }

    /// Sets every grid to the equilibrium of `(rho, ux, uy) = field(x, y)` (physical position,
    /// lattice density and velocity, the same on all grids); resets the time.
    pub fn init_with(&mut self, mut field: impl FnMut(f64, f64) -> (f64, f64, f64)) {
        for grid in &mut self.levels {
            grid.init_with(&mut field);
        }
        for l in 0..self.couplings.len() {
            read_edges(&self.levels[l], &mut self.couplings[l]);
            let c = &mut self.couplings[l];
            c.old.clone_from(&c.new);
        }
    }

    /// One coarse step (`2^l` steps of level `l`). Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        for f in self.forces.iter_mut() {
            *f = [0.0; 2];
        }
        self.step_level(0)
    }

    /// One step of level `l` and, recursively, two of every finer level.
    fn step_level(&mut self, l: usize) -> Result<(), LbmError> {
        if let Err(e) = self.levels[l].step() {
            return Err(self.located(l, e));
        }
        if l + 1 == self.levels.len() {
            // Mean over the 2^l sub-steps, and a force on level l is 2^-l times the coarse-lattice
            // force with the same coefficient (the reference length doubles per level).
            let w = 0.25f64.powi(l as i32);
            for (acc, f) in self.forces.iter_mut().zip(self.levels[l].body_forces()) {
                acc[0] += w * f[0];
                acc[1] += w * f[1];
            }
            return Ok(());
        }
        {
            let c = &mut self.couplings[l];
            std::mem::swap(&mut c.old, &mut c.new);
            read_edges(&self.levels[l], c);
        }
        for theta in [0.5f32, 1.0] {
            self.step_level(l + 1)?;
            write_ring(&mut self.levels[l + 1], &self.couplings[l], theta);
        }
        let interior = self.levels[l].time().is_multiple_of(FULL_RESTRICTION_EVERY);
        let (coarse, fine) = self.levels.split_at_mut(l + 1);
        restrict(&mut coarse[l], &fine[0], &self.couplings[l], interior);
        Ok(())
    }

    /// Gives every coarser grid the finer solution under its patches (finest first), which
    /// [`step`](Self::step) does only every [`FULL_RESTRICTION_EVERY`] steps away from the patch
    /// edges. Call it before reading a coarser grid's fields under a patch; the solution itself
    /// does not change.
    pub fn sync(&mut self) {
        for l in (0..self.couplings.len()).rev() {
            let (coarse, fine) = self.levels.split_at_mut(l + 1);
            restrict(&mut coarse[l], &fine[0], &self.couplings[l], true);
        }
    }

    /// Advances `n` coarse steps.
    pub fn advance(&mut self, n: u64) -> Result<(), LbmError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// A divergence on level `l`, located on the coarse grid.
    fn located(&self, l: usize, e: LbmError) -> LbmError {
        match e {
            LbmError::Diverged { reason, mut x, mut y, .. } if l > 0 => {
                for c in self.couplings[..l].iter().rev() {
                    x = c.patch.x[0] + x / 2;
                    y = c.patch.y[0] + y / 2;
                }
                LbmError::Diverged {
                    step: self.levels[0].time(),
                    reason: format!("{reason} (refinement level {l})"),
                    x,
                    y,
                }
            }
            other => other,
        }
    }

    /// Hydrodynamic force on each body (from the finest level), averaged over the last coarse
    /// step and expressed in coarse lattice units, so coefficients use the coarse reference
    /// length.
    pub fn body_forces(&self) -> &[[f64; 2]] {
        &self.forces
    }

    /// Multiplies the coarse grid's velocity sides by `scale` (inlet ramps).
    pub fn set_boundary_velocity_scale(&mut self, scale: f64) {
        self.levels[0].set_boundary_velocity_scale(scale);
    }

    /// The grid over the whole domain. Under the patches it holds the fine solution as of the last
    /// full restriction: call [`sync`](Self::sync) before reading its fields there.
    pub fn coarse(&self) -> &D2q9 {
        &self.levels[0]
    }

    /// The finest patch.
    pub fn fine(&self) -> &D2q9 {
        &self.levels[self.levels.len() - 1]
    }

    /// Every grid, coarse first (under each patch, see [`coarse`](Self::coarse)).
    pub fn levels(&self) -> &[D2q9] {
        &self.levels
    }

    /// Coarse steps since the last initialisation.
    pub fn time(&self) -> u64 {
        self.levels[0].time()
    }

    /// Node updates per coarse step (level `l`'s fluid nodes count `2^l` times), for MLUPS.
    pub fn node_updates_per_step(&self) -> usize {
        self.levels.iter().enumerate().map(|(l, g)| g.fluid_nodes() << l).sum()
    }
}

/// Reads grid `coarse`'s moments on the patch's four edge lines into `c.new`.
fn read_edges(coarse: &D2q9, c: &mut Coupling) {
    let [x0, x1] = c.patch.x;
    let [y0, y1] = c.patch.y;
    let read = |x: usize, y: usize| -> Moments {
        let (d, ux, uy, q) = hermite_stress(&coarse.node_populations(x, y));
        [d, ux, uy, q[0], q[1], q[2]]
    };
    let [south, north, west, east] = &mut c.new;
    for (k, x) in (x0..=x1).enumerate() {
        south[k] = read(x, y0);
        north[k] = read(x, y1);
    }
    for (k, y) in (y0..=y1).enumerate() {
        west[k] = read(x0, y);
        east[k] = read(x1, y);
    }
}

/// Overwrites the patch's outer ring with populations rebuilt from the coarse edge moments at
/// time `t + theta` (coarse steps).
fn write_ring(fine: &mut D2q9, c: &Coupling, theta: f32) {
    let (fx, fy) = (fine.nx(), fine.ny());
    let at = |line: usize, i: usize| -> [f32; Q] {
        let a = interp(&c.old[line], i);
        let b = interp(&c.new[line], i);
        let m: Moments = std::array::from_fn(|k| (1.0 - theta) * a[k] + theta * b[k]);
        let q = c.convert.to_fine(1.0 + m[0], [m[3], m[4], m[5]]);
        rebuild(m[0], m[1], m[2], q, c.recursive)
    };
    for i in 0..fx {
        fine.set_node_populations(i, 0, &at(0, i));
        fine.set_node_populations(i, fy - 1, &at(1, i));
    }
    for j in 1..fy - 1 {
        fine.set_node_populations(0, j, &at(2, j));
        fine.set_node_populations(fx - 1, j, &at(3, j));
    }
}

/// Nodes of a row restricted together: gathered from the fine row, converted in a branch-free
/// loop the compiler vectorises, written back where both nodes are fluid.
const RESTRICT_CHUNK: usize = 64;

/// Coarse steps between two restrictions of a patch's whole interior; the ring next to its edge
/// lines is restricted every step.
///
/// Only that ring feeds the coupling: D2Q9 streams between neighbours, so the edge lines read
/// after a coarse step ([`read_edges`]) depend on the nodes one inside them, and the nodes deeper
/// under the patch reach the edge lines only through the ring, which is overwritten after every
/// step. Between full restrictions the deeper nodes run the coarse scheme from the fine solution
/// they were last given; nothing reads them but outputs, and [`Refined::sync`] restricts them on
/// demand. So the fine solution and the forces are bitwise the same as with a full restriction
/// every step, at an eighth of its memory traffic. Every few steps rather than never, so that
/// the coarse copy (the coarse grid's own scheme around a body it does not resolve, at a
/// relaxation time close to 1/2) never runs long enough to drift or trip the divergence check.
pub(crate) const FULL_RESTRICTION_EVERY: u64 = 8;

/// Gives coarse fluid nodes strictly inside the patch the moments of the fine node on them: every
/// such node with `interior`, else only the ring next to the patch's edge lines (rows in
/// parallel; the same result for any thread count).
fn restrict(coarse: &mut D2q9, fine: &D2q9, c: &Coupling, interior: bool) {
    let [x0, x1] = c.patch.x;
    let [y0, y1] = c.patch.y;
    let (convert, recursive) = (c.convert, c.recursive);
    let (nc, nf) = (coarse.nx(), fine.nx());
    coarse.rewrite_rows(y0 + 1..y1, |y, solid, row| {
        let (fine_solid, fine_row) = fine.row(2 * (y - y0));
        let span = |xa: usize, xb: usize, row: &mut [f32]| {
            let mut g = [[0.0f32; RESTRICT_CHUNK]; Q];
            let mut x = xa;
            while x < xb {
                let m = (xb - x).min(RESTRICT_CHUNK);
                for (i, gi) in g.iter_mut().enumerate() {
                    let src = &fine_row[i * nf..(i + 1) * nf];
                    for (k, v) in gi[..m].iter_mut().enumerate() {
                        *v = src[2 * (x + k - x0)];
                    }
                }
                let [g0, g1, g2, g3, g4, g5, g6, g7, g8] = &mut g;
                for k in 0..m {
                    let p = [g0[k], g1[k], g2[k], g3[k], g4[k], g5[k], g6[k], g7[k], g8[k]];
                    let (d, ux, uy, q) = hermite_stress(&p);
                    let out = rebuild(d, ux, uy, convert.to_coarse(1.0 + d, q), recursive);
                    (g0[k], g1[k], g2[k], g3[k], g4[k]) = (out[0], out[1], out[2], out[3], out[4]);
                    (g5[k], g6[k], g7[k], g8[k]) = (out[5], out[6], out[7], out[8]);
                }
                for k in 0..m {
                    let (xc, xf) = (x + k, 2 * (x + k - x0));
                    if solid[xc] || fine_solid[xf] {
                        continue;
                    }
                    for (i, gi) in g.iter().enumerate() {
                        row[i * nc + xc] = gi[k];
                    }
                }
                x += m;
            }
        };
        if interior || y == y0 + 1 || y + 1 == y1 {
            span(x0 + 1, x1, row);
        } else {
            span(x0 + 1, x0 + 2, row);
            span(x1 - 1, x1, row);
        }
    });
}

/// Converts a post-collision non-equilibrium stress between a grid and its 2:1 patch (2D and
/// 3D alike: the factor depends on the stress only through its Frobenius norm).
///
/// Chapman-Enskog gives `Pi^neq = -2 rho c_s^2 tau S` (lattice units), so after a collision
/// `Pi* = (1 - 1/tau) Pi^neq = -2 rho c_s^2 (tau - 1) S`; the strain rate in lattice units halves
/// from the coarse grid to the fine one. With the Smagorinsky model the relaxation time is local,
/// `tau = tau0 + a |S|` with `a = les / 6` (the closed form of [`super::collision::collide_les`]'s
/// quadratic, `|S|` the Frobenius norm), so `|Pi*| = 2 rho c_s^2 (1 - tau0 - a |S|) |S|` is solved
/// for `|S|` (the smaller root, where `tau < 1`); without it `a = 0` and the map is the constant
/// factor `(tau_f - 1) / (2 (tau_c - 1))`. The trace of the stress (relaxed with its own rate) is
/// carried along with the same factor, as its post-collision value is zero for the regularised
/// operator anyway.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StressMap {
    tau_c: f32,
    tau_f: f32,
    a: f32,
}

/// Frobenius norm of a 2D stress `[xx, yy, xy]`.
#[inline]
fn norm2(q: [f32; 3]) -> f32 {
    (q[0] * q[0] + q[1] * q[1] + 2.0 * q[2] * q[2]).sqrt()
}

impl StressMap {
    pub(crate) fn new(tau_c: f64, tau_f: f64, smagorinsky: f64) -> Self {
        StressMap {
            tau_c: tau_c as f32,
            tau_f: tau_f as f32,
            a: (18.0 * 2f64.sqrt() * smagorinsky * smagorinsky / 6.0) as f32,
        }
    }

    /// `|S|` and the local `tau` of a post-collision stress of norm `norm` on a grid with `tau0`.
    #[inline]
    fn strain(&self, rho: f32, norm: f32, tau0: f32) -> (f32, f32) {
        let b = 1.0 - tau0;
        let c = 1.5 * norm / rho;
        // a s^2 - b s + c = 0, smaller root written without cancellation (a = 0 gives s = c / b).
        let disc = (b * b - 4.0 * self.a * c).max(0.0);
        let s = 2.0 * c / (b + disc.sqrt());
        (s, tau0 + self.a * s)
    }

    /// The factor that takes a coarse post-collision stress of norm `norm` to the fine grid's.
    #[inline]
    pub(crate) fn fine_factor(self, rho: f32, norm: impl FnOnce() -> f32) -> f32 {
        if self.a == 0.0 {
            // No square root per node without a subgrid model.
            return (self.tau_f - 1.0) / (2.0 * (self.tau_c - 1.0));
        }
        let (s, tau_c) = self.strain(rho, norm(), self.tau_c);
        let tau_f = self.tau_f + self.a * 0.5 * s;
        (tau_f - 1.0) / (2.0 * (tau_c - 1.0))
    }

    /// The factor that takes a fine post-collision stress of norm `norm` to the coarse grid's.
    #[inline]
    pub(crate) fn coarse_factor(self, rho: f32, norm: impl FnOnce() -> f32) -> f32 {
        if self.a == 0.0 {
            return 2.0 * (self.tau_c - 1.0) / (self.tau_f - 1.0);
        }
        let (s, tau_f) = self.strain(rho, norm(), self.tau_f);
        let tau_c = self.tau_c + self.a * 2.0 * s;
        2.0 * (tau_c - 1.0) / (tau_f - 1.0)
    }

    /// Coarse post-collision stress to the fine grid's.
    #[inline]
    fn to_fine(self, rho: f32, q: [f32; 3]) -> [f32; 3] {
        let k = self.fine_factor(rho, || norm2(q));
        q.map(|v| k * v)
    }

    /// Fine post-collision stress to the coarse grid's.
    #[inline]
    fn to_coarse(self, rho: f32, q: [f32; 3]) -> [f32; 3] {
        let k = self.coarse_factor(rho, || norm2(q));
        q.map(|v| k * v)
    }
}

/// Post-collision populations from density deviation, velocity and post-collision stress `q`:
/// the regularised form ([`hermite_populations`]), plus, for the recursive operator, the third-
/// and fourth-order terms its collision writes ([`add_third_and_fourth_order`]).
#[inline(always)]
fn rebuild(drho: f32, ux: f32, uy: f32, q: [f32; 3], recursive: bool) -> [f32; Q] {
    let mut g = hermite_populations(drho, ux, uy, q);
    if recursive {
        add_third_and_fourth_order(&mut g, 1.0 + drho, ux, uy, q);
    }
    g
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbm::collision::{collide_les, Relax, OP_REG};

    /// A node of the simple shear flow `u = (gamma y, 0)` after a Smagorinsky collision with
    /// `tau0`: before it, equilibrium plus the Chapman-Enskog stress `Pi_xy = -2 rho c_s^2 tau S_xy`
    /// of the local relaxation time `tau = tau0 + a |S|`, `|S| = gamma / sqrt(2)`.
    fn sheared(tau0: f64, gamma: f32, smagorinsky: f64) -> [f32; Q] {
        let a = (18.0 * 2f64.sqrt() * smagorinsky * smagorinsky / 6.0) as f32;
        let tau = tau0 as f32 + a * gamma / 2f32.sqrt();
        let mut g = hermite_populations(0.0, 0.02, 0.0, [0.0, 0.0, -tau * gamma / 3.0]);
        collide_les::<OP_REG, false, true>(&mut g, Relax::new(tau0, smagorinsky), 0.0, 0.0);
        g
    }

    #[test]
    fn the_stress_map_is_its_own_inverse_and_matches_the_strain_rate_ratio() {
        for smagorinsky in [0.0, 0.1, 0.17] {
            let (tau_c, tau_f) = (0.506, 0.512);
            let map = StressMap::new(tau_c, tau_f, smagorinsky);
            let q = [1.0e-4, -1.0e-4, 3.0e-3];
            let back = map.to_coarse(1.0, map.to_fine(1.0, q));
            for k in 0..3 {
                assert!((back[k] - q[k]).abs() < 1e-6 * q[2].abs(), "C_s {smagorinsky}: {back:?} vs {q:?}");
            }
            // The strain rate read back on each side halves from coarse to fine.
            let (s_c, _) = map.strain(1.0, norm2(q), tau_c as f32);
            let (s_f, _) = map.strain(1.0, norm2(map.to_fine(1.0, q)), tau_f as f32);
            assert!((s_f / s_c - 0.5).abs() < 1e-4, "C_s {smagorinsky}: {s_c} -> {s_f}");
        }
    }

    #[test]
    fn the_strain_read_back_from_a_smagorinsky_collision_is_the_strain_put_in() {
        // The collision's own local tau must be recovered from its post-collision stress.
        for smagorinsky in [0.0, 0.1] {
            let map = StressMap::new(0.506, 0.512, smagorinsky);
            let g = sheared(0.506, 0.01, smagorinsky);
            let (_, _, _, q) = crate::lbm::collision::hermite_stress(&g);
            let (s, _) = map.strain(1.0, norm2(q), 0.506);
            let expected = 0.01 / 2f32.sqrt();
            assert!((s / expected - 1.0).abs() < 1e-5, "C_s {smagorinsky}: |S| {s} vs {expected}");
        }
    }
}
