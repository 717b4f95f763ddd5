//! Runs one validation case on the D2Q9 solver (one uniform grid, or nested 2:1 patches around
//! the bodies when the case has `[refinement]`): plan (lattice numbers, refusals), spin-up and
//! averaging, force history (from the finest grid), final vorticity field (coarse grid).

use std::sync::Arc;
use std::time::Instant;

use hgym_solvers::geometry::{Circle, Naca4, OpenCavity, Rectangle, Shape, Stenosis};
use hgym_solvers::lbm::{Collision, D2q9, D2q9Config, Grid, LbmError, Patch, Refined, Side, Sides, Units};

use super::case::{BoundaryKind, BoundarySpec, GeometrySpec, Level, LoadedCase, Profile, MAX_NODES};
use super::ValidateError;

/// The body of a case as a signed-distance shape.
pub fn build_shape(g: &GeometrySpec) -> Arc<dyn Shape> {
    match g {
        GeometrySpec::Circle { center, diameter } => Arc::new(Circle {
            center: *center,
            radius: 0.5 * diameter,
        }),
        GeometrySpec::Square { center, side } => Arc::new(Rectangle {
            center: *center,
            size: [*side, *side],
        }),
        GeometrySpec::Naca {
            digits,
            chord,
            leading_edge,
            aoa_deg,
        } => {
            // Digits were checked when the case was parsed; fall back to a symmetric 12 % section.
            Arc::new(
                Naca4::from_digits(digits, *chord, *leading_edge, *aoa_deg)
                    .unwrap_or_else(|| Naca4::new(0.0, 0.0, 0.12, *chord, *leading_edge, *aoa_deg)),
            )
        }
        GeometrySpec::Cavity {
            leading_edge,
            length,
            depth,
        } => Arc::new(OpenCavity {
            leading_edge: *leading_edge,
            length: *length,
            depth: *depth,
        }),
        GeometrySpec::Stenosis {
            center,
            width,
            length,
            severity,
        } => Arc::new(Stenosis {
            center: *center,
            width: *width,
            length: *length,
            severity: *severity,
        }),
    }
}

/// The solver's domain edges for a case's boundary kinds; `inlet` is the lattice velocity
/// profile of the (west) inlet, one value per row.
pub fn sides_of(b: &BoundarySpec, inlet: &[[f32; 2]]) -> Sides {
    let side = |k: BoundaryKind| match k {
        BoundaryKind::Inlet => Side::Velocity { profile: inlet.to_vec() },
        BoundaryKind::Outlet => Side::Outlet,
        BoundaryKind::Periodic => Side::Periodic,
        BoundaryKind::Wall => Side::Wall,
        BoundaryKind::FreeSlip => Side::FreeSlip,
    };
    Sides {
        west: side(b.west),
        east: side(b.east),
        south: side(b.south),
        north: side(b.north),
    }
}

/// Lattice numbers of a case at one level.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Plan {
    pub level: Level,
    pub units: Units,
    pub nx: usize,
    pub ny: usize,
    pub tau: f64,
    pub mach: f64,
    pub collision: Collision,
    pub spin_up_steps: u64,
    pub total_steps: u64,
    /// The nested patches, if the case has `[refinement]` regions.
    pub refinement: Option<RefinementPlan>,
}

/// Lattice numbers of the nested patches: each in the node indices of the grid it refines
/// (ranges inclusive), and the finest grid's cells per length and relaxation time
/// (`tau_l - 1/2 = 2^l (tau - 1/2)`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct RefinementPlan {
    pub patches: Vec<Patch>,
    pub cells_per_length: f64,
    pub tau: f64,
}

impl Plan {
    pub fn new(c: &LoadedCase, level: Level) -> Result<Self, ValidateError> {
        let case = &c.case;
        let name = case.case.name.clone();
        let l = case.geometry.reference_length();
        let n = c.cells_per_length(level) as f64;
        // `n` cells per reference length L; lengths in the case file are in the same units as L.
        let units = Units {
            cells_per_length: n,
            u_lattice: case.flow.lattice_velocity,
            reynolds: case.flow.reynolds,
        };
        let tau = units.tau();
        let margin = case.flow.collision.min_tau_margin();
        if tau - 0.5 < margin {
            let n_min = (margin * case.flow.reynolds / (3.0 * case.flow.lattice_velocity)).ceil();
            return Err(ValidateError::Unrunnable {
                case: name,
                field: "resolution".into(),
                message: format!(
                    "at the {} level ({n} cells per length) tau = {tau:.5} is too close to 1/2 for the {} collision \
                     (tau - 1/2 must be >= {margin}); use at least {n_min} cells per length, a larger lattice_velocity, \
                     or collision = \"regularized\"",
                    level.name(),
                    case.flow.collision.name()
                ),
            });
        }
        let d = &case.domain;
        let nx = ((d.x[1] - d.x[0]) * n / l).round() as usize;
        let ny = ((d.y[1] - d.y[0]) * n / l).round() as usize;
        if nx < 8 || ny < 8 {
            return Err(ValidateError::Unrunnable {
                case: name,
                field: "domain".into(),
                message: format!("{nx} x {ny} cells is too small; enlarge the domain or the resolution"),
            });
        }
        if nx * ny > MAX_NODES {
            return Err(ValidateError::Unrunnable {
                case: name,
                field: "resolution".into(),
                message: format!(
                    "{nx} x {ny} = {} cells exceeds the limit of {MAX_NODES}; use a coarser level or a smaller domain",
                    nx * ny
                ),
            });
        }
        // Cell-centred nodes: level-0 node i sits at x0 + (i + 1/2) dx; a patch takes the nodes
        // of the grid it refines that cover its region, and its own node 0 sits on the first.
        let refinement = case.refinement.as_ref().map(|rf| {
            let mut origin = [d.x[0] + 0.5 * l / n, d.y[0] + 0.5 * l / n];
            let (mut dx, mut size) = (l / n, [nx, ny]);
            let mut patches = Vec::new();
            for [rx0, rx1, ry0, ry1] in rf.regions.iter().copied() {
                let lo = |v: f64, o: f64, n: usize| (((v - o) / dx).floor().max(0.0) as usize).min(n - 1);
                let hi = |v: f64, o: f64, n: usize| (((v - o) / dx).ceil().max(0.0) as usize).min(n - 1);
                let p = Patch {
                    x: [lo(rx0, origin[0], size[0]), hi(rx1, origin[0], size[0])],
                    y: [lo(ry0, origin[1], size[1]), hi(ry1, origin[1], size[1])],
                };
                origin = [origin[0] + p.x[0] as f64 * dx, origin[1] + p.y[0] as f64 * dx];
                dx *= 0.5;
                size = [2 * (p.x[1] - p.x[0]) + 1, 2 * (p.y[1] - p.y[0]) + 1];
                patches.push(p);
            }
            let scale = (1u64 << patches.len()) as f64;
            RefinementPlan {
                patches,
                cells_per_length: scale * n,
                tau: 0.5 + scale * (tau - 0.5),
            }
        });
        // Time is in units of L/U.
        let spin_up_steps = units.steps(case.time.spin_up);
        let total_steps = spin_up_steps + units.steps(case.time.average);
        Ok(Plan {
            level,
            units,
            nx,
            ny,
            tau,
            mach: units.mach(),
            collision: case.flow.collision,
            spin_up_steps,
            total_steps,
            refinement,
        })
    }
}

/// A scalar field on the grid, for plots (`NaN` inside bodies).
#[derive(Clone, Debug)]
pub struct Field {
    pub nx: usize,
    pub ny: usize,
    /// Physical extent `[x0, x1, y0, y1]`.
    pub extent: [f64; 4],
    pub values: Vec<f32>,
}

impl Field {
    /// Writes the field as a PNG colour map titled `label`, with a symmetric colour range at the
    /// 98th percentile of |value| (so a few extremes do not wash out the rest).
    pub fn write_png(&self, path: &std::path::Path, label: &str) -> Result<(), String> {
        let vmax = crate::report::plots::abs_quantile(&self.values, 0.98);
        let title = format!("{label} (colour range +-{vmax:.2})");
        crate::report::plots::field(path, &title, self.nx, self.ny, self.extent, &self.values, vmax)
    }
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum RunStatus {
    Completed,
    Diverged { step: u64, message: String },
}

/// Everything a run produced.
#[derive(Clone, Debug)]
pub struct RunOutput {
    pub plan: Plan,
    /// Time (L/U), drag and lift coefficients, one sample per lattice step.
    pub t: Vec<f64>,
    pub cd: Vec<f64>,
    pub cl: Vec<f64>,
    /// Drag and lift of each body (totals are `cd`, `cl`).
    pub cd_bodies: Vec<Vec<f64>>,
    pub cl_bodies: Vec<Vec<f64>>,
    pub vorticity: Field,
    pub status: RunStatus,
    pub wall_time_s: f64,
    pub steps: u64,
    pub mlups: f64,
}

/// Runs `case` at `plan`; `progress(done, total)` is called every few hundred steps.
pub fn run(c: &LoadedCase, plan: &Plan, progress: &mut dyn FnMut(u64, u64)) -> Result<RunOutput, ValidateError> {
    let case = &c.case;
    let l = case.geometry.reference_length();
    let n = plan.units.cells_per_length;
    let dx = l / n;
    let u = case.flow.lattice_velocity;
    let d = &case.domain;
    let (nx, ny) = (plan.nx, plan.ny);
    // Cell-centred nodes: walls of the domain fall exactly on its edges.
    let grid = Grid {
        origin: [d.x[0] + 0.5 * dx, d.y[0] + 0.5 * dx],
        dx,
    };
    let peak = u * c.inlet_peak_factor();
    let inlet_u = |y: f64| -> f64 {
        match case.inlet.profile {
            Profile::Uniform => u,
            Profile::Parabolic => {
                let s = (y - d.y[0]) / (d.y[1] - d.y[0]);
                4.0 * peak * s * (1.0 - s)
            }
        }
    };
    let inlet: Vec<[f32; 2]> = (0..ny).map(|j| [inlet_u(grid.position(0.0, j as f64)[1]) as f32, 0.0]).collect();
    let sides = sides_of(&case.boundaries, &inlet);
    let mut cfg = D2q9Config::new(nx, ny, plan.tau, sides);
    cfg.collision = plan.collision;
    cfg.smagorinsky = case.flow.smagorinsky;
    cfg.grid = grid;
    cfg.check_interval = 200;
    cfg.sponges = case.sponge.iter().map(|sp| sp.lattice(n, u)).collect();
    let steps_per_time = n / u;
    if case.inlet.characteristic_time > 0.0 {
        cfg.characteristic_inlet = Some(case.inlet.characteristic_time * steps_per_time);
    }
    let bodies: Vec<_> = std::iter::once(&case.geometry).chain(&case.more_bodies).map(build_shape).collect();
    let n_bodies = bodies.len();
    let built = match &plan.refinement {
        None => D2q9::new(cfg, bodies).map(|s| Grids::Uniform(Box::new(s))),
        Some(r) => Refined::new(cfg, &r.patches, bodies).map(Grids::Refined),
    };
    let mut solver = built.map_err(|e| match e {
        LbmError::Config { field, message } => ValidateError::Unrunnable {
            case: case.case.name.clone(),
            field: field.to_string(),
            message,
        },
        other => ValidateError::Solver(other.to_string()),
    })?;

    // Initial state: the inflow everywhere, plus a transverse kick just behind the body, centred
    // a quarter length off the axis on the side of its sign: a negative perturbation is the exact
    // mirror image (y -> -y) of the positive one, so it selects the mirror branch of a flow with
    // two (a pitchfork bifurcation's asymmetric states).
    let center = case.geometry.center();
    let kick = case.flow.perturbation * u;
    let side = if case.flow.perturbation < 0.0 { -1.0 } else { 1.0 };
    let ramp = case.inlet.ramp;
    let start_u = if ramp > 0.0 { 0.0 } else { 1.0 };
    solver.init_with(|x, y| {
        let r2 = ((x - center[0] - l) / l).powi(2) + ((y - center[1] - side * 0.25 * l) / l).powi(2);
        (1.0, start_u * inlet_u(y), kick * (-4.0 * r2).exp())
    });

    let total = plan.total_steps;
    let mut t = Vec::with_capacity(total as usize);
    let mut cd = Vec::with_capacity(total as usize);
    let mut cl = Vec::with_capacity(total as usize);
    let mut cd_bodies = vec![Vec::with_capacity(total as usize); n_bodies];
    let mut cl_bodies = vec![Vec::with_capacity(total as usize); n_bodies];
    let coef = 0.5 * u * u * n;
    let started = Instant::now();
    let mut status = RunStatus::Completed;
    let report_every = 250u64;
    for s in 0..total {
        if ramp > 0.0 {
            let time = s as f64 / steps_per_time;
            let r = if time >= ramp {
                1.0
            } else {
                0.5 * (1.0 - (std::f64::consts::PI * time / ramp).cos())
            };
            solver.set_boundary_velocity_scale(r);
        }
        if let Err(e) = solver.step() {
            let step = match &e {
                LbmError::Diverged { step, .. } => *step,
                _ => s + 1,
            };
            status = RunStatus::Diverged {
                step,
                message: e.to_string(),
            };
            break;
        }
        let forces = solver.body_forces();
        t.push((s + 1) as f64 / steps_per_time);
        cd.push(forces.iter().map(|f| f[0]).sum::<f64>() / coef);
        cl.push(forces.iter().map(|f| f[1]).sum::<f64>() / coef);
        for (b, f) in forces.iter().enumerate() {
            cd_bodies[b].push(f[0] / coef);
            cl_bodies[b].push(f[1] / coef);
        }
        if (s + 1) % report_every == 0 {
            progress(s + 1, total);
        }
    }
    progress(solver.time(), total);
    let wall = started.elapsed().as_secs_f64();
    let steps = solver.time();
    let mlups = (solver.node_updates_per_step() as f64 * steps as f64) / wall.max(1e-9) / 1e6;
    solver.sync();
    let vorticity = vorticity_field(solver.coarse(), &plan.units, [d.x[0], d.x[1], d.y[0], d.y[1]]);
    Ok(RunOutput {
        plan: plan.clone(),
        t,
        cd,
        cl,
        cd_bodies,
        cl_bodies,
        vorticity,
        status,
        wall_time_s: wall,
        steps,
        mlups,
    })
}

/// The grid(s) a case runs on: one uniform grid, or a coarse grid with nested 2:1 patches.
enum Grids {
    Uniform(Box<D2q9>),
    Refined(Refined),
}

impl Grids {
    fn step(&mut self) -> Result<(), LbmError> {
        match self {
            Grids::Uniform(s) => s.step(),
            Grids::Refined(r) => r.step(),
        }
    }

    /// Forces on the bodies in the level's lattice units (from the finest patch when refined).
    fn body_forces(&self) -> &[[f64; 2]] {
        match self {
            Grids::Uniform(s) => s.body_forces(),
            Grids::Refined(r) => r.body_forces(),
        }
    }

    fn set_boundary_velocity_scale(&mut self, scale: f64) {
        match self {
            Grids::Uniform(s) => s.set_boundary_velocity_scale(scale),
            Grids::Refined(r) => r.set_boundary_velocity_scale(scale),
        }
    }

    fn init_with(&mut self, field: impl FnMut(f64, f64) -> (f64, f64, f64)) {
        match self {
            Grids::Uniform(s) => s.init_with(field),
            Grids::Refined(r) => r.init_with(field),
        }
    }

    /// Gives the coarse grid the fine solution under the patches (see `Refined::sync`).
    fn sync(&mut self) {
        if let Grids::Refined(r) = self {
            r.sync();
        }
    }

    /// The grid over the whole domain (call `sync` first to read it under the patches).
    fn coarse(&self) -> &D2q9 {
        match self {
            Grids::Uniform(s) => s,
            Grids::Refined(r) => r.coarse(),
        }
    }

    fn time(&self) -> u64 {
        self.coarse().time()
    }

    fn node_updates_per_step(&self) -> usize {
        match self {
            Grids::Uniform(s) => s.fluid_nodes(),
            Grids::Refined(r) => r.node_updates_per_step(),
        }
    }
}

/// Vorticity `w = dv/dx - du/dy` by central differences, in units of U/L; NaN in bodies and
/// wherever the field is not finite.
pub fn vorticity_field(s: &D2q9, units: &Units, extent: [f64; 4]) -> Field {
    let (nx, ny) = (s.nx(), s.ny());
    let mut rho = vec![0.0f32; nx * ny];
    let mut ux = vec![0.0f32; nx * ny];
    let mut uy = vec![0.0f32; nx * ny];
    s.macroscopic(&mut rho, &mut ux, &mut uy);
    let mut w = vec![f32::NAN; nx * ny];
    for y in 1..ny - 1 {
        for x in 1..nx - 1 {
            if s.is_solid(x, y) {
                continue;
            }
            let dvdx = 0.5 * (uy[y * nx + x + 1] - uy[y * nx + x - 1]);
            let dudy = 0.5 * (ux[(y + 1) * nx + x] - ux[(y - 1) * nx + x]);
            w[y * nx + x] = units.vorticity((dvdx - dudy) as f64) as f32;
        }
    }
    Field { nx, ny, extent, values: w }
}
