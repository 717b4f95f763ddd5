//! Temperature as a passive scalar carried by a 3D lattice-Boltzmann flow: the D3Q7
//! advection-diffusion scheme (Krüger et al., *The Lattice Boltzmann Method*, Springer 2017,
//! ch. 8.3), the 3D form of [`crate::lbm::thermal`]:
//!
//! `g_i(x + c_i, t + 1) = g_i - (g_i - g_i^eq) / tau_g`,  `g_i^eq = w_i T (1 + c_i . u / c_s^2)`,
//!
//! with `c_s^2 = 1/4`, `w_0 = 1/4`, `w_{1..6} = 1/8`, `T = sum g_i`, and the diffusivity
//! `kappa = c_s^2 (tau_g - 1/2) = (tau_g - 1/2) / 4` (lattice units). The velocity is the flow
//! solver's ([`Lbm3::velocity_field`](super::Lbm3::velocity_field)), node by node; the
//! temperature does not act back on the flow.
//!
//! Boundaries, as in 2D, all applied in the pull step:
//! - solid nodes and [`ThermalSide::Temperature`] faces: fixed temperature by anti-bounce-back
//!   half-way between the nodes, `g_i(x, t+1) = -g*_opp(i)(x, t) + 2 w_i T_w`;
//! - [`ThermalSide::ZeroGradient`]: the population entering from outside is the node's own
//!   post-collision one in that direction;
//! - [`ThermalSide::Periodic`].
//!
//! Populations are `f32` in two arrays, plane by plane like the flow's
//! (`g[((z 7 + i) ny + y) nx + x]`); planes run in parallel and the step allocates nothing. One
//! process: the field is not split over ranks.

use rayon::prelude::*;

use super::super::error::LbmError;
use super::super::thermal::ThermalSide;

/// Number of discrete velocities of D3Q7.
pub const Q7: usize = 7;
/// D3Q7 directions: 0 rest, then +x, -x, +y, -y, +z, -z.
pub const C7: [[i32; 3]; Q7] = [[0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
pub const W7: [f32; Q7] = [0.25, 0.125, 0.125, 0.125, 0.125, 0.125, 0.125];
pub const OPP7: [usize; Q7] = [0, 2, 1, 4, 3, 6, 5];

/// The temperature field of a 3D box and its lattice.
#[derive(Clone, Debug)]
pub struct Thermal3 {
    n: [usize; 3],
    omega: f32,
    /// Post-collision populations.
    g: Vec<f32>,
    g_next: Vec<f32>,
    solid: Vec<bool>,
    /// Fluid nodes whose six neighbours are fluid nodes inside the box (no boundary rule).
    interior: Vec<bool>,
    wall_temperature: f32,
    /// `faces[2 a]` at the low end of axis `a`, `faces[2 a + 1]` at the high end.
    faces: [ThermalSide; 6],
    time: u64,
}

/// What one step reads (split from the field so the destination can be borrowed mutably).
struct StepCtx<'a> {
    n: [usize; 3],
    g: &'a [f32],
    solid: &'a [bool],
    interior: &'a [bool],
    faces: [ThermalSide; 6],
    wall_temperature: f32,
    omega: f32,
    u: [&'a [f32]; 3],
}

#[inline(always)]
fn index(n: [usize; 3], p: [usize; 3], i: usize) -> usize {
    ((p[2] * Q7 + i) * n[1] + p[1]) * n[0] + p[0]
}

/// BGK collision of one node's arriving populations `p` with the flow velocity `u`:
/// `p_i - omega (p_i - w_i T (1 + 4 c_i . u))`, `T = sum p_i`.
#[inline(always)]
fn collide(p: [f32; Q7], u: [f32; 3], omega: f32) -> [f32; Q7] {
    let t = p[0] + p[1] + p[2] + p[3] + p[4] + p[5] + p[6];
    let (w0, w) = (W7[0] * t, W7[1] * t);
    let [a, b, c] = u.map(|v| 4.0 * v);
    let eq = [
        w0,
        w * (1.0 + a),
        w * (1.0 - a),
        w * (1.0 + b),
        w * (1.0 - b),
        w * (1.0 + c),
        w * (1.0 - c),
    ];
    std::array::from_fn(|i| p[i] - omega * (p[i] - eq[i]))
}

impl StepCtx<'_> {
    /// Stream and collide every fluid node of plane `z`; `out` is that plane of the destination
    /// (`[(i ny + y) nx + x]`). Runs of interior nodes take [`Self::bulk_run`], the others
    /// [`Self::pull_at_boundary`].
    fn plane(&self, z: usize, out: &mut [f32]) {
        let [nx, ny, _] = self.n;
        let plane = nx * ny;
        for y in 0..ny {
            let row = (z * ny + y) * nx;
            let mut x = 0;
            while x < nx {
                if self.interior[row + x] {
                    let mut end = x + 1;
                    while end < nx && self.interior[row + end] {
                        end += 1;
                    }
                    self.bulk_run([x, y, z], end - x, out);
                    x = end;
                    continue;
                }
                if !self.solid[row + x] {
                    let c = row + x;
                    let post = collide(
                        self.pull_at_boundary([x, y, z]),
                        [self.u[0][c], self.u[1][c], self.u[2][c]],
                        self.omega,
                    );
                    for (i, v) in post.into_iter().enumerate() {
                        out[i * plane + y * nx + x] = v;
                    }
                }
                x += 1;
            }
        }
    }

    /// `len` nodes from `p` along x, all with six fluid neighbours inside the box: plain pull
    /// streaming `g_i(x - c_i)` and the collision, in a loop without branches.
    fn bulk_run(&self, p: [usize; 3], len: usize, out: &mut [f32]) {
        let n = self.n;
        let src = |i: usize| {
            let c = C7[i];
            let s = [0, 1, 2].map(|a| (p[a] as isize - c[a] as isize) as usize);
            let start = index(n, s, i);
            &self.g[start..start + len]
        };
        let s: [&[f32]; Q7] = std::array::from_fn(src);
        let c0 = (p[2] * n[1] + p[1]) * n[0] + p[0];
        let (ux, uy, uz) = (&self.u[0][c0..c0 + len], &self.u[1][c0..c0 + len], &self.u[2][c0..c0 + len]);
        let plane = n[0] * n[1];
        let o0 = p[1] * n[0] + p[0];
        for k in 0..len {
            let post = collide(std::array::from_fn(|i| s[i][k]), [ux[k], uy[k], uz[k]], self.omega);
            for (i, v) in post.into_iter().enumerate() {
                out[i * plane + o0 + k] = v;
            }
        }
    }

    /// The populations arriving at fluid node `p` when a neighbour is solid or outside the box:
    /// the boundary rules of the module documentation.
    fn pull_at_boundary(&self, p: [usize; 3]) -> [f32; Q7] {
        let n = self.n;
        std::array::from_fn(|i| {
            let own_opp = self.g[index(n, p, OPP7[i])];
            // D3Q7 moves along one axis at a time.
            let Some(a) = (0..3).find(|&a| C7[i][a] != 0) else {
                return self.g[index(n, p, 0)];
            };
            let s = p[a] as isize - C7[i][a] as isize;
            if !(0..n[a] as isize).contains(&s) {
                let face = 2 * a + usize::from(s >= 0);
                return match self.faces[face] {
                    ThermalSide::Periodic => {
                        let mut q = p;
                        q[a] = s.rem_euclid(n[a] as isize) as usize;
                        self.g[index(n, q, i)]
                    }
                    ThermalSide::Temperature(t) => -own_opp + 2.0 * W7[i] * t,
                    ThermalSide::ZeroGradient => self.g[index(n, p, i)],
                };
            }
            let mut q = p;
            q[a] = s as usize;
            if self.solid[(q[2] * n[1] + q[1]) * n[0] + q[0]] {
                -own_opp + 2.0 * W7[i] * self.wall_temperature
            } else {
                self.g[index(n, q, i)]
            }
        })
    }
}

/// Marks the fluid nodes whose six neighbours are fluid nodes inside the box.
fn interior_mask(n: [usize; 3], solid: &[bool]) -> Vec<bool> {
    let [nx, ny, nz] = n;
    let mut m = vec![false; nx * ny * nz];
    for z in 1..nz.saturating_sub(1) {
        for y in 1..ny.saturating_sub(1) {
            for x in 1..nx.saturating_sub(1) {
                let c = (z * ny + y) * nx + x;
                m[c] = [c, c - 1, c + 1, c - nx, c + nx, c - nx * ny, c + nx * ny]
                    .iter()
                    .all(|&k| !solid[k]);
            }
        }
    }
    m
}

fn config_error(field: &'static str, message: String) -> LbmError {
    LbmError::Config { field, message }
}

impl Thermal3 {
    /// `n` nodes; `solid`: the flow's solid nodes (`[(z ny + y) nx + x]`), held at
    /// `wall_temperature`; `tau`: relaxation time (`kappa = (tau - 1/2) / 4`); `faces` as the
    /// flow's (`2 a` the low end of axis `a`).
    pub fn new(n: [usize; 3], tau: f64, faces: [ThermalSide; 6], solid: Vec<bool>, wall_temperature: f64) -> Result<Self, LbmError> {
        let cells = n.iter().product::<usize>();
        if n.iter().any(|&v| v < 2) || solid.len() != cells {
            return Err(config_error(
                "n",
                format!("{n:?} nodes with a solid mask of {} values", solid.len()),
            ));
        }
        if !(tau.is_finite() && tau > 0.5) {
            return Err(config_error(
                "tau",
                format!("the thermal relaxation time {tau} must exceed 1/2 (kappa = (tau - 1/2) / 4 > 0)"),
            ));
        }
        let periodic = |s: ThermalSide| s == ThermalSide::Periodic;
        if (0..3).any(|a| periodic(faces[2 * a]) != periodic(faces[2 * a + 1])) {
            return Err(config_error("faces", "opposite faces must both be periodic or neither".into()));
        }
        let mut t = Thermal3 {
            n,
            omega: (1.0 / tau) as f32,
            g: vec![0.0; Q7 * cells],
            g_next: vec![0.0; Q7 * cells],
            interior: interior_mask(n, &solid),
            solid,
            wall_temperature: wall_temperature as f32,
            faces,
            time: 0,
        };
        t.init_with(|_| 0.0);
        Ok(t)
    }

    /// Sets every fluid node to rest equilibrium at `temperature(p)` (node indices).
    pub fn init_with(&mut self, temperature: impl Fn([usize; 3]) -> f64) {
        let [nx, ny, nz] = self.n;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let p = [x, y, z];
                    let t = if self.solid[(z * ny + y) * nx + x] {
                        0.0
                    } else {
                        temperature(p) as f32
                    };
                    for (i, w) in W7.iter().enumerate() {
                        self.g[index(self.n, p, i)] = w * t;
                    }
                }
            }
        }
        self.g_next.copy_from_slice(&self.g);
        self.time = 0;
    }

    /// Changes the temperature of a [`ThermalSide::Temperature`] face from the next step on (the
    /// stenotic pipe's inlet-temperature action).
    pub fn set_face_temperature(&mut self, face: usize, temperature: f64) -> Result<(), LbmError> {
        match self.faces.get_mut(face) {
            Some(ThermalSide::Temperature(t)) if temperature.is_finite() => {
                *t = temperature as f32;
                Ok(())
            }
            Some(ThermalSide::Temperature(_)) => Err(config_error("faces", format!("temperature {temperature} is not finite"))),
            other => Err(config_error(
                "faces",
                format!("face {face} is {other:?}, not a fixed-temperature face"),
            )),
        }
    }

    /// One step with the flow's velocity `u` (lattice units, `[(z ny + y) nx + x]` per
    /// component). Every node's update depends only on the previous populations: the same
    /// result for any thread count.
    pub fn step(&mut self, u: [&[f32]; 3]) -> Result<(), LbmError> {
        let cells = self.solid.len();
        if u.iter().any(|c| c.len() != cells) {
            return Err(config_error("velocity", format!("each component needs {cells} values")));
        }
        let ctx = StepCtx {
            n: self.n,
            g: &self.g,
            solid: &self.solid,
            interior: &self.interior,
            faces: self.faces,
            wall_temperature: self.wall_temperature,
            omega: self.omega,
            u,
        };
        let plane = Q7 * self.n[0] * self.n[1];
        self.g_next.par_chunks_mut(plane).enumerate().for_each(|(z, out)| ctx.plane(z, out));
        std::mem::swap(&mut self.g, &mut self.g_next);
        self.time += 1;
        Ok(())
    }

    /// Temperature at node `p` (the wall temperature inside solids).
    pub fn temperature(&self, p: [usize; 3]) -> f32 {
        if self.solid[(p[2] * self.n[1] + p[1]) * self.n[0] + p[0]] {
            return self.wall_temperature;
        }
        (0..Q7).map(|i| self.g[index(self.n, p, i)]).sum()
    }

    /// Trilinear interpolation of the temperature at lattice coordinates `xi` (node `p` at
    /// `p`), clamped to the box.
    pub fn sample(&self, xi: [f64; 3]) -> f64 {
        let mut base = [0usize; 3];
        let mut frac = [0.0f64; 3];
        for a in 0..3 {
            let t = xi[a].clamp(0.0, (self.n[a] - 1) as f64);
            base[a] = (t.floor() as usize).min(self.n[a] - 2);
            frac[a] = t - base[a] as f64;
        }
        let mut s = 0.0;
        for corner in 0..8 {
            let mut w = 1.0;
            let mut p = base;
            for a in 0..3 {
                let up = (corner >> a) & 1;
                w *= if up == 1 { frac[a] } else { 1.0 - frac[a] };
                p[a] += up;
            }
            if w != 0.0 {
                s += w * self.temperature(p) as f64;
            }
        }
        s
    }

    /// Sum of the temperature over fluid nodes (the conserved "heat" of a closed box).
    pub fn total(&self) -> f64 {
        let [nx, ny, nz] = self.n;
        let mut s = 0.0;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    if !self.solid[(z * ny + y) * nx + x] {
                        s += self.temperature([x, y, z]) as f64;
                    }
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

    /// The branch-free interior runs and the general boundary path give bitwise the same step:
    /// the same field stepped with the interior mask and with every node on the general path.
    /// A solid, fixed-temperature, open and periodic faces, and velocities of both signs (and
    /// exact zeros) in every component are present.
    #[test]
    fn interior_runs_match_the_general_path_bitwise() {
        let n = [19, 13, 11];
        let solid: Vec<bool> = (0..n[0] * n[1] * n[2])
            .map(|c| {
                let (x, y, z) = ((c % n[0]) as i32, ((c / n[0]) % n[1]) as i32, (c / (n[0] * n[1])) as i32);
                (x - 8).pow(2) + (y - 6).pow(2) + (z - 5).pow(2) <= 6
            })
            .collect();
        let faces = [
            ThermalSide::Temperature(1.3),
            ThermalSide::ZeroGradient,
            ThermalSide::Periodic,
            ThermalSide::Periodic,
            ThermalSide::Temperature(0.7),
            ThermalSide::ZeroGradient,
        ];
        let mut fast = Thermal3::new(n, 0.55, faces, solid, 1.0).unwrap();
        fast.init_with(|p| 0.9 + 0.01 * ((p[0] * 7 + p[1] * 3 + p[2] * 5) % 11) as f64);
        assert!(fast.interior.iter().filter(|&&b| b).count() > fast.solid.len() / 3);
        let mut general = fast.clone();
        general.interior.fill(false);
        let cells = fast.solid.len();
        let u: [Vec<f32>; 3] = std::array::from_fn(|a| (0..cells).map(|c| 0.01 * (((c + a) % 7) as f32 - 3.0)).collect());
        for _ in 0..5 {
            fast.step([&u[0], &u[1], &u[2]]).unwrap();
            general.step([&u[0], &u[1], &u[2]]).unwrap();
        }
        let bits = |t: &Thermal3| t.populations().iter().map(|g| g.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&general));
    }
}
