//! The `Env` of every 2D lattice-Boltzmann family: builds the solver from a spec, reaches the
//! attractor once (cached), and runs control intervals with smoothed actuation.
//!
//! - `reset(seed)`: loads the developed-flow state (spun up on first use, then cached in memory
//!   and on disk under the spec hash and level) and advances it by a seed-dependent number of
//!   half control intervals (0-63), so different seeds start at different shedding phases and the
//!   same seed always starts at the same one, bitwise.
//! - `step(action)`: NaN or infinite components are an error; finite values outside [-1, 1] are
//!   clipped and counted in `info["clipped"]`. Over the interval's `n` solver steps the actuation
//!   goes from the previous to the new value with the spec's ramp. The reward uses the
//!   interval-averaged force coefficients, which `info` reports (`C_D`, `C_L`, and per body
//!   `C_D_b`, `C_L_b`; under the gust reward also `dC_L`, the lift's deviation from the
//!   undisturbed flow's mean), with `t` and the physical actuation `actuation_k` (units of U or U/D).
//!   A solver blow-up ends the episode with `terminated = true`, `info["diverged"] = 1` and the
//!   reason in `info.text["reason"]`.
//! - A spec with `thermal` also carries a temperature field (D2Q5, stepped after every flow step
//!   with the flow's velocity), observed as a fourth value per probe and cached with the flow;
//!   with `inflow` the west velocity oscillates (its phase continues from the spin-up, so the
//!   seed-dependent start also picks the phase of the oscillation).

use std::path::{Path, PathBuf};

use hgym_agents::{checked_action, BoxSpace, Env, EnvError, Info, StepResult};
use hgym_solvers::lbm::thermal::{Thermal, ThermalSide};
use hgym_solvers::lbm::{D2q9, Edge, LbmError, Side, Units};

use super::actuation::{apply, Jet};
use super::family::{merged, CalibrateError, FamilySpec, FlowEnv, Spec};
use super::seeding::splitmix64;
use super::spec::{ActuationSpec, EnvSpec, RewardSpec};
use super::EnvInputError;
use crate::flow::{FlowError, LbmFlow, Level};

pub struct LbmEnv {
    spec: EnvSpec,
    level: Level,
    units: Units,
    solver: D2q9,
    steps_per_action: u64,
    jets: Vec<Jet>,
    centers: Vec<[f64; 2]>,
    /// The wall links the actuator can move (`actuation::moving_links`).
    moving: Vec<usize>,
    a_old: Vec<f64>,
    actions_taken: usize,
    live: bool,
    clock: super::clock::SolverClock,
    attractor: Option<Vec<f32>>,
    cache_dir: Option<PathBuf>,
    t0: u64,
    /// The temperature field, with the velocity buffers it is stepped with.
    thermal: Option<Thermal>,
    fields: [Vec<f32>; 3],
    /// Seed of the inflow noise (0 during the spin-up, the episode's seed after a reset).
    noise_seed: u64,
}

fn backend(e: impl std::fmt::Display) -> EnvError {
    EnvError::Backend(e.to_string())
}

impl LbmEnv {
    /// Builds the solver for `spec` at `level` through the flow layer (`EnvSpec::flow_setup`,
    /// then `FlowSetup::check`, `plan` and `build`: the path validation runs); `cache_dir` keeps
    /// developed-flow states between processes (none: in memory only).
    pub fn new(mut spec: EnvSpec, level: Level, cache_dir: Option<PathBuf>) -> Result<Self, EnvError> {
        // Level-specific statistics where the committed table has them (the spec carries the
        // default level's).
        if let Some(n) = super::calibrate::level_normalization(&spec, level) {
            spec.normalization = n;
        }
        spec.reward = spec.reward.at_level(level);
        let setup = spec.flow_setup();
        let flow_error = |e: FlowError| match e {
            FlowError::Invalid { .. } => EnvError::InvalidSpec(format!("{}: {e}", spec.id)),
            FlowError::Solver(_) => EnvError::Backend(format!("{}: {e}", spec.id)),
        };
        setup.check().map_err(flow_error)?;
        let plan = setup.plan(level).map_err(flow_error)?;
        let units = plan.units;
        let (nx, ny) = (plan.nx, plan.ny);
        let solver = setup.build(&plan).and_then(LbmFlow::into_uniform).map_err(flow_error)?;
        let thermal = match &spec.thermal {
            None => None,
            Some(_) if solver.rank().1 > 1 => {
                return Err(EnvError::InvalidSpec(format!(
                    "{}: its temperature field runs on one process (it is not split over ranks); run it without mpirun",
                    spec.id
                )))
            }
            Some(th) => {
                let side = |s: &Side, edge: Edge| match (s, edge) {
                    (Side::Periodic, _) => ThermalSide::Periodic,
                    (Side::Outlet, _) => ThermalSide::ZeroGradient,
                    (_, Edge::West) => ThermalSide::Temperature(th.inlet_temperature as f32),
                    _ => ThermalSide::Temperature(th.wall_temperature as f32),
                };
                let s = &solver.config().sides;
                let sides = [
                    side(&s.west, Edge::West),
                    side(&s.east, Edge::East),
                    side(&s.south, Edge::South),
                    side(&s.north, Edge::North),
                ];
                let solid = (0..ny)
                    .flat_map(|y| (0..nx).map(move |x| (x, y)))
                    .map(|(x, y)| solver.is_solid(x, y))
                    .collect();
                let tau = 0.5 + 3.0 * units.nu() / th.prandtl;
                let mut t = Thermal::new(nx, ny, tau, sides, solid, th.wall_temperature).map_err(backend)?;
                t.init_with(|_, _| th.initial_temperature);
                Some(t)
            }
        };
        let fields = if thermal.is_some() {
            [vec![0.0; nx * ny], vec![0.0; nx * ny], vec![0.0; nx * ny]]
        } else {
            Default::default()
        };
        let steps_per_action = units.steps(spec.control_interval).max(1);
        if matches!(spec.actuation, ActuationSpec::InletTemperature { .. }) && thermal.is_none() {
            return Err(EnvError::InvalidSpec(format!(
                "{}: an inlet-temperature actuator needs a [thermal] section",
                spec.id
            )));
        }
        let (jets, centers) =
            super::actuation::resolve(&spec.actuation, &spec.bodies).map_err(|m| EnvError::InvalidSpec(format!("{}: {m}", spec.id)))?;
        let act_dim = spec.act_dim();
        let moving = super::actuation::moving_links(&solver, &spec.actuation, &jets, &centers, act_dim);
        Ok(LbmEnv {
            spec,
            level,
            units,
            solver,
            steps_per_action,
            jets,
            centers,
            moving,
            a_old: vec![0.0; act_dim],
            actions_taken: 0,
            live: false,
            clock: Default::default(),
            attractor: None,
            cache_dir,
            t0: 0,
            thermal,
            fields,
            noise_seed: 0,
        })
    }

    pub fn spec(&self) -> &EnvSpec {
        &self.spec
    }

    pub fn steps_per_action(&self) -> u64 {
        self.steps_per_action
    }

    pub fn solver(&self) -> &D2q9 {
        &self.solver
    }

    /// The temperature field, for specs with a `[thermal]` section.
    pub fn thermal(&self) -> Option<&Thermal> {
        self.thermal.as_ref()
    }

    /// Lattice <-> non-dimensional units at this env's level.
    pub fn units(&self) -> &Units {
        &self.units
    }

    /// Sets the wall velocities for physical actuation `a` (units of U or U/D).
    fn actuate(&mut self, a: &[f64]) {
        apply(
            &mut self.solver,
            &self.moving,
            &self.spec.actuation,
            &self.jets,
            &self.centers,
            a,
            &self.units,
        );
        if let (ActuationSpec::InletTemperature { .. }, Some(th)) = (&self.spec.actuation, &mut self.thermal) {
            // Finite and within the spec's range by construction (see `step`).
            let _ = th.set_side_temperature(Edge::West, a[0]);
        }
    }

    /// One lattice step of everything the spec has: the oscillatory inflow's scale, the flow,
    /// and the temperature carried by it. Without those, exactly `D2q9::step`.
    fn substep(&mut self) -> Result<(), LbmError> {
        if let Some(inflow) = &self.spec.inflow {
            let t = self.solver.time() as f64 * self.units.time_per_step();
            let scale = inflow.scale(self.spec.reynolds, t, self.spec.control_interval, self.noise_seed);
            self.solver.set_boundary_velocity_scale(scale);
        }
        self.solver.step()?;
        if let Some(th) = &mut self.thermal {
            let [rho, ux, uy] = &mut self.fields;
            self.solver.macroscopic(rho, ux, uy);
            th.step(ux, uy);
        }
        Ok(())
    }

    fn advance(&mut self, n: u64) -> Result<(), LbmError> {
        if self.thermal.is_none() && self.spec.inflow.is_none() {
            return self.solver.advance(n);
        }
        for _ in 0..n {
            self.substep()?;
        }
        Ok(())
    }

    /// Temperature (units of T_wall) at a physical point, bilinear.
    fn temperature_at(&self, p: [f64; 2]) -> Option<f64> {
        let th = self.thermal.as_ref()?;
        let g = self.solver.config().grid;
        let t_wall = self.spec.thermal.as_ref().map_or(1.0, |s| s.wall_temperature);
        Some(th.sample((p[0] - g.origin[0]) / g.dx, (p[1] - g.origin[1]) / g.dx) / t_wall)
    }

    /// The actuation with the actuators at rest: zero, or the starting inlet temperature.
    fn rest_actuation(&self) -> Vec<f64> {
        match (&self.spec.actuation, &self.spec.thermal) {
            (ActuationSpec::InletTemperature { .. }, Some(th)) => vec![th.inlet_temperature],
            _ => vec![0.0; self.spec.act_dim()],
        }
    }

    fn bound(&self) -> f64 {
        match &self.spec.actuation {
            ActuationSpec::ZnmfJets { max_velocity, .. }
            | ActuationSpec::ZnmfJetsPerBody { max_velocity, .. }
            | ActuationSpec::Jets { max_velocity, .. } => *max_velocity,
            ActuationSpec::Rotation { max_omega, .. } => *max_omega,
            ActuationSpec::InletTemperature { max_change, .. } => *max_change,
        }
    }

    /// The cache key covers only what shapes the developed (uncontrolled) flow: geometry, domain,
    /// boundaries, resolution, Re, lattice and collision settings, spin-up. Not the ID, the
    /// actuators (the attractor is reached with them at rest, so a jet and a rotary variant of one
    /// flow share it), probes, reward, timing, episode length, normalisation or gust: calibration,
    /// rollouts, training and every variant of a flow share one state per level.
    fn cache_file(&self) -> Option<PathBuf> {
        let mut physics = self.spec.clone();
        physics.id.clear();
        physics.family.clear();
        physics.description.clear();
        physics.actuation = ActuationSpec::Rotation {
            bodies: vec![],
            max_omega: 0.0,
        };
        physics.normalization = Default::default();
        physics.episode_actions = 0;
        physics.control_interval = 0.0;
        physics.probes.clear();
        physics.reward = RewardSpec::DragLift { lift_weight: 0.0 };
        physics.gust = None;
        physics.ramp = Default::default();
        let hash = physics.hash();
        self.cache_dir.as_ref().map(|d| match self.solver.rank() {
            (_, 1) => d.join(format!("flow-{}-{}.f32", self.level.name(), &hash[..16])),
            // Under MPI each rank keeps its own slab.
            (r, n) => d.join(format!("flow-{}-{}-rank{r}of{n}.f32", self.level.name(), &hash[..16])),
        })
    }

    /// Makes sure `self.attractor` holds the developed flow: from the disk cache, or by spinning
    /// up (`reset` then copies it into the solver from there, once).
    fn develop(&mut self) -> Result<(), EnvError> {
        if self.attractor.is_none() {
            let want = self.solver.population_count() + self.thermal.as_ref().map_or(0, |t| t.populations().len());
            let cached = self.cache_file().and_then(|p| super::spin_up::load_state(&p, want));
            // Under MPI the ranks spin up together unless every one of them has its slab cached.
            self.attractor = if self.solver.all_ranks(cached.is_some()) {
                cached
            } else {
                Some(self.spin_up()?)
            };
        }
        Ok(())
    }

    /// The developed flow by spinning up (stored in the disk cache).
    fn spin_up(&mut self) -> Result<Vec<f32>, EnvError> {
        // Spin up from the uniform flow with a transverse kick just behind the last body (fluid
        // that a body says starts at rest, at rest).
        let u = self.spec.lattice_velocity;
        let bodies = &self.spec.bodies;
        let centers: Vec<[f64; 2]> = self.spec.bodies.iter().map(|b| b.center()).collect();
        let x_back = centers.iter().map(|c| c[0]).fold(f64::NEG_INFINITY, f64::max);
        let y_mid = centers.iter().map(|c| c[1]).sum::<f64>() / centers.len().max(1) as f64;
        let c = if centers.is_empty() { [0.0, 0.0] } else { [x_back, y_mid] };
        self.solver.init_with(|x, y| {
            if bodies.iter().any(|b| b.starts_at_rest([x, y])) {
                return (1.0, 0.0, 0.0);
            }
            let r2 = (x - c[0] - 1.0).powi(2) + (y - c[1] - 0.25).powi(2);
            (1.0, u, 0.3 * u * (-4.0 * r2).exp())
        });
        let rest = self.rest_actuation();
        self.actuate(&rest);
        self.noise_seed = 0;
        let steps = self.units.steps(self.spec.spin_up);
        let id = self.spec.id.clone();
        super::spin_up::run_reported(&id, steps, |n| self.advance(n))
            .map_err(|e| EnvError::Backend(format!("{}: spin-up diverged: {e}", self.spec.id)))?;
        let mut state = self.solver.populations().to_vec();
        if let Some(th) = &self.thermal {
            state.extend_from_slice(th.populations());
        }
        if let Some(path) = self.cache_file() {
            super::spin_up::store_state(&path, &state);
        }
        Ok(state)
    }

    /// Mass (lattice units per step) that each actuator alone injects at `action` (in [-1, 1],
    /// a fraction of its bound), summed over the bodies: nonzero for a jet that reaches wall
    /// links, zero for a rotation or a zero-net-mass-flux pair. Leaves the actuators at rest.
    /// For tests and diagnostics.
    pub fn actuator_mass_sources(&mut self, action: f64) -> Vec<f64> {
        let dim = self.spec.act_dim();
        let bound = self.bound();
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

    /// Raw probe values (u, v, p per probe; units of U and rho U^2).
    pub fn raw_observation(&self) -> Result<Vec<f64>, EnvError> {
        let mut obs = Vec::with_capacity(self.spec.obs_dim());
        let values = self.solver.probes(&self.spec.probes).map_err(backend)?;
        for (p, [rho, ux, uy]) in self.spec.probes.iter().zip(values) {
            obs.push(self.units.velocity(ux));
            obs.push(self.units.velocity(uy));
            obs.push(self.units.pressure(rho));
            if let Some(t) = self.temperature_at(*p) {
                obs.push(t);
            }
        }
        Ok(obs)
    }

    fn observation(&self) -> Result<Vec<f64>, EnvError> {
        let mut obs = self.raw_observation()?;
        self.spec.normalization.apply(&mut obs);
        Ok(obs)
    }

    /// With a gust, sets the (west) inflow for episode time `t` to `(U, v_gust(t))`; without one,
    /// the inflow stays as built.
    fn set_gust(&mut self, t: f64) -> Result<(), EnvError> {
        let Some(g) = &self.spec.gust else {
            return Ok(());
        };
        let v = g.velocity(t);
        let u = self.spec.lattice_velocity;
        self.solver.set_side_velocity(Edge::West, [u, u * v]).map_err(backend)
    }

    fn time(&self) -> f64 {
        (self.solver.time() - self.t0) as f64 * self.units.time_per_step()
    }
}

impl Env for LbmEnv {
    /// Probe values, normalised by the calibrated statistics to about [-1, 1] for the
    /// uncontrolled flow, and unbounded: actuation drives probes far outside the uncontrolled
    /// range (JetPinball_2D_Re75 at coarse passes 5 scales under full blowing), so no finite
    /// bound would be a promise the env keeps.
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(self.spec.obs_dim(), f64::NEG_INFINITY, f64::INFINITY)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.spec.act_dim())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        self.develop()?;
        let state = self.attractor.as_deref().unwrap_or_default();
        let n_flow = self.solver.population_count();
        // An oscillating inflow continues its phase from the end of the spin-up.
        let time = if self.spec.inflow.is_some() {
            self.units.steps(self.spec.spin_up)
        } else {
            0
        };
        self.solver.set_populations(&state[..n_flow], time).map_err(backend)?;
        if let Some(th) = &mut self.thermal {
            th.set_populations(&state[n_flow..]).map_err(backend)?;
        }
        self.noise_seed = seed;
        self.a_old = self.rest_actuation();
        let rest = self.a_old.clone();
        self.actuate(&rest);
        self.set_gust(0.0)?;
        let offset = (splitmix64(seed) % 64) * (self.steps_per_action / 2).max(1);
        self.advance(offset).map_err(backend)?;
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
        let bound = self.bound();
        let a_new: Vec<f64> = match &self.spec.actuation {
            // The action is a change of the inlet temperature.
            ActuationSpec::InletTemperature { range, .. } => {
                vec![(self.a_old[0] + a[0] * bound).clamp(range[0], range[1])]
            }
            _ => a.iter().map(|v| v * bound).collect(),
        };
        let n_bodies = self.spec.bodies.len();
        let mut cd = vec![0.0; n_bodies];
        let mut cl = vec![0.0; n_bodies];
        let n = self.steps_per_action;
        let scale = 0.5 * self.units.u_lattice * self.units.u_lattice * self.units.cells_per_length;
        let mut diverged = None;
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
            if let Err(e) = stepped {
                diverged = Some(e.to_string());
                break;
            }
            for (b, f) in self.solver.body_forces().iter().enumerate() {
                cd[b] += f[0] / scale / n as f64;
                cl[b] += f[1] / scale / n as f64;
            }
        }
        self.a_old = a_new.clone();
        self.actions_taken += 1;
        let mut info = Info::default();
        info.set("t", self.time());
        info.set("clipped", clipped as f64);
        for (k, v) in a_new.iter().enumerate() {
            info.set(&format!("actuation_{k}"), *v);
        }
        for b in 0..n_bodies {
            info.set(&format!("C_D_{b}"), cd[b]);
            info.set(&format!("C_L_{b}"), cl[b]);
        }
        let forces = IntervalForces { c_d: cd, c_l: cl };
        let (c_d, c_l) = forces.totals();
        info.set("C_D", c_d);
        info.set("C_L", c_l);
        if let Some(d) = self.spec.reward.lift_deviation(c_l) {
            info.set("dC_L", d);
        }
        let probe_temperature = match &self.spec.reward {
            RewardSpec::ProbeTemperature { probe, .. } => {
                let t = self.spec.probes.get(*probe).and_then(|p| self.temperature_at(*p));
                info.set("T_target", t.unwrap_or(f64::NAN));
                t
            }
            _ => None,
        };
        if let Some(reason) = diverged {
            self.live = false;
            info.set("diverged", 1.0);
            info.set_text("reason", reason);
            let obs = vec![0.0; self.spec.obs_dim()];
            return Ok(StepResult {
                obs,
                reward: 0.0,
                terminated: true,
                truncated: false,
                info,
            });
        }
        let obs = self.observation()?;
        let reward = reward(&self.spec.reward, &forces, &obs, probe_temperature);
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
}

/// Interval-averaged force coefficients of each body, `C = F / (rho U^2 L / 2)` (what `info`
/// reports as `C_D_b`, `C_L_b` and their sums `C_D`, `C_L`).
#[derive(Clone, Debug, PartialEq)]
pub struct IntervalForces {
    pub c_d: Vec<f64>,
    pub c_l: Vec<f64>,
}

impl IntervalForces {
    /// Total drag and lift over the bodies.
    pub fn totals(&self) -> (f64, f64) {
        (self.c_d.iter().sum(), self.c_l.iter().sum())
    }
}

/// The reward of one interval from its forces, the (normalised) observation `obs` at its end,
/// and the temperature at the reward's probe (`ProbeTemperature` only, units of T_wall).
pub fn reward(spec: &RewardSpec, forces: &IntervalForces, obs: &[f64], probe_temperature: Option<f64>) -> f64 {
    let (c_d, c_l) = forces.totals();
    match spec {
        RewardSpec::DragLift { lift_weight } => {
            let mut r = 0.0;
            for (d, l) in forces.c_d.iter().zip(&forces.c_l) {
                r -= d.abs();
                r -= lift_weight * l.abs();
            }
            r
        }
        RewardSpec::TotalDragLift { lift_weight } => -c_d.abs() - lift_weight * c_l.abs(),
        RewardSpec::ProbeDeviation => -9.0 * obs.iter().map(|o| o * o).sum::<f64>(),
        RewardSpec::ProbeTemperature { target, weight, .. } => -weight * (probe_temperature.unwrap_or(f64::NAN) - target).abs(),
        RewardSpec::GustLoads {
            c_l_ref,
            c_d_ref,
            drag_weight,
            ..
        } => -(c_l - c_l_ref).abs() - drag_weight * (c_d - c_d_ref).abs(),
    }
}

impl hgym_agents::DifferentiableEnv for LbmEnv {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend(format!(
            "{} is not differentiable (only the spectral Kolmogorov flows are); use ppo, ddpg or td3",
            self.spec.id
        )))
    }
}

/// The 2D lattice-Boltzmann families (cylinder, pinball, square, cavity, NACA 0012, pipe) share
/// this spec type and [`LbmEnv`].
impl FamilySpec for EnvSpec {
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
        if self.thermal.is_some() {
            "lbm-d2q9+q5"
        } else {
            "lbm-d2q9"
        }
    }

    fn obs_dim(&self) -> usize {
        EnvSpec::obs_dim(self)
    }

    fn act_dim(&self) -> usize {
        EnvSpec::act_dim(self)
    }

    fn control_interval(&self) -> f64 {
        self.control_interval
    }

    fn layout(&self) -> super::layout::Layout {
        super::layout::Layout::of(self)
    }

    fn calibrated(&self) -> bool {
        !self.normalization.mean.is_empty()
    }

    fn hash(&self) -> String {
        EnvSpec::hash(self)
    }

    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }

    fn to_toml(&self) -> String {
        EnvSpec::to_toml(self)
    }

    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError> {
        merged(self, over, &self.id, EnvSpec::check)
    }

    fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError> {
        Ok(Box::new(LbmEnv::new(self.clone(), level, cache)?))
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
            super::calibrate::calibrate(self, level, actions, cache, &mut |k, _| progress(k))
        })
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

impl super::clock::SolverTime for LbmEnv {
    fn solver_seconds(&self) -> f64 {
        self.clock.seconds()
    }
}
