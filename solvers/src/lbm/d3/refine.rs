//! Local grid refinement (2:1 per level) of the 3D solver: nested fine boxes around the bodies,
//! embedded in the coarse box that covers the whole domain.
//!
//! The scheme is the 2D solver's ([`crate::lbm::Refined`]: the vertex-centred coupling of Lagrava,
//! Malaspinas, Latt & Chopard, J. Comput. Phys. 231, 4808, 2012, with regularised populations at
//! the interface) on boxes. Both grids carry the same physical viscosity in convective scaling
//! (`dx_f = dx_c / 2`, `dt_f = dt_c / 2`), so `tau_f - 1/2 = 2 (tau_c - 1/2)`, and a post-collision
//! non-equilibrium stress converts as `Pi*_f = Pi*_c (tau_f - 1) / (2 (tau_c - 1))` (with the local
//! relaxation times of the Smagorinsky model when it is on).
//!
//! One step `t -> t + 1` of a grid with a patch (recursively through the levels):
//! 1. the coarse grid steps everywhere;
//! 2. on the patch's six faces (coarse nodes) the density, velocity and post-collision stress are
//!    read after the step and interpolated to the fine nodes of the face: cubic `(-1, 9, 9, -1)/16`
//!    along each in-plane axis between coarse nodes (tensor product where both are half-way),
//!    linear next to the face's edges;
//! 3. the fine grid steps twice; after each sub-step its outer shell (the fine nodes on the
//!    coarse faces) is overwritten with regularised populations rebuilt from those moments,
//!    interpolated linearly in time (`t + 1/2`, then `t + 1`);
//! 4. the coarse nodes strictly inside the patch take the moments of the fine node on top of them
//!    (restriction): the layer next to the faces every step (the only one the coupling reads,
//!    D3Q19 and D3Q27 stream between neighbours), the whole interior every
//!    [`FULL_RESTRICTION_EVERY`] steps and on [`Refined3::sync`].
//!
//! The interface carries the regularised part of the populations (equilibrium plus
//! `w_i 9/2 Q_i : Pi*`), which is what the regularised collision writes; with BGK the higher-order
//! non-equilibrium is dropped there. Bodies live on the finest box (forces come from there; the
//! coarser grids mark them solid too, but their nodes near them are overwritten); faces and
//! absorbing layers stay on the coarse box, which the patches must keep clear of.
//!
//! A patch may also cover a periodic axis of the grid it refines whole (a body extruded along a
//! periodic span: its range there is every node, `0..=n - 1`). Its fine grid then wraps along that
//! axis with `2 n` nodes and has no faces across it; the faces along it interpolate across the
//! wrap (cubic everywhere), and the restriction takes every coarse node along it. No flux
//! correction: mass is conserved to the interpolation's truncation error, as in Lagrava et al.
//! A refined box runs in one process (not split over MPI ranks).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::collision::equilibrium;
use super::lattice::Lattice3;
use super::solver::{D3Config, Grid3, Lbm3};
use crate::geometry::Solid;
use crate::lbm::error::LbmError;
use crate::lbm::refine::{StressMap, FULL_RESTRICTION_EVERY};

/// A refined box in the node indices of the grid it refines, both ends included. Along a
/// periodic axis of that grid, `lo = 0` and `hi = n - 1` make the box cover the axis whole (see
/// the module docs); otherwise it keeps clear of the grid's faces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Patch3 {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
}

/// Density deviation, velocity and post-collision non-equilibrium stress
/// `[xx, yy, zz, xy, xz, yz]` of one node.
type Moments = [f32; 10];

/// Nodes a patch keeps between a body and its faces, and between its faces and the faces of the
/// grid it refines (as in 2D).
const BODY_MARGIN_FINE: usize = 4;
const EDGE_MARGIN_COARSE: usize = 2;

/// The two in-plane axes of a face normal to `axis`, in increasing order.
const fn in_plane(axis: usize) -> [usize; 2] {
    match axis {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// One face of a patch: the coarse moments on it, and their interpolation to the fine nodes at
/// the start (`old`) and the end (`new`) of the coarse grid's current step.
struct Face {
    axis: usize,
    /// Coarse node index along `axis` (the patch's `lo` or `hi`).
    at: usize,
    /// Coarse nodes along the two in-plane axes.
    coarse_dims: [usize; 2],
    /// Whether each in-plane axis wraps (the patch covers a periodic axis whole).
    periodic: [bool; 2],
    coarse: Vec<Moments>,
    old: Vec<Moments>,
    new: Vec<Moments>,
}

impl Face {
    /// Fine nodes along the two in-plane axes.
    fn fine_dims(&self) -> [usize; 2] {
        [0, 1].map(|k| fine_len(self.coarse_dims[k], self.periodic[k]))
    }
}

/// Fine nodes over `n` coarse nodes: both ends included, or `2 n` around a periodic axis.
fn fine_len(n: usize, periodic: bool) -> usize {
    if periodic {
        2 * n
    } else {
        2 * n - 1
    }
}

/// The coupling between grid `l` and the patch `l + 1` inside it.
struct Coupling {
    patch: Patch3,
    /// The periodic axes the patch covers whole.
    spans: [bool; 3],
    convert: StressMap,
    /// The patch's faces across the axes it does not span, in the order (axis, low side first).
    faces: Vec<Face>,
}

impl Coupling {
    /// The face normal to `axis` on the high side or the low one, if the patch has it.
    fn face(&self, axis: usize, high: bool) -> Option<&Face> {
        self.faces.iter().find(|f| f.axis == axis && (f.at == self.patch.hi[axis]) == high)
    }
}

/// A 3D grid over the whole domain with nested 2:1 boxes around the bodies (see the module
/// docs): level 0 is the coarse grid, each further level refines a box of the one before.
pub struct Refined3<const Q: usize, L: Lattice3<Q>> {
    levels: Vec<Lbm3<Q, L>>,
    couplings: Vec<Coupling>,
    /// Mean force over the last coarse step, from the finest level, in coarse lattice units.
    forces: Vec<[f64; 3]>,
}

fn config_error(message: impl Into<String>) -> LbmError {
    LbmError::Config {
        field: "refinement",
        message: message.into(),
    }
}

impl<const Q: usize, L: Lattice3<Q>> Refined3<Q, L> {
    /// Plans every grid: `cfg` is the coarse box over the whole domain; `patches[0]` refines a box
    /// of it (coarse node indices), `patches[1]` a box of that patch (its node indices), and so
    /// on. The finest patch must contain every body with a margin; each patch stays clear of the
    /// faces of the grid it refines and of the absorbing layers, or covers a periodic axis whole.
    pub fn new(cfg: D3Config, patches: &[Patch3], bodies: &[&dyn Solid]) -> Result<Self, LbmError> {
        if patches.is_empty() {
            return Err(config_error("at least one patch is needed (use Lbm3 for a uniform grid)"));
        }
        if cfg.body_force != [0.0; 3] {
            return Err(config_error("a body force is not coupled across the interface yet"));
        }
        if cfg.segments != 1 {
            return Err(config_error(
                "spanwise force segments are not reported on a refined grid (the finest box does not span the domain)",
            ));
        }
        let m = EDGE_MARGIN_COARSE;
        for sp in &cfg.sponges {
            let (a, high) = (sp.face / 2, sp.face % 2 == 1);
            let p = patches[0];
            let clear = if high {
                p.hi[a] + sp.width + m < cfg.n[a]
            } else {
                p.lo[a] > sp.width + m
            };
            if !clear {
                return Err(config_error(format!(
                    "the first patch overlaps the absorbing layer on face {} ({} nodes); move it or thin the layer",
                    sp.face, sp.width
                )));
            }
        }
        let mut wraps = [0, 1, 2].map(|a| cfg.faces.periodic_axis(a));
        let mut spans = Vec::with_capacity(patches.len());
        let mut cfgs = vec![cfg];
        for (l, p) in patches.iter().enumerate() {
            let parent = &cfgs[l];
            let spanned = [0, 1, 2].map(|a| wraps[a] && p.lo[a] == 0 && p.hi[a] + 1 == parent.n[a]);
            for a in 0..3 {
                if spanned[a] {
                    continue;
                }
                if p.hi[a] < p.lo[a] + 4 {
                    return Err(config_error(format!(
                        "patch {} ({:?}..={:?} in level {l}'s nodes) must span at least 4 cells along each axis",
                        l + 1,
                        p.lo,
                        p.hi
                    )));
                }
                if p.lo[a] < m || p.hi[a] + m >= parent.n[a] {
                    return Err(config_error(format!(
                        "patch {} ({:?}..={:?}) must keep {m} nodes from the faces of level {l} ({:?} nodes), \
                         or cover a periodic axis whole (0..={} along it)",
                        l + 1,
                        p.lo,
                        p.hi,
                        parent.n,
                        parent.n[a] - 1
                    )));
                }
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
            // The fine grid wraps along the axes it spans (D3Config's faces default to periodic);
            // its other faces are the shell the coupling rewrites.
            let n = [0, 1, 2].map(|a| fine_len(p.hi[a] - p.lo[a] + 1, spanned[a]));
            let mut fine = D3Config::new(n, tau_f);
            fine.grid = Grid3 {
                origin: parent.grid.position(p.lo),
                dx: 0.5 * parent.grid.dx,
            };
            fine.collision = parent.collision;
            fine.smagorinsky = parent.smagorinsky;
            fine.check_interval = 2 * parent.check_interval;
            fine.rho_bounds = parent.rho_bounds;
            fine.u_max = parent.u_max;
            fine.stream_stores = parent.stream_stores;
            cfgs.push(fine);
            spans.push(spanned);
            wraps = spanned;
        }
        let levels = cfgs
            .into_iter()
            .map(|c| Lbm3::<Q, L>::new(c, bodies))
            .collect::<Result<Vec<_>, _>>()?;

        for (l, (p, spanned)) in patches.iter().zip(&spans).enumerate() {
            let grid = &levels[l];
            for_each_node(grid.config().n, |q| {
                let inside = (0..3).all(|a| spanned[a] || (q[a] > p.lo[a] + 1 && q[a] + 1 < p.hi[a]));
                if grid.is_solid(q) && !inside {
                    return Err(config_error(format!(
                        "node {q:?} of level {l} is inside a body but outside patch {}; every body must lie in every patch",
                        l + 1
                    )));
                }
                Ok(())
            })?;
        }

        let finest = &levels[levels.len() - 1];
        let n = finest.config().n;
        let k = BODY_MARGIN_FINE;
        let spanned = wraps;
        for_each_node(n, |p| {
            let near = (0..3).any(|a| !spanned[a] && (p[a] < k || p[a] + k >= n[a]));
            if near && finest.is_solid(p) {
                return Err(config_error(format!(
                    "a body reaches within {k} nodes of the finest patch's faces (node {p:?} of level {}); enlarge the patch",
                    levels.len() - 1
                )));
            }
            Ok(())
        })?;
        let couplings = patches
            .iter()
            .zip(&spans)
            .zip(&levels)
            .map(|((p, &spanned), coarse)| {
                let tau_c = coarse.config().tau;
                let faces = (0..6)
                    .filter(|f| !spanned[f / 2])
                    .map(|f| {
                        let (axis, high) = (f / 2, f % 2 == 1);
                        let coarse_dims = in_plane(axis).map(|b| p.hi[b] - p.lo[b] + 1);
                        let periodic = in_plane(axis).map(|b| spanned[b]);
                        let fine_nodes = fine_len(coarse_dims[0], periodic[0]) * fine_len(coarse_dims[1], periodic[1]);
                        Face {
                            axis,
                            at: if high { p.hi[axis] } else { p.lo[axis] },
                            coarse_dims,
                            periodic,
                            coarse: vec![[0.0; 10]; coarse_dims[0] * coarse_dims[1]],
                            old: vec![[0.0; 10]; fine_nodes],
                            new: vec![[0.0; 10]; fine_nodes],
                        }
                    })
                    .collect();
                Coupling {
                    patch: *p,
                    spans: spanned,
                    convert: StressMap::new(tau_c, 0.5 + 2.0 * (tau_c - 0.5), coarse.config().smagorinsky),
                    faces,
                }
            })
            .collect();
        let n_bodies = bodies.len();
        let mut r = Refined3 {
            levels,
            couplings,
            forces: vec![[0.0; 3]; n_bodies],
        };
        r.init_with(|_| (1.0, [0.0; 3]));
        Ok(r)
    }

    /// Sets every grid to the equilibrium of `(rho, u) = field(x)` (physical position, lattice
    /// density and velocity, the same on all grids); resets the time.
    pub fn init_with(&mut self, field: impl Fn([f64; 3]) -> (f64, [f64; 3])) {
        for grid in &mut self.levels {
            let g = grid.config().grid;
            grid.set_equilibrium(|x, y, z| field(g.position([x, y, z])));
            grid.reset_time();
        }
        for l in 0..self.couplings.len() {
            read_faces(&self.levels[l], &mut self.couplings[l]);
            for f in &mut self.couplings[l].faces {
                f.old.clone_from(&f.new);
            }
        }
    }

    /// One coarse step (`2^l` steps of level `l`). Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        for f in self.forces.iter_mut() {
            *f = [0.0; 3];
        }
        self.step_level(0)
    }

    /// One step of level `l` and, recursively, two of every finer level.
    fn step_level(&mut self, l: usize) -> Result<(), LbmError> {
        if let Err(e) = self.levels[l].step() {
            return Err(self.located(l, e));
        }
        if l + 1 == self.levels.len() {
            // Mean over the 2^l sub-steps; a force on level l is 4^-l times the coarse-lattice
            // force with the same coefficient (the reference area quadruples per level).
            let w = 0.125f64.powi(l as i32);
            for (acc, f) in self.forces.iter_mut().zip(self.levels[l].body_forces()) {
                for a in 0..3 {
                    acc[a] += w * f[a];
                }
            }
            return Ok(());
        }
        {
            let c = &mut self.couplings[l];
            for f in &mut c.faces {
                std::mem::swap(&mut f.old, &mut f.new);
            }
            read_faces(&self.levels[l], c);
        }
        for theta in [0.5f32, 1.0] {
            self.step_level(l + 1)?;
            write_shell(&mut self.levels[l + 1], &self.couplings[l], theta);
        }
        let interior = self.levels[l].time().is_multiple_of(FULL_RESTRICTION_EVERY);
        let (coarse, fine) = self.levels.split_at_mut(l + 1);
        restrict(&mut coarse[l], &fine[0], &self.couplings[l], interior);
        Ok(())
    }

    /// Gives every coarser grid the finer solution under its patches (finest first), which
    /// [`step`](Self::step) does only every [`FULL_RESTRICTION_EVERY`] steps away from the faces.
    /// Call it before reading a coarser grid's fields under a patch.
    pub fn sync(&mut self) {
        for l in (0..self.couplings.len()).rev() {
            let (coarse, fine) = self.levels.split_at_mut(l + 1);
            restrict(&mut coarse[l], &fine[0], &self.couplings[l], true);
        }
    }

    /// A divergence on level `l`, located on the coarse grid.
    fn located(&self, l: usize, e: LbmError) -> LbmError {
        match e {
            LbmError::Diverged3 { reason, mut at, .. } if l > 0 => {
                for c in self.couplings[..l].iter().rev() {
                    at = [0, 1, 2].map(|a| c.patch.lo[a] + at[a] / 2);
                }
                LbmError::Diverged3 {
                    step: self.levels[0].time(),
                    reason: format!("{reason} (refinement level {l})"),
                    at,
                }
            }
            other => other,
        }
    }

    /// Force on each body (from the finest level) averaged over the last coarse step, in coarse
    /// lattice units, so coefficients use the coarse reference area.
    pub fn body_forces(&self) -> &[[f64; 3]] {
        &self.forces
    }

    /// Sets the wall velocity of body `b` on every level (lattice velocities are the same on all
    /// of them in convective scaling).
    pub fn set_wall_velocity(&mut self, b: usize, u: impl Fn([f64; 3]) -> [f64; 3]) {
        for grid in &mut self.levels {
            grid.set_wall_velocity(b, &u);
        }
    }

    /// The grid over the whole domain (its faces, inlet and absorbing layers). Under the patches
    /// it holds the fine solution as of the last full restriction (see [`sync`](Self::sync)).
    pub fn coarse(&self) -> &Lbm3<Q, L> {
        &self.levels[0]
    }

    /// The coarse grid, to change its faces (inlet velocity, profile, ramp).
    pub fn coarse_mut(&mut self) -> &mut Lbm3<Q, L> {
        &mut self.levels[0]
    }

    /// Every grid, coarse first.
    pub fn levels(&self) -> &[Lbm3<Q, L>] {
        &self.levels
    }

    /// The patches, each in the node indices of the grid it refines.
    pub fn patches(&self) -> impl Iterator<Item = Patch3> + '_ {
        self.couplings.iter().map(|c| c.patch)
    }

    /// Coarse steps since the last initialisation.
    pub fn time(&self) -> u64 {
        self.levels[0].time()
    }

    /// Node updates per coarse step (level `l`'s nodes count `2^l` times), for MLUPS.
    pub fn node_updates_per_step(&self) -> usize {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, g)| g.config().n.iter().product::<usize>() << l)
            .sum()
    }

    /// Density and lattice velocity at physical point `x` (trilinear), from the finest level
    /// whose box holds it with a node to spare (the coarser ones under a patch need
    /// [`sync`](Self::sync) first, so they are not read there).
    pub fn probe(&self, x: [f64; 3]) -> Result<(f64, [f64; 3]), LbmError> {
        for (l, grid) in self.levels.iter().enumerate().rev() {
            let c = grid.config();
            let spanned = if l == 0 { [false; 3] } else { self.couplings[l - 1].spans };
            let inside = (0..3).all(|a| {
                let s = (x[a] - c.grid.origin[a]) / c.grid.dx;
                if spanned[a] {
                    s >= 0.0 && s <= c.n[a] as f64
                } else {
                    s >= 1.0 && s <= (c.n[a] - 2) as f64
                }
            });
            if inside {
                return grid.probe(x);
            }
        }
        self.levels[0].probe(x)
    }
}

/// Runs `f` on every node of a box of `n` nodes in storage order, stopping at the first error.
fn for_each_node(n: [usize; 3], mut f: impl FnMut([usize; 3]) -> Result<(), LbmError>) -> Result<(), LbmError> {
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                f([x, y, z])?;
            }
        }
    }
    Ok(())
}

/// Density deviation, velocity and non-equilibrium stress of post-collision populations `g`:
/// `Pi = sum_i c_i c_i g_i - (drho/3 I + rho u u)` (the equilibrium's second moment in closed
/// form, exact for D3Q19 and D3Q27).
fn read_moments<const Q: usize, L: Lattice3<Q>>(g: &[f32; Q]) -> Moments {
    let mut drho = 0.0f32;
    let mut j = [0.0f32; 3];
    let mut pi = [0.0f32; 6];
    for i in 0..Q {
        let c = L::C_REF[i].map(|v| v as f32);
        drho += g[i];
        for a in 0..3 {
            j[a] += c[a] * g[i];
            pi[a] += c[a] * c[a] * g[i];
        }
        pi[3] += c[0] * c[1] * g[i];
        pi[4] += c[0] * c[2] * g[i];
        pi[5] += c[1] * c[2] * g[i];
    }
    let rho = 1.0 + drho;
    let u = j.map(|v| v / rho);
    for a in 0..3 {
        pi[a] -= drho / 3.0 + rho * u[a] * u[a];
    }
    pi[3] -= rho * u[0] * u[1];
    pi[4] -= rho * u[0] * u[2];
    pi[5] -= rho * u[1] * u[2];
    [drho, u[0], u[1], u[2], pi[0], pi[1], pi[2], pi[3], pi[4], pi[5]]
}

/// Frobenius norm of the stress in `m`.
fn stress_norm(m: &Moments) -> f32 {
    let d = m[4] * m[4] + m[5] * m[5] + m[6] * m[6];
    let o = m[7] * m[7] + m[8] * m[8] + m[9] * m[9];
    (d + 2.0 * o).sqrt()
}

/// Regularised post-collision populations of `m` with its stress scaled by `k`: the equilibrium
/// plus `w_i 9/2 Q_i : (k Pi)`, `Q_i = c_i c_i - I/3`.
fn rebuild<const Q: usize, L: Lattice3<Q>>(m: &Moments, k: f32) -> [f32; Q] {
    let mut g = equilibrium::<Q, L>(m[0], [m[1], m[2], m[3]]);
    let p = [4, 5, 6, 7, 8, 9].map(|i| k * m[i]);
    let third_tr = (p[0] + p[1] + p[2]) / 3.0;
    for i in 0..Q {
        let c = L::C_REF[i].map(|v| v as f32);
        let qp = c[0] * c[0] * p[0] + c[1] * c[1] * p[1] + c[2] * c[2] * p[2] - third_tr
            + 2.0 * (c[0] * c[1] * p[3] + c[0] * c[2] * p[4] + c[1] * c[2] * p[5]);
        g[i] += L::W_REF[i] * 4.5 * qp;
    }
    g
}

/// Coarse nodes and weights of fine index `i` along a line of `len` coarse nodes (`i / 2` in
/// coarse nodes): the node itself at even `i`, else the 4-point cubic `(-1, 9, 9, -1) / 16`, linear
/// next to the line's ends, or across the wrap of a `periodic` line.
fn weights(i: usize, len: usize, periodic: bool) -> ([usize; 4], [f32; 4], usize) {
    let k = i / 2;
    if i.is_multiple_of(2) {
        ([k, 0, 0, 0], [1.0, 0.0, 0.0, 0.0], 1)
    } else if periodic {
        let at = |d: usize| (k + len + d - 1) % len;
        ([at(0), at(1), at(2), at(3)], [-1.0 / 16.0, 9.0 / 16.0, 9.0 / 16.0, -1.0 / 16.0], 4)
    } else if k >= 1 && k + 2 < len {
        ([k - 1, k, k + 1, k + 2], [-1.0 / 16.0, 9.0 / 16.0, 9.0 / 16.0, -1.0 / 16.0], 4)
    } else {
        ([k, k + 1, 0, 0], [0.5, 0.5, 0.0, 0.0], 2)
    }
}

/// Reads grid `coarse`'s moments on the patch's six faces and interpolates them to the fine
/// nodes of each face (into `new`), faces in parallel.
fn read_faces<const Q: usize, L: Lattice3<Q>>(coarse: &Lbm3<Q, L>, c: &mut Coupling) {
    let lo = c.patch.lo;
    c.faces.par_iter_mut().for_each(|face| {
        let [b, cc] = in_plane(face.axis);
        let [nb, nc] = face.coarse_dims;
        for jc in 0..nc {
            for jb in 0..nb {
                let mut p = [0; 3];
                p[face.axis] = face.at;
                p[b] = lo[b] + jb;
                p[cc] = lo[cc] + jc;
                face.coarse[jc * nb + jb] = read_moments::<Q, L>(&coarse.node_populations(p));
            }
        }
        let [fb, fc] = face.fine_dims();
        let [pb, pc] = face.periodic;
        for ic in 0..fc {
            let (kc, wc, mc) = weights(ic, nc, pc);
            for ib in 0..fb {
                let (kb, wb, mb) = weights(ib, nb, pb);
                let mut m = [0.0f32; 10];
                for s in 0..mc {
                    for r in 0..mb {
                        let w = wc[s] * wb[r];
                        let src = &face.coarse[kc[s] * nb + kb[r]];
                        for (v, x) in m.iter_mut().zip(src) {
                            *v += w * x;
                        }
                    }
                }
                face.new[ic * fb + ib] = m;
            }
        }
    });
}

/// Overwrites the patch's outer shell with populations rebuilt from the face moments at time
/// `t + theta` (coarse steps), planes in parallel. A node on an edge or corner of the box lies on
/// two or three faces, which agree there (the interpolation across a face is exact at its edge
/// nodes); it takes the z face's value, else the y face's. Along a spanned axis there is no face.
fn write_shell<const Q: usize, L: Lattice3<Q>>(fine: &mut Lbm3<Q, L>, c: &Coupling, theta: f32) {
    let n = fine.config().n;
    let [nx, ny, nz] = n;
    let z_faces = [c.face(2, false), c.face(2, true)];
    let y_faces = [(0, c.face(1, false)), (ny - 1, c.face(1, true))];
    let x_faces = [(0, c.face(0, false)), (nx - 1, c.face(0, true))];
    // Rows the x faces own: all but those of the y faces.
    let rows = if c.spans[1] { 0..ny } else { 1..ny - 1 };
    let at = |face: &Face, ib: usize, ic: usize| -> [f32; Q] {
        let k = ic * face.fine_dims()[0] + ib;
        let (a, z) = (&face.old[k], &face.new[k]);
        let m: Moments = std::array::from_fn(|k| (1.0 - theta) * a[k] + theta * z[k]);
        let f = c.convert.fine_factor(1.0 + m[0], || stress_norm(&m));
        rebuild::<Q, L>(&m, f)
    };
    fine.rewrite_planes(0..nz, |z, _, plane| {
        let mut put = |x: usize, y: usize, g: [f32; Q]| {
            for (i, v) in g.iter().enumerate() {
                plane[(i * ny + y) * nx + x] = *v;
            }
        };
        // A z face holds (x, y), a y face (x, z), an x face (y, z).
        let z_face = match z {
            0 => z_faces[0],
            _ if z == nz - 1 => z_faces[1],
            _ => None,
        };
        if let Some(face) = z_face {
            for y in 0..ny {
                for x in 0..nx {
                    put(x, y, at(face, x, y));
                }
            }
            return;
        }
        for (y, face) in y_faces {
            if let Some(face) = face {
                for x in 0..nx {
                    put(x, y, at(face, x, z));
                }
            }
        }
        for (x, face) in x_faces {
            if let Some(face) = face {
                for y in rows.clone() {
                    put(x, y, at(face, y, z));
                }
            }
        }
    });
}

/// Gives coarse fluid nodes strictly inside the patch the moments of the fine node on them: every
/// such node with `interior`, else only the layer next to the patch's faces (planes in parallel).
fn restrict<const Q: usize, L: Lattice3<Q>>(coarse: &mut Lbm3<Q, L>, fine: &Lbm3<Q, L>, c: &Coupling, interior: bool) {
    let (lo, hi) = (c.patch.lo, c.patch.hi);
    let [nx, ny, _] = coarse.config().n;
    // Strictly inside, or every node along a spanned axis (which has no faces and no ring).
    let inner = |a: usize| if c.spans[a] { lo[a]..hi[a] + 1 } else { lo[a] + 1..hi[a] };
    let on_ring = |v: usize, a: usize| !c.spans[a] && (v == lo[a] + 1 || v + 1 == hi[a]);
    coarse.rewrite_planes(inner(2), |z, solid, plane| {
        for y in inner(1) {
            let whole_row = interior || on_ring(y, 1) || on_ring(z, 2);
            for x in inner(0) {
                if !whole_row && !on_ring(x, 0) {
                    continue;
                }
                let q = [2 * (x - lo[0]), 2 * (y - lo[1]), 2 * (z - lo[2])];
                if solid[y * nx + x] || fine.is_solid(q) {
                    continue;
                }
                let m = read_moments::<Q, L>(&fine.node_populations(q));
                let k = c.convert.coarse_factor(1.0 + m[0], || stress_norm(&m));
                for (i, v) in rebuild::<Q, L>(&m, k).iter().enumerate() {
                    plane[(i * ny + y) * nx + x] = *v;
                }
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lbm::d3::D3q19;

    #[test]
    fn moments_read_back_from_rebuilt_populations_are_the_moments_put_in() {
        let m: Moments = [0.01, 0.03, -0.02, 0.01, 1e-4, -2e-4, 1e-4, 3e-4, -1e-4, 2e-4];
        let back = read_moments::<19, D3q19>(&rebuild::<19, D3q19>(&m, 1.0));
        for k in 0..10 {
            assert!((back[k] - m[k]).abs() < 2e-6, "moment {k}: {} vs {}", back[k], m[k]);
        }
    }

    #[test]
    fn the_face_interpolation_is_exact_for_cubics_inside_and_for_straight_lines_at_the_ends() {
        let cubic = |s: f64| 0.5 - 0.2 * s + 0.03 * s * s - 0.004 * s * s * s;
        let line = |s: f64| 0.5 - 0.2 * s;
        let len = 9;
        for i in 0..2 * len - 1 {
            let (k, w, m) = weights(i, len, false);
            let f: &dyn Fn(f64) -> f64 = if m == 2 { &line } else { &cubic };
            let v: f64 = (0..m).map(|r| w[r] as f64 * f(k[r] as f64)).sum();
            let exact = f(i as f64 / 2.0);
            assert!((v - exact).abs() < 1e-6, "fine index {i} ({m} points): {v} vs {exact}");
        }
    }

    #[test]
    fn the_interpolation_around_a_periodic_line_wraps_and_is_fourth_order() {
        let (k, _, m) = weights(31, 16, true);
        assert_eq!((k, m), ([14, 15, 0, 1], 4));
        let error = |len: usize| {
            let f = |s: f64| (2.0 * std::f64::consts::PI * s / len as f64).sin();
            (0..2 * len)
                .map(|i| {
                    let (k, w, m) = weights(i, len, true);
                    let v: f64 = (0..m).map(|r| w[r] as f64 * f(k[r] as f64)).sum();
                    (v - f(i as f64 / 2.0)).abs()
                })
                .fold(0.0, f64::max)
        };
        let (e16, e32) = (error(16), error(32));
        assert!(e16 / e32 > 12.0, "errors {e16:.3e} (16 nodes) and {e32:.3e} (32): not fourth order");
    }
}
