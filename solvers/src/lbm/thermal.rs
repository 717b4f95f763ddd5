//! Temperature as a passive scalar carried by a lattice-Boltzmann flow: the D2Q5
//! advection-diffusion scheme (Krüger et al., *The Lattice Boltzmann Method*, Springer 2017,
//! ch. 8.3), the "second distribution" of thermal LBM solvers.
//!
//! `g_i(x + c_i, t + 1) = g_i - (g_i - g_i^eq) / tau_g`,  `g_i^eq = w_i T (1 + c_i . u / c_s^2)`,
//!
//! with `c_s^2 = 1/3`, `w_0 = 1/3`, `w_{1..4} = 1/6`, `T = sum g_i`, and the diffusivity
//! `kappa = c_s^2 (tau_g - 1/2)` (lattice units; `kappa = nu / Pr` couples it to the flow). The
//! velocity `u` is the flow solver's, node by node; the temperature does not act back on the
//! flow (no buoyancy).
//!
//! Boundaries, all applied in the pull step:
//! - solid nodes (the flow's bodies) and [`ThermalSide::Temperature`] sides: fixed temperature by
//!   anti-bounce-back half-way between the nodes, `g_opp(i)(x, t+1) = -g*_i(x, t) + 2 w_i T_w`
//!   (Krüger et al. eq. 8.47 with `u_w = 0`);
//! - [`ThermalSide::ZeroGradient`]: an open side, the population entering from outside is the
//!   node's own post-collision one in that direction (zero normal gradient);
//! - [`ThermalSide::Periodic`].
//!
//! Populations are `f32`; two arrays (A-B), direction-major (`g[i * n + cell]`). The step
//! allocates nothing.

use rayon::prelude::*;

use super::domain::Edge;
use super::error::LbmError;
use super::probes::bilinear;

/// Number of discrete velocities of D2Q5.
pub const Q5: usize = 5;
/// D2Q5 directions: 0 rest, 1 E, 2 N, 3 W, 4 S.
pub const CX5: [i32; Q5] = [0, 1, 0, -1, 0];
pub const CY5: [i32; Q5] = [0, 0, 1, 0, -1];
pub const W5: [f32; Q5] = [1.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0];
pub const OPP5: [usize; Q5] = [0, 3, 4, 1, 2];

/// What the temperature does at one edge of the domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThermalSide {
    Periodic,
    /// Fixed temperature (a heated wall, an inlet's temperature).
    Temperature(f32),
    /// Open: zero normal gradient (an outlet).
    ZeroGradient,
}

/// The temperature field and its lattice.
#[derive(Clone, Debug)]
pub struct Thermal {
    nx: usize,
    ny: usize,
    omega: f32,
    /// Post-collision populations.
    g: Vec<f32>,
    g_next: Vec<f32>,
    solid: Vec<bool>,
    /// Fluid nodes with no solid or outside neighbour (see [`interior_mask`]).
    interior: Vec<bool>,
    wall_temperature: f32,
    /// West, east, south, north.
    sides: [ThermalSide; 4],
    time: u64,
}

/// What one step reads (split from the solver so the destination can be borrowed mutably).
struct StepCtx<'a> {
    nx: usize,
    ny: usize,
    g: &'a [f32],
    solid: &'a [bool],
    interior: &'a [bool],
    sides: [ThermalSide; 4],
    wall_temperature: f32,
    omega: f32,
    ux: &'a [f32],
    uy: &'a [f32],
}

impl StepCtx<'_> {
    /// Stream (pull, with the boundary rules for populations that come from a wall or from
    /// outside) and collide every fluid node of row `y`; `out[i]` is row `y` of direction `i`.
    /// Runs of interior nodes take [`Self::bulk_run`], the others [`Self::pull_at_boundary`].
    fn row(&self, y: usize, mut out: [&mut [f32]; Q5]) {
        let nx = self.nx;
        let mut x = 0;
        while x < nx {
            let c = y * nx + x;
            if self.interior[c] {
                let mut end = x + 1;
                while end < nx && self.interior[y * nx + end] {
                    end += 1;
                }
                self.bulk_run(y, x, end, &mut out);
                x = end;
                continue;
            }
            if !self.solid[c] {
                let post = collide(self.pull_at_boundary(x, y), self.ux[c], self.uy[c], self.omega);
                for (o, p) in out.iter_mut().zip(post) {
                    o[x] = p;
                }
            }
            x += 1;
        }
    }

    /// Nodes `x0..x1` of row `y`, all with four fluid neighbours inside the domain: plain pull
    /// streaming `p_i = g_i(x - c_i)` and the collision, in a loop without branches that the
    /// compiler vectorises.
    fn bulk_run(&self, y: usize, x0: usize, x1: usize, out: &mut [&mut [f32]; Q5]) {
        let (nx, g) = (self.nx, self.g);
        let n = nx * self.ny;
        let (c0, len) = (y * nx + x0, x1 - x0);
        let src = |i: usize, shift: isize| {
            let start = (i * n + c0) as isize + shift;
            &g[start as usize..start as usize + len]
        };
        let (s0, s1, s2, s3, s4) = (src(0, 0), src(1, -1), src(2, -(nx as isize)), src(3, 1), src(4, nx as isize));
        let (ux, uy) = (&self.ux[c0..c0 + len], &self.uy[c0..c0 + len]);
        let [o0, o1, o2, o3, o4] = out;
        let (o0, o1, o2) = (&mut o0[x0..x1], &mut o1[x0..x1], &mut o2[x0..x1]);
        let (o3, o4) = (&mut o3[x0..x1], &mut o4[x0..x1]);
        for k in 0..len {
            let p = collide([s0[k], s1[k], s2[k], s3[k], s4[k]], ux[k], uy[k], self.omega);
            (o0[k], o1[k], o2[k], o3[k], o4[k]) = (p[0], p[1], p[2], p[3], p[4]);
        }
    }

    /// The populations arriving at fluid node `(x, y)` when a neighbour is a solid node or
    /// outside the domain: the boundary rules of the module documentation.
    fn pull_at_boundary(&self, x: usize, y: usize) -> [f32; Q5] {
        let (nx, ny, g) = (self.nx, self.ny, self.g);
        let n = nx * ny;
        let c = y * nx + x;
        let mut p = [0.0f32; Q5];
        for (i, pi) in p.iter_mut().enumerate() {
            let (sx, sy) = (x as isize - CX5[i] as isize, y as isize - CY5[i] as isize);
            let outside = match (sx < 0, sx >= nx as isize, sy < 0, sy >= ny as isize) {
                (true, _, _, _) => Some(self.sides[0]),
                (_, true, _, _) => Some(self.sides[1]),
                (_, _, true, _) => Some(self.sides[2]),
                (_, _, _, true) => Some(self.sides[3]),
                _ => None,
            };
            let own_opp = g[OPP5[i] * n + c];
            *pi = match outside {
                None => {
                    let s = sy as usize * nx + sx as usize;
                    if self.solid[s] {
                        -own_opp + 2.0 * W5[i] * self.wall_temperature
                    } else {
                        g[i * n + s]
                    }
                }
                Some(ThermalSide::Periodic) => {
                    let s = sy.rem_euclid(ny as isize) as usize * nx + sx.rem_euclid(nx as isize) as usize;
                    g[i * n + s]
                }
                Some(ThermalSide::Temperature(t)) => -own_opp + 2.0 * W5[i] * t,
                Some(ThermalSide::ZeroGradient) => g[i * n + c],
            };
        }
        p
    }
}

/// BGK collision of one node's arriving populations `p` with the flow velocity `(u, v)`:
/// `p_i - omega (p_i - w_i T (1 + 3 c_i . u))`, `T = sum p_i` (`c_i . u` written out as `+-u`,
/// `+-v` or nothing for the D2Q5 directions 0 rest, 1 E, 2 N, 3 W, 4 S).
#[inline(always)]
fn collide(p: [f32; Q5], u: f32, v: f32, omega: f32) -> [f32; Q5] {
    let t: f32 = p.iter().sum();
    let (u3, v3) = (3.0 * u, 3.0 * v);
    let eq = [
        W5[0] * t,
        W5[1] * t * (1.0 + u3),
        W5[2] * t * (1.0 + v3),
        W5[3] * t * (1.0 - u3),
        W5[4] * t * (1.0 - v3),
    ];
    std::array::from_fn(|i| p[i] - omega * (p[i] - eq[i]))
}

/// Marks the nodes whose four D2Q5 neighbours are all fluid nodes inside the domain: there the
/// step streams without any boundary rule.
fn interior_mask(nx: usize, ny: usize, solid: &[bool]) -> Vec<bool> {
    let mut m = vec![false; nx * ny];
    for y in 1..ny.saturating_sub(1) {
        for x in 1..nx - 1 {
            let c = y * nx + x;
            m[c] = !solid[c] && !solid[c - 1] && !solid[c + 1] && !solid[c - nx] && !solid[c + nx];
        }
    }
    m
}

fn side_index(e: Edge) -> usize {
    match e {
        Edge::West => 0,
        Edge::East => 1,
        Edge::South => 2,
        Edge::North => 3,
    }
}

fn config_error(field: &'static str, message: String) -> LbmError {
    LbmError::Config { field, message }
}

impl Thermal {
    /// `solid`: the flow's solid nodes (row-major, `nx * ny`), held at `wall_temperature`;
    /// `tau`: relaxation time (`kappa = (tau - 1/2) / 3`); `sides`: west, east, south, north.
    pub fn new(nx: usize, ny: usize, tau: f64, sides: [ThermalSide; 4], solid: Vec<bool>, wall_temperature: f64) -> Result<Self, LbmError> {
        if nx < 2 || ny < 2 || solid.len() != nx * ny {
            return Err(config_error(
                "size",
                format!("{nx} x {ny} nodes with a solid mask of {} values", solid.len()),
            ));
        }
        if !(tau.is_finite() && tau > 0.5) {
            return Err(config_error(
                "tau",
                format!("the thermal relaxation time {tau} must exceed 1/2 (kappa = (tau - 1/2) / 3 > 0)"),
            ));
        }
        let periodic = |s: ThermalSide| s == ThermalSide::Periodic;
        if periodic(sides[0]) != periodic(sides[1]) || periodic(sides[2]) != periodic(sides[3]) {
            return Err(config_error("sides", "opposite sides must both be periodic or neither".into()));
        }
        let n = nx * ny;
        let mut t = Thermal {
            nx,
            ny,
            omega: (1.0 / tau) as f32,
            g: vec![0.0; Q5 * n],
            g_next: vec![0.0; Q5 * n],
            interior: interior_mask(nx, ny, &solid),
            solid,
            wall_temperature: wall_temperature as f32,
            sides,
            time: 0,
        };
        t.init_with(|_, _| 0.0);
        Ok(t)
    }

    /// Sets every fluid node to rest equilibrium at `temperature(x, y)` (node indices).
    pub fn init_with(&mut self, mut temperature: impl FnMut(usize, usize) -> f64) {
        let n = self.nx * self.ny;
        for y in 0..self.ny {
            for x in 0..self.nx {
                let c = y * self.nx + x;
                let t = if self.solid[c] { 0.0 } else { temperature(x, y) as f32 };
                for (i, w) in W5.iter().enumerate() {
                    self.g[i * n + c] = w * t;
                }
            }
        }
        self.g_next.copy_from_slice(&self.g);
        self.time = 0;
    }

    /// Changes the temperature of a [`ThermalSide::Temperature`] side from the next step on (the
    /// stenotic pipe's inlet-temperature action).
    pub fn set_side_temperature(&mut self, edge: Edge, temperature: f64) -> Result<(), LbmError> {
        let s = &mut self.sides[side_index(edge)];
        match s {
            ThermalSide::Temperature(t) if temperature.is_finite() => {
                *t = temperature as f32;
                Ok(())
            }
            ThermalSide::Temperature(_) => Err(config_error("sides", format!("temperature {temperature} is not finite"))),
            other => Err(config_error(
                "sides",
                format!("the {} side is {other:?}, not a fixed-temperature side", edge.name()),
            )),
        }
    }

    /// One step with the flow's velocity field `ux`, `uy` (row-major, lattice units). Rows run
    /// in parallel; every node's update depends only on the previous populations, so the result
    /// is the same for any thread count.
    pub fn step(&mut self, ux: &[f32], uy: &[f32]) {
        let n = self.nx * self.ny;
        let ctx = StepCtx {
            nx: self.nx,
            ny: self.ny,
            g: &self.g,
            solid: &self.solid,
            interior: &self.interior,
            sides: self.sides,
            wall_temperature: self.wall_temperature,
            omega: self.omega,
            ux,
            uy,
        };
        // The five direction planes of the destination, split into rows.
        let (p0, rest) = self.g_next.split_at_mut(n);
        let (p1, rest) = rest.split_at_mut(n);
        let (p2, rest) = rest.split_at_mut(n);
        let (p3, p4) = rest.split_at_mut(n);
        let nx = self.nx;
        (
            p0.par_chunks_mut(nx),
            p1.par_chunks_mut(nx),
            p2.par_chunks_mut(nx),
            p3.par_chunks_mut(nx),
            p4.par_chunks_mut(nx),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(y, (r0, r1, r2, r3, r4))| ctx.row(y, [r0, r1, r2, r3, r4]));
        std::mem::swap(&mut self.g, &mut self.g_next);
        self.time += 1;
    }

    /// Temperature at node `(x, y)` (the wall temperature inside solids).
    pub fn temperature(&self, x: usize, y: usize) -> f32 {
        let c = y * self.nx + x;
        if self.solid[c] {
            return self.wall_temperature;
        }
        let n = self.nx * self.ny;
        (0..Q5).map(|i| self.g[i * n + c]).sum()
    }

    /// Bilinear interpolation of the temperature at lattice coordinates `(xi, eta)` (node
    /// `(i, j)` at `(i, j)`), clamped to the grid.
    pub fn sample(&self, xi: f64, eta: f64) -> f64 {
        let xi = xi.clamp(0.0, (self.nx - 1) as f64);
        let eta = eta.clamp(0.0, (self.ny - 1) as f64);
        bilinear(xi, eta, self.nx, self.ny)
            .iter()
            .map(|&(x, y, w)| w * self.temperature(x, y) as f64)
            .sum()
    }

    /// Sum of the temperature over fluid nodes (the conserved "heat" of a closed domain).
    pub fn total(&self) -> f64 {
        let mut s = 0.0;
        for y in 0..self.ny {
            for x in 0..self.nx {
                if !self.solid[y * self.nx + x] {
                    s += self.temperature(x, y) as f64;
                }
            }
        }
        s
    }

    /// Raw populations (checkpoints, cached states).
    pub fn populations(&self) -> &[f32] {
        &self.g
    }

    pub fn set_populations(&mut self, g: &[f32]) -> Result<(), LbmError> {
        if g.len() != self.g.len() {
            return Err(config_error(
                "populations",
                format!("expected {} values, got {}", self.g.len(), g.len()),
            ));
        }
        self.g.copy_from_slice(g);
        Ok(())
    }

    pub fn time(&self) -> u64 {
        self.time
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free interior loop and the general boundary path give bitwise the same step:
    /// the same field stepped once with the interior mask and once with every node on the
    /// general path. Solids, fixed-temperature, open and periodic sides, and a velocity with
    /// both signs (and exact zeros) in both components are all present.
    #[test]
    fn interior_runs_match_the_general_path_bitwise() {
        let (nx, ny) = (23, 17);
        let solid: Vec<bool> = (0..nx * ny)
            .map(|c| {
                let (x, y) = ((c % nx) as i32, (c / nx) as i32);
                (x - 9).pow(2) + (y - 8).pow(2) <= 9
            })
            .collect();
        let sides = [
            ThermalSide::Temperature(1.3),
            ThermalSide::ZeroGradient,
            ThermalSide::Periodic,
            ThermalSide::Periodic,
        ];
        let mut fast = Thermal::new(nx, ny, 0.55, sides, solid, 1.0).unwrap();
        fast.init_with(|x, y| 0.9 + 0.01 * ((x * 7 + y * 3) % 11) as f64);
        assert!(fast.interior.iter().filter(|&&b| b).count() > nx * ny / 2);
        let mut general = fast.clone();
        general.interior.fill(false);
        let ux: Vec<f32> = (0..nx * ny).map(|c| 0.01 * ((c % 7) as f32 - 3.0)).collect();
        let uy: Vec<f32> = (0..nx * ny).map(|c| 0.013 * ((c % 5) as f32 - 2.0)).collect();
        for _ in 0..5 {
            fast.step(&ux, &uy);
            general.step(&ux, &uy);
        }
        let bits = |t: &Thermal| t.populations().iter().map(|g| g.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&general));
    }
}
