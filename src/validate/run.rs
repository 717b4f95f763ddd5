//! Runs one validation case on the D2Q9 solver (one uniform grid, or nested 2:1 patches around
//! the bodies when the case has `[refinement]`): plan (lattice numbers, refusals), spin-up and
//! averaging, force history (from the finest grid), final vorticity field (coarse grid).

//! Runs one validation case: its flow is built by the flow layer (`FlowSetup::build`, the path
//! the environments run), started from the inflow with an optional kick behind the body, spun up
//! and averaged; records the force history (from the finest grid) and the final vorticity field
//! (coarse grid).

use std::time::Instant;

use hgym_solvers::lbm::LbmError;

use super::case::{flow_error, Level, LoadedCase, Quantity};
use super::wake::{Wake, WakeSampler, SAMPLE_EVERY};
use super::ValidateError;
use crate::flow::{plane_vorticity, vorticity_field, Field, FlowError, FlowPlan, FlowSetup, LbmFlow, LbmFlow3};
use hgym_solvers::lbm::Units;

/// Most lattice steps a case may run (its force series hold 8 bytes per step and series).
pub const MAX_STEPS: u64 = 20_000_000;
/// Fewest lattice steps in an averaging window.
pub const MIN_AVERAGE_STEPS: u64 = 100;

/// Lattice numbers of a case at one level: its flow's, and the steps of the spin-up and the run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Plan {
    pub flow: FlowPlan,
    pub spin_up_steps: u64,
    pub total_steps: u64,
}

impl Plan {
    pub fn new(c: &LoadedCase, level: Level) -> Result<Self, ValidateError> {
        let case = &c.case;
        let flow = case.flow_setup().plan(level).map_err(|e| flow_error(&case.case.name, e))?;
        // Time is in units of L/U; counted in floating point first, so that no count wraps.
        let per_step = flow.units.time_per_step();
        let (spin_up, average) = (case.time.spin_up / per_step, case.time.average / per_step);
        let refuse = |message: String| ValidateError::Unrunnable {
            case: case.case.name.clone(),
            field: "time".into(),
            message,
        };
        if spin_up + average > MAX_STEPS as f64 {
            let series = (3 + 2 * (1 + case.more_bodies.len())) as f64 * 8.0 * (spin_up + average);
            return Err(refuse(format!(
                "spin_up + average = {} L/U is {:.3e} lattice steps at level {level:?} ({:.1} GB of force series); the limit is {MAX_STEPS} steps: shorten the times or use a coarser level",
                case.time.spin_up + case.time.average,
                spin_up + average,
                series / 1e9
            )));
        }
        if average.round() < MIN_AVERAGE_STEPS as f64 {
            return Err(refuse(format!(
                "average = {} L/U is {} lattice steps at level {level:?}; the window needs at least {MIN_AVERAGE_STEPS} (average >= {:.3})",
                case.time.average,
                average.round(),
                MIN_AVERAGE_STEPS as f64 * per_step
            )));
        }
        let spin_up_steps = flow.units.steps(case.time.spin_up);
        let total_steps = spin_up_steps + flow.units.steps(case.time.average);
        Ok(Plan {
            flow,
            spin_up_steps,
            total_steps,
        })
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
    /// The mean wake on the centreline, when the case measures its recirculation length.
    pub wake: Option<Wake>,
    pub status: RunStatus,
    pub wall_time_s: f64,
    pub steps: u64,
    pub mlups: f64,
}

/// Runs `case` at `plan`; `progress(done, total)` is called every few hundred steps.
pub fn run(c: &LoadedCase, plan: &Plan, progress: &mut dyn FnMut(u64, u64)) -> Result<RunOutput, ValidateError> {
    let case = &c.case;
    let setup = case.flow_setup();
    let l = setup.reference_length();
    let n = plan.flow.units.cells_per_length;
    let u = case.flow.lattice_velocity;
    let d = &case.domain;
    let steps_per_time = n / u;
    let n_bodies = setup.bodies.len();
    let mut solver = Solver::build(&setup, &plan.flow).map_err(|e| flow_error(&case.case.name, e))?;

    // Initial state: the inflow everywhere, plus a transverse kick just behind the body, centred
    // a quarter length off the axis on the side of its sign: a negative perturbation is the exact
    // mirror image (y -> -y) of the positive one, so it selects the mirror branch of a flow with
    // two (a pitchfork bifurcation's asymmetric states).
    let center = case.geometry.center();
    let kick = case.flow.perturbation * u;
    let side = if case.flow.perturbation < 0.0 { -1.0 } else { 1.0 };
    let ramp = case.inlet.ramp;
    let start_u = if ramp > 0.0 { 0.0 } else { 1.0 };
    solver.init_with(
        &|x, y| {
            let r2 = ((x - center[0] - l) / l).powi(2) + ((y - center[1] - side * 0.25 * l) / l).powi(2);
            (1.0, start_u * setup.inlet_velocity(y), kick * (-4.0 * r2).exp())
        },
        setup.span.as_ref(),
    );

    let total = plan.total_steps;
    let mut t = Vec::with_capacity(total as usize);
    let mut cd = Vec::with_capacity(total as usize);
    let mut cl = Vec::with_capacity(total as usize);
    let mut cd_bodies = vec![Vec::with_capacity(total as usize); n_bodies];
    let mut cl_bodies = vec![Vec::with_capacity(total as usize); n_bodies];
    // F / (rho U^2 A / 2) in lattice units: A = L per unit (lattice) span in 2D, the reference
    // area (in L^2) times n^2 in 3D.
    let area = match setup.span {
        None => n,
        Some(_) => setup.reference_area() * n * n,
    };
    let coef = 0.5 * u * u * area;
    let mut wake = if case.measure.quantities.contains(&Quantity::RecirculationLength) {
        WakeSampler::new(&setup, n, &solver.span_nodes())
    } else {
        None
    };
    let wake_every = ((SAMPLE_EVERY * steps_per_time).round() as u64).max(1);
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
                LbmError::Diverged { step, .. } | LbmError::Diverged3 { step, .. } => *step,
                _ => s + 1,
            };
            status = RunStatus::Diverged {
                step,
                message: e.to_string(),
            };
            break;
        }
        t.push((s + 1) as f64 / steps_per_time);
        let (mut sum_x, mut sum_y) = (0.0, 0.0);
        solver.each_force(&mut |b, fx, fy| {
            sum_x += fx;
            sum_y += fy;
            cd_bodies[b].push(fx / coef);
            cl_bodies[b].push(fy / coef);
        });
        cd.push(sum_x / coef);
        cl.push(sum_y / coef);
        if let Some(w) = wake.as_mut().filter(|_| s + 1 > plan.spin_up_steps && (s + 1) % wake_every == 0) {
            let ux = solver
                .streamwise(w.points())
                .map_err(|e| flow_error(&case.case.name, FlowError::Solver(e)))?;
            w.add(ux.into_iter().map(|v| v / u));
        }
        if (s + 1) % report_every == 0 {
            progress(s + 1, total);
        }
    }
    progress(solver.time(), total);
    let wall = started.elapsed().as_secs_f64();
    let steps = solver.time();
    let mlups = (solver.node_updates_per_step() as f64 * steps as f64) / wall.max(1e-9) / 1e6;
    let vorticity = solver.vorticity(&plan.flow.units, [d.x[0], d.x[1], d.y[0], d.y[1]]);
    Ok(RunOutput {
        plan: plan.clone(),
        t,
        cd,
        cl,
        cd_bodies,
        cl_bodies,
        vorticity,
        wake: wake.map(|w| w.finish()),
        status,
        wall_time_s: wall,
        steps,
        mlups,
    })
}

/// The solver a case runs on: a 2D flow (uniform or refined) or a 3D one.
enum Solver {
    Flat(LbmFlow),
    Span(LbmFlow3),
}

impl Solver {
    fn build(setup: &FlowSetup, plan: &FlowPlan) -> Result<Self, FlowError> {
        match setup.span {
            None => setup.build(plan).map(Solver::Flat),
            Some(_) => setup.build3(plan).map(Solver::Span),
        }
    }

    /// Every node at `field(x, y) = (rho, u, v)`; along a periodic span the transverse `v`
    /// (the kick) is modulated by `1 + 0.5 sin(2 pi (z - z0) / L_z)`, as the 3D environments'
    /// spin-up does: a kick uniform along a periodic span keeps an extruded flow exactly
    /// two-dimensional forever. Other spans (a sphere's, a cube's) take it uniform.
    fn init_with(&mut self, field: &dyn Fn(f64, f64) -> (f64, f64, f64), span: Option<&crate::flow::SpanSpec>) {
        match self {
            Solver::Flat(s) => s.init_with(field),
            Solver::Span(s) => {
                let wave = span
                    .filter(|sp| sp.boundary == crate::flow::BoundaryKind::Periodic)
                    .map(|sp| (sp.z[0], sp.length()));
                s.init_with(|p| {
                    let (rho, u, v) = field(p[0], p[1]);
                    let along = wave.map_or(1.0, |(z0, lz)| 1.0 + 0.5 * (2.0 * std::f64::consts::PI * (p[2] - z0) / lz).sin());
                    (rho, [u, v * along, 0.0])
                })
            }
        }
    }

    fn set_boundary_velocity_scale(&mut self, scale: f64) {
        match self {
            Solver::Flat(s) => s.set_boundary_velocity_scale(scale),
            Solver::Span(s) => s.set_boundary_velocity_scale(scale),
        }
    }

    fn step(&mut self) -> Result<(), LbmError> {
        match self {
            Solver::Flat(s) => s.step(),
            Solver::Span(s) => s.step(),
        }
    }

    /// Streamwise and transverse (y) force on each body in turn, lattice units.
    fn each_force(&self, f: &mut dyn FnMut(usize, f64, f64)) {
        match self {
            Solver::Flat(s) => s.body_forces().iter().enumerate().for_each(|(b, v)| f(b, v[0], v[1])),
            Solver::Span(s) => s.body_forces().iter().enumerate().for_each(|(b, v)| f(b, v[0], v[1])),
        }
    }

    /// Node positions along the span (none in 2D).
    fn span_nodes(&self) -> Vec<f64> {
        match self {
            Solver::Flat(_) => vec![],
            Solver::Span(s) => {
                let grid = s.grid();
                (0..s.n()[2]).map(|k| grid.position([0, 0, k])[2]).collect()
            }
        }
    }

    /// Streamwise lattice velocity at each point (`z` ignored in 2D; the coarse grid's there).
    fn streamwise(&mut self, points: &[[f64; 3]]) -> Result<Vec<f64>, LbmError> {
        match self {
            Solver::Flat(s) => {
                s.sync();
                let points: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
                Ok(s.coarse().probes(&points)?.into_iter().map(|v| v[1]).collect())
            }
            Solver::Span(s) => Ok(s.probes(points)?.into_iter().map(|(_, v)| v[0]).collect()),
        }
    }

    fn time(&self) -> u64 {
        match self {
            Solver::Flat(s) => s.time(),
            Solver::Span(s) => s.time(),
        }
    }

    fn node_updates_per_step(&self) -> usize {
        match self {
            Solver::Flat(s) => s.node_updates_per_step(),
            Solver::Span(s) => s.node_updates_per_step(),
        }
    }

    /// The final vorticity: of the whole (coarse) grid in 2D, of the mid-span plane in 3D.
    fn vorticity(&mut self, units: &Units, extent: [f64; 4]) -> Field {
        match self {
            Solver::Flat(s) => {
                s.sync();
                vorticity_field(s.coarse(), units, extent)
            }
            Solver::Span(s) => {
                s.sync();
                let [nx, ny, nz] = s.n();
                plane_vorticity(&s.velocity_plane(nz / 2), [nx, ny], units, extent)
            }
        }
    }
}
