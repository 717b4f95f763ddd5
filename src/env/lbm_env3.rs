//! The `Env` of every 3D lattice-Boltzmann family ([`Env3Spec`]), with the 2D environment's
//! contract (`lbm_env.rs`): the developed flow cached per spec and level, a seed-dependent start
//! of 0-63 half control intervals after it, smoothed actuation, interval-averaged forces, a
//! blow-up ending the episode with `terminated` and the reason in `info`.
//!
//! Forces: `C_D`, `C_L`, `C_S` are the x, y, z forces over `rho U^2 A / 2`, with `A` the set-up's
//! reference area (span times L for an extruded body, the frontal area of a sphere or cube; a
//! segment's share of it for a segment). `info` reports the totals, per body (`C_D_b`, `C_L_b`,
//! `C_S_b`) and per segment summed over the bodies (`C_D_seg{s}`, `C_L_seg{s}`). The reward's
//! lift is the lateral force's magnitude `|(C_L, C_S)|` (a sphere's or cube's wake may tilt
//! either way).
//!
//! Agents: a section actuator on more than one segment makes one agent per segment
//! (`hgym_agents::multi`), each seeing its segment's probes and setting its segment's actuators.
//!
//! A spec with `thermal` also carries a temperature field (D3Q7, stepped after every flow step
//! with the flow's velocity; one process only), observed at the probes and set at the inlet by an
//! inlet-temperature actuator; with `inflow` the inlet's scale oscillates, as in 2D
//! (`lbm_env.rs`).

use std::path::{Path, PathBuf};

use hgym_agents::multi::Agents;
use hgym_agents::{checked_action, BoxSpace, Env, EnvError, Info, StepResult};
use hgym_solvers::lbm::d3::Thermal3;
use hgym_solvers::lbm::thermal::ThermalSide;
use hgym_solvers::lbm::{LbmError, Units};

use super::actuation::{section_velocity, Jet};
use super::family::{merged, CalibrateError, FamilySpec, FlowEnv, Spec};
use super::seeding::splitmix64;
use super::spec::{ActuationSpec, RewardSpec};
use super::spec3::{Actuation3Spec, Env3Spec};
use super::EnvInputError;
use crate::flow::{BoundaryKind, FlowError, LbmFlow3, Level};

pub struct LbmEnv3 {
    spec: Env3Spec,
    level: Level,
    units: Units,
    solver: LbmFlow3,
    steps_per_action: u64,
    /// Section actuators: the resolved jets and rotation centres.
    jets: Vec<Jet>,
    centers: Vec<[f64; 2]>,
    probes: Vec<[f64; 3]>,
    /// `rho U^2 A / 2` of the whole span and of one segment, lattice units.
    force_scale: f64,
    segment_scale: f64,
    a_old: Vec<f64>,
    actions_taken: usize,
    live: bool,
    clock: super::clock::SolverClock,
    attractor: Option<Vec<f32>>,
    cache_dir: Option<PathBuf>,
    t0: u64,
    segment_rewards: Vec<f64>,
    /// The temperature field (specs with `thermal`) and the flow velocity it is carried by.
    thermal: Option<Thermal3>,
    velocity: [Vec<f32>; 3],
    /// Seed of the inflow noise (0 during the spin-up, the episode's seed after a reset).
    noise_seed: u64,
}

fn backend(e: impl std::fmt::Display) -> EnvError {
    EnvError::Backend(e.to_string())
}

/// Interval-averaged force coefficients: per body, and per (body, segment) at `b S + s`.
struct Coefficients {
    body: Vec<[f64; 3]>,
    segment: Vec<[f64; 3]>,
}

/// The reward of an interval from its forces, the (normalised) observation at its end and the
/// temperature at the reward's probe: `-sum |C_D| - w sum |(C_L, C_S)|` over `forces` (each
/// body's own, `drag_lift`), or of their sum (`total_drag_lift`); `-|C_L - C_L,ref| - w |C_D -
/// C_D,ref|` of their sum (`gust_loads`); `-9 sum obs^2` (`probe_deviation`); `-w |T - T_target|`
/// (`probe_temperature`); as in 2D.
fn reward(spec: &RewardSpec, forces: &[[f64; 3]], obs: &[f64], probe_temperature: Option<f64>) -> f64 {
    let lateral = |f: &[f64; 3]| f[1].hypot(f[2]);
    match spec {
        RewardSpec::DragLift { lift_weight } => forces.iter().map(|f| -f[0].abs() - lift_weight * lateral(f)).sum(),
        RewardSpec::TotalDragLift { lift_weight } => {
            let t = forces.iter().fold([0.0; 3], |t, f| [t[0] + f[0], t[1] + f[1], t[2] + f[2]]);
            -t[0].abs() - lift_weight * lateral(&t)
        }
        RewardSpec::ProbeDeviation => -9.0 * obs.iter().map(|o| o * o).sum::<f64>(),
        RewardSpec::GustLoads {
            c_l_ref,
            c_d_ref,
            drag_weight,
            ..
        } => {
            let (c_d, c_l) = forces.iter().fold((0.0, 0.0), |(d, l), f| (d + f[0], l + f[1]));
            -(c_l - c_l_ref).abs() - drag_weight * (c_d - c_d_ref).abs()
        }
        RewardSpec::ProbeTemperature { target, weight, .. } => -weight * (probe_temperature.unwrap_or(f64::NAN) - target).abs(),
    }
}

/// The temperature field of `spec` on the solver's grid: the flow's solid nodes at the wall
/// temperature, the inlet at the inlet temperature, open outlets at zero gradient, periodic
/// faces periodic, every other face at the wall temperature; `kappa = nu / Pr`. One process.
fn thermal_field(spec: &Env3Spec, solver: &LbmFlow3, units: &Units) -> Result<Option<Thermal3>, EnvError> {
    let Some(th) = &spec.thermal else {
        return Ok(None);
    };
    if solver.rank().1 > 1 {
        return Err(EnvError::InvalidSpec(format!(
            "{}: its temperature field runs on one process (it is not split over ranks); run it without mpirun",
            spec.id
        )));
    }
    let side = |k: BoundaryKind, inlet: bool| match k {
        BoundaryKind::Periodic => ThermalSide::Periodic,
        BoundaryKind::Outlet => ThermalSide::ZeroGradient,
        BoundaryKind::Inlet if inlet => ThermalSide::Temperature(th.inlet_temperature as f32),
        _ => ThermalSide::Temperature(th.wall_temperature as f32),
    };
    let b = &spec.boundaries;
    let z = spec.span.boundary;
    let faces = [
        side(b.west, true),
        side(b.east, false),
        side(b.south, false),
        side(b.north, false),
        side(z, false),
        side(z, false),
    ];
    let n = solver.n();
    let solid = (0..n[2])
        .flat_map(|z| (0..n[1]).flat_map(move |y| (0..n[0]).map(move |x| [x, y, z])))
        .map(|p| solver.is_solid(p))
        .collect();
    // D3Q7: kappa = (tau - 1/2) / 4.
    let tau = 0.5 + 4.0 * units.nu() / th.prandtl;
    let mut field = Thermal3::new(n, tau, faces, solid, th.wall_temperature).map_err(backend)?;
    field.init_with(|_| th.initial_temperature);
    Ok(Some(field))
}

impl LbmEnv3 {
    /// Builds the solver for `spec` at `level` through the flow layer (`check`, `plan`,
    /// `build3`); `cache_dir` keeps developed-flow states between processes.
    pub fn new(spec: Env3Spec, level: Level, cache_dir: Option<PathBuf>) -> Result<Self, EnvError> {
        spec.check().map_err(|m| EnvError::InvalidSpec(format!("{}: {m}", spec.id)))?;
        let setup = spec.flow_setup();
        let flow_error = |e: FlowError| match e {
            FlowError::Invalid { .. } => EnvError::InvalidSpec(format!("{}: {e}", spec.id)),
            FlowError::Solver(_) => EnvError::Backend(format!("{}: {e}", spec.id)),
        };
        let plan = setup.plan(level).map_err(flow_error)?;
        let units = plan.units;
        let solver = setup.build3(&plan).map_err(flow_error)?;
        let (jets, centers) = match &spec.actuation {
            Actuation3Spec::Segments { actuator } => {
                super::actuation::resolve(actuator, &spec.bodies).map_err(|m| EnvError::InvalidSpec(format!("{}: {m}", spec.id)))?
            }
            Actuation3Spec::SurfaceJets { .. } => (vec![], vec![]),
        };
        let n = units.cells_per_length / setup.reference_length();
        let force_scale = 0.5 * units.u_lattice * units.u_lattice * setup.reference_area() * n * n;
        let segment_scale = force_scale / spec.segments() as f64;
        let steps_per_action = units.steps(spec.control_interval).max(1);
        let act_dim = spec.act_dim();
        let thermal = thermal_field(&spec, &solver, &units)?;
        let cells = if thermal.is_some() { solver.n().iter().product() } else { 0 };
        Ok(LbmEnv3 {
            thermal,
            velocity: std::array::from_fn(|_| vec![0.0; cells]),
            noise_seed: 0,
            probes: spec.probe_points(),
            segment_rewards: vec![0.0; spec.segments()],
            spec,
            level,
            units,
            solver,
            steps_per_action,
            jets,
            centers,
            force_scale,
            segment_scale,
            a_old: vec![0.0; act_dim],
            actions_taken: 0,
            live: false,
            clock: Default::default(),
            attractor: None,
            cache_dir,
            t0: 0,
        })
    }

    pub fn spec(&self) -> &Env3Spec {
        &self.spec
    }

    pub fn solver(&self) -> &LbmFlow3 {
        &self.solver
    }

    pub fn units(&self) -> &Units {
        &self.units
    }

    pub fn steps_per_action(&self) -> u64 {
        self.steps_per_action
    }

    /// The temperature field, for specs with a `[thermal]` section.
    pub fn thermal(&self) -> Option<&Thermal3> {
        self.thermal.as_ref()
    }

    /// Sets every body's wall velocity for physical actuation `a` (units of U or U/D), or the
    /// inlet's temperature (units of T_wall).
    fn actuate(&mut self, a: &[f64]) {
        let units = self.units;
        let lattice = |u: [f64; 3]| u.map(|v| units.lattice_velocity(v));
        match &self.spec.actuation {
            Actuation3Spec::Segments {
                actuator: ActuationSpec::InletTemperature { .. },
            } => {
                if let Some(th) = &mut self.thermal {
                    // Finite and within the spec's range by construction (see `step`).
                    let _ = th.set_face_temperature(0, a[0]);
                }
            }
            Actuation3Spec::Segments { actuator } => {
                let k = actuator.dim();
                let (z0, lz, segments) = (self.spec.span.z[0], self.spec.span.length(), self.spec.segments());
                let (jets, centers) = (&self.jets, &self.centers);
                for b in 0..self.spec.bodies.len() {
                    self.solver.set_wall_velocity(b, |p| {
                        // The segment of the wall point (wrapped into the span).
                        let z = (p[2] - z0).rem_euclid(lz);
                        let s = ((z / lz * segments as f64) as usize).min(segments - 1);
                        let u = section_velocity(actuator, jets, centers, b, &a[s * k..(s + 1) * k], [p[0], p[1]]);
                        lattice([u[0], u[1], 0.0])
                    });
                }
            }
            Actuation3Spec::SurfaceJets { body, jets, .. } => {
                for b in 0..self.spec.bodies.len() {
                    let on = b == *body;
                    self.solver.set_wall_velocity(b, |p| {
                        let mut u = [0.0; 3];
                        if on {
                            for (jet, a) in jets.iter().zip(a) {
                                let s = jet.profile(p);
                                (0..3).for_each(|c| u[c] += a * s[c]);
                            }
                        }
                        lattice(u)
                    });
                }
            }
        }
    }

    /// The actuation with the actuators at rest: zero, or the starting inlet temperature.
    fn rest_actuation(&self) -> Vec<f64> {
        match (&self.spec.actuation, &self.spec.thermal) {
            (
                Actuation3Spec::Segments {
                    actuator: ActuationSpec::InletTemperature { .. },
                },
                Some(th),
            ) => vec![th.inlet_temperature],
            _ => vec![0.0; self.spec.act_dim()],
        }
    }

    /// One lattice step of everything the spec has: the oscillatory inflow's scale, the flow,
    /// and the temperature carried by it. Without those, exactly the flow's step.
    fn substep(&mut self) -> Result<(), LbmError> {
        if let Some(inflow) = &self.spec.inflow {
            let t = self.solver.time() as f64 * self.units.time_per_step();
            let scale = inflow.scale(self.spec.reynolds, t, self.spec.control_interval, self.noise_seed);
            self.solver.set_boundary_velocity_scale(scale);
        }
        self.solver.step()?;
        if let Some(th) = &mut self.thermal {
            let [ux, uy, uz] = &mut self.velocity;
            self.solver.velocity_field([ux, uy, uz])?;
            th.step([ux, uy, uz])?;
        }
        Ok(())
    }

    /// The state a developed-flow cache keeps: the populations, then the temperature's.
    fn state(&self) -> Vec<f32> {
        let mut state = self.solver.populations().to_vec();
        if let Some(th) = &self.thermal {
            state.extend_from_slice(th.populations());
        }
        state
    }

    /// Mass (lattice units per step) each action alone injects at `action` (in [-1, 1], a
    /// fraction of the bound), summed over the bodies: nonzero for a jet that reaches wall links,
    /// zero for a rotation or a zero-net-mass-flux pair. Leaves the actuators at rest.
    pub fn actuator_mass_sources(&mut self, action: f64) -> Vec<f64> {
        let dim = self.spec.act_dim();
        let bound = self.spec.actuation.bound();
        let mut out = Vec::with_capacity(dim);
        for k in 0..dim {
            let mut a = vec![0.0; dim];
            a[k] = action * bound;
            self.actuate(&a);
            out.push((0..self.spec.bodies.len()).map(|b| self.solver.wall_mass_source(b)).sum());
        }
        let rest = self.rest_actuation();
        self.actuate(&rest);
        out
    }

    /// Cache key: what shapes the developed flow (actuators at rest, so the jet and rotary
    /// variants of a flow share it), as in 2D.
    fn cache_file(&self) -> Option<PathBuf> {
        let mut physics = self.spec.clone();
        physics.id.clear();
        physics.family.clear();
        physics.description.clear();
        physics.actuation = Actuation3Spec::SurfaceJets {
            body: 0,
            jets: vec![],
            max_velocity: 0.0,
        };
        physics.normalization = Default::default();
        physics.episode_actions = 0;
        physics.control_interval = 0.0;
        physics.probes.clear();
        physics.reward = RewardSpec::DragLift { lift_weight: 0.0 };
        physics.agent_reward = Default::default();
        physics.ramp = Default::default();
        physics.gust = None;
        let hash = physics.hash();
        self.cache_dir.as_ref().map(|d| match self.solver.rank() {
            (_, 1) => d.join(format!("flow3-{}-{}.f32", self.level.name(), &hash[..16])),
            // Under MPI each rank keeps its own slab.
            (r, n) => d.join(format!("flow3-{}-{}-rank{r}of{n}.f32", self.level.name(), &hash[..16])),
        })
    }

    /// The developed flow into `self.attractor` (`reset` copies it into the solver from there):
    /// from the disk cache, or by spinning up from the free stream with a kick behind the last
    /// body, modulated along the span so that 3D modes grow (fluid that a body says starts at
    /// rest, the cavity's, at rest).
    fn develop(&mut self) -> Result<(), EnvError> {
        if self.attractor.is_some() {
            return Ok(());
        }
        let want = self.solver.populations().len() + self.thermal.as_ref().map_or(0, |t| t.populations().len());
        let cached = self.cache_file().and_then(|p| super::spin_up::load_state(&p, want));
        // Under MPI the ranks spin up together unless every one of them has its slab cached.
        if self.solver.all_ranks(cached.is_some()) {
            self.attractor = cached;
            return Ok(());
        }
        let u = self.spec.lattice_velocity;
        let centers: Vec<[f64; 2]> = self.spec.bodies.iter().map(|b| b.center()).collect();
        let x_back = centers.iter().map(|c| c[0]).fold(f64::NEG_INFINITY, f64::max);
        let y_mid = centers.iter().map(|c| c[1]).sum::<f64>() / centers.len().max(1) as f64;
        let c = [x_back, y_mid];
        let (z0, lz) = (self.spec.span.z[0], self.spec.span.length());
        let bodies = &self.spec.bodies;
        self.solver.init_with(|p| {
            if bodies.iter().any(|b| b.starts_at_rest([p[0], p[1]])) {
                return (1.0, [0.0; 3]);
            }
            let r2 = (p[0] - c[0] - 1.0).powi(2) + (p[1] - c[1] - 0.25).powi(2);
            let along = 1.0 + 0.5 * (2.0 * std::f64::consts::PI * (p[2] - z0) / lz).sin();
            (1.0, [u, 0.3 * u * along * (-4.0 * r2).exp(), 0.0])
        });
        let rest = self.rest_actuation();
        self.actuate(&rest);
        self.noise_seed = 0;
        let steps = self.units.steps(self.spec.spin_up);
        let id = self.spec.id.clone();
        super::spin_up::run_reported(&id, steps, |n| (0..n).try_for_each(|_| self.substep()))
            .map_err(|e| EnvError::Backend(format!("{}: spin-up diverged: {e}", self.spec.id)))?;
        let state = self.state();
        if let Some(path) = self.cache_file() {
            super::spin_up::store_state(&path, &state);
        }
        self.attractor = Some(state);
        Ok(())
    }

    /// Raw probe values, `(u, v, w, p)` and with a temperature field `T`, per probe and segment
    /// (units of U, rho U^2 and T_wall).
    pub fn raw_observation(&self) -> Result<Vec<f64>, EnvError> {
        let mut obs = Vec::with_capacity(self.spec.obs_dim());
        for ((rho, u), x) in self.solver.probes(&self.probes).map_err(backend)?.into_iter().zip(&self.probes) {
            obs.extend(u.map(|v| self.units.velocity(v)));
            obs.push(self.units.pressure(rho));
            if let Some(t) = self.temperature_at(*x) {
                obs.push(t);
            }
        }
        Ok(obs)
    }

    /// Temperature (units of T_wall) at a physical point, trilinear.
    fn temperature_at(&self, x: [f64; 3]) -> Option<f64> {
        let th = self.thermal.as_ref()?;
        let g = self.solver.grid();
        let t_wall = self.spec.thermal.as_ref().map_or(1.0, |s| s.wall_temperature);
        Some(th.sample([0, 1, 2].map(|a| (x[a] - g.origin[a]) / g.dx)) / t_wall)
    }

    fn observation(&self) -> Result<Vec<f64>, EnvError> {
        let mut obs = self.raw_observation()?;
        self.spec.normalization.apply(&mut obs);
        Ok(obs)
    }

    /// With a gust, sets the inflow for episode time `t` to `(U, v_gust(t), 0)`; without one,
    /// the inflow stays as built.
    fn set_gust(&mut self, t: f64) -> Result<(), LbmError> {
        let Some(g) = &self.spec.gust else {
            return Ok(());
        };
        let u = self.spec.lattice_velocity;
        self.solver.set_face_velocity(0, [u, u * g.velocity(t), 0.0])
    }

    fn time(&self) -> f64 {
        (self.solver.time() - self.t0) as f64 * self.units.time_per_step()
    }

    /// Runs one control interval ramping from `a_old` to `a_new`; the interval's mean force
    /// coefficients, or the solver's reason for stopping.
    fn interval(&mut self, a_new: &[f64]) -> Result<Coefficients, LbmError> {
        let n_bodies = self.spec.bodies.len();
        let segments = self.spec.segments();
        let mut c = Coefficients {
            body: vec![[0.0; 3]; n_bodies],
            segment: vec![[0.0; 3]; n_bodies * segments],
        };
        let n = self.steps_per_action;
        let mut now = self.a_old.clone();
        for s in 0..n {
            let tau = (s + 1) as f64 / n as f64;
            for (k, v) in now.iter_mut().enumerate() {
                *v = self.spec.ramp.blend(self.a_old[k], a_new[k], tau);
            }
            self.actuate(&now);
            self.set_gust(self.time())?;
            let t = std::time::Instant::now();
            let stepped = self.substep();
            self.clock.stop(t);
            stepped?;
            for (acc, f) in c.body.iter_mut().zip(self.solver.body_forces()) {
                (0..3).for_each(|a| acc[a] += f[a] / self.force_scale / n as f64);
            }
            for (acc, f) in c.segment.iter_mut().zip(self.solver.segment_forces()) {
                (0..3).for_each(|a| acc[a] += f[a] / self.segment_scale / n as f64);
            }
        }
        Ok(c)
    }

    fn agent_count(&self) -> usize {
        match &self.spec.actuation {
            Actuation3Spec::Segments { .. } if self.spec.segments() > 1 => self.spec.segments(),
            _ => 0,
        }
    }
}

impl Env for LbmEnv3 {
    /// Probe values, normalised by the calibrated statistics when there are any; unbounded.
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(self.spec.obs_dim(), f64::NEG_INFINITY, f64::INFINITY)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.spec.act_dim())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        self.develop()?;
        // `develop` leaves the flow's populations and then the temperature's (`state`).
        let state = self.attractor.as_deref().unwrap_or_default();
        let (flow, heat) = state.split_at(self.solver.populations().len().min(state.len()));
        // An oscillating inflow continues its phase from the end of the spin-up.
        let time = if self.spec.inflow.is_some() {
            self.units.steps(self.spec.spin_up)
        } else {
            0
        };
        self.solver.set_populations(flow, time).map_err(backend)?;
        if let Some(th) = &mut self.thermal {
            th.set_populations(heat).map_err(backend)?;
        }
        self.noise_seed = seed;
        self.a_old = self.rest_actuation();
        let rest = self.a_old.clone();
        self.actuate(&rest);
        self.set_gust(0.0).map_err(backend)?;
        let offset = (splitmix64(seed) % 64) * (self.steps_per_action / 2).max(1);
        for _ in 0..offset {
            self.substep().map_err(backend)?;
        }
        self.t0 = self.solver.time();
        self.actions_taken = 0;
        self.live = true;
        let mut info = Info::default();
        info.set("t", 0.0);
        info.set("phase_steps", offset as f64);
        Ok((self.observation()?, info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let bound = self.spec.actuation.bound();
        let a_new: Vec<f64> = match &self.spec.actuation {
            // The action is a change of the inlet temperature.
            Actuation3Spec::Segments {
                actuator: ActuationSpec::InletTemperature { range, .. },
            } => vec![(self.a_old[0] + a[0] * bound).clamp(range[0], range[1])],
            _ => a.iter().map(|v| v * bound).collect(),
        };
        let result = self.interval(&a_new);
        self.a_old = a_new.clone();
        self.actions_taken += 1;
        let mut info = Info::default();
        info.set("t", self.time());
        info.set("clipped", clipped as f64);
        for (k, v) in a_new.iter().enumerate() {
            info.set(&format!("actuation_{k}"), *v);
        }
        let c = match result {
            Ok(c) => c,
            Err(e) => {
                self.live = false;
                info.set("diverged", 1.0);
                info.set_text("reason", e.to_string());
                return Ok(StepResult {
                    obs: vec![0.0; self.spec.obs_dim()],
                    reward: 0.0,
                    terminated: true,
                    truncated: false,
                    info,
                });
            }
        };
        let segments = self.spec.segments();
        let obs = self.observation()?;
        let probe_temperature = match &self.spec.reward {
            RewardSpec::ProbeTemperature { probe, .. } => {
                let t = self.probes.get(*probe).and_then(|p| self.temperature_at(*p));
                info.set("T_target", t.unwrap_or(f64::NAN));
                t
            }
            _ => None,
        };
        let per_segment = obs.len() / segments;
        let mut total = [0.0; 3];
        for (b, f) in c.body.iter().enumerate() {
            for (a, name) in ["C_D", "C_L", "C_S"].iter().enumerate() {
                info.set(&format!("{name}_{b}"), f[a]);
                total[a] += f[a];
            }
        }
        info.set("C_D", total[0]);
        info.set("C_L", total[1]);
        info.set("C_S", total[2]);
        if let Some(d) = self.spec.reward.lift_deviation(total[1]) {
            info.set("dC_L", d);
        }
        for s in 0..segments {
            let of_segment: Vec<[f64; 3]> = (0..c.body.len()).map(|b| c.segment[b * segments + s]).collect();
            info.set(&format!("C_D_seg{s}"), of_segment.iter().map(|f| f[0]).sum());
            info.set(&format!("C_L_seg{s}"), of_segment.iter().map(|f| f[1]).sum());
            self.segment_rewards[s] = reward(
                &self.spec.reward,
                &of_segment,
                &obs[s * per_segment..(s + 1) * per_segment],
                probe_temperature,
            );
        }
        let reward = reward(&self.spec.reward, &c.body, &obs, probe_temperature);
        let truncated = self.actions_taken >= self.spec.episode_actions;
        if truncated {
            self.live = false;
        }
        Ok(StepResult {
            obs,
            reward,
            terminated: false,
            truncated,
            info,
        })
    }

    /// One agent per spanwise segment of a section actuator: its segment's probes and actions.
    fn agents(&self) -> Option<Agents> {
        let segments = self.agent_count();
        if segments == 0 {
            return None;
        }
        let (per_obs, per_act) = (self.spec.obs_dim() / segments, self.spec.act_dim() / segments);
        let obs = (0..segments).map(|s| (s * per_obs..(s + 1) * per_obs).collect()).collect();
        let act = (0..segments).map(|s| (s * per_act..(s + 1) * per_act).collect()).collect();
        Agents::new(self.spec.obs_dim(), self.spec.act_dim(), obs, act, self.spec.agent_reward).ok()
    }

    /// Each segment's reward over the last interval (its forces, or its probes).
    fn agent_rewards(&self) -> Vec<f64> {
        if self.agent_count() == 0 {
            return vec![];
        }
        self.segment_rewards.clone()
    }
}

impl hgym_agents::DifferentiableEnv for LbmEnv3 {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend(format!(
            "{} is not differentiable (only the spectral Kolmogorov flows are); use ppo, ddpg or td3",
            self.spec.id
        )))
    }
}

impl super::fields::FlowFields for LbmEnv3 {
    /// The mid-span plane: `u`, `v` in units of U and the spanwise vorticity in U/L.
    fn snapshot(&mut self) -> crate::data::field::Snapshot {
        let [nx, ny, nz] = self.solver.n();
        let d = &self.spec.domain;
        let extent = [d.x[0], d.x[1], d.y[0], d.y[1]];
        let (mut u, mut v) = (vec![f32::NAN; nx * ny], vec![f32::NAN; nx * ny]);
        let plane = self.solver.velocity_plane(nz / 2);
        for (k, w) in plane.iter().enumerate() {
            if let Some(w) = w {
                u[k] = self.units.velocity(w[0]) as f32;
                v[k] = self.units.velocity(w[1]) as f32;
            }
        }
        let w = crate::flow::plane_vorticity(&plane, [nx, ny], &self.units, extent).values;
        crate::data::field::Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx,
            ny,
            extent,
            fields: vec![("u".into(), u), ("v".into(), v), ("vorticity".into(), w)],
        }
    }
}

/// Hash of the spec with what the uncontrolled statistics do not depend on removed
/// (normalisation, reward, episode length).
pub fn physics_hash(spec: &Env3Spec) -> String {
    let mut s = spec.clone();
    s.normalization = Default::default();
    s.reward = RewardSpec::DragLift { lift_weight: 0.0 };
    s.agent_reward = Default::default();
    s.episode_actions = 0;
    s.hash()
}

/// The committed statistics of `spec` at `level` (`ID` for the default level, `ID@level` for the
/// others), if they were measured on this physics.
pub fn committed_normalization(spec: &Env3Spec, level: Level) -> Option<super::spec::Normalization> {
    let key = super::calibrate::table_key(&spec.id, level);
    super::calibrate::matching(super::calibrate::table().get(&key), &physics_hash(spec), spec.obs_dim())
}

/// The 3D lattice-Boltzmann families share this spec type and [`LbmEnv3`].
impl FamilySpec for Env3Spec {
    fn id(&self) -> &str {
        &self.id
    }

    fn family(&self) -> &str {
        &self.family
    }

    fn reynolds(&self) -> f64 {
        self.reynolds
    }

    fn solver(&self) -> &'static str {
        match (self.span.lattice, self.thermal.is_some()) {
            (crate::flow::span::Lattice3Name::D3q19, false) => "lbm-d3q19",
            (crate::flow::span::Lattice3Name::D3q19, true) => "lbm-d3q19+q7",
            (crate::flow::span::Lattice3Name::D3q27, false) => "lbm-d3q27",
            (crate::flow::span::Lattice3Name::D3q27, true) => "lbm-d3q27+q7",
        }
    }

    fn dimension(&self) -> u8 {
        3
    }

    fn obs_dim(&self) -> usize {
        Env3Spec::obs_dim(self)
    }

    fn act_dim(&self) -> usize {
        Env3Spec::act_dim(self)
    }

    fn layout(&self) -> super::layout::Layout {
        super::layout::Layout::of3(self)
    }

    fn control_interval(&self) -> f64 {
        self.control_interval
    }

    fn calibrated(&self) -> bool {
        !self.normalization.mean.is_empty()
    }

    fn hash(&self) -> String {
        Env3Spec::hash(self)
    }

    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }

    fn to_toml(&self) -> String {
        Env3Spec::to_toml(self)
    }

    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError> {
        merged(self, over, &self.id, Env3Spec::check)
    }

    fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError> {
        let mut spec = self.clone();
        if let Some(n) = committed_normalization(self, level) {
            spec.normalization = n;
        }
        Ok(Box::new(LbmEnv3::new(spec, level, cache)?))
    }

    fn calibrate(
        &self,
        level: Level,
        actions: usize,
        cache: Option<PathBuf>,
        table: Option<&Path>,
        progress: &mut dyn FnMut(usize),
    ) -> Result<(String, PathBuf), CalibrateError> {
        super::calibrate::measure_and_record(&self.id, level, actions, table, || {
            let mut raw = self.clone();
            raw.normalization = Default::default();
            raw.episode_actions = actions.max(1);
            let mut env = LbmEnv3::new(raw, level, cache)?;
            let entry = super::calibrate::statistics(&mut env, &self.id, actions, LbmEnv3::raw_observation, &mut |k, _| progress(k))?;
            Ok(super::calibrate::Entry {
                spec_hash: physics_hash(self),
                level: level.name().into(),
                ..entry
            })
        })
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

impl super::clock::SolverTime for LbmEnv3 {
    fn solver_seconds(&self) -> f64 {
        self.clock.seconds()
    }
}
