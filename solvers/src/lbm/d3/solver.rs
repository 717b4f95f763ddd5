//! The 3D solver: construction (plan the solid nodes, links and specials once) and the step
//! (execute many: rayon over rows, no allocation, bitwise the same for any thread count).

use rayon::prelude::*;

use super::super::aligned::AlignedVec;
use super::super::collision::{Collision, Relax, OP_BGK, OP_REG};
use super::super::error::LbmError;
use super::super::solver::STREAM_STORES_ABOVE_BYTES;
use super::collision::{collide, equilibrium, moments};
use super::kernel::{bouzidi, gather, index, plane, Ctx, Link, Special, PAD};
use super::lattice::Lattice3;
use super::sides::{Face, Faces};
use super::sponge::{apply_plane, Sponge3, Sponge3Plan};
use crate::geometry::Solid;

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

/// Selects the kernel monomorphised for the operator, forcing and subgrid model.
fn plane_fn<const Q: usize, L: Lattice3<Q>>(collision: Collision, forced: bool, les: bool) -> PlaneFn {
    monomorphised!(plane, collision, forced, les)
}

/// A D3Q19 or D3Q27 lattice-Boltzmann solver on a periodic box with immersed bodies.
pub struct Lbm3<const Q: usize, L: Lattice3<Q>> {
    cfg: D3Config,
    relax: Relax,
    velocity_scale: f32,
    f: AlignedVec,
    f_next: AlignedVec,
    plan: Plan,
    bodies: usize,
    /// Force on each (body, segment), `[b * segments + s]`, during the last step.
    segment_forces: Vec<[f64; 3]>,
    body_forces: Vec<[f64; 3]>,
    sponges: Vec<Sponge3Plan>,
    time: u64,
    _lattice: std::marker::PhantomData<L>,
}

/// What the step reads besides the populations, planned once.
struct Plan {
    solid: Vec<bool>,
    specials: Vec<Special>,
    row_start: Vec<u32>,
    row_bulk: Vec<bool>,
    links: Vec<Link>,
}

fn ctx<'a, const Q: usize>(cfg: &'a D3Config, plan: &'a Plan, relax: Relax, velocity_scale: f32) -> Ctx<'a> {
    Ctx {
        n: cfg.n,
        periodic: [0, 1, 2].map(|a| cfg.faces.periodic_axis(a)),
        faces: &cfg.faces,
        velocity_scale,
        relax,
        force: cfg.body_force.map(|v| v as f32),
        solid: &plan.solid,
        specials: &plan.specials,
        row_start: &plan.row_start,
        row_bulk: &plan.row_bulk,
        links: &plan.links,
        stream_stores: cfg
            .stream_stores
            .unwrap_or(cfg.n.iter().product::<usize>() * Q * 4 * 2 > STREAM_STORES_ABOVE_BYTES),
    }
}

impl<const Q: usize, L: Lattice3<Q>> Lbm3<Q, L> {
    /// Plans the solver: solid nodes (`sdf < 0` of any body), the links of every fluid node
    /// whose neighbour is solid (with the wall fraction along the link) and the specials of
    /// every row. The flow starts at rest.
    pub fn new(cfg: D3Config, bodies: &[&dyn Solid]) -> Result<Self, LbmError> {
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
        let cells = nx * ny * nz;
        if cells >= u32::MAX as usize {
            return Err(config("n", format!("{cells} nodes exceed the 2^32 a link index can address")));
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
        let periodic = [0, 1, 2].map(|a| cfg.faces.periodic_axis(a));
        let node = |p: [usize; 3]| (p[2] * ny + p[1]) * nx + p[0];
        let pos = |p: [usize; 3]| cfg.grid.position(p);
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
        let mut specials = Vec::new();
        let mut links = Vec::new();
        let mut row_start = Vec::with_capacity(ny * nz + 1);
        let mut row_bulk = Vec::with_capacity(ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                row_start.push(specials.len() as u32);
                let at_face = |v: usize, n: usize, a: usize| !periodic[a] && (v == 0 || v + 1 == n);
                let bulk = !at_face(y, ny, 1) && !at_face(z, nz, 2);
                row_bulk.push(bulk);
                for x in 0..nx {
                    let p = [x, y, z];
                    let is_solid = solid[node(p)];
                    let start = links.len() as u32;
                    if !is_solid {
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
                    if !bulk || is_solid || end > start || end_node {
                        specials.push(Special {
                            x: x as u32,
                            solid: is_solid,
                            link_start: start,
                            link_end: end,
                        });
                    }
                }
            }
        }
        row_start.push(specials.len() as u32);
        Ok(Lbm3 {
            sponges: cfg.sponges.iter().map(Sponge3Plan::new::<Q, L>).collect(),
            relax: Relax::new(cfg.tau, cfg.smagorinsky),
            velocity_scale: 1.0,
            f: AlignedVec::zeros_padded(cells * Q, PAD),
            f_next: AlignedVec::zeros_padded(cells * Q, PAD),
            plan: Plan {
                solid,
                specials,
                row_start,
                row_bulk,
                links,
            },
            bodies: bodies.len(),
            segment_forces: vec![[0.0; 3]; bodies.len() * cfg.segments],
            body_forces: vec![[0.0; 3]; bodies.len()],
            time: 0,
            cfg,
            _lattice: std::marker::PhantomData,
        })
    }

    pub fn config(&self) -> &D3Config {
        &self.cfg
    }

    /// Steps taken.
    pub fn time(&self) -> u64 {
        self.time
    }

    fn node(&self, p: [usize; 3]) -> usize {
        (p[2] * self.cfg.n[1] + p[1]) * self.cfg.n[0] + p[0]
    }

    pub fn is_solid(&self, p: [usize; 3]) -> bool {
        self.plan.solid[self.node(p)]
    }

    /// Number of links into bodies.
    pub fn link_count(&self) -> usize {
        self.plan.links.len()
    }

    /// Sets every fluid node to the equilibrium of `init(x, y, z) = (rho, u)`.
    pub fn set_equilibrium(&mut self, init: impl Fn(usize, usize, usize) -> (f64, [f64; 3])) {
        let [nx, ny, nz] = self.cfg.n;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let (rho, u) = if self.plan.solid[(z * ny + y) * nx + x] {
                        (1.0, [0.0; 3])
                    } else {
                        init(x, y, z)
                    };
                    let geq = equilibrium::<Q, L>((rho - 1.0) as f32, u.map(|v| v as f32));
                    for (i, g) in geq.iter().enumerate() {
                        self.f[index::<Q>(self.cfg.n, [x, y, z], i)] = *g;
                    }
                }
            }
        }
    }

    /// Populations of node `p` (shifted, `f_i - w_i`).
    fn populations(&self, p: [usize; 3]) -> [f32; Q] {
        std::array::from_fn(|i| self.f[index::<Q>(self.cfg.n, p, i)])
    }

    /// Density and velocity of node `p` (`u = (j + F/2) / rho` with a body force).
    pub fn rho_u(&self, p: [usize; 3]) -> (f64, [f64; 3]) {
        let (drho, j) = moments::<Q, L>(&self.populations(p));
        let rho = 1.0 + drho as f64;
        (rho, [0, 1, 2].map(|a| (j[a] as f64 + 0.5 * self.cfg.body_force[a]) / rho))
    }

    /// Total mass of the fluid, `sum_x sum_i f_i` (f64 sum in node order).
    pub fn mass(&self) -> f64 {
        let mut m = 0.0f64;
        let [nx, ny, nz] = self.cfg.n;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    if !self.plan.solid[(z * ny + y) * nx + x] {
                        m += 1.0 + self.populations([x, y, z]).iter().map(|&g| g as f64).sum::<f64>();
                    }
                }
            }
        }
        m
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

    /// Momentum exchange (Ladd 1994; Mei et al. 2002): over every link, the momentum the
    /// population carries into the wall and back, `c_i (g*_i(x) + g_k(x, t+1))` with
    /// `i = opp(k)`, summed per (body, segment) in link order, then per body in segment order.
    /// The rest-state parts `w_i c_i` cancel over a closed body, so the shifted populations give
    /// the force directly.
    fn link_forces(c: &Ctx, src: &[f32], segments: usize, per_segment: &mut [[f64; 3]], per_body: &mut [[f64; 3]]) {
        per_segment.iter_mut().for_each(|f| *f = [0.0; 3]);
        let [nx, ny, nz] = c.n;
        for l in c.links {
            let n = l.node as usize;
            let p = [n % nx, (n / nx) % ny, n / (nx * ny)];
            let i = L::OPP_REF[l.k as usize];
            let g = src[c.idx::<Q>(p, i)] as f64 + bouzidi::<Q, L>(c, src, p, l) as f64;
            let f = &mut per_segment[l.body as usize * segments + p[2] * segments / nz];
            for a in 0..3 {
                f[a] += L::C_REF[i][a] as f64 * g;
            }
        }
        for (b, total) in per_body.iter_mut().enumerate() {
            *total = [0.0; 3];
            for f in &per_segment[b * segments..(b + 1) * segments] {
                for a in 0..3 {
                    total[a] += f[a];
                }
            }
        }
    }

    /// Advances one time step. Allocates nothing.
    pub fn step(&mut self) -> Result<(), LbmError> {
        let kernel = plane_fn::<Q, L>(self.cfg.collision, self.cfg.body_force != [0.0; 3], self.cfg.smagorinsky > 0.0);
        let ctx = ctx::<Q>(&self.cfg, &self.plan, self.relax, self.velocity_scale);
        let (src, src_ext) = (&self.f[..], self.f.padded());
        let plane_len = Q * self.cfg.n[0] * self.cfg.n[1];
        self.f_next.par_chunks_mut(plane_len).enumerate().for_each(|(z, out)| {
            kernel(&ctx, src, src_ext, z, out);
            apply_plane(&self.sponges, out, z, self.cfg.n, &self.plan.solid);
        });
        Self::link_forces(&ctx, src, self.cfg.segments, &mut self.segment_forces, &mut self.body_forces);
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    /// Slow oracle for tests: every node through the general path (gather, bounce-back,
    /// collide), one thread, no bulk loop.
    #[doc(hidden)]
    pub fn step_reference(&mut self) -> Result<(), LbmError> {
        let forced = self.cfg.body_force != [0.0; 3];
        let les = self.cfg.smagorinsky > 0.0;
        let ctx = ctx::<Q>(&self.cfg, &self.plan, self.relax, self.velocity_scale);
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
        let (mut segment, mut body) = (vec![[0.0; 3]; self.bodies * self.cfg.segments], vec![[0.0; 3]; self.bodies]);
        Self::link_forces(&ctx, &self.f, self.cfg.segments, &mut segment, &mut body);
        (self.segment_forces, self.body_forces) = (segment, body);
        for (z, plane) in next.chunks_mut(Q * nx * ny).enumerate() {
            apply_plane(&self.sponges, plane, z, self.cfg.n, &self.plan.solid);
        }
        self.f_next.copy_from_slice(&next);
        std::mem::swap(&mut self.f, &mut self.f_next);
        self.finish_step()
    }

    fn finish_step(&mut self) -> Result<(), LbmError> {
        self.time += 1;
        if let Some(b) = self.body_forces.iter().position(|f| f.iter().any(|v| !v.is_finite())) {
            let at = self
                .plan
                .links
                .iter()
                .find(|l| l.body as usize == b)
                .map(|l| l.node as usize)
                .unwrap_or(0);
            let [nx, ny, _] = self.cfg.n;
            return Err(LbmError::Diverged3 {
                step: self.time,
                reason: format!("the force on body {b} is not finite"),
                at: [at % nx, (at / nx) % ny, at / (nx * ny)],
            });
        }
        if self.cfg.check_interval > 0 && self.time.is_multiple_of(self.cfg.check_interval) {
            self.check()?;
        }
        Ok(())
    }

    /// Scans every node for NaN, density out of `rho_bounds` or speed above `u_max`; names the
    /// first offending node in node order.
    pub fn check(&self) -> Result<(), LbmError> {
        let [nx, ny, nz] = self.cfg.n;
        let [rho_lo, rho_hi] = self.cfg.rho_bounds;
        let u_max = self.cfg.u_max;
        let bad = (0..ny * nz).into_par_iter().find_map_first(|r| {
            let (y, z) = (r % ny, r / ny);
            (0..nx).find_map(|x| {
                if self.plan.solid[(z * ny + y) * nx + x] {
                    return None;
                }
                let g = self.populations([x, y, z]);
                let reason = if g.iter().any(|v| !v.is_finite()) {
                    "NaN in the populations".to_string()
                } else {
                    let (drho, j) = moments::<Q, L>(&g);
                    let rho = 1.0 + drho;
                    let u = (j[0] * j[0] + j[1] * j[1] + j[2] * j[2]).sqrt() / rho;
                    if rho < rho_lo {
                        format!("density {rho:.4} below {rho_lo}")
                    } else if rho > rho_hi {
                        format!("density {rho:.4} above {rho_hi}")
                    } else if u > u_max {
                        format!("lattice speed {u:.4} above {u_max} (Mach {:.2})", u * 3f32.sqrt())
                    } else {
                        return None;
                    }
                };
                Some((reason, [x, y, z]))
            })
        });
        match bad {
            Some((reason, at)) => Err(LbmError::Diverged3 {
                step: self.time,
                reason,
                at,
            }),
            None => Ok(()),
        }
    }

    /// Sets face `face` (`2 a` the low end of axis `a`, `2 a + 1` the high end) to a velocity
    /// face of lattice velocity `u` from the next step on (a gust at the inlet); refused for a
    /// face that is not a velocity face.
    pub fn set_face_velocity(&mut self, face: usize, u: [f64; 3]) -> Result<(), LbmError> {
        match self.cfg.faces.0.get(face) {
            Some(Face::Velocity(_)) => {
                self.cfg.faces.0[face] = Face::Velocity(u.map(|v| v as f32));
                Ok(())
            }
            other => Err(LbmError::Config {
                field: "faces",
                message: format!("face {face} is {}, not a velocity face", other.map_or("absent", Face::name)),
            }),
        }
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
            let p = self.cfg.grid.position([n % nx, (n / nx) % ny, n / (nx * ny)]);
            let c = L::C_REF[l.k as usize];
            let at = [0, 1, 2].map(|a| p[a] - l.q as f64 * c[a] as f64 * dx);
            l.uw = u(at).map(|v| v as f32);
        }
    }

    /// Mass the moving-wall terms of body `b`'s links inject per step (lattice units): over its
    /// links `6 w_k c_k . u_w`, divided by `2 q` where the interpolated bounce-back does
    /// (`q >= 1/2`). Zero for a wall moving along itself; a jet's outflow otherwise.
    pub fn wall_mass_source(&self, b: usize) -> f64 {
        let mut m = 0.0f64;
        for l in self.plan.links.iter().filter(|l| l.body as usize == b) {
            let k = l.k as usize;
            let c = L::C_REF[k];
            let cu: f64 = (0..3).map(|a| c[a] as f64 * l.uw[a] as f64).sum();
            let term = 6.0 * L::W_REF[k] as f64 * cu;
            m += if l.q < 0.5 { term } else { term / (2.0 * l.q as f64) };
        }
        m
    }

    /// Density and velocity at the physical point `x`, trilinear between the eight nodes
    /// around it (wrapping along periodic axes). Solid nodes count as resting fluid.
    pub fn probe(&self, x: [f64; 3]) -> Result<(f64, [f64; 3]), LbmError> {
        let g = self.cfg.grid;
        let mut base = [0usize; 3];
        let mut frac = [0.0f64; 3];
        for a in 0..3 {
            let n = self.cfg.n[a];
            let t = (x[a] - g.origin[a]) / g.dx;
            let periodic = self.cfg.faces.periodic_axis(a);
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
            let mut w = 1.0;
            let mut p = [0usize; 3];
            for a in 0..3 {
                let up = (corner >> a) & 1;
                w *= if up == 1 { frac[a] } else { 1.0 - frac[a] };
                p[a] = (base[a] + up) % self.cfg.n[a];
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
        Ok((rho, u))
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
