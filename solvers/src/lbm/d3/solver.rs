//! The 3D solver: construction (plan the solid nodes, links and specials once) and the step
//! (execute many: rayon over rows, no allocation, bitwise the same for any thread count).

use rayon::prelude::*;

use super::super::aligned::AlignedVec;
use super::super::collision::{Collision, Relax, OP_BGK, OP_REG, OP_STREAM};
use super::super::error::LbmError;
use super::super::solver::STREAM_STORES_ABOVE_BYTES;
use super::super::specials::{RowSpecials, Special};
use super::collision::{collide, equilibrium, moments};
use super::kernel::{bouzidi, gather, index, plan_pulls, plane_narrow, plane_widest, Ctx, FaceMoments, FacePull, Link, PAD};
use super::lattice::Lattice3;
use super::sides::{Face, Faces};
use super::sponge::{apply_plane, Layers, Sponge3, Sponge3Plan};
use crate::comm::{Comm, Solo};
use crate::geometry::Solid;
use crate::lbm::part::Part;

/// Where node `(i, j, k)` sits in physical space: `origin + (i, j, k) dx`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid3 {
    pub origin: [f64; 3],
    pub dx: f64,
}

impl Grid3 {
    /// Lattice units: node `(i, j, k)` at `(i, j, k)`.
    pub fn lattice() -> Self {
        Grid3 { origin: [0.0; 3], dx: 1.0 }
    }

    pub fn position(&self, p: [usize; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + p[a] as f64 * self.dx)
    }
}

/// Everything needed to build an [`Lbm3`]. Bodies are placed in the physical coordinates of
/// `grid`.
#[derive(Clone, Debug)]
pub struct D3Config {
    /// Nodes along x, y, z.
    pub n: [usize; 3],
    pub faces: Faces,
    pub grid: Grid3,
    /// Equal spanwise (z) segments the forces on each body are also reported for.
    pub segments: usize,
    /// Relaxation time; `nu = (tau - 1/2) / 3`.
    pub tau: f64,
    pub collision: Collision,
    /// Smagorinsky constant (regularised operator only; 0 = none).
    pub smagorinsky: f64,
    /// Uniform body force per unit volume, Guo forcing.
    pub body_force: [f64; 3],
    /// Full blow-up scan every this many steps (0: never).
    pub check_interval: u64,
    pub rho_bounds: [f32; 2],
    pub u_max: f32,
    /// Non-temporal stores for the bulk: `None` decides by size (as in 2D,
    /// [`STREAM_STORES_ABOVE_BYTES`]). A performance knob only: results are bitwise the same.
    pub stream_stores: Option<bool>,
    /// Absorbing layers, applied after each collision.
    pub sponges: Vec<Sponge3>,
}

impl D3Config {
    /// Defaults for everything but the size and the relaxation time.
    pub fn new(n: [usize; 3], tau: f64) -> Self {
        D3Config {
            n,
            faces: Faces::periodic(),
            grid: Grid3::lattice(),
            segments: 1,
            tau,
            collision: Collision::Regularized,
            smagorinsky: 0.0,
            body_force: [0.0; 3],
            check_interval: 100,
            rho_bounds: [0.5, 2.0],
            u_max: 0.5,
            stream_stores: None,
            sponges: vec![],
        }
    }
}

/// The plane kernel for one set of compile-time switches.
type PlaneFn = fn(&Ctx, &[f32], &[f32], usize, &mut [f32]);

/// `$f::<Q, L, OP, FORCED, LES>` for the operator, forcing and subgrid model chosen at run time
/// (the subgrid model exists only for the regularised operator): the kernel and the oracle's
/// collision are picked by the same table.
macro_rules! monomorphised {
    ($f:ident, $collision:expr, $forced:expr, $les:expr) => {
        match ($collision, $forced, $les) {
            (Collision::Bgk, false, _) => $f::<Q, L, OP_BGK, false, false>,
            (Collision::Bgk, true, _) => $f::<Q, L, OP_BGK, true, false>,
            (_, false, false) => $f::<Q, L, OP_REG, false, false>,
            (_, true, false) => $f::<Q, L, OP_REG, true, false>,
            (_, false, true) => $f::<Q, L, OP_REG, false, true>,
            (_, true, true) => $f::<Q, L, OP_REG, true, true>,
        }
    };
}

/// Selects the kernel monomorphised for the operator, forcing and subgrid model, on the widest
/// vector blocks the CPU runs or (`narrow`) on 8-node blocks.
fn plane_fn<const Q: usize, L: Lattice3<Q>>(collision: Collision, forced: bool, les: bool, narrow: bool) -> PlaneFn {
    if narrow {
        monomorphised!(plane_narrow, collision, forced, les)
    } else {
        monomorphised!(plane_widest, collision, forced, les)
    }
}

/// What the blow-up scan found at a node.
#[derive(Clone, Copy)]
enum Bad {
    NaN,
    RhoLow(f32),
    RhoHigh(f32),
    Speed(f32),
}

impl Bad {
    /// As two numbers, to be summed over the ranks.
    fn code(self) -> (f64, f64) {
        match self {
            Bad::NaN => (0.0, 0.0),
            Bad::RhoLow(v) => (1.0, v as f64),
            Bad::RhoHigh(v) => (2.0, v as f64),
            Bad::Speed(v) => (3.0, v as f64),
        }
    }

    fn from_code(code: f64, value: f32) -> Self {
        match code as u8 {
            1 => Bad::RhoLow(value),
            2 => Bad::RhoHigh(value),
            3 => Bad::Speed(value),
            _ => Bad::NaN,
        }
    }
}

/// Layer `i` along `axis` of a box of `n` nodes as runs of contiguous populations,
/// `run(start, len)` in a fixed order (the order a layer is packed in for its neighbour).
fn layer_runs<const Q: usize>(n: [usize; 3], axis: usize, i: usize, mut run: impl FnMut(usize, usize)) {
    let range = |a: usize| if a == axis { i..i + 1 } else { 0..n[a] };
    for z in range(2) {
        for q in 0..Q {
            for y in range(1) {
                if axis == 0 {
                    run(index::<Q>(n, [i, y, z], q), 1);
                } else {
                    run(index::<Q>(n, [0, y, z], q), n[0]);
                }
            }
        }
    }
}

/// A D3Q19 or D3Q27 lattice-Boltzmann solver on a periodic box with immersed bodies, in one
/// process or split over ranks ([`Lbm3::new_split`]).
pub struct Lbm3<const Q: usize, L: Lattice3<Q>> {
    /// The configuration of the box this process holds (its slab and ghost layers when split).
    cfg: D3Config,
    /// The configuration of the whole box.
    global_cfg: D3Config,
    part: Part,
    comm: Box<dyn Comm>,
    /// One layer of populations across the split axis, sent and received after each step.
    halo_send: Vec<f32>,
    halo_recv: Vec<f32>,
    /// The moments of the velocity and outlet faces' layers, gathered at the start of each step.
    face_moments: FaceMoments,
    /// The velocity faces' profiles (see `Ctx::face_profiles`).
    face_profiles: [Vec<f32>; 6],
    /// Per (body, segment, index along the split axis) force sums, before and after the ranks'
    /// sum: `[((b segments + s) n_axis + i) 3 + a]`.
    partial: Vec<f64>,
    summed: Vec<f64>,
    /// Each link's momentum exchange in the last step, and the `partial` entry it adds to
    /// (`3 bin`), planned once.
    link_force: Vec<[f64; 3]>,
    link_bin: Vec<u32>,
    relax: Relax,
    velocity_scale: f32,
    f: AlignedVec,
    f_next: AlignedVec,
    plan: Plan,
    /// Force on each (body, segment), `[b * segments + s]`, during the last step.
    segment_forces: Vec<[f64; 3]>,
    body_forces: Vec<[f64; 3]>,
    sponges: Vec<Sponge3Plan>,
    time: u64,
    /// Run the bulk on 8-node blocks even where the CPU has 16 ([`Lbm3::use_narrow_blocks`]).
    narrow_blocks: bool,
    _lattice: std::marker::PhantomData<L>,
}

/// What the step reads besides the populations, planned once.
struct Plan {
    solid: Vec<bool>,
    specials: RowSpecials,
    row_bulk: Vec<bool>,
    links: Vec<Link>,
    pulls: Vec<FacePull>,
    pull_start: Vec<u32>,
}

impl Plan {
    /// Plans the face pulls of every special fluid node (the faces of `cfg`).
    fn plan_pulls<const Q: usize, L: Lattice3<Q>>(&mut self, cfg: &D3Config) -> Result<(), LbmError> {
        if cfg.n.iter().product::<usize>() * Q > u32::MAX as usize {
            return Err(LbmError::Config {
                field: "n",
                message: format!(
                    "{} x {} x {} nodes x {Q} populations exceed the 2^32 a rank can index; split the box over more ranks",
                    cfg.n[0], cfg.n[1], cfg.n[2]
                ),
            });
        }
        let (mut pulls, mut pull_start) = (Vec::new(), Vec::with_capacity(self.specials.len() + 1));
        let (none, uniform) = (FaceMoments::default(), Default::default());
        let c = ctx::<Q>(cfg, self, &none, &uniform, Relax::new(cfg.tau, 0.0), 1.0, Layers(&[]));
        let [_, ny, _] = cfg.n;
        for r in 0..self.specials.rows() {
            let (y, z) = (r % ny, r / ny);
            for sp in self.specials.row(r).1 {
                pull_start.push(pulls.len() as u32);
                if !sp.solid {
                    plan_pulls::<Q, L>(&c, [sp.x as usize, y, z], &mut pulls);
                }
            }
        }
        pull_start.push(pulls.len() as u32);
        self.pulls = pulls;
        self.pull_start = pull_start;
        Ok(())
    }
}

fn ctx<'a, const Q: usize>(
    cfg: &'a D3Config,
    plan: &'a Plan,
    face_moments: &'a FaceMoments,
    face_profiles: &'a [Vec<f32>; 6],
    relax: Relax,
    velocity_scale: f32,
    layers: Layers<'a>,
) -> Ctx<'a> {
    Ctx {
        n: cfg.n,
        periodic: [0, 1, 2].map(|a| cfg.faces.periodic_axis(a)),
        faces: &cfg.faces,
        velocity_scale,
        relax,
        force: cfg.body_force.map(|v| v as f32),
        solid: &plan.solid,
        specials: &plan.specials,
        row_bulk: &plan.row_bulk,
        links: &plan.links,
        pulls: &plan.pulls,
        pull_start: &plan.pull_start,
        face_moments,
        face_profiles,
        stream_stores: cfg
            .stream_stores
            .unwrap_or(cfg.n.iter().product::<usize>() * Q * 4 * 2 > STREAM_STORES_ABOVE_BYTES),
        layers,
    }
}

impl<const Q: usize, L: Lattice3<Q>> Lbm3<Q, L> {
    /// Plans the solver: solid nodes (`sdf < 0` of any body), the links of every fluid node
    /// whose neighbour is solid (with the wall fraction along the link) and the specials of
    /// every row. The flow starts at rest.
    pub fn new(cfg: D3Config, bodies: &[&dyn Solid]) -> Result<Self, LbmError> {
        Self::new_split(cfg, bodies, Box::new(Solo))
    }

    /// This rank's slab of the box `cfg` split over the ranks of `comm` along y or z
    /// ([`split_axis`](super::split_axis)): every rank calls this, and then every method below
    /// together (each step exchanges ghost layers; forces, probes, mass and the blow-up scan are
    /// summed over the ranks, bitwise the same as one process's). Node coordinates in arguments
    /// and errors are global.
    pub fn new_split(cfg: D3Config, bodies: &[&dyn Solid], comm: Box<dyn Comm>) -> Result<Self, LbmError> {
        let [nx, ny, nz] = cfg.n;
        let config = |field: &'static str, message: String| LbmError::Config { field, message };
        if nx < 1 || ny < 1 || nz < 1 {
            return Err(config("n", format!("every axis needs at least one node, got {:?}", cfg.n)));
        }
        for sp in &cfg.sponges {
            let a = sp.face / 2;
            if sp.face >= 6 || sp.width == 0 || sp.width > cfg.n[a.min(2)] || !(sp.strength > 0.0 && sp.strength <= 1.0) {
                return Err(config(
                    "sponges",
                    format!("a layer needs a face 0-5, a width of 1 to the nodes along its axis and a strength in (0, 1]; got {sp:?}"),
                ));
            }
        }
        if cfg.tau <= 0.5 + cfg.collision.min_tau_margin() {
            return Err(config(
                "tau",
                format!(
                    "{} leaves no stability margin for {} (needs > {}); use a finer grid or a lower lattice velocity",
                    cfg.tau,
                    cfg.collision.name(),
                    0.5 + cfg.collision.min_tau_margin()
                ),
            ));
        }
        if cfg.collision == Collision::Recursive {
            return Err(config(
                "collision",
                "the recursive-regularised operator is 2D only; use regularized (or bgk)".into(),
            ));
        }
        if cfg.smagorinsky > 0.0 && !cfg.collision.is_regularized() {
            return Err(config("smagorinsky", "the subgrid model needs the regularised operator".into()));
        }
        if let Some(a) = cfg.faces.mismatched_axis() {
            return Err(config(
                "faces",
                format!(
                    "axis {} has one periodic face and one not; make both periodic or neither",
                    ["x", "y", "z"][a]
                ),
            ));
        }
        if cfg.segments == 0 || !nz.is_multiple_of(cfg.segments) {
            return Err(config(
                "segments",
                format!(
                    "{} spanwise segments do not divide the {nz} nodes along z; use a divisor of {nz}",
                    cfg.segments
                ),
            ));
        }
        if bodies.len() > u16::MAX as usize {
            return Err(config("bodies", format!("{} bodies; at most {}", bodies.len(), u16::MAX)));
        }
        // This rank's box: its slab, and a ghost layer (whose faces are placeholders, overwritten
        // by the exchange) towards each neighbour.
        let part =
            Part::of(cfg.n, [0, 1, 2].map(|a| cfg.faces.periodic_axis(a)), comm.rank(), comm.size()).map_err(|m| config("ranks", m))?;
        let global_cfg = cfg.clone();
        let mut cfg = cfg;
        cfg.n = part.local_n();
        for (ghost, face) in [(part.below, 2 * part.axis), (part.above, 2 * part.axis + 1)] {
            if ghost.is_some() {
                cfg.faces.0[face] = Face::Wall;
            }
        }
        let [nx, ny, nz] = cfg.n;
        let cells = nx * ny * nz;
        if cells >= u32::MAX as usize {
            return Err(config(
                "n",
                format!("{cells} nodes exceed the 2^32 a link index can address; split the box over more ranks"),
            ));
        }
        let periodic = [0, 1, 2].map(|a| cfg.faces.periodic_axis(a));
        let node = |p: [usize; 3]| (p[2] * ny + p[1]) * nx + p[0];
        let pos = |p: [usize; 3]| cfg.grid.position(part.global(p));
        let inside = |x: [f64; 3]| bodies.iter().position(|b| b.sdf(x) < 0.0);
        let mut solid = vec![false; cells];
        // Bodies that are the same at every z: the first plane, copied along the span.
        let planes = if bodies.iter().all(|b| b.z_invariant()) { 1 } else { nz };
        for z in 0..planes {
            for y in 0..ny {
                for x in 0..nx {
                    solid[node([x, y, z])] = inside(pos([x, y, z])).is_some();
                }
            }
        }
        for z in planes..nz {
            solid.copy_within(0..nx * ny, z * nx * ny);
        }
        // The source `p - c` of a pull, wrapped along periodic axes; `None` outside the box.
        let source = |p: [usize; 3], c: [i32; 3]| -> Option<[usize; 3]> {
            let mut s = [0usize; 3];
            for a in 0..3 {
                let v = p[a] as isize - c[a] as isize;
                let n = cfg.n[a] as isize;
                s[a] = if (0..n).contains(&v) {
                    v as usize
                } else if periodic[a] {
                    v.rem_euclid(n) as usize
                } else {
                    return None;
                };
            }
            Some(s)
        };
        let mut specials = RowSpecials::with_rows(ny * nz);
        let mut links = Vec::new();
        let mut row_bulk = Vec::with_capacity(ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                specials.begin_row();
                let at_face = |v: usize, n: usize, a: usize| !periodic[a] && (v == 0 || v + 1 == n);
                let bulk = !at_face(y, ny, 1) && !at_face(z, nz, 2);
                row_bulk.push(bulk);
                for x in 0..nx {
                    let p = [x, y, z];
                    let is_solid = solid[node(p)];
                    // A ghost node is not stepped (the exchange fills it) and has no links.
                    let skip = is_solid || !part.owns(p);
                    let start = links.len() as u32;
                    if !skip {
                        for k in 1..Q {
                            let Some(s) = source(p, L::C_REF[k]) else { continue };
                            if !solid[node(s)] {
                                continue;
                            }
                            // The unwrapped segment from the node towards its solid source.
                            let a = pos(p);
                            let b = [0, 1, 2].map(|d| a[d] - L::C_REF[k][d] as f64 * cfg.grid.dx);
                            let body = inside(pos(s)).unwrap_or(0);
                            links.push(Link {
                                node: node(p) as u32,
                                k: k as u8,
                                q: bodies[body].wall_fraction(a, b) as f32,
                                uw: [0.0; 3],
                                body: body as u16,
                            });
                        }
                    }
                    let end = links.len() as u32;
                    // A row's ends wrap along a periodic x inside the bulk loop (which needs 3 nodes).
                    let end_node = (x == 0 || x + 1 >= nx) && !(periodic[0] && nx >= 3);
                    if !bulk || skip || end > start || end_node {
                        specials.push(Special {
                            x: x as u32,
                            solid: skip,
                            link_start: start,
                            link_end: end,
                        });
                    }
                }
            }
        }
        specials.finish();
        let mut plan = Plan {
            solid,
            specials,
            row_bulk,
            links,
            pulls: Vec::new(),
            pull_start: Vec::new(),
        };
        plan.plan_pulls::<Q, L>(&cfg)?;
        let layer = if part.is_split() { Q * cells / cfg.n[part.axis] } else { 0 };
        let sums = bodies.len() * cfg.segments * part.n_global[part.axis] * 3;
        Ok(Lbm3 {
            halo_send: vec![0.0; layer],
            halo_recv: vec![0.0; layer],
            partial: vec![0.0; sums],
            link_force: vec![[0.0; 3]; plan.links.len()],
            link_bin: plan.links.iter().map(|l| link_bin(&part, cfg.n, cfg.segments, l)).collect(),
            sponges: cfg.sponges.iter().map(|s| Sponge3Plan::new::<Q, L>(s, &part)).collect(),
            summed: vec![0.0; sums],
            part,
            comm,
            global_cfg,
            relax: Relax::new(cfg.tau, cfg.smagorinsky),
            velocity_scale: 1.0,
            f: AlignedVec::zeros_padded(cells * Q, PAD),
            f_next: AlignedVec::zeros_padded(cells * Q, PAD),
            plan,
            face_moments: FaceMoments::new(cfg.n, &cfg.faces),
            face_profiles: Default::default(),
            segment_forces: vec![[0.0; 3]; bodies.len() * cfg.segments],
            body_forces: vec![[0.0; 3]; bodies.len()],
            time: 0,
            cfg,
            narrow_blocks: false,
            _lattice: std::marker::PhantomData,
        })
    }

    /// The configuration of the whole box.
    pub fn config(&self) -> &D3Config {
        &self.global_cfg
    }

    /// Steps taken.
    pub fn time(&self) -> u64 {
        self.time
    }

    /// Restarts the step count (a refined grid's levels after a new initial state).
    pub(crate) fn reset_time(&mut self) {
        self.time = 0;
    }

    /// This rank's number and the number of ranks the box is split over.
    pub fn rank(&self) -> (usize, usize) {
        (self.comm.rank(), self.comm.size())
    }

    /// Whether `yes` holds on every rank (every rank calls this together): for decisions the
    /// ranks must take alike, such as reading a cached state only if every rank has its slab.
    pub fn all_ranks(&self, yes: bool) -> bool {
        self.comm.all(yes)
    }

    /// Whether this rank owns global node `p` (its slab, not a ghost layer).
    pub fn owns(&self, p: [usize; 3]) -> bool {
        self.part.local(p).is_some_and(|l| self.part.owns(l))
    }

    /// Index of global node `p`, which this rank must hold (own or as a ghost).
    fn node(&self, p: [usize; 3]) -> usize {
        let [nx, ny, _] = self.cfg.n;
        let l = self
            .part
            .local(p)
            .unwrap_or_else(|| panic!("node {p:?} lies outside this rank's slab {:?}", self.part));
        (l[2] * ny + l[1]) * nx + l[0]
    }

    /// Whether global node `p` is inside a body (this rank must hold it).
    pub fn is_solid(&self, p: [usize; 3]) -> bool {
        self.plan.solid[self.node(p)]
    }

    /// Number of links into bodies (from the nodes this rank owns).
    pub fn link_count(&self) -> usize {
        self.plan.links.len()
    }

    /// Sets every fluid node to the equilibrium of `init(x, y, z) = (rho, u)` (global node).
    pub fn set_equilibrium(&mut self, init: impl Fn(usize, usize, usize) -> (f64, [f64; 3])) {
        let [nx, ny, nz] = self.cfg.n;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let (rho, u) = if self.plan.solid[(z * ny + y) * nx + x] {
                        (1.0, [0.0; 3])
                    } else {
                        let [gx, gy, gz] = self.part.global([x, y, z]);
                        init(gx, gy, gz)
                    };
                    let geq = equilibrium::<Q, L>((rho - 1.0) as f32, u.map(|v| v as f32));
                    for (i, g) in geq.iter().enumerate() {
                        self.f[index::<Q>(self.cfg.n, [x, y, z], i)] = *g;
                    }
                }
            }
        }
    }

    /// Populations of local node `l` (shifted, `f_i - w_i`).
    fn populations(&self, l: [usize; 3]) -> [f32; Q] {
        std::array::from_fn(|i| self.f[index::<Q>(self.cfg.n, l, i)])
    }

    /// Populations of node `p` of a box this process holds whole (a refinement interface's
    /// reads; local and global indices agree there).
    pub(crate) fn node_populations(&self, p: [usize; 3]) -> [f32; Q] {
        debug_assert_eq!(self.comm.size(), 1, "refinement couples whole boxes");
        self.populations(p)
    }

    /// Rewrites planes `zs` of a box this process holds whole, planes in parallel (grid coupling:
    /// a refined patch's shell and restriction): `rewrite(z, solid, plane)` gets plane `z`'s
    /// solid flags (`[y nx + x]`) and populations (`[(i ny + y) nx + x]`). A plane's new values
    /// must depend on its position and the inputs alone, so the result is the same for any thread
    /// count. Allocates nothing.
    pub(crate) fn rewrite_planes(&mut self, zs: std::ops::Range<usize>, rewrite: impl Fn(usize, &[bool], &mut [f32]) + Sync) {
        debug_assert_eq!(self.comm.size(), 1, "refinement couples whole boxes");
        let [nx, ny, _] = self.cfg.n;
        let (solid, z0, nz) = (&self.plan.solid, zs.start, zs.len());
        self.f
            .par_chunks_mut(Q * nx * ny)
            .skip(z0)
            .take(nz)
            .enumerate()
            .for_each(|(k, plane)| {
                let z = z0 + k;
                rewrite(z, &solid[z * nx * ny..(z + 1) * nx * ny], plane);
            });
    }

    fn local_rho_u(&self, l: [usize; 3]) -> (f64, [f64; 3]) {
        let (drho, j) = moments::<Q, L>(&self.populations(l));
        let rho = 1.0 + drho as f64;
        (rho, [0, 1, 2].map(|a| (j[a] as f64 + 0.5 * self.cfg.body_force[a]) / rho))
    }

    /// Density and velocity of global node `p`, which this rank must hold (`u = (j + F/2) / rho`
    /// with a body force).
    pub fn rho_u(&self, p: [usize; 3]) -> (f64, [f64; 3]) {
        let [nx, ny, _] = self.cfg.n;
        let n = self.node(p);
        self.local_rho_u([n % nx, (n / nx) % ny, n / (nx * ny)])
    }

    /// The velocity of every node this process holds (its slab and ghost layers when split),
    /// `u[a][(z ny + y) nx + x]` over the local box, zero inside bodies: `u = (j + F/2) / rho`
    /// from the populations after the last step, in f32 (lattice units). What a passive scalar
    /// carried by the flow reads ([`super::Thermal3`]); planes in parallel, no allocation.
    pub fn velocity_field(&self, u: [&mut [f32]; 3]) -> Result<(), LbmError> {
        let n = self.cfg.n;
        let plane = n[0] * n[1];
        let cells = plane * n[2];
        if u.iter().any(|c| c.len() != cells) {
            return Err(LbmError::Config {
                field: "velocity_field",
                message: format!("each component needs {cells} values ({:?} nodes)", n),
            });
        }
        let half_force = self.cfg.body_force.map(|v| 0.5 * v as f32);
        let (f, solid) = (&self.f[..], &self.plan.solid[..]);
        // Rows in chunks on the stack: each direction's row is read contiguously, and each node
        // sums its populations in `moments`' order (the same values as `rho_u`).
        const CHUNK: usize = 64;
        let [ux, uy, uz] = u;
        ux.par_chunks_mut(plane)
            .zip(uy.par_chunks_mut(plane))
            .zip(uz.par_chunks_mut(plane))
            .enumerate()
            .for_each(|(z, ((ux, uy), uz))| {
                for y in 0..n[1] {
                    for x0 in (0..n[0]).step_by(CHUNK) {
                        let len = CHUNK.min(n[0] - x0);
                        let mut drho = [0.0f32; CHUNK];
                        let mut j = [[0.0f32; CHUNK]; 3];
                        for i in 0..Q {
                            let start = index::<Q>(n, [x0, y, z], i);
                            let row = &f[start..start + len];
                            for k in 0..len {
                                drho[k] += row[k];
                            }
                            for a in 0..3 {
                                let ca = L::C_REF[i][a];
                                if ca != 0 {
                                    for k in 0..len {
                                        j[a][k] += ca as f32 * row[k];
                                    }
                                }
                            }
                        }
                        for k in 0..len {
                            let c = y * n[0] + x0 + k;
                            if solid[z * plane + c] {
                                (ux[c], uy[c], uz[c]) = (0.0, 0.0, 0.0);
                                continue;
                            }
                            let rho = 1.0 + drho[k];
                            ux[c] = (j[0][k] + half_force[0]) / rho;
                            uy[c] = (j[1][k] + half_force[1]) / rho;
                            uz[c] = (j[2][k] + half_force[2]) / rho;
                        }
                    }
                }
            });
        Ok(())
    }

    /// The velocity of every node of the plane at global `z`, `[y nx + x]`, `None` inside bodies;
    /// on every rank (each node filled in by the rank that owns it).
    pub fn velocity_plane(&self, z: usize) -> Vec<Option<[f64; 3]>> {
        let [nx, ny, _] = self.part.n_global;
        // Per node: 1 (fluid) or 2 (solid) where owned, then the velocity.
        let mut mine = vec![0.0f64; 4 * nx * ny];
        for y in 0..ny {
            for x in 0..nx {
                if !self.owns([x, y, z]) {
                    continue;
                }
                let v = &mut mine[4 * (y * nx + x)..4 * (y * nx + x + 1)];
                if self.is_solid([x, y, z]) {
                    v[0] = 2.0;
                } else {
                    let u = self.rho_u([x, y, z]).1;
                    v.copy_from_slice(&[1.0, u[0], u[1], u[2]]);
                }
            }
        }
        let mut all = vec![0.0f64; mine.len()];
        self.comm.sum(&mine, &mut all);
        all.chunks(4).map(|v| (v[0] == 1.0).then_some([v[1], v[2], v[3]])).collect()
    }

    /// Total mass of the fluid, `sum_x sum_i f_i`: summed per index along the split axis in node
    /// order, then over the indices in order (every rank gets the same bits).
    pub fn mass(&self) -> f64 {
        let [nx, ny, nz] = self.cfg.n;
        let fluid = (0..nz)
            .flat_map(|z| (0..ny).flat_map(move |y| (0..nx).map(move |x| [x, y, z])))
            .filter(|&l| self.part.owns(l) && !self.plan.solid[(l[2] * ny + l[1]) * nx + l[0]]);
        self.split_sum(fluid.map(|l| (l[self.part.axis], 1.0 + self.populations(l).iter().map(|&g| g as f64).sum::<f64>())))
    }

    /// The sum of `terms` (local index along the split axis, value), bitwise the same on any
    /// number of ranks: per global index first, then in index order (see [`super::part`]).
    fn split_sum(&self, terms: impl Iterator<Item = (usize, f64)>) -> f64 {
        let mut per_index = vec![0.0f64; self.part.n_global[self.part.axis]];
        for (i, v) in terms {
            per_index[self.part.global_index(i)] += v;
        }
        let mut summed = vec![0.0; per_index.len()];
        self.comm.sum(&per_index, &mut summed);
        summed.iter().sum()
    }

    /// Force of the fluid on each body during the last step (momentum exchange over its links,
    /// lattice units): the sum of its segments' forces.
    pub fn body_forces(&self) -> &[[f64; 3]] {
        &self.body_forces
    }

    /// Force on each spanwise segment of each body during the last step, `[b * segments + s]`;
    /// segment `s` holds the links of the nodes `z` with `z segments / nz = s`.
    pub fn segment_forces(&self) -> &[[f64; 3]] {
        &self.segment_forces
    }

    /// Momentum exchange (Ladd 1994; Mei et al. 2002): over every link (of owned nodes only), the
    /// momentum the population carries into the wall and back, `c_i (g*_i(x) + g_k(x, t+1))` with
    /// `i = opp(k)`, summed in link order per (body, segment, index along the split axis) into
    /// `partial`. The rest-state parts `w_i c_i` cancel over a closed body, so the shifted
    /// populations give the force directly.
    ///
    /// The slow form, one link after the other (the oracle's); [`Self::link_forces_parallel`] is
    /// the step's.
    fn link_forces(c: &Ctx, src: &[f32], part: &Part, segments: usize, partial: &mut [f64]) {
        partial.iter_mut().for_each(|f| *f = 0.0);
        let [nx, ny, _] = c.n;
        let n_axis = part.n_global[part.axis];
        for l in c.links {
            let n = l.node as usize;
            let p = [n % nx, (n / nx) % ny, n / (nx * ny)];
            let g = part.global(p);
            let i = L::OPP_REF[l.k as usize];
            let v = src[c.idx::<Q>(p, i)] as f64 + bouzidi::<Q, L>(c, src, p, l) as f64;
            let s = g[2] * segments / part.n_global[2];
            let at = ((l.body as usize * segments + s) * n_axis + g[part.axis]) * 3;
            for a in 0..3 {
                partial[at + a] += L::C_REF[i][a] as f64 * v;
            }
        }
    }

    /// [`Self::link_forces`] with each link's exchange computed in parallel into `link_force`,
    /// then added into `partial` in link order at the planned bins: the same sums, bitwise.
    fn link_forces_parallel(c: &Ctx, src: &[f32], link_bin: &[u32], link_force: &mut [[f64; 3]], partial: &mut [f64]) {
        let [nx, ny, _] = c.n;
        link_force
            .par_iter_mut()
            .zip(c.links.par_iter())
            .with_min_len(1024)
            .for_each(|(out, l)| {
                let n = l.node as usize;
                let p = [n % nx, (n / nx) % ny, n / (nx * ny)];
                let i = L::OPP_REF[l.k as usize];
                let v = src[c.idx::<Q>(p, i)] as f64 + bouzidi::<Q, L>(c, src, p, l) as f64;
                *out = L::C_REF[i].map(|ci| ci as f64 * v);
            });
        partial.iter_mut().for_each(|f| *f = 0.0);
        for (&bin, f) in link_bin.iter().zip(link_force.iter()) {
            let at = 3 * bin as usize;
            for a in 0..3 {
                partial[at + a] += f[a];
            }
        }
    }

    /// The forces per segment (the ranks' partial sums added in order along the split axis) and
    /// per body (its segments in order).
    fn total_forces(&mut self) {
        self.comm.sum(&self.partial, &mut self.summed);
        let n_axis = self.part.n_global[self.part.axis];
        for (f, sums) in self.segment_forces.iter_mut().zip(self.summed.chunks(3 * n_axis)) {
            *f = [0.0; 3];
            for v in sums.chunks(3) {
                for a in 0..3 {
                    f[a] += v[a];
                }
            }
        }
        let segments = self.cfg.segments;
        for (b, total) in self.body_forces.iter_mut().enumerate() {
            *total = [0.0; 3];
            for f in &self.segment_forces[b * segments..(b + 1) * segments] {
                for a in 0..3 {
                    total[a] += f[a];
                }
            }
        }
    }

    /// Sends the owned layers next to each neighbour into its ghost layer and fills this rank's
    /// ghosts from them: up the split axis, then down. Allocates nothing.
    fn exchange(&mut self) {
        let (axis, n, own) = (self.part.axis, self.cfg.n, self.part.own.clone());
        // Up: the last owned layer to the rank above, into ghost 0 from the rank below; then down.
        let passes = [
            (own.end - 1, self.part.above, 0, self.part.below),
            (own.start, self.part.below, n[axis] - 1, self.part.above),
        ];
        for (send, to, recv, from) in passes {
            if to.is_some() {
                let mut k = 0;
                layer_runs::<Q>(n, axis, send, |start, len| {
                    self.halo_send[k..k + len].copy_from_slice(&self.f[start..start + len]);
                    k += len;
                });
            }
            self.comm
                .shift(to.map(|r| (&self.halo_send[..], r)), from.map(|r| (&mut self.halo_recv[..], r)));
            if from.is_some() {
                let mut k = 0;
                layer_runs::<Q>(n, axis, recv, |start, len| {
                    self.f[start..start + len].copy_from_slice(&self.halo_recv[k..k + len]);
                    k += len;
                });
            }
        }
    }

    /// Advances one time step (every rank together). Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        let kernel = plane_fn::<Q, L>(
            self.cfg.collision,
            self.cfg.body_force != [0.0; 3],
            self.cfg.smagorinsky > 0.0,
            self.narrow_blocks,
        );
        self.step_with(kernel)
    }

    /// A step of the same kernel with no collision (free streaming: every population pulled and
    /// stored, no arithmetic), for `hgym bench lbm`: the ceiling the kernel's memory access
    /// pattern allows, measured beside the kernel. Not a flow: the populations only travel.
    #[doc(hidden)]
    pub fn step_streaming_only(&mut self) -> Result<(), LbmError> {
        let kernel: PlaneFn = if self.narrow_blocks {
            plane_narrow::<Q, L, OP_STREAM, false, false>
        } else {
            plane_widest::<Q, L, OP_STREAM, false, false>
        };
        self.step_with(kernel)
    }

    fn step_with(&mut self, kernel: PlaneFn) -> Result<(), LbmError> {
        self.face_moments.fill::<Q, L>(self.cfg.n, &self.f);
        let ctx = ctx::<Q>(
            &self.cfg,
            &self.plan,
            &self.face_moments,
            &self.face_profiles,
            self.relax,
            self.velocity_scale,
            Layers(&self.sponges),
        );
        let (src, src_ext) = (&self.f[..], self.f.padded());
        let plane_len = Q * self.cfg.n[0] * self.cfg.n[1];
        self.f_next
            .par_chunks_mut(plane_len)
            .enumerate()
            .for_each(|(z, out)| kernel(&ctx, src, src_ext, z, out));
        Self::link_forces_parallel(&ctx, src, &self.link_bin, &mut self.link_force, &mut self.partial);
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    /// Runs the bulk loop on 8-node blocks (AVX2) even on a CPU with AVX-512F, for tests: both
    /// widths give bitwise the same populations.
    #[doc(hidden)]
    pub fn use_narrow_blocks(&mut self) {
        self.narrow_blocks = true;
    }

    /// Slow oracle for tests: every node through the general path (gather, bounce-back,
    /// collide), one thread, no bulk loop.
    #[doc(hidden)]
    pub fn step_reference(&mut self) -> Result<(), LbmError> {
        let forced = self.cfg.body_force != [0.0; 3];
        let les = self.cfg.smagorinsky > 0.0;
        // The oracle computes what enters through the faces itself (`gather`, `face_value`)
        // and applies the layers in a pass of its own (`apply_plane`).
        let ctx = ctx::<Q>(
            &self.cfg,
            &self.plan,
            &self.face_moments,
            &self.face_profiles,
            self.relax,
            self.velocity_scale,
            Layers(&self.sponges),
        );
        let collide_fn: fn(&mut [f32; Q], Relax, [f32; 3]) = monomorphised!(collide, self.cfg.collision, forced, les);
        let [nx, ny, nz] = self.cfg.n;
        let mut next = vec![0.0f32; self.f.len()];
        let mut link = 0;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let n = (z * ny + y) * nx + x;
                    if self.plan.solid[n] {
                        continue;
                    }
                    let start = link;
                    while link < self.plan.links.len() && self.plan.links[link].node as usize == n {
                        link += 1;
                    }
                    let mut g = gather::<Q, L>(&ctx, &self.f, [x, y, z], &self.plan.links[start..link]);
                    collide_fn(&mut g, ctx.relax, ctx.force);
                    for (i, gi) in g.iter().enumerate() {
                        next[ctx.idx::<Q>([x, y, z], i)] = *gi;
                    }
                }
            }
        }
        Self::link_forces(&ctx, &self.f, &self.part, self.cfg.segments, &mut self.partial);
        for (z, plane) in next.chunks_mut(Q * nx * ny).enumerate() {
            apply_plane(&self.sponges, plane, z, self.cfg.n, &self.part, &self.plan.solid);
        }
        self.f_next.copy_from_slice(&next);
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    /// After the populations of a step: the ghost layers, the forces, the checks.
    fn finish_step(&mut self) -> Result<(), LbmError> {
        self.exchange();
        self.total_forces();
        self.time += 1;
        if let Some(b) = self.body_forces.iter().position(|f| f.iter().any(|v| !v.is_finite())) {
            return Err(LbmError::Diverged3 {
                step: self.time,
                reason: format!("the force on body {b} is not finite"),
                at: self.first_link_of(b),
            });
        }
        if self.cfg.check_interval > 0 && self.time.is_multiple_of(self.cfg.check_interval) {
            self.check()?;
        }
        Ok(())
    }

    /// The global node of body `b`'s first link on this rank (where a force went wrong).
    fn first_link_of(&self, b: usize) -> [usize; 3] {
        let [nx, ny, _] = self.cfg.n;
        let at = self
            .plan
            .links
            .iter()
            .find(|l| l.body as usize == b)
            .map(|l| l.node as usize)
            .unwrap_or(0);
        self.part.global([at % nx, (at / nx) % ny, at / (nx * ny)])
    }

    /// Scans every node for NaN, density out of `rho_bounds` or speed above `u_max`; names the
    /// first offending node in global node order (every rank the same).
    pub fn check(&self) -> Result<(), LbmError> {
        let [nx, ny, nz] = self.cfg.n;
        let [rho_lo, rho_hi] = self.cfg.rho_bounds;
        let u_max = self.cfg.u_max;
        // (global node index, what, value) of this rank's first bad node.
        let bad = (0..ny * nz).into_par_iter().find_map_first(|r| {
            let (y, z) = (r % ny, r / ny);
            (0..nx).find_map(|x| {
                if self.plan.solid[(z * ny + y) * nx + x] || !self.part.owns([x, y, z]) {
                    return None;
                }
                let g = self.populations([x, y, z]);
                let (drho, j) = moments::<Q, L>(&g);
                let rho = 1.0 + drho;
                let u = (j[0] * j[0] + j[1] * j[1] + j[2] * j[2]).sqrt() / rho;
                let what = if g.iter().any(|v| !v.is_finite()) {
                    Bad::NaN
                } else if rho < rho_lo {
                    Bad::RhoLow(rho)
                } else if rho > rho_hi {
                    Bad::RhoHigh(rho)
                } else if u > u_max {
                    Bad::Speed(u)
                } else {
                    return None;
                };
                let [gx, gy, gz] = self.part.global([x, y, z]);
                let [gnx, gny, _] = self.part.n_global;
                Some(((gz * gny + gy) * gnx + gx, what))
            })
        });
        let (node, what) = if self.comm.size() == 1 {
            match bad {
                Some(b) => b,
                None => return Ok(()),
            }
        } else {
            // Every rank's first, in rank slots: the one earliest in node order wins.
            let size = self.comm.size();
            let mut mine = vec![0.0f64; 3 * size];
            if let Some((node, what)) = bad {
                let (code, value) = what.code();
                mine[3 * self.comm.rank()..3 * self.comm.rank() + 3].copy_from_slice(&[1.0 + node as f64, code, value]);
            }
            let mut all = vec![0.0f64; 3 * size];
            self.comm.sum(&mine, &mut all);
            let first = all.chunks(3).filter(|c| c[0] > 0.0).min_by(|a, b| a[0].total_cmp(&b[0]));
            let Some(c) = first else { return Ok(()) };
            (c[0] as usize - 1, Bad::from_code(c[1], c[2] as f32))
        };
        let [gnx, gny, _] = self.part.n_global;
        let reason = match what {
            Bad::NaN => "NaN in the populations".to_string(),
            Bad::RhoLow(rho) => format!("density {rho:.4} below {rho_lo}"),
            Bad::RhoHigh(rho) => format!("density {rho:.4} above {rho_hi}"),
            Bad::Speed(u) => format!("lattice speed {u:.4} above {u_max} (Mach {:.2})", u * 3f32.sqrt()),
        };
        Err(LbmError::Diverged3 {
            step: self.time,
            reason,
            at: [node % gnx, (node / gnx) % gny, node / (gnx * gny)],
        })
    }

    /// Sets face `face` (`2 a` the low end of axis `a`, `2 a + 1` the high end) to a velocity
    /// face of lattice velocity `u` from the next step on (a gust at the inlet); refused for a
    /// face that is not a velocity face.
    pub fn set_face_velocity(&mut self, face: usize, u: [f64; 3]) -> Result<(), LbmError> {
        match self.global_cfg.faces.0.get(face) {
            Some(Face::Velocity(_)) => {
                let v = Face::Velocity(u.map(|v| v as f32));
                self.global_cfg.faces.0[face] = v.clone();
                // A rank whose end of the axis is a ghost layer has no such face.
                if matches!(self.cfg.faces.0[face], Face::Velocity(_)) {
                    self.cfg.faces.0[face] = v;
                }
                Ok(())
            }
            other => Err(LbmError::Config {
                field: "faces",
                message: format!("face {face} is {}, not a velocity face", other.map_or("absent", Face::name)),
            }),
        }
    }

    /// Multiplies the velocity of face `face` at each of its nodes by `profile(x)`, `x` the
    /// node's physical position, from the next step on (a pipe's Poiseuille inflow); refused for
    /// a face that is not a velocity face.
    pub fn set_face_profile(&mut self, face: usize, profile: impl Fn([f64; 3]) -> f64) -> Result<(), LbmError> {
        if !matches!(self.global_cfg.faces.0.get(face), Some(Face::Velocity(_))) {
            return Err(LbmError::Config {
                field: "faces",
                message: format!("face {face} is not a velocity face; a profile shapes an inflow"),
            });
        }
        // A rank whose end of the axis is a ghost layer has no such face.
        if !matches!(self.cfg.faces.0[face], Face::Velocity(_)) {
            return Ok(());
        }
        self.face_profiles[face] = FaceMoments::layer(self.cfg.n, face)
            .map(|p| profile(self.cfg.grid.position(self.part.global(p))) as f32)
            .collect();
        Ok(())
    }

    /// Multiplies every velocity face by `scale` from the next step on (inlet ramps, gusts).
    pub fn set_velocity_scale(&mut self, scale: f64) {
        self.velocity_scale = scale as f32;
    }

    /// Sets the wall velocity of every link of body `b` from the next step on: `u(x)` at the
    /// wall crossing `x` (physical coordinates; lattice velocity). Rotation and jets are this.
    pub fn set_wall_velocity(&mut self, b: usize, u: impl Fn([f64; 3]) -> [f64; 3]) {
        let [nx, ny, _] = self.cfg.n;
        let dx = self.cfg.grid.dx;
        for l in self.plan.links.iter_mut().filter(|l| l.body as usize == b) {
            let n = l.node as usize;
            let p = self.cfg.grid.position(self.part.global([n % nx, (n / nx) % ny, n / (nx * ny)]));
            let c = L::C_REF[l.k as usize];
            let at = [0, 1, 2].map(|a| p[a] - l.q as f64 * c[a] as f64 * dx);
            l.uw = u(at).map(|v| v as f32);
        }
    }

    /// Mass the moving-wall terms of body `b`'s links inject per step (lattice units): over its
    /// links `6 w_k c_k . u_w`, divided by `2 q` where the interpolated bounce-back does
    /// (`q >= 1/2`). Zero for a wall moving along itself; a jet's outflow otherwise. Summed as
    /// the forces are (per index along the split axis, then in order).
    pub fn wall_mass_source(&self, b: usize) -> f64 {
        let [nx, ny, _] = self.cfg.n;
        let terms = self.plan.links.iter().filter(|l| l.body as usize == b).map(|l| {
            let n = l.node as usize;
            let p = [n % nx, (n / nx) % ny, n / (nx * ny)];
            let k = l.k as usize;
            let c = L::C_REF[k];
            let cu: f64 = (0..3).map(|a| c[a] as f64 * l.uw[a] as f64).sum();
            let term = 6.0 * L::W_REF[k] as f64 * cu;
            (p[self.part.axis], if l.q < 0.5 { term } else { term / (2.0 * l.q as f64) })
        });
        self.split_sum(terms)
    }

    /// Density and velocity at the physical point `x`, trilinear between the eight nodes
    /// around it (wrapping along periodic axes). Solid nodes count as resting fluid. Split over
    /// ranks, the rank owning the first of the eight interpolates and the others add zeros.
    pub fn probe(&self, x: [f64; 3]) -> Result<(f64, [f64; 3]), LbmError> {
        Ok(self.probes(&[x])?[0])
    }

    /// [`Self::probe`] at each point of `xs`, summed over the ranks in one message.
    pub fn probes(&self, xs: &[[f64; 3]]) -> Result<Vec<(f64, [f64; 3])>, LbmError> {
        let mut local = Vec::with_capacity(4 * xs.len());
        for x in xs {
            local.extend(self.probe_local(*x)?);
        }
        let summed = if self.part.is_split() {
            let mut summed = vec![0.0; local.len()];
            self.comm.sum(&local, &mut summed);
            summed
        } else {
            local
        };
        Ok(summed.chunks_exact(4).map(|v| (v[0], [v[1], v[2], v[3]])).collect())
    }

    /// `(rho, u)` at `x` as [`Self::probe`] computes it if this rank owns the first corner,
    /// zeros otherwise.
    fn probe_local(&self, x: [f64; 3]) -> Result<[f64; 4], LbmError> {
        let g = self.global_cfg.grid;
        let mut base = [0usize; 3];
        let mut frac = [0.0f64; 3];
        for a in 0..3 {
            let n = self.global_cfg.n[a];
            let t = (x[a] - g.origin[a]) / g.dx;
            let periodic = self.global_cfg.faces.periodic_axis(a);
            let hi = if periodic { n as f64 } else { (n - 1) as f64 };
            if !(0.0..=hi).contains(&t) {
                return Err(LbmError::Config {
                    field: "probe",
                    message: format!(
                        "point ({:.4}, {:.4}, {:.4}) lies outside the domain along {} ({:.4} to {:.4})",
                        x[0],
                        x[1],
                        x[2],
                        ["x", "y", "z"][a],
                        g.origin[a],
                        g.origin[a] + hi * g.dx
                    ),
                });
            }
            let i = (t.floor() as usize).min(if periodic { n - 1 } else { n.saturating_sub(2) });
            base[a] = i;
            frac[a] = t - i as f64;
        }
        let (mut rho, mut u) = (0.0, [0.0; 3]);
        for corner in 0..8 {
            if !self.owns(base) {
                break;
            }
            let mut w = 1.0;
            let mut p = [0usize; 3];
            for a in 0..3 {
                let up = (corner >> a) & 1;
                w *= if up == 1 { frac[a] } else { 1.0 - frac[a] };
                p[a] = (base[a] + up) % self.global_cfg.n[a];
            }
            if w == 0.0 {
                continue;
            }
            let (r, v) = if self.plan.solid[self.node(p)] {
                (1.0, [0.0; 3])
            } else {
                self.rho_u(p)
            };
            rho += w * r;
            for a in 0..3 {
                u[a] += w * v[a];
            }
        }
        Ok([rho, u[0], u[1], u[2]])
    }

    /// The populations (for checkpoints and tests).
    pub fn populations_raw(&self) -> &[f32] {
        &self.f
    }

    /// Restores populations taken with [`Self::populations_raw`] from a solver of the same
    /// configuration, and the step count `time`.
    pub fn set_populations(&mut self, f: &[f32], time: u64) -> Result<(), LbmError> {
        if f.len() != self.f.len() {
            return Err(LbmError::Config {
                field: "populations",
                message: format!("expected {} values, got {}", self.f.len(), f.len()),
            });
        }
        self.f.copy_from_slice(f);
        self.time = time;
        Ok(())
    }

    /// Fills the spare array with NaN (tests: results must not depend on its contents).
    #[doc(hidden)]
    pub fn poison_scratch(&mut self) {
        self.f_next.iter_mut().for_each(|v| *v = f32::NAN);
    }
}

/// The entry of the force sums (`partial`, in threes) that link `l` adds to: its body, its
/// node's segment and its node's index along the split axis.
fn link_bin(part: &Part, n: [usize; 3], segments: usize, l: &Link) -> u32 {
    let node = l.node as usize;
    let g = part.global([node % n[0], (node / n[0]) % n[1], node / (n[0] * n[1])]);
    let s = g[2] * segments / part.n_global[2];
    ((l.body as usize * segments + s) * part.n_global[part.axis] + g[part.axis]) as u32
}
