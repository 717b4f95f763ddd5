//! The D2Q9 solver: construction (plan once) and the step (execute many, no allocation).

use std::borrow::Cow;
use std::sync::Arc;

use rayon::prelude::*;

use crate::comm::{Comm, Solo};

use super::aa::{aa_row_fn, canonical_into, gather_specials, swap_directions, Cells, Propagation};
use super::aligned::AlignedVec;
use super::boundary::InletReference;
use super::check::{scan_row, RowStat};
use super::collision::{equilibrium, moments, Collision, Relax};
use super::domain::{Edge, Grid, Side, Sides};
use super::error::LbmError;
use super::forces::link_forces;
use super::kernel::{row_fn, KernelCtx, Link};
use super::lattice::{CX, CY, OPP, Q};
use super::part::Part;
use super::post::{Form, Frame, Loc, Post};
use super::specials::{RowSpecials, Special};
use super::sponge::{apply_row, Sponge, SpongePlan};
use crate::geometry::Shape;

/// A node within `ON_WALL` grid spacings of a body's wall (`sdf <= ON_WALL dx`) is a wall node:
/// solid, and the links that reach it carry `q = 1`. Without the margin a wall that passes
/// through a row of nodes (a square's face on a node-centred grid, or on a refined patch whose
/// nodes fall on the coarse cell faces) was split by the rounding of `origin + i dx`: some of its
/// nodes solid, the others fluid with `q` clamped to 1e-3, and the flow saw a ragged wall. The
/// square at Re 200 with 24 cells per side and its faces on nodes gave St 0.1633, C_D 1.443,
/// C_L' 0.361 against 0.1572, 1.470, 0.420 with its faces between nodes (71 of the 96 face
/// nodes solid). The margin is far above the rounding of positions (1e-15 relative) and far
/// below any distance the scheme resolves.
pub const ON_WALL: f64 = 1e-9;

/// Everything needed to build a [`D2q9`]. Plain data: threads are whatever rayon pool the step
/// runs in, and never change the result.
#[derive(Clone, Debug)]
pub struct D2q9Config {
    pub nx: usize,
    pub ny: usize,
    /// Relaxation time; `nu = (tau - 1/2) / 3`.
    pub tau: f64,
    pub collision: Collision,
    /// Smagorinsky constant `C_s` of the subgrid viscosity (regularised operator only; 0 = none,
    /// 0.1-0.17 usual). Needed for under-resolved runs at Re >= 1000.
    pub smagorinsky: f64,
    pub sides: Sides,
    /// Uniform body force per unit volume (lattice units), Guo forcing; zero for none.
    pub body_force: [f64; 2],
    /// Physical position of the nodes (used to place bodies and probes).
    pub grid: Grid,
    /// Full scan for blow-up (NaN, density or speed out of bounds) every this many steps;
    /// non-finite forces on a body are caught every step.
    pub check_interval: u64,
    /// Allowed density range and maximum lattice speed before the run counts as diverged.
    pub rho_bounds: [f32; 2],
    pub u_max: f32,
    /// Non-temporal stores for the interior: `None` decides by size
    /// ([`STREAM_STORES_ABOVE_BYTES`]). A performance knob only: results are bitwise the same.
    pub stream_stores: Option<bool>,
    /// Absorbing layers along edges (none by default), see [`super::sponge`].
    pub sponges: Vec<Sponge>,
    /// Make every [`Side::Velocity`] edge non-reflecting for pressure waves (see
    /// [`super::boundary::InletReference`]), its reference density averaged over this many
    /// steps; `None` (the default) keeps the rigid velocity edge.
    pub characteristic_inlet: Option<f64>,
    /// How the fast kernel streams: `None` decides by size (the AA pattern where the arrays are
    /// larger than the caches, as for `stream_stores`; pulling in cache, where it measured
    /// faster). A grid split over ranks always pulls. A performance knob only: results are
    /// bitwise the same.
    pub propagation: Option<Propagation>,
}

impl D2q9Config {
    /// A configuration with the defaults for everything but size, relaxation time and edges.
    pub fn new(nx: usize, ny: usize, tau: f64, sides: Sides) -> Self {
        D2q9Config {
            nx,
            ny,
            tau,
            collision: Collision::Regularized,
            smagorinsky: 0.0,
            sides,
            body_force: [0.0, 0.0],
            grid: Grid::lattice(),
            check_interval: 100,
            rho_bounds: [0.5, 2.0],
            u_max: 0.5,
            stream_stores: None,
            sponges: Vec::new(),
            characteristic_inlet: None,
            propagation: None,
        }
    }
}

/// A point where a lattice link crosses a body's wall.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallPoint {
    /// Physical position of the crossing.
    pub position: [f64; 2],
    /// Outward unit normal of the body there.
    pub normal: [f64; 2],
    /// Which body.
    pub body: usize,
}

/// D2Q9 lattice Boltzmann solver (see the module docs for the scheme), on one process or on a
/// rank's slab of the grid ([`D2q9::new_split`]).
pub struct D2q9 {
    /// This rank's grid: its slab and ghost rows (the whole grid on one process).
    cfg: D2q9Config,
    /// The whole grid's configuration.
    global: D2q9Config,
    part: Part,
    comm: Box<dyn Comm>,
    /// The whole grid's solid nodes when split (`None`: `solid` is the whole grid's).
    solid_global: Option<Vec<bool>>,
    /// Force terms per (body, global row, axis), this rank's and summed over the ranks.
    partial: Vec<f64>,
    summed: Vec<f64>,
    relax: Relax,
    /// Current post-collision populations, shifted (`g = f - w`), row-blocked SoA, laid out as
    /// `form` says (see [`super::post`]).
    f: AlignedVec,
    /// The other half of the A-B pair (pull), or scratch for changes of form (AA).
    f_next: AlignedVec,
    form: Form,
    /// Streamed form: the values that leave through non-periodic edges (empty when pulling).
    halo: Vec<f32>,
    /// AA: each special's arriving populations, gathered before the sweep (empty when pulling).
    stash: Vec<f32>,
    /// Step with the AA pattern ([`super::aa`]) rather than the pull kernel.
    aa: bool,
    solid: Vec<bool>,
    specials: RowSpecials,
    links: Vec<Link>,
    wall_points: Vec<WallPoint>,
    bodies: Vec<Arc<dyn Shape>>,
    body_forces: Vec<[f64; 2]>,
    row_stats: Vec<RowStat>,
    sponges: Vec<SpongePlan>,
    velocity_scale: f32,
    inlet_reference: Option<InletReference>,
    time: u64,
}

impl std::fmt::Debug for D2q9 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("D2q9")
            .field("nx", &self.global.nx)
            .field("ny", &self.global.ny)
            .field("rank", &self.comm.rank())
            .field("ranks", &self.comm.size())
            .field("tau", &self.cfg.tau)
            .field("links", &self.links.len())
            .field("time", &self.time)
            .finish()
    }
}

/// The read-only view of the solver that one step's kernel needs (split from `self` so that the
/// destination array can be borrowed mutably beside it). One argument per field of `self` the
/// kernel reads: that is the split borrow.
fn kernel_ctx<'a>(
    cfg: &'a D2q9Config,
    relax: Relax,
    solid: &'a [bool],
    specials: &'a RowSpecials,
    links: &'a [Link],
    velocity_scale: f32,
    inlet_reference: Option<InletReference>,
) -> KernelCtx<'a> {
    KernelCtx {
        nx: cfg.nx,
        ny: cfg.ny,
        relax,
        fx: cfg.body_force[0] as f32,
        fy: cfg.body_force[1] as f32,
        periodic_x: cfg.sides.west == Side::Periodic,
        periodic_y: cfg.sides.south == Side::Periodic,
        sides: &cfg.sides,
        solid,
        specials,
        links,
        velocity_scale,
        inlet_reference,
        stream_stores: cfg.stream_stores.unwrap_or(cfg.nx * cfg.ny * Q * 4 * 2 > STREAM_STORES_ABOVE_BYTES),
        frame: frame_of(cfg),
    }
}

/// The grid's size and periodicity (this rank's rows).
fn frame_of(cfg: &D2q9Config) -> Frame {
    Frame {
        nx: cfg.nx,
        ny: cfg.ny,
        periodic_x: cfg.sides.west == Side::Periodic,
        periodic_y: cfg.sides.south == Side::Periodic,
    }
}

/// Above this size of the two population arrays the kernel writes with non-temporal stores
/// (no write-allocate read: 72 instead of 108 bytes of traffic per node). Below it the arrays
/// live in the last-level cache (32 MB here), where ordinary stores are faster because the next
/// step reads the values back from the cache. The choice depends only on the grid size and
/// never changes a result.
pub const STREAM_STORES_ABOVE_BYTES: usize = 48 << 20;

fn config_error(field: &'static str, message: impl Into<String>) -> LbmError {
    LbmError::Config {
        field,
        message: message.into(),
    }
}

impl D2q9 {
    /// Plans the run: marks solid nodes, finds every link that crosses a wall with its Bouzidi
    /// fraction `q`, lists the nodes that need the general path, and initialises the rest state.
    pub fn new(cfg: D2q9Config, bodies: Vec<Arc<dyn Shape>>) -> Result<Self, LbmError> {
        Self::new_split(cfg, bodies, Box::new(Solo))
    }

    /// This rank's slab of the grid `cfg` split over the ranks of `comm` along y (see
    /// [`super::part`]): every rank calls this, and then every method below together. Each step
    /// exchanges the ghost rows; forces, probes, mass, fields and the blow-up scan come out on
    /// every rank bitwise as one process computes them. Node coordinates in arguments and errors
    /// are the whole grid's. The characteristic inlet (a mean along its edge) is not split.
    pub fn new_split(cfg: D2q9Config, bodies: Vec<Arc<dyn Shape>>, comm: Box<dyn Comm>) -> Result<Self, LbmError> {
        let (nx, ny) = (cfg.nx, cfg.ny);
        if nx < 3 || ny < 3 {
            return Err(config_error(
                "size",
                format!("the grid must be at least 3 x 3 nodes, got {nx} x {ny}"),
            ));
        }
        if nx
            .checked_mul(ny)
            .and_then(|n| n.checked_mul(Q))
            .is_none_or(|n| n > u32::MAX as usize)
        {
            return Err(config_error("size", format!("{nx} x {ny} nodes is too large")));
        }
        let margin = cfg.tau - 0.5;
        if !cfg.tau.is_finite() || margin < cfg.collision.min_tau_margin() {
            return Err(config_error(
                "tau",
                format!(
                    "tau = {:.6} is too close to 1/2 for the {} operator (needs tau - 1/2 >= {}); \
                     use more cells per length or a lower lattice velocity",
                    cfg.tau,
                    cfg.collision.name(),
                    cfg.collision.min_tau_margin()
                ),
            ));
        }
        if !(cfg.smagorinsky.is_finite() && (0.0..=1.0).contains(&cfg.smagorinsky)) {
            return Err(config_error(
                "smagorinsky",
                format!("C_s = {} must be in [0, 1] (0.1-0.17 is usual)", cfg.smagorinsky),
            ));
        }
        if cfg.smagorinsky > 0.0 && !cfg.collision.is_regularized() {
            return Err(config_error(
                "smagorinsky",
                "the subgrid model is built into the regularised operators; use collision = regularized or recursive",
            ));
        }
        let s = &cfg.sides;
        if (s.west == Side::Periodic) != (s.east == Side::Periodic) {
            return Err(config_error("sides", "west and east must both be periodic or neither"));
        }
        if (s.south == Side::Periodic) != (s.north == Side::Periodic) {
            return Err(config_error("sides", "south and north must both be periodic or neither"));
        }
        for (name, side, len) in [
            ("west", &s.west, ny),
            ("east", &s.east, ny),
            ("south", &s.south, nx),
            ("north", &s.north, nx),
        ] {
            if let Side::Velocity { profile } = side {
                if profile.len() != len {
                    return Err(config_error(
                        "sides",
                        format!("the {name} velocity profile has {} values, the side has {len} nodes", profile.len()),
                    ));
                }
                if profile.iter().any(|u| !u[0].is_finite() || !u[1].is_finite()) {
                    return Err(config_error("sides", format!("the {name} velocity profile is not finite")));
                }
            }
        }
        for sp in &cfg.sponges {
            let across = match sp.edge {
                Edge::West | Edge::East => nx,
                Edge::South | Edge::North => ny,
            };
            if sp.width == 0 || sp.width >= across {
                return Err(config_error(
                    "sponges",
                    format!(
                        "the {} layer is {} nodes thick; it must be 1 to {}",
                        sp.edge.name(),
                        sp.width,
                        across - 1
                    ),
                ));
            }
            if !(sp.strength > 0.0 && sp.strength <= 1.0) {
                return Err(config_error(
                    "sponges",
                    format!("the {} layer's strength {} must be in (0, 1]", sp.edge.name(), sp.strength),
                ));
            }
            if !(sp.rho.is_finite() && sp.rho > 0.0 && sp.u[0].is_finite() && sp.u[1].is_finite()) {
                return Err(config_error(
                    "sponges",
                    format!("the {} layer's target state is not finite", sp.edge.name()),
                ));
            }
            if s.get(sp.edge) == &Side::Periodic {
                return Err(config_error(
                    "sponges",
                    format!("the {} edge is periodic; a layer needs an open or closed edge", sp.edge.name()),
                ));
            }
        }
        let periodic_x = s.west == Side::Periodic;
        let periodic_y = s.south == Side::Periodic;
        if comm.size() > 1 && cfg.characteristic_inlet.is_some() {
            return Err(config_error(
                "characteristic_inlet",
                "the characteristic inlet averages the density along its edge on one process; \
                 run without mpirun or with a rigid inlet (characteristic_time = 0)",
            ));
        }
        let part =
            Part::of([nx, ny, 1], [periodic_x, periodic_y, false], comm.rank(), comm.size()).map_err(|m| config_error("ranks", m))?;
        let grid = cfg.grid;

        // Solid nodes: inside a body, or on its wall (see `ON_WALL`).
        let on_wall = ON_WALL * grid.dx;
        let mut solid = vec![false; nx * ny];
        let mut owner = vec![u16::MAX; nx * ny];
        for (b, body) in bodies.iter().enumerate() {
            let bb = body.bounding_box();
            let lo_x = (((bb[0] - grid.origin[0]) / grid.dx).floor().max(0.0)) as usize;
            let lo_y = (((bb[1] - grid.origin[1]) / grid.dx).floor().max(0.0)) as usize;
            let hi_x = (((bb[2] - grid.origin[0]) / grid.dx).ceil().min((nx - 1) as f64)).max(0.0) as usize;
            let hi_y = (((bb[3] - grid.origin[1]) / grid.dx).ceil().min((ny - 1) as f64)).max(0.0) as usize;
            for y in lo_y.min(ny - 1)..=hi_y {
                for x in lo_x.min(nx - 1)..=hi_x {
                    if body.sdf(grid.position(x as f64, y as f64)) <= on_wall && !solid[y * nx + x] {
                        solid[y * nx + x] = true;
                        owner[y * nx + x] = b as u16;
                    }
                }
            }
        }
        if !bodies.is_empty() && solid.iter().all(|&s| s) {
            return Err(config_error("bodies", "the bodies fill the whole domain; enlarge the domain"));
        }

        // This rank's grid: its rows and a ghost row (whose edge is a placeholder, filled by the
        // exchange) towards each neighbour; a velocity edge's profile cut to the rows.
        let global = cfg.clone();
        let mut cfg = cfg;
        let gy = |yl: usize| part.global_index(yl);
        let nyl = part.local_n()[1];
        cfg.ny = nyl;
        if part.below.is_some() {
            cfg.sides.south = Side::Wall;
        }
        if part.above.is_some() {
            cfg.sides.north = Side::Wall;
        }
        for side in [&mut cfg.sides.west, &mut cfg.sides.east] {
            if let Side::Velocity { profile } = side {
                *profile = (0..nyl).map(|yl| profile[gy(yl)]).collect();
            }
        }
        let local_periodic_y = cfg.sides.south == Side::Periodic;

        // Links and the nodes that need the general path, row by row; a link is planned in the
        // whole grid (wrapping, positions, the body it meets) and stored at this rank's node.
        let wrap = |v: isize, n: usize, periodic: bool| -> Option<usize> {
            if v >= 0 && (v as usize) < n {
                Some(v as usize)
            } else if periodic {
                Some(v.rem_euclid(n as isize) as usize)
            } else {
                None
            }
        };
        let bulk_row = |yl: usize| local_periodic_y || (yl > 0 && yl + 1 < nyl);
        let mut specials = RowSpecials::with_rows(nyl);
        let mut links = Vec::new();
        let mut wall_points = Vec::new();
        for yl in 0..nyl {
            specials.begin_row();
            let y = gy(yl);
            // A ghost row is not stepped (the exchange fills it) and has no links.
            let ghost = !part.owns([0, yl, 0]);
            for x in 0..nx {
                let edge = x == 0 || x + 1 == nx || !bulk_row(yl);
                if ghost || solid[y * nx + x] {
                    specials.push(Special {
                        x: x as u32,
                        solid: true,
                        link_start: 0,
                        link_end: 0,
                    });
                    continue;
                }
                let link_start = links.len() as u32;
                for k in 1..Q {
                    let xs = wrap(x as isize - CX[k] as isize, nx, periodic_x);
                    let ys = wrap(y as isize - CY[k] as isize, ny, periodic_y);
                    let (Some(xs), Some(ys)) = (xs, ys) else { continue };
                    if !solid[ys * nx + xs] {
                        continue;
                    }
                    let b = owner[ys * nx + xs] as usize;
                    let i = OPP[k];
                    let a = grid.position(x as f64, y as f64);
                    let bpt = grid.position(x as f64 + CX[i] as f64, y as f64 + CY[i] as f64);
                    let body = &bodies[b];
                    let q = if body.sdf(bpt) <= on_wall {
                        body.wall_fraction(a, bpt)
                    } else {
                        0.5
                    };
                    let q = q.clamp(1e-3, 1.0);
                    let wp = [a[0] + q * (bpt[0] - a[0]), a[1] + q * (bpt[1] - a[1])];
                    links.push(Link {
                        cell: (yl * nx + x) as u32,
                        k: k as u8,
                        q: q as f32,
                        uw: [0.0, 0.0],
                        body: b as u16,
                    });
                    wall_points.push(WallPoint {
                        position: wp,
                        normal: body.normal(wp),
                        body: b,
                    });
                }
                let link_end = links.len() as u32;
                if edge || link_end > link_start {
                    specials.push(Special {
                        x: x as u32,
                        solid: false,
                        link_start,
                        link_end,
                    });
                }
            }
        }
        specials.finish();

        let local_solid: Vec<bool> = (0..nyl)
            .flat_map(|yl| solid[gy(yl) * nx..(gy(yl) + 1) * nx].iter().copied())
            .collect();
        let solid_global = part.is_split().then_some(solid);
        let relax = Relax::new(cfg.tau, cfg.smagorinsky);
        let n_bodies = bodies.len();
        let sums = n_bodies * ny * 2;
        let large = cfg.nx * cfg.ny * Q * 4 * 2 > STREAM_STORES_ABOVE_BYTES;
        let aa = cfg.propagation.unwrap_or(if large { Propagation::Aa } else { Propagation::Pull }) == Propagation::Aa && !part.is_split();
        let mut solver = D2q9 {
            relax,
            f: AlignedVec::zeros(nx * nyl * Q),
            f_next: AlignedVec::zeros(nx * nyl * Q),
            form: Form::Canonical,
            halo: if aa { vec![0.0; frame_of(&cfg).halo_len()] } else { Vec::new() },
            stash: if aa { vec![0.0; specials.len() * Q] } else { Vec::new() },
            aa,
            solid: local_solid,
            solid_global,
            specials,
            links,
            wall_points,
            bodies,
            body_forces: vec![[0.0; 2]; n_bodies],
            partial: vec![0.0; sums],
            summed: vec![0.0; sums],
            row_stats: vec![RowStat::default(); nyl],
            sponges: cfg.sponges.iter().map(SpongePlan::new).collect(),
            velocity_scale: 1.0,
            inlet_reference: cfg.characteristic_inlet.map(InletReference::new),
            time: 0,
            cfg,
            global,
            part,
            comm,
        };
        solver.init_with(|_, _| (1.0, 0.0, 0.0));
        Ok(solver)
    }

    /// Sets every fluid node to the equilibrium of `(rho, ux, uy) = field(x, y)` (physical
    /// position, lattice density and velocity); solid nodes rest. Resets the time to zero.
    pub fn init_with(&mut self, mut field: impl FnMut(f64, f64) -> (f64, f64, f64)) {
        let (nx, ny, nyl) = (self.global.nx, self.global.ny, self.cfg.ny);
        // Every node of the whole grid in order (a field may draw random numbers), kept on the
        // rows this rank holds.
        let rows: Vec<usize> = (0..nyl).map(|yl| self.part.global_index(yl)).collect();
        for y in 0..ny {
            let held: Vec<usize> = (0..nyl).filter(|&yl| rows[yl] == y).collect();
            for x in 0..nx {
                let e = if self.is_solid(x, y) {
                    [0.0; Q]
                } else {
                    let p = self.cfg.grid.position(x as f64, y as f64);
                    let (rho, ux, uy) = field(p[0], p[1]);
                    equilibrium((rho - 1.0) as f32, ux as f32, uy as f32)
                };
                for &yl in &held {
                    for (i, v) in e.iter().enumerate() {
                        self.f[(yl * Q + i) * nx + x] = *v;
                    }
                }
            }
        }
        self.f_next.copy_from_slice(&self.f);
        self.form = Form::Canonical;
        self.time = 0;
        let post = Post::canonical(&self.f, frame_of(&self.cfg));
        if let Some(r) = &mut self.inlet_reference {
            r.reset(&self.cfg.sides, &post, &self.solid, nx, nyl);
        }
    }

    /// The current post-collision populations, whatever their form.
    fn post(&self) -> Post<'_> {
        Post {
            f: &self.f,
            halo: &self.halo,
            form: self.form,
            frame: frame_of(&self.cfg),
        }
    }

    /// Brings the populations to the canonical form (slot `(x, i)` holds `f*_i(x)`).
    fn canonicalize(&mut self) {
        match self.form {
            Form::Canonical => {}
            Form::Swapped => swap_directions(&mut self.f, self.cfg.nx),
            Form::Streamed => {
                let post = Post {
                    f: &self.f,
                    halo: &self.halo,
                    form: self.form,
                    frame: frame_of(&self.cfg),
                };
                canonical_into(&post, &mut self.f_next);
                std::mem::swap(&mut self.f, &mut self.f_next);
            }
        }
        self.form = Form::Canonical;
    }

    /// Advances the characteristic inlets' reference densities by one step (if there are any).
    fn update_inlet_reference(&mut self) {
        if let Some(mut r) = self.inlet_reference {
            r.update(&self.cfg.sides, &self.post(), &self.solid, self.cfg.nx, self.cfg.ny);
            self.inlet_reference = Some(r);
        }
    }

    /// Advances one time step (every rank together). Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        if self.aa {
            return self.step_aa();
        }
        let ctx = kernel_ctx(
            &self.cfg,
            self.relax,
            &self.solid,
            &self.specials,
            &self.links,
            self.velocity_scale,
            self.inlet_reference,
        );
        let src = &self.f;
        let row_len = Q * self.cfg.nx;
        let forced = self.cfg.body_force != [0.0, 0.0];
        let rows = self.f_next.par_chunks_mut(row_len).enumerate().with_min_len(4);
        let kernel = row_fn(self.cfg.collision, forced, self.cfg.smagorinsky > 0.0, false);
        let (nx, ny, sponges, solid, part) = (self.cfg.nx, self.global.ny, &self.sponges, &self.solid, &self.part);
        rows.for_each(|(y, row)| {
            kernel(&ctx, src, row, y);
            if part.owns([0, y, 0]) {
                apply_row(sponges, row, part.global_index(y), nx, ny, &solid[y * nx..(y + 1) * nx]);
            }
        });
        link_forces(
            &ctx,
            &Post::canonical(src, ctx.frame),
            |y| part.global_index(y),
            ny,
            &mut self.partial,
        );
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    /// One step of the AA pattern (one process): the specials' arriving populations and the
    /// link forces from the previous values, then every row in place (see [`super::aa`]).
    fn step_aa(&mut self) -> Result<(), LbmError> {
        if self.form == Form::Canonical {
            swap_directions(&mut self.f, self.cfg.nx);
            self.form = Form::Swapped;
        }
        let ctx = kernel_ctx(
            &self.cfg,
            self.relax,
            &self.solid,
            &self.specials,
            &self.links,
            self.velocity_scale,
            self.inlet_reference,
        );
        let post = Post {
            f: &self.f,
            halo: &self.halo,
            form: self.form,
            frame: ctx.frame,
        };
        gather_specials(&ctx, &post, &mut self.stash);
        link_forces(&ctx, &post, |y| y, self.cfg.ny, &mut self.partial);
        let odd = self.form == Form::Swapped;
        let forced = self.cfg.body_force != [0.0, 0.0];
        let kernel = aa_row_fn(self.cfg.collision, forced, self.cfg.smagorinsky > 0.0);
        let cells = Cells::new(&mut self.f, &mut self.halo);
        let (stash, sponges) = (&self.stash, &self.sponges);
        (0..self.cfg.ny)
            .into_par_iter()
            .with_min_len(4)
            .for_each(|y| kernel(&ctx, &cells, stash, sponges, y, odd));
        self.form = if odd { Form::Streamed } else { Form::Swapped };
        self.finish_step()
    }

    /// The rest of a step after the kernel: the ghost rows, the forces summed over the ranks,
    /// the characteristic inlet, and the blow-up checks.
    fn finish_step(&mut self) -> Result<(), LbmError> {
        self.exchange();
        self.time += 1;
        self.update_inlet_reference();
        self.total_forces();
        for (b, force) in self.body_forces.iter().enumerate() {
            if !force[0].is_finite() || !force[1].is_finite() {
                let (x, y) = self.first_link_of(b);
                return Err(LbmError::Diverged {
                    step: self.time,
                    reason: format!("the force on body {b} is not finite"),
                    x,
                    y,
                });
            }
        }
        if self.cfg.check_interval > 0 && self.time.is_multiple_of(self.cfg.check_interval) {
            self.check()?;
        }
        Ok(())
    }

    /// Advances `n` steps.
    pub fn advance(&mut self, n: u64) -> Result<(), LbmError> {
        for _ in 0..n {
            self.step()?;
        }
        Ok(())
    }

    /// Scans every node for NaN, density out of `rho_bounds` or speed above `u_max`; reports the
    /// first bad node in row order (the same on every rank).
    pub fn check(&mut self) -> Result<(), LbmError> {
        let post = Post {
            f: &self.f,
            halo: &self.halo,
            form: self.form,
            frame: frame_of(&self.cfg),
        };
        let (nx, solid, part) = (self.cfg.nx, &self.solid, &self.part);
        self.row_stats.par_iter_mut().enumerate().for_each(|(y, st)| {
            *st = if part.owns([0, y, 0]) {
                scan_row(&post, solid, nx, y)
            } else {
                RowStat::default()
            };
        });
        let [rho_lo, rho_hi] = self.cfg.rho_bounds;
        let u2_max = self.cfg.u_max * self.cfg.u_max;
        // This rank's first bad node: (global row, x, what, value), `what` 1-4 as below.
        let bad = self
            .row_stats
            .iter()
            .enumerate()
            .filter(|(y, _)| part.owns([0, *y, 0]))
            .find_map(|(y, st)| {
                let y = part.global_index(y) as f64;
                if let Some(x) = st.nan_at {
                    Some([y, x as f64, 1.0, 0.0])
                } else if st.rho_min.0 < rho_lo {
                    Some([y, st.rho_min.1 as f64, 2.0, st.rho_min.0 as f64])
                } else if st.rho_max.0 > rho_hi {
                    Some([y, st.rho_max.1 as f64, 3.0, st.rho_max.0 as f64])
                } else if st.u2_max.0 > u2_max {
                    Some([y, st.u2_max.1 as f64, 4.0, st.u2_max.0.sqrt() as f64])
                } else {
                    None
                }
            });
        // The lowest rank's first comes first in row order.
        let Some(first) = self.comm.lowest_rank(bad.as_ref().map(|b| &b[..]), 4) else {
            return Ok(());
        };
        let [y, x, what, value] = [first[0], first[1], first[2], first[3]];
        let value = value as f32;
        let reason = match what as u8 {
            1 => "NaN in the populations".to_string(),
            2 => format!("density {value:.4} below {rho_lo}"),
            3 => format!("density {value:.4} above {rho_hi}"),
            _ => format!(
                "lattice speed {value:.4} above {} (Mach {:.2})",
                self.cfg.u_max,
                value * 3f32.sqrt()
            ),
        };
        Err(LbmError::Diverged {
            step: self.time,
            reason,
            x: x as usize,
            y: y as usize,
        })
    }

    /// Multiplies every [`Side::Velocity`] profile by `scale` from the next step on (inlet ramps).
    pub fn set_boundary_velocity_scale(&mut self, scale: f64) {
        self.velocity_scale = scale as f32;
    }

    /// Sets every node of the [`Side::Velocity`] edge `edge` to the lattice velocity `u` from the
    /// next step on: time-dependent inflow (a gust, a pulsatile inlet). Allocates nothing.
    pub fn set_side_velocity(&mut self, edge: Edge, u: [f64; 2]) -> Result<(), LbmError> {
        if !(u[0].is_finite() && u[1].is_finite()) {
            return Err(config_error("sides", format!("the {} velocity {u:?} is not finite", edge.name())));
        }
        match self.global.sides.get_mut(edge) {
            Side::Velocity { profile } => {
                profile.fill([u[0] as f32, u[1] as f32]);
                // This rank's copy: the same edge (a velocity edge is never a ghost's placeholder).
                if let Side::Velocity { profile } = self.cfg.sides.get_mut(edge) {
                    profile.fill([u[0] as f32, u[1] as f32]);
                }
                Ok(())
            }
            other => Err(config_error(
                "sides",
                format!("the {} edge is a {} side, not a velocity side", edge.name(), other.name()),
            )),
        }
    }

    /// Sets the wall velocity (lattice units) of every link of `body` from its wall point:
    /// rotation is `u_w = Omega x (p - c)`, a jet a normal velocity over an arc. The same path
    /// serves every moving-wall boundary.
    pub fn set_wall_velocity(&mut self, body: usize, mut velocity: impl FnMut(&WallPoint) -> [f64; 2]) {
        for (l, wp) in self.links.iter_mut().zip(&self.wall_points) {
            if l.body as usize == body {
                let u = velocity(wp);
                l.uw = [u[0] as f32, u[1] as f32];
            }
        }
    }

    /// Sets the wall velocity of the listed links only (indices into [`D2q9::wall_points`]);
    /// the others keep theirs.
    pub fn set_link_velocities(&mut self, links: &[usize], mut velocity: impl FnMut(&WallPoint) -> [f64; 2]) {
        for &l in links {
            let u = velocity(&self.wall_points[l]);
            self.links[l].uw = [u[0] as f32, u[1] as f32];
        }
    }

    /// Mass (lattice units) that the moving-wall terms of the Bouzidi rule inject into the fluid
    /// per step for `body`: `sum over links of 6 w_k rho_w c_k . u_w` (divided by `2q` where
    /// `q >= 1/2`), with `rho_w = 1`. Zero for a resting wall; zero to round-off for a
    /// zero-net-mass-flux jet pair.
    pub fn wall_mass_source(&self, body: usize) -> f64 {
        let nx = self.cfg.nx;
        let terms = self.links.iter().filter(|l| l.body as usize == body).map(|l| {
            let k = l.k as usize;
            let cu = CX[k] as f64 * l.uw[0] as f64 + CY[k] as f64 * l.uw[1] as f64;
            let term = 6.0 * super::lattice::W[k] as f64 * cu;
            (l.cell as usize / nx, if l.q < 0.5 { term } else { term / (2.0 * l.q as f64) })
        });
        self.split_sum(terms)
    }

    /// The wall points (one per link) of every body, this rank's links.
    pub fn wall_points(&self) -> &[WallPoint] {
        &self.wall_points
    }

    /// Hydrodynamic force on each body during the last step, lattice units, by the
    /// Galilean-invariant momentum exchange of Wen et al. (J. Comput. Phys. 266, 2014).
    pub fn body_forces(&self) -> &[[f64; 2]] {
        &self.body_forces
    }

    pub fn bodies(&self) -> &[Arc<dyn Shape>] {
        &self.bodies
    }

    /// Steps taken since the last initialisation.
    pub fn time(&self) -> u64 {
        self.time
    }

    /// Nodes along x of the whole grid.
    pub fn nx(&self) -> usize {
        self.global.nx
    }

    /// Nodes along y of the whole grid.
    pub fn ny(&self) -> usize {
        self.global.ny
    }

    /// The whole grid's configuration.
    pub fn config(&self) -> &D2q9Config {
        &self.global
    }

    /// `(rank, ranks)` of the group the grid is split over; `(0, 1)` on one process.
    pub fn rank(&self) -> (usize, usize) {
        (self.comm.rank(), self.comm.size())
    }

    /// Whether `yes` holds on every rank (a collective: every rank calls it).
    pub fn all_ranks(&self, yes: bool) -> bool {
        self.comm.all(yes)
    }

    /// Whether node `(x, y)` of the whole grid is solid.
    pub fn is_solid(&self, x: usize, y: usize) -> bool {
        self.solid_global.as_ref().unwrap_or(&self.solid)[y * self.global.nx + x]
    }

    /// Number of fluid nodes of the whole grid.
    pub fn fluid_nodes(&self) -> usize {
        self.solid_global.as_ref().unwrap_or(&self.solid).iter().filter(|s| !**s).count()
    }

    /// Whether this rank owns row `y` of the whole grid (every row, on one process).
    pub(crate) fn owns_row(&self, y: usize) -> bool {
        self.local_row(y).is_some_and(|yl| self.part.owns([0, yl, 0]))
    }

    /// Triples summed over the ranks (each held by one rank, zeros elsewhere: exact).
    pub(crate) fn sum_over_ranks(&self, v: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
        if !self.part.is_split() {
            return v;
        }
        let flat: Vec<f64> = v.iter().flatten().copied().collect();
        let mut all = vec![0.0; flat.len()];
        self.comm.sum(&flat, &mut all);
        all.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// This rank's row of row `y` of the whole grid, if it holds it (owned or ghost).
    fn local_row(&self, y: usize) -> Option<usize> {
        self.part.local([0, y, 0]).map(|p| p[1])
    }

    /// Density and velocity of node `(x, y)` of the whole grid (lattice units); on a split grid
    /// the node must be on this rank's rows (owned or ghost).
    pub fn node(&self, x: usize, y: usize) -> (f32, f32, f32) {
        let y = self.local_row(y).expect("node: a row this rank does not hold");
        self.density_velocity(&self.post().node(x, y))
    }

    /// The nine shifted post-collision populations `g_i = f_i* - w_i` of node `(x, y)`.
    ///
    /// This and the three methods after it couple nested grids, which run on one process: on a
    /// split grid they would address this rank's rows, and they are refused there.
    pub fn node_populations(&self, x: usize, y: usize) -> [f32; Q] {
        assert!(!self.part.is_split(), "grid coupling on a split grid");
        self.post().node(x, y)
    }

    /// Overwrites the shifted post-collision populations of node `(x, y)` (grid coupling: the
    /// next step streams them like any other node's). Allocates nothing.
    pub fn set_node_populations(&mut self, x: usize, y: usize, g: &[f32; Q]) {
        assert!(!self.part.is_split(), "grid coupling on a split grid");
        let frame = frame_of(&self.cfg);
        for (i, v) in g.iter().enumerate() {
            match frame.locate(self.form, x, y, i) {
                Loc::Grid(k) => self.f[k] = *v,
                Loc::Halo(k) => self.halo[k] = *v,
            }
        }
    }

    /// Rewrites rows `ys` of the shifted post-collision populations, rows in parallel (grid
    /// coupling: the restriction of a refined patch): `rewrite(y, solid, row)` gets row `y`'s
    /// solid flags (`solid[x]`) and populations (`row[i * nx + x]`, population `i` of node `x`).
    /// A row's new values must depend on its position and the inputs alone, so the result is
    /// the same for any thread count. Allocates nothing.
    pub fn rewrite_rows(&mut self, ys: std::ops::Range<usize>, rewrite: impl Fn(usize, &[bool], &mut [f32]) + Sync) {
        assert!(!self.part.is_split(), "grid coupling on a split grid");
        self.canonicalize();
        let nx = self.cfg.nx;
        let (solid, y0, ny) = (&self.solid, ys.start, ys.len());
        self.f.par_chunks_mut(Q * nx).skip(y0).take(ny).enumerate().for_each(|(k, row)| {
            let y = y0 + k;
            rewrite(y, &solid[y * nx..(y + 1) * nx], row);
        });
    }

    /// Row `y`'s solid flags (`[x]`) and shifted post-collision populations (`[i * nx + x]`).
    /// Needs the pull propagation ([`D2q9Config::propagation`]), which keeps rows canonical.
    pub fn row(&self, y: usize) -> (&[bool], &[f32]) {
        assert!(!self.part.is_split(), "grid coupling on a split grid");
        assert!(
            self.form == Form::Canonical,
            "row: the AA pattern holds rows in another form; couple grids with propagation = Pull"
        );
        let nx = self.cfg.nx;
        (&self.solid[y * nx..(y + 1) * nx], &self.f[y * Q * nx..(y + 1) * Q * nx])
    }

    /// Density and (half-force-corrected) velocity of one node's shifted populations.
    #[inline(always)]
    fn density_velocity(&self, g: &[f32; Q]) -> (f32, f32, f32) {
        let (drho, jx, jy) = moments(g);
        let rho = 1.0 + drho;
        let (fx, fy) = (self.cfg.body_force[0] as f32, self.cfg.body_force[1] as f32);
        (rho, (jx + 0.5 * fx) / rho, (jy + 0.5 * fy) / rho)
    }

    /// Fills density and velocity fields of the whole grid (row-major `y * nx + x`, lattice
    /// units). Rows run in parallel (each node is independent: the same result for any thread
    /// count); on a split grid each rank fills its rows and the fields are summed over the ranks
    /// (exact: every value comes from one rank).
    pub fn macroscopic(&self, rho: &mut [f32], ux: &mut [f32], uy: &mut [f32]) {
        let nx = self.cfg.nx;
        let part = &self.part;
        let post = self.post();
        rho.par_chunks_mut(nx)
            .zip(ux.par_chunks_mut(nx))
            .zip(uy.par_chunks_mut(nx))
            .take(self.global.ny)
            .enumerate()
            .for_each(|(y, ((r, u), v))| {
                let held = self.local_row(y).filter(|&yl| part.owns([0, yl, 0]));
                let Some(yl) = held else {
                    r.fill(0.0);
                    u.fill(0.0);
                    v.fill(0.0);
                    return;
                };
                for x in 0..nx.min(r.len()) {
                    (r[x], u[x], v[x]) = self.density_velocity(&post.node(x, yl));
                }
            });
        if self.part.is_split() {
            for field in [rho, ux, uy] {
                let mine: Vec<f64> = field.iter().map(|&v| v as f64).collect();
                let mut all = vec![0.0; mine.len()];
                self.comm.sum(&mine, &mut all);
                field.iter_mut().zip(&all).for_each(|(v, a)| *v = *a as f32);
            }
        }
    }

    /// Total mass `sum rho` over fluid nodes, in f64: per row in node order, then over the rows
    /// in order (every rank gets the same bits).
    pub fn total_mass(&self) -> f64 {
        let nx = self.cfg.nx;
        let fluid = (0..self.cfg.ny)
            .filter(|&y| self.part.owns([0, y, 0]))
            .flat_map(|y| (0..nx).map(move |x| (x, y)))
            .filter(|&(x, y)| !self.solid[y * nx + x]);
        let post = self.post();
        self.split_sum(fluid.map(|(x, y)| (y, 1.0 + post.node(x, y).iter().map(|&g| g as f64).sum::<f64>())))
    }

    /// The sum of `terms` (this rank's row, value), bitwise the same on any number of ranks: per
    /// row of the whole grid first, then in row order (see [`super::part`]).
    fn split_sum(&self, terms: impl Iterator<Item = (usize, f64)>) -> f64 {
        let mut per_row = vec![0.0f64; self.global.ny];
        for (y, v) in terms {
            per_row[self.part.global_index(y)] += v;
        }
        let mut summed = vec![0.0; per_row.len()];
        self.comm.sum(&per_row, &mut summed);
        summed.iter().sum()
    }

    /// The forces of the last step: the per-row terms summed over the ranks, then over the rows
    /// in order, per body.
    fn total_forces(&mut self) {
        self.comm.sum(&self.partial, &mut self.summed);
        for (f, rows) in self.body_forces.iter_mut().zip(self.summed.chunks(2 * self.global.ny)) {
            *f = [0.0; 2];
            for v in rows.chunks(2) {
                f[0] += v[0];
                f[1] += v[1];
            }
        }
    }

    /// The first link of body `b` in the whole grid's order (where a non-finite force is reported).
    fn first_link_of(&self, b: usize) -> (usize, usize) {
        let nx = self.cfg.nx;
        let mine = self.links.iter().find(|l| l.body as usize == b).map(|l| {
            let y = l.cell as usize / nx;
            [(l.cell as usize % nx) as f64, self.part.global_index(y) as f64]
        });
        let first = self.comm.lowest_rank(mine.as_ref().map(|m| &m[..]), 2);
        first.map_or((0, 0), |c| (c[0] as usize, c[1] as usize))
    }

    /// Sends the owned rows next to each neighbour into its ghost row and fills this rank's
    /// ghosts from them: up, then down. Rows are contiguous, so they go as they lie. Allocates
    /// nothing.
    fn exchange(&mut self) {
        if !self.part.is_split() {
            return;
        }
        let len = Q * self.cfg.nx;
        let (own, last) = (self.part.own.clone(), self.cfg.ny - 1);
        // Up: the last owned row to the rank above, into ghost 0 from the rank below; then down.
        let passes = [
            (own.end - 1, self.part.above, 0, self.part.below),
            (own.start, self.part.below, last, self.part.above),
        ];
        for (send, to, recv, from) in passes {
            let (lo, hi) = self.f.split_at_mut(send.max(recv) * len);
            let (send_row, recv_row) = if send < recv {
                (&lo[send * len..][..len], &mut hi[..len])
            } else {
                (&hi[..len], &mut lo[recv * len..][..len])
            };
            self.comm.shift(to.map(|r| (send_row, r)), from.map(|r| (recv_row, r)));
        }
    }

    /// The shifted post-collision populations in the canonical row-blocked SoA (see the crate
    /// docs; slot `(x, i)` holds `f*_i(x)`); for tests and checkpoints. Borrowed when the
    /// array holds them so, else converted.
    pub fn populations(&self) -> Cow<'_, [f32]> {
        match self.form {
            Form::Canonical => Cow::Borrowed(&self.f),
            _ => {
                let mut f = vec![0.0; self.f.len()];
                canonical_into(&self.post(), &mut f);
                Cow::Owned(f)
            }
        }
    }

    /// How many values [`Self::populations`] holds.
    pub fn population_count(&self) -> usize {
        self.f.len()
    }

    /// Overwrites the populations (e.g. from a checkpoint) and sets the step counter.
    pub fn set_populations(&mut self, f: &[f32], time: u64) -> Result<(), LbmError> {
        if f.len() != self.f.len() {
            return Err(config_error(
                "populations",
                format!("expected {} values, got {}", self.f.len(), f.len()),
            ));
        }
        self.f.copy_from_slice(f);
        self.form = Form::Canonical;
        self.time = time;
        Ok(())
    }

    /// Slow oracle for tests: the same step written as a plain loop over nodes and directions
    /// (no bulk/special split, no vectorisation), single-threaded.
    #[doc(hidden)]
    pub fn step_reference(&mut self) -> Result<(), LbmError> {
        self.canonicalize();
        let ctx = kernel_ctx(
            &self.cfg,
            self.relax,
            &self.solid,
            &self.specials,
            &self.links,
            self.velocity_scale,
            self.inlet_reference,
        );
        let forced = self.cfg.body_force != [0.0, 0.0];
        let row_len = Q * self.cfg.nx;
        let kernel = row_fn(self.cfg.collision, forced, self.cfg.smagorinsky > 0.0, true);
        let (nx, ny, part) = (self.cfg.nx, self.global.ny, &self.part);
        for (y, row) in self.f_next.chunks_mut(row_len).enumerate() {
            kernel(&ctx, &self.f, row, y);
            if part.owns([0, y, 0]) {
                apply_row(&self.sponges, row, part.global_index(y), nx, ny, &self.solid[y * nx..(y + 1) * nx]);
            }
        }
        link_forces(
            &ctx,
            &Post::canonical(&self.f, ctx.frame),
            |y| part.global_index(y),
            ny,
            &mut self.partial,
        );
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    /// Fills the spare array with NaN (tests: results must not depend on its contents).
    #[doc(hidden)]
    pub fn poison_scratch(&mut self) {
        self.f_next.iter_mut().for_each(|v| *v = f32::NAN);
    }
}
