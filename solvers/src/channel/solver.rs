//! The channel solver: incompressible Navier-Stokes on the staggered grid of [`Grid`], advanced by
//! the low-storage three-stage Runge-Kutta scheme of Wray (Spalart, Moser & Rogers 1991) with a
//! projection after every stage (the fractional-step method of CaNS, Costa 2018):
//!
//! `u* = u + dt (gamma_s R(u) + zeta_s R_prev)`, `div grad phi = div u*`, `u = u* - grad phi`,
//! `gamma = (8/15, 5/12, 3/4)`, `zeta = (0, -17/60, -5/12)`, `alpha_s = gamma_s + zeta_s`.
//!
//! The projection is linear and leaves a divergence-free field unchanged, so each step is the RK3
//! step of `du/dt = P R(u)` on divergence-free fields: third order in time, divergence-free to
//! round-off. Everything is explicit (the viscous limit on `dt` is checked up front). The flow is
//! driven by a constant pressure gradient or held at a constant bulk velocity by a uniform
//! correction after each projection. Wall transpiration (`v` on the wall faces, or through a
//! free-slip top) is prescribed per wall cell and must carry no net volume flux. A [`Fringe`] makes
//! the periodic box compute a spatially developing flow, and a [`Trip`] makes its layer turbulent.

use rayon::prelude::*;

use super::error::ChannelError;
use super::fringe::{BaseFlow, Fringe, FringeSpec};
use super::grid::{Grid, Top};
use super::operators::{correct_uw_row, correct_v_row, divergence_row, rhs_uw_row, rhs_v_row, Fields};
use super::poisson::Poisson;
use super::trip::{Trip, TripSpec};

const GAMMA: [f64; 3] = [8.0 / 15.0, 5.0 / 12.0, 3.0 / 4.0];
const ZETA: [f64; 3] = [0.0, -17.0 / 60.0, -5.0 / 12.0];
/// Time of each stage within the step, in units of `dt`.
const STAGE_TIME: [f64; 3] = [0.0, 8.0 / 15.0, 2.0 / 3.0];
/// Grid rows per parallel task (a row is `nx` values); any value gives the same bits.
const ROWS_PER_TASK: usize = 8;

/// How the flow is driven in x.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drive {
    /// A constant bulk velocity (mean of `u` over the channel), held by the mean pressure gradient.
    FlowRate(f64),
    /// A constant mean pressure gradient `-dP/dx`.
    PressureGradient(f64),
}

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChannelConfig {
    /// Cells `[nx, ny, nz]`.
    pub n: [usize; 3],
    /// Box `[lx, ly, lz]`.
    pub length: [f64; 3],
    /// tanh stretching strength in y (0 uniform).
    pub stretch: f64,
    pub top: Top,
    /// Kinematic viscosity.
    pub nu: f64,
    pub dt: f64,
    pub drive: Drive,
    /// Steps between CFL checks (0: never).
    pub check_interval: u64,
}

/// Largest stable `dt` of RK3 for explicit diffusion: `|lambda dt| <= 2.51` on the real axis,
/// with `lambda` bounded by `nu (4/dx^2 + 4/dz^2 + max_j 4/(dyf_j dyc_j))` and a margin of 10 %.
pub fn viscous_dt_limit(g: &Grid, nu: f64) -> f64 {
    damped_dt_limit(g, nu, 0.0)
}

/// The same limit with a linear damping of rate `damping` (a fringe) added to the diffusion.
fn damped_dt_limit(g: &Grid, nu: f64, damping: f64) -> f64 {
    let ymax = (0..g.ny)
        .map(|j| 2.0 / g.dyf[j] * (1.0 / g.dyc[j] + 1.0 / g.dyc[j + 1]))
        .fold(0.0, f64::max);
    let lam = nu * (4.0 / (g.dx * g.dx) + 4.0 / (g.dz * g.dz) + ymax) + damping;
    0.9 * 2.51 / lam
}

/// A velocity field of a channel with its grid size and its clock (for caching developed flows:
/// a trip's forcing depends on the time).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChannelState {
    pub n: [usize; 3],
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub w: Vec<f64>,
    pub steps: u64,
    pub time: f64,
}

pub struct Channel {
    grid: Grid,
    cfg: ChannelConfig,
    u: Vec<f64>,
    v: Vec<f64>,
    w: Vec<f64>,
    /// `phi` of the last projection; the pressure is `phi / (alpha dt)`.
    phi: Vec<f64>,
    phi_scale: f64,
    r: [Vec<f64>; 3],
    r_prev: [Vec<f64>; 3],
    poisson: Poisson,
    fringe: Option<Fringe>,
    trip: Option<Trip>,
    /// Per-plane partial sums, reduced in plane order.
    partial: Vec<f64>,
    /// The mean pressure gradient of the last stage (the drive, or what holds the flow rate).
    drive_now: f64,
    step: u64,
    time: f64,
}

impl Channel {
    /// A channel at rest with no transpiration.
    pub fn new(cfg: ChannelConfig) -> Result<Self, ChannelError> {
        let grid = Grid::new(cfg.n, cfg.length, cfg.stretch, cfg.top)?;
        if !(cfg.nu > 0.0 && cfg.nu.is_finite()) {
            return Err(ChannelError::config("nu", format!("{} must be positive", cfg.nu)));
        }
        let limit = viscous_dt_limit(&grid, cfg.nu);
        if !(cfg.dt > 0.0 && cfg.dt <= limit) {
            return Err(ChannelError::config(
                "dt",
                format!("{} is outside (0, {limit:.4e}], the viscous stability limit of this grid", cfg.dt),
            ));
        }
        let drive_now = match cfg.drive {
            Drive::PressureGradient(g) if g.is_finite() => g,
            Drive::FlowRate(ub) if ub.is_finite() => 0.0,
            d => return Err(ChannelError::config("drive", format!("{d:?} is not finite"))),
        };
        let cells = grid.cells();
        let faces = grid.nx * (grid.ny + 1) * grid.nz;
        let bufs = || [vec![0.0; cells], vec![0.0; faces], vec![0.0; cells]];
        Ok(Channel {
            poisson: Poisson::new(&grid),
            fringe: None,
            trip: None,
            u: vec![0.0; cells],
            v: vec![0.0; faces],
            w: vec![0.0; cells],
            phi: vec![0.0; cells],
            phi_scale: 1.0,
            r: bufs(),
            r_prev: bufs(),
            partial: vec![0.0; grid.nz],
            drive_now,
            step: 0,
            time: 0.0,
            grid,
            cfg,
        })
    }

    pub fn grid(&self) -> &Grid {
        &self.grid
    }
    pub fn config(&self) -> &ChannelConfig {
        &self.cfg
    }
    pub fn time(&self) -> f64 {
        self.time
    }
    pub fn steps(&self) -> u64 {
        self.step
    }
    /// `u` on the x-faces, `at(i, j, k)` order.
    pub fn u(&self) -> &[f64] {
        &self.u
    }
    /// `v` on the y-faces (`ny + 1` rows per plane, the walls included), `at_v` order.
    pub fn v(&self) -> &[f64] {
        &self.v
    }
    /// `w` on the z-faces.
    pub fn w(&self) -> &[f64] {
        &self.w
    }
    /// Mean pressure gradient `-dP/dx` of the last stage.
    pub fn drive(&self) -> f64 {
        self.drive_now
    }

    /// Pressure at the cell centres (up to a constant) from the last projection, into `out`.
    pub fn pressure(&self, out: &mut [f64]) {
        for (o, p) in out.iter_mut().zip(&self.phi) {
            *o = p / self.phi_scale;
        }
    }

    /// Replaces the velocity (the wall rows of `v` are kept: they are the transpiration) and
    /// projects it onto divergence-free fields.
    pub fn set_velocity(&mut self, u: &[f64], v: &[f64], w: &[f64]) -> Result<(), ChannelError> {
        let g = &self.grid;
        for (what, got, want) in [
            ("u", u.len(), self.u.len()),
            ("v", v.len(), self.v.len()),
            ("w", w.len(), self.w.len()),
        ] {
            if got != want {
                return Err(ChannelError::Size { what, got, want });
            }
        }
        self.u.copy_from_slice(u);
        self.w.copy_from_slice(w);
        for k in 0..g.nz {
            for j in 1..g.ny {
                let a = g.at_v(0, j, k);
                self.v[a..a + g.nx].copy_from_slice(&v[a..a + g.nx]);
            }
        }
        self.project(1.0);
        self.hold_flow_rate();
        Ok(())
    }

    /// For a flow-rate drive, shifts `u` uniformly to the target bulk velocity; returns the shift.
    fn hold_flow_rate(&mut self) -> f64 {
        let Drive::FlowRate(target) = self.cfg.drive else { return 0.0 };
        let du = target - self.bulk_velocity();
        self.u.par_iter_mut().for_each(|u| *u += du);
        du
    }

    /// The current velocity field and clock.
    pub fn state(&self) -> ChannelState {
        ChannelState {
            n: self.cfg.n,
            u: self.u.clone(),
            v: self.v.clone(),
            w: self.w.clone(),
            steps: self.step,
            time: self.time,
        }
    }

    /// Replaces the velocity, wall rows included, and the clock by a state of
    /// [`Channel::state`] bit for bit (it is divergence-free already), so a run continued from a
    /// cached state is the run that cached it.
    pub fn restore(&mut self, s: &ChannelState) -> Result<(), ChannelError> {
        let fits = s.n == self.cfg.n && s.u.len() == self.u.len() && s.v.len() == self.v.len() && s.w.len() == self.w.len();
        if !fits {
            return Err(ChannelError::config(
                "n",
                format!("a state of {:?} cells does not fit this {:?} grid", s.n, self.cfg.n),
            ));
        }
        self.u.copy_from_slice(&s.u);
        self.v.copy_from_slice(&s.v);
        self.w.copy_from_slice(&s.w);
        self.step = s.steps;
        self.time = s.time;
        Ok(())
    }

    /// Sets wall-normal velocity on the wall faces, `nx nz` values each in `at(i, 0, k)` order
    /// (i + k nx): `bottom` positive is blowing into the fluid, `top` positive is suction out of it
    /// (both are `v`). The net flux must vanish. Through a free-slip top it is the outflow that
    /// sets the free stream of a boundary layer (its `u` keeps a zero normal derivative).
    pub fn set_transpiration(&mut self, bottom: &[f64], top: &[f64]) -> Result<(), ChannelError> {
        let g = &self.grid;
        let n = g.nx * g.nz;
        for (what, got) in [("bottom transpiration", bottom.len()), ("top transpiration", top.len())] {
            if got != n {
                return Err(ChannelError::Size { what, got, want: n });
            }
        }
        let net = (bottom.iter().sum::<f64>() - top.iter().sum::<f64>()) / n as f64;
        let scale = bottom.iter().chain(top).fold(0.0f64, |m, &x| m.max(x.abs()));
        if !(net.abs() <= 1e-12 * scale.max(f64::MIN_POSITIVE)) {
            return Err(ChannelError::NetTranspiration { net });
        }
        for k in 0..g.nz {
            for i in 0..g.nx {
                self.v[g.at_v(i, 0, k)] = bottom[k * g.nx + i];
                self.v[g.at_v(i, g.ny, k)] = top[k * g.nx + i];
            }
        }
        Ok(())
    }

    /// Laminar Poiseuille flow for the drive (a free-slip top is the centre plane of a channel
    /// twice as high): `u = u_c y (2h - y) / h^2` with `u_c = G h^2 / (2 nu)` for a pressure
    /// gradient `G`, or the `u_c` whose discrete bulk velocity is the target (about `1.5 U_b`).
    pub fn set_laminar(&mut self) {
        let g = &self.grid;
        let h = match g.top {
            Top::Wall => 0.5 * g.ly,
            Top::FreeSlip => g.ly,
        };
        let shape = |y: f64| y * (2.0 * h - y) / (h * h);
        let amp = match self.cfg.drive {
            Drive::FlowRate(ub) => {
                let bulk: f64 = (0..g.ny).map(|j| g.dyf[j] * shape(g.yc[j])).sum::<f64>() / g.ly;
                ub / bulk
            }
            Drive::PressureGradient(grad) => grad * h * h / (2.0 * self.cfg.nu),
        };
        for k in 0..g.nz {
            for j in 0..g.ny {
                let a = g.at(0, j, k);
                self.u[a..a + g.nx].fill(amp * shape(g.yc[j]));
            }
        }
        self.w.fill(0.0);
        for k in 0..g.nz {
            for j in 1..g.ny {
                let a = g.at_v(0, j, k);
                self.v[a..a + g.nx].fill(0.0);
            }
        }
    }

    /// The laminar profile plus a finite disturbance that trips turbulence: `noise()` (values in
    /// [-1, 1], drawn in a fixed order) times `amplitude`, and spanwise streaks of wavelength
    /// `lz / 2` in `u`, all vanishing at the walls, projected onto divergence-free fields.
    pub fn set_disturbed_laminar(&mut self, amplitude: f64, mut noise: impl FnMut() -> f64) {
        self.set_laminar();
        let g = &self.grid;
        let h = match g.top {
            Top::Wall => 0.5 * g.ly,
            Top::FreeSlip => g.ly,
        };
        let env = |y: f64| y * (2.0 * h - y) / (h * h);
        let two_pi = 2.0 * std::f64::consts::PI;
        for k in 0..g.nz {
            let streak = (2.0 * two_pi * (k as f64 + 0.5) * g.dz / g.lz).sin();
            for j in 0..g.ny {
                for i in 0..g.nx {
                    let wave = (two_pi * (i as f64 + 0.5) * g.dx / g.lx).sin();
                    let a = amplitude * env(g.yc[j]);
                    self.u[g.at(i, j, k)] += a * (noise() + 0.7 * streak);
                    self.w[g.at(i, j, k)] += a * (noise() + 0.3 * wave);
                    if j > 0 {
                        self.v[g.at_v(i, j, k)] += amplitude * env(g.yf[j]) * noise();
                    }
                }
            }
        }
        self.project(1.0);
        self.hold_flow_rate();
    }

    /// Adds a fringe region pulling towards `base`; the time step must also be stable for its
    /// damping. The top's outflow is the caller's to set (`base.top()` for a free-slip top).
    pub fn set_fringe(&mut self, spec: FringeSpec, base: BaseFlow) -> Result<(), ChannelError> {
        let fringe = Fringe::new(&self.grid, spec, base)?;
        let limit = damped_dt_limit(&self.grid, self.cfg.nu, spec.lambda_max);
        if self.cfg.dt > limit {
            return Err(ChannelError::config(
                "fringe",
                format!(
                    "lambda_max = {} needs dt <= {limit:.4e} (dt is {}); lower one of them",
                    spec.lambda_max, self.cfg.dt
                ),
            ));
        }
        self.fringe = Some(fringe);
        Ok(())
    }

    pub fn fringe(&self) -> Option<&Fringe> {
        self.fringe.as_ref()
    }

    /// Adds a boundary-layer trip on the bottom wall.
    pub fn set_trip(&mut self, spec: TripSpec) -> Result<(), ChannelError> {
        let g = &self.grid;
        self.trip = Some(Trip::new(spec, g.nx, g.dx, g.nz, g.lz)?);
        Ok(())
    }

    /// One time step (three stages).
    pub fn step(&mut self) -> Result<(), ChannelError> {
        let dt = self.cfg.dt;
        for s in 0..3 {
            if let Some(trip) = &mut self.trip {
                trip.at_time(self.time + STAGE_TIME[s] * dt);
            }
            self.rhs();
            let (a, b) = (GAMMA[s] * dt, ZETA[s] * dt);
            for (x, (r, rp)) in [&mut self.u, &mut self.v, &mut self.w]
                .into_iter()
                .zip(self.r.iter().zip(&self.r_prev))
            {
                if s == 0 {
                    x.par_iter_mut().zip(r.par_iter()).for_each(|(x, r)| *x += a * r);
                } else {
                    x.par_iter_mut()
                        .zip(r.par_iter().zip(rp.par_iter()))
                        .for_each(|(x, (r, rp))| *x += a * r + b * rp);
                }
            }
            std::mem::swap(&mut self.r, &mut self.r_prev);
            let alpha_dt = (GAMMA[s] + ZETA[s]) * dt;
            self.project(alpha_dt);
            if let Drive::FlowRate(_) = self.cfg.drive {
                self.drive_now = self.hold_flow_rate() / alpha_dt;
            }
        }
        self.step += 1;
        self.time += dt;
        let every = self.cfg.check_interval;
        if every > 0 && self.step.is_multiple_of(every) {
            let cfl = self.cfl();
            if !(cfl <= 1.7) {
                return Err(ChannelError::Diverged {
                    step: self.step,
                    time: self.time,
                    cfl,
                });
            }
        }
        Ok(())
    }

    fn rhs(&mut self) {
        let g = &self.grid;
        let f = Fields {
            u: &self.u,
            v: &self.v,
            w: &self.w,
        };
        let nu = self.cfg.nu;
        let drive = match self.cfg.drive {
            Drive::PressureGradient(grad) => grad,
            Drive::FlowRate(_) => 0.0,
        };
        let (nx, ny) = (g.nx, g.ny);
        let (fringe, trip) = (self.fringe.as_ref(), self.trip.as_ref());
        let [ru, rv, rw] = &mut self.r;
        ru.par_chunks_mut(nx)
            .zip(rw.par_chunks_mut(nx))
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .for_each(|(r, (ru, rw))| {
                let (j, k) = (r % ny, r / ny);
                rhs_uw_row(g, &f, nu, drive, j, k, ru, rw);
                if let Some(fr) = fringe {
                    let a = g.at(0, j, k);
                    fr.force_uw_row(j, &f.u[a..a + nx], &f.w[a..a + nx], ru, rw);
                }
            });
        rv.par_chunks_mut(nx)
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .filter(|(r, _)| r % (ny + 1) != 0 && r % (ny + 1) != ny)
            .for_each(|(r, rv)| {
                let (j, k) = (r % (ny + 1), r / (ny + 1));
                rhs_v_row(g, &f, nu, j, k, rv);
                if let Some(fr) = fringe {
                    let a = g.at_v(0, j, k);
                    fr.force_v_row(j, &f.v[a..a + nx], rv);
                }
                if let Some(t) = trip {
                    t.force_v_row(g.yf[j], k, rv);
                }
            });
    }

    /// `div grad phi = div u`, `u -= grad phi`; `alpha_dt` scales `phi` to a pressure.
    fn project(&mut self, alpha_dt: f64) {
        divergence(
            &self.grid,
            &Fields {
                u: &self.u,
                v: &self.v,
                w: &self.w,
            },
            &mut self.phi,
        );
        self.poisson.solve(&mut self.phi);
        self.phi_scale = alpha_dt;
        let g = &self.grid;
        let (nx, ny) = (g.nx, g.ny);
        let phi = &self.phi;
        self.u
            .par_chunks_mut(nx)
            .zip(self.w.par_chunks_mut(nx))
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .for_each(|(r, (u, w))| correct_uw_row(g, phi, r % ny, r / ny, u, w));
        self.v
            .par_chunks_mut(nx)
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .filter(|(r, _)| r % (ny + 1) != 0 && r % (ny + 1) != ny)
            .for_each(|(r, v)| correct_v_row(g, phi, r % (ny + 1), r / (ny + 1), v));
    }

    /// Largest absolute divergence over the cells (a diagnostic; it allocates a row per task).
    pub fn max_divergence(&self) -> f64 {
        let g = &self.grid;
        let f = Fields {
            u: &self.u,
            v: &self.v,
            w: &self.w,
        };
        (0..g.nz * g.ny)
            .into_par_iter()
            .map_init(
                || vec![0.0; g.nx],
                |row, r| {
                    divergence_row(g, &f, r % g.ny, r / g.ny, row);
                    row.iter().fold(0.0f64, |m, d| m.max(d.abs()))
                },
            )
            .reduce(|| 0.0, f64::max)
    }

    /// Mean of `u` over the channel volume.
    pub fn bulk_velocity(&mut self) -> f64 {
        let g = &self.grid;
        let u = &self.u;
        self.partial.par_iter_mut().enumerate().for_each(|(k, s)| {
            let mut acc = 0.0;
            for j in 0..g.ny {
                let a = g.at(0, j, k);
                acc += g.dyf[j] * u[a..a + g.nx].iter().sum::<f64>();
            }
            *s = acc;
        });
        self.partial.iter().sum::<f64>() / (g.ly * (g.nx * g.nz) as f64)
    }

    /// Plane-averaged profile of `u` at the cell centres (`ny` values).
    pub fn mean_u(&self, out: &mut [f64]) {
        let g = &self.grid;
        for (j, o) in out.iter_mut().enumerate().take(g.ny) {
            let mut acc = 0.0;
            for k in 0..g.nz {
                let a = g.at(0, j, k);
                acc += self.u[a..a + g.nx].iter().sum::<f64>();
            }
            *o = acc / (g.nx * g.nz) as f64;
        }
    }

    /// Wall shear stress `nu du/dy` at the bottom wall per wall cell (`nx nz`, at the u positions),
    /// and at the top wall as `nu du/dn` into the fluid (zero for a free-slip top).
    pub fn wall_shear(&self, bottom: &mut [f64], top: &mut [f64]) {
        let g = &self.grid;
        let nu = self.cfg.nu;
        let [_, b0, b1] = g.bottom_gradient();
        let [_, t0, t1] = g.top_gradient();
        for k in 0..g.nz {
            for i in 0..g.nx {
                let s = |j| self.u[g.at(i, j, k)];
                bottom[k * g.nx + i] = nu * (b0 * s(0) + b1 * s(1));
                top[k * g.nx + i] = match g.top {
                    Top::Wall => nu * (t0 * s(g.ny - 1) + t1 * s(g.ny - 2)),
                    Top::FreeSlip => 0.0,
                };
            }
        }
    }

    /// Courant number `dt max(|u|/dx + |v|/dy + |w|/dz)`.
    pub fn cfl(&mut self) -> f64 {
        let g = &self.grid;
        let (u, v, w) = (&self.u, &self.v, &self.w);
        let dt = self.cfg.dt;
        self.partial.par_iter_mut().enumerate().for_each(|(k, s)| {
            let mut m = 0.0f64;
            for j in 0..g.ny {
                for i in 0..g.nx {
                    let c = u[g.at(i, j, k)].abs() / g.dx + v[g.at_v(i, j + 1, k)].abs() / g.dyf[j] + w[g.at(i, j, k)].abs() / g.dz;
                    m = m.max(if c.is_nan() { f64::INFINITY } else { c });
                }
            }
            *s = m;
        });
        dt * self.partial.iter().fold(0.0f64, |m, &x| m.max(x))
    }
}

/// Divergence of the velocity in every cell, into `out`.
fn divergence(g: &Grid, f: &Fields, out: &mut [f64]) {
    out.par_chunks_mut(g.nx)
        .enumerate()
        .with_min_len(ROWS_PER_TASK)
        .for_each(|(r, d)| divergence_row(g, f, r % g.ny, r / g.ny, d));
}
