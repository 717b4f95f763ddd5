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
    sides: [ThermalSide; 4],
    wall_temperature: f32,
    omega: f32,
    ux: &'a [f32],
    uy: &'a [f32],
}

impl StepCtx<'_> {
    /// Stream (pull, with the boundary rules for populations that come from a wall or from
    /// outside) and collide every fluid node of row `y`; `out[i]` is row `y` of direction `i`.
    // `x` is a lattice coordinate (neighbours, sides), not only an index.
    #[allow(clippy::needless_range_loop)]
    fn row(&self, y: usize, out: [&mut [f32]; Q5]) {
        let (nx, ny, g) = (self.nx, self.ny, self.g);
        let n = nx * ny;
        for x in 0..nx {
            let c = y * nx + x;
            if self.solid[c] {
                continue;
            }
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
            let t: f32 = p.iter().sum();
            let (u, v) = (self.ux[c], self.uy[c]);
            for (i, pi) in p.iter().enumerate() {
                let eq = W5[i] * t * (1.0 + 3.0 * (CX5[i] as f32 * u + CY5[i] as f32 * v));
                out[i][x] = pi - self.omega * (pi - eq);
            }
        }
    }
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
