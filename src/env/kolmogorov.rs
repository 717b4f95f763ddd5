//! Kolmogorov flow (`Kolmogorov_2D_Re{40,100,200}`): 2D turbulence on `(0, 2 pi)^2` driven by
//! `sin(k_f y) e_x` with `k_f = 4` (the paper's differentiable environment; Farazmand & Sapsis
//! 2017 for the bursting regime at Re 40), on the pseudo-spectral solver of
//! `hgym_solvers::spectral` and its discrete adjoint.
//!
//! - Actions: four amplitudes `a_i` of extra forcing `a_i sin(k_i y) e_x`, `k_i = 4, 5, 6, 7`;
//!   normalised actions in [-1, 1] map to `a_i = action * max_amplitude` (bound in units of the
//!   base forcing amplitude). Constant over a control interval (no ramp: the forcing enters the
//!   vorticity equation directly, there is no actuator to accelerate).
//! - Observations: `(u, v)` at an 8 x 8 grid of points `(2 pi i / 8, 2 pi j / 8)` (grid nodes at
//!   every level), divided by `3 u_rms` of the uncontrolled flow.
//! - Rewards, averaged over the solver steps of the interval (`eps` the dissipation rate
//!   `nu <omega^2>`, `eps_lam = Re / (2 k_f^2)` the laminar one):
//!   `dissipation`: `r = -mean(eps + w max(0, eps - theta)) / eps_lam - c |a|^2` with
//!   `theta = mean + 3 std` of the uncontrolled dissipation (the paper's extreme events);
//!   `mixing`: `r = mean(TKE) / TKE_ref - c |a|^2` with TKE the kinetic energy of the fluctuation
//!   about the x-averaged profile and `TKE_ref` its uncontrolled mean. HydroGym's JAX env ships
//!   with a zero TKE weight, so its default reward ignores the flow; here the flow term always
//!   counts. `|a|^2` is the sum of squared normalised actions.
//! - Differentiable: [`DifferentiableEnv::reward_action_gradients`] sweeps back over the stored
//!   states with the solver's step VJP.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use hgym_agents::{checked_action, BoxSpace, DifferentiableEnv, Env, EnvError, Info, StepResult};
use hgym_solvers::spectral::{Complex64 as C, Kolmogorov, KolmogorovConfig};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::family::{merged, CalibrateError, Family, FamilySpec, FlowEnv, Spec};
use super::seeding::splitmix64;
use super::{info_value, EnvInputError};
use crate::flow::{Level, ResolutionSpec};

pub const REYNOLDS: [u32; 3] = [40, 100, 200];

/// What the reward asks for.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Objective {
    /// Penalise the dissipation rate, and by `extreme_weight` its excess over mean + 3 std.
    Dissipation { extreme_weight: f64 },
    /// Reward turbulent kinetic energy (mixing).
    Mixing,
}

/// Statistics of the uncontrolled flow (`hgym envs calibrate ID`), at the default level.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct FlowStatistics {
    pub spec_hash: String,
    pub level: String,
    pub time: f64,
    pub u_rms: f64,
    pub dissipation_mean: f64,
    pub dissipation_std: f64,
    pub tke_mean: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KolmogorovSpec {
    pub id: String,
    pub family: String,
    pub description: String,
    pub reynolds: f64,
    pub kf: u32,
    /// Grid points per side at each level.
    pub resolution: ResolutionSpec,
    /// Solver time step on the 64-point grid; other grids scale it by 64 / n (same CFL).
    pub dt_at_64: f64,
    pub control_wavenumbers: Vec<u32>,
    /// Bound of each control amplitude, in units of the base forcing amplitude.
    pub max_amplitude: f64,
    /// Time between actions (units of 1 / (k_1 U) with the forcing's natural scales: L = 1, A = 1).
    pub control_interval: f64,
    pub episode_actions: usize,
    /// Uncontrolled time from the perturbed laminar state to the attractor.
    pub spin_up: f64,
    /// Probes per side (the observation grid).
    pub probes_per_side: usize,
    pub objective: Objective,
    /// Weight `c` of the action penalty `c |a|^2`.
    pub action_penalty: f64,
    #[serde(default)]
    pub statistics: FlowStatistics,
}

impl KolmogorovSpec {
    /// The checks [`KolmogorovEnv::new`] would otherwise meet late: positive finite Re, step and
    /// amplitude; control wavenumbers 1 to 7; probes that sit on every level's grid; the episode.
    pub(crate) fn check(&self) -> Result<(), String> {
        super::family::check_episode(self.control_interval, self.episode_actions, self.spin_up)?;
        for (key, v) in [
            ("reynolds", self.reynolds),
            ("dt_at_64", self.dt_at_64),
            ("max_amplitude", self.max_amplitude),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key} must be a positive number, got {v}"));
            }
        }
        if !(self.action_penalty.is_finite() && self.action_penalty >= 0.0) {
            return Err(format!("action_penalty must be zero or positive, got {}", self.action_penalty));
        }
        if self.control_wavenumbers.is_empty() || self.control_wavenumbers.iter().any(|k| !(1..=7).contains(k)) {
            return Err(format!(
                "control_wavenumbers must list wavenumbers 1 to 7, got {:?}",
                self.control_wavenumbers
            ));
        }
        for level in Level::ALL {
            let n = self.n(level);
            if self.probes_per_side == 0 || !n.is_multiple_of(self.probes_per_side) {
                return Err(format!(
                    "probes_per_side = {} does not divide the {n}-point grid of the {level:?} level",
                    self.probes_per_side
                ));
            }
        }
        Ok(())
    }

    pub fn hash(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        format!("{:x}", Sha256::digest(json.as_bytes()))
    }

    /// Hash of what shapes the uncontrolled flow (for the statistics and the attractor cache).
    pub fn physics_hash(&self) -> String {
        let physics = (self.reynolds, self.kf, &self.resolution, self.dt_at_64, self.spin_up);
        format!(
            "{:x}",
            Sha256::digest(serde_json::to_string(&physics).unwrap_or_default().as_bytes())
        )
    }

    pub fn obs_dim(&self) -> usize {
        2 * self.probes_per_side * self.probes_per_side
    }

    pub fn act_dim(&self) -> usize {
        self.control_wavenumbers.len()
    }

    pub fn n(&self, level: Level) -> usize {
        (match level {
            Level::Coarse => self.resolution.coarse,
            Level::Default => self.resolution.default,
            Level::Fine => self.resolution.fine,
        }) as usize
    }

    pub fn dt(&self, level: Level) -> f64 {
        self.dt_at_64 * 64.0 / self.n(level) as f64
    }

    /// Laminar dissipation rate `Re / (2 k_f^2)`.
    pub fn dissipation_laminar(&self) -> f64 {
        self.reynolds / (2.0 * (self.kf as f64).powi(2))
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the spec as TOML: {e}\n"))
    }
}

/// The committed statistics table.
pub const TABLE: &str = include_str!("../../benchmarks/envs/kolmogorov.toml");

/// Where [`TABLE`] lives, from the repository root.
pub const TABLE_PATH: &str = "benchmarks/envs/kolmogorov.toml";

/// The Kolmogorov flows over [`REYNOLDS`].
pub struct KolmogorovFlows;

impl Family for KolmogorovFlows {
    fn specs(&self) -> Vec<Spec> {
        all().into_iter().map(Spec::new).collect()
    }
}

impl FamilySpec for KolmogorovSpec {
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
        "spectral"
    }

    fn obs_dim(&self) -> usize {
        KolmogorovSpec::obs_dim(self)
    }

    fn act_dim(&self) -> usize {
        KolmogorovSpec::act_dim(self)
    }

    fn control_interval(&self) -> f64 {
        self.control_interval
    }

    fn differentiable(&self) -> bool {
        true
    }

    fn calibrated(&self) -> bool {
        self.statistics.u_rms > 0.0
    }

    fn hash(&self) -> String {
        KolmogorovSpec::hash(self)
    }

    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }

    fn to_toml(&self) -> String {
        KolmogorovSpec::to_toml(self)
    }

    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError> {
        merged(self, over, &self.id, KolmogorovSpec::check)
    }

    fn make(&self, level: Level, _cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError> {
        Ok(Box::new(KolmogorovEnv::new(self.clone(), level)?))
    }

    /// Records the flow statistics under the ID (the table holds one level per ID).
    fn calibrate(
        &self,
        level: Level,
        actions: usize,
        _cache: Option<PathBuf>,
        table: Option<&Path>,
        progress: &mut dyn FnMut(usize),
    ) -> Result<(String, PathBuf), CalibrateError> {
        let table = super::family::calibration_table::<FlowStatistics>(actions, table, TABLE_PATH)?;
        let st = calibrate(self, level, actions, progress)?;
        let summary = format!(
            "{}: u_rms {:.4}, dissipation {:.4} +- {:.4} (laminar {:.4}), TKE {:.4} over {} time units",
            self.id,
            st.u_rms,
            st.dissipation_mean,
            st.dissipation_std,
            self.dissipation_laminar(),
            st.tke_mean,
            st.time
        );
        crate::report::table::record(&table, &[(self.id.clone(), st)])?;
        Ok((summary, table))
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

pub fn spec(re: u32) -> KolmogorovSpec {
    let mut s = KolmogorovSpec {
        id: format!("Kolmogorov_2D_Re{re}"),
        family: "kolmogorov".into(),
        description: format!("2D Kolmogorov flow at Re {re}, k_f = 4, forcing amplitudes at k = 4..7"),
        reynolds: re as f64,
        kf: 4,
        resolution: ResolutionSpec {
            coarse: 32,
            default: 64,
            fine: 128,
        },
        // Advective CFL (|u| + |v|) k_max dt stays below ~1 on the attractor.
        dt_at_64: match re {
            40 => 0.02,
            100 => 0.01,
            _ => 0.005,
        },
        control_wavenumbers: vec![4, 5, 6, 7],
        max_amplitude: 0.5,
        control_interval: 1.0,
        episode_actions: 100,
        spin_up: 300.0,
        probes_per_side: 8,
        objective: Objective::Dissipation { extreme_weight: 10.0 },
        action_penalty: 0.1,
        statistics: FlowStatistics::default(),
    };
    let hash = s.physics_hash();
    if let Some(st) = crate::report::table::committed(TABLE, &s.id, &hash, |st: &FlowStatistics| &st.spec_hash) {
        s.statistics = st;
    }
    s
}

pub fn all() -> Vec<KolmogorovSpec> {
    REYNOLDS.iter().map(|re| spec(*re)).collect()
}

/// Attractor states shared by every env of the process, keyed by physics hash and level.
fn attractors() -> &'static Mutex<HashMap<String, Vec<C>>> {
    static CACHE: OnceLock<Mutex<HashMap<String, Vec<C>>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

fn backend(e: impl std::fmt::Display) -> EnvError {
    EnvError::Backend(e.to_string())
}

/// One control interval of the stored trajectory.
#[derive(Default)]
struct Record {
    start: Vec<C>,
    physical: Vec<f64>,
    normalised: Vec<f64>,
}

pub struct KolmogorovEnv {
    spec: KolmogorovSpec,
    level: Level,
    solver: Kolmogorov,
    substeps: usize,
    history: Vec<Record>,
    /// Records of earlier episodes, whose buffers the next steps fill again (a step allocates no
    /// state-sized vector once an episode as long has run).
    spare: Vec<Record>,
    live: bool,
    clock: super::clock::SolverClock,
    theta: f64,
    tke_ref: f64,
    obs_scale: f64,
    /// The velocity fields the probes read, reused every step.
    u: Vec<f64>,
    v: Vec<f64>,
}

impl KolmogorovEnv {
    pub fn new(spec: KolmogorovSpec, level: Level) -> Result<Self, EnvError> {
        let n = spec.n(level);
        let cfg = KolmogorovConfig {
            n,
            reynolds: spec.reynolds,
            kf: spec.kf,
            forcing: 1.0,
            dt: spec.dt(level),
            control_wavenumbers: spec.control_wavenumbers.clone(),
        };
        spec.check().map_err(|m| EnvError::Backend(format!("{}: {m}", spec.id)))?;
        let solver = Kolmogorov::new(cfg).map_err(backend)?;
        let substeps = (spec.control_interval / spec.dt(level)).round().max(1.0) as usize;
        let st = &spec.statistics;
        let calibrated = st.u_rms > 0.0;
        Ok(KolmogorovEnv {
            theta: if calibrated {
                st.dissipation_mean + 3.0 * st.dissipation_std
            } else {
                f64::INFINITY
            },
            tke_ref: if calibrated { st.tke_mean } else { 1.0 },
            obs_scale: if calibrated { 3.0 * st.u_rms } else { 1.0 },
            spec,
            level,
            solver,
            substeps,
            history: vec![],
            spare: vec![],
            live: false,
            clock: Default::default(),
            u: vec![0.0; n * n],
            v: vec![0.0; n * n],
        })
    }

    pub fn spec(&self) -> &KolmogorovSpec {
        &self.spec
    }

    pub fn solver(&mut self) -> &mut Kolmogorov {
        &mut self.solver
    }

    pub fn substeps(&self) -> usize {
        self.substeps
    }

    /// The developed flow: from the process cache, or spun up from the laminar state with a
    /// fixed large-scale perturbation.
    fn attractor(&mut self) -> Result<Vec<C>, EnvError> {
        let key = format!("{}-{}", self.spec.physics_hash(), self.level.name());
        if let Some(w) = attractors().lock().ok().and_then(|m| m.get(&key).cloned()) {
            return Ok(w);
        }
        let n = self.solver.n();
        let h = 2.0 * std::f64::consts::PI / n as f64;
        let lam = self.solver.laminar();
        let kick: Vec<f64> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 * h, (i / n) as f64 * h);
                0.5 * (x.cos() + (x + 2.0 * y).sin() + 0.5 * (3.0 * x - y).cos())
            })
            .collect();
        self.solver.set_vorticity(&kick);
        let w: Vec<C> = self.solver.omega.iter().zip(&lam).map(|(a, b)| *a + *b).collect();
        self.solver.omega = w;
        let steps = (self.spec.spin_up / self.spec.dt(self.level)).round() as u64;
        let zero = vec![0.0; self.spec.act_dim()];
        let id = self.spec.id.clone();
        super::spin_up::run_reported(&id, steps, |n| (0..n).try_for_each(|_| self.solver.step(&zero)))
            .map_err(|e| EnvError::Backend(format!("{}: spin-up failed: {e}", self.spec.id)))?;
        let w = self.solver.omega.clone();
        if let Ok(mut m) = attractors().lock() {
            m.insert(key, w.clone());
        }
        Ok(w)
    }

    fn observation(&mut self) -> Vec<f64> {
        self.solver.velocity_into(&mut self.u, &mut self.v);
        let (u, v, n) = (&self.u, &self.v, self.solver.n());
        let p = self.spec.probes_per_side;
        let stride = n / p;
        let mut obs = Vec::with_capacity(2 * p * p);
        for j in 0..p {
            for i in 0..p {
                let k = (j * stride) * n + i * stride;
                obs.push(u[k] / self.obs_scale);
                obs.push(v[k] / self.obs_scale);
            }
        }
        obs
    }

    /// The per-substep flow term of the reward from that substep's dissipation rate and TKE
    /// (before the 1/M average).
    fn flow_term(&self, dissipation: f64, tke: f64) -> f64 {
        match self.spec.objective {
            Objective::Dissipation { extreme_weight } => {
                -(dissipation + extreme_weight * (dissipation - self.theta).max(0.0)) / self.spec.dissipation_laminar()
            }
            Objective::Mixing => tke / self.tke_ref,
        }
    }

    /// Adds `scale * d(flow_term)/dw` at state `w` to `out`.
    fn add_flow_gradient(&self, w: &[C], scale: f64, out: &mut [C]) {
        match self.spec.objective {
            Objective::Dissipation { extreme_weight } => {
                let e = self.solver.dissipation_of(w);
                let slope = 1.0 + if e > self.theta { extreme_weight } else { 0.0 };
                self.solver
                    .add_dissipation_gradient(w, -scale * slope / self.spec.dissipation_laminar(), out);
            }
            Objective::Mixing => self.solver.add_tke_gradient(w, scale / self.tke_ref, out),
        }
    }

    /// Recomputes the reward from a step's info (the contract's consistency check); an error
    /// names a missing key.
    pub fn reward_from_info(&self, info: &Info) -> Result<f64, EnvError> {
        let flow = match self.spec.objective {
            Objective::Dissipation { extreme_weight } => {
                -(info_value(info, "dissipation")? + extreme_weight * info_value(info, "dissipation_excess")?)
                    / self.spec.dissipation_laminar()
            }
            Objective::Mixing => info_value(info, "tke")? / self.tke_ref,
        };
        Ok(flow - self.spec.action_penalty * info_value(info, "action_sq")?)
    }
}

impl Env for KolmogorovEnv {
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(self.spec.obs_dim(), -5.0, 5.0)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.spec.act_dim())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        self.solver.omega = self.attractor()?;
        let zero = vec![0.0; self.spec.act_dim()];
        // A seed-dependent start on the attractor: 0-63 half control intervals further on.
        let offset = (splitmix64(seed) % 64) as usize * (self.substeps / 2).max(1);
        for _ in 0..offset {
            self.solver.step(&zero).map_err(backend)?;
        }
        self.spare.append(&mut self.history);
        self.live = true;
        let mut info = Info::default();
        info.set("t", 0.0);
        info.set("phase_steps", offset as f64);
        info.set("dissipation", self.solver.dissipation());
        info.set("tke", self.solver.tke());
        Ok((self.observation(), info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let mut record = self.spare.pop().unwrap_or_default();
        record.start.clear();
        record.start.extend_from_slice(&self.solver.omega);
        record.physical.clear();
        record.physical.extend(a.iter().map(|v| v * self.spec.max_amplitude));
        record.normalised.clear();
        record.normalised.extend_from_slice(&a);
        self.history.push(record);
        let physical = &self.history[self.history.len() - 1].physical;
        let m = self.substeps;
        let (mut eps, mut excess, mut tke, mut flow) = (0.0, 0.0, 0.0, 0.0);
        let mut failure = None;
        for _ in 0..m {
            let t = std::time::Instant::now();
            let stepped = self.solver.step(physical);
            self.clock.stop(t);
            if let Err(e) = stepped {
                failure = Some(e.to_string());
                break;
            }
            let (e, k) = (self.solver.dissipation(), self.solver.tke());
            eps += e / m as f64;
            excess += (e - self.theta).max(0.0) / m as f64;
            tke += k / m as f64;
            flow += self.flow_term(e, k) / m as f64;
        }
        let t = self.history.len() as f64 * self.spec.control_interval;
        let mut info = Info::default();
        info.set("t", t);
        info.set("clipped", clipped as f64);
        for (k, v) in physical.iter().enumerate() {
            info.set(&format!("actuation_{k}"), *v);
        }
        let action_sq: f64 = a.iter().map(|v| v * v).sum();
        info.set("action_sq", action_sq);
        info.set("dissipation", eps);
        info.set("dissipation_excess", excess);
        info.set("D_over_Dlam", eps / self.spec.dissipation_laminar());
        info.set("tke", tke);
        if let Some(reason) = failure {
            self.live = false;
            info.set("diverged", 1.0);
            info.set_text("reason", reason);
            return Ok(StepResult {
                obs: vec![0.0; self.spec.obs_dim()],
                reward: 0.0,
                terminated: true,
                truncated: false,
                info,
            });
        }
        let reward = flow - self.spec.action_penalty * action_sq;
        let truncated = self.history.len() >= self.spec.episode_actions;
        if truncated {
            self.live = false;
        }
        Ok(StepResult {
            obs: self.observation(),
            reward,
            terminated: false,
            truncated,
            info,
        })
    }
}

impl DifferentiableEnv for KolmogorovEnv {
    fn reward_action_gradients(&mut self, k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        let total = self.history.len();
        let k = k.min(total);
        let len = self.solver.spectral_len();
        let m = self.substeps;
        let mut lambda = vec![C::default(); len];
        let mut lambda_prev = vec![C::default(); len];
        let mut out = vec![vec![0.0; self.spec.act_dim()]; k];
        let mut states: Vec<Vec<C>> = vec![vec![C::default(); len]; m + 1];
        for j in (total - k..total).rev() {
            let rec = &self.history[j];
            let (start, physical, normalised) = (rec.start.clone(), rec.physical.clone(), rec.normalised.clone());
            // Replay the interval, keeping every substep state (checkpointing at actions).
            states[0].copy_from_slice(&start);
            for s in 0..m {
                let (done, rest) = states.split_at_mut(s + 1);
                self.solver.step_from(&done[s], &physical, &mut rest[0]).map_err(backend)?;
            }
            let mut bar_a = vec![0.0; self.spec.act_dim()];
            for s in (1..=m).rev() {
                self.add_flow_gradient(&states[s], 1.0 / m as f64, &mut lambda);
                self.solver
                    .step_vjp(&states[s - 1], &physical, &lambda, &mut lambda_prev, &mut bar_a)
                    .map_err(backend)?;
                std::mem::swap(&mut lambda, &mut lambda_prev);
            }
            let g = &mut out[j - (total - k)];
            for ((g, ba), an) in g.iter_mut().zip(&bar_a).zip(&normalised) {
                *g = ba * self.spec.max_amplitude - 2.0 * self.spec.action_penalty * an;
            }
        }
        Ok(out)
    }
}

/// Runs `actions` uncontrolled intervals from `reset(0)` and returns the flow's statistics:
/// RMS probe velocity, mean and standard deviation of the interval-mean dissipation, mean TKE.
pub fn calibrate(spec: &KolmogorovSpec, level: Level, actions: usize, progress: &mut dyn FnMut(usize)) -> Result<FlowStatistics, EnvError> {
    let mut raw = spec.clone();
    raw.statistics = FlowStatistics::default();
    raw.episode_actions = actions.max(1);
    let mut env = KolmogorovEnv::new(raw, level)?;
    env.reset(0)?;
    let zero = vec![0.0; spec.act_dim()];
    let (mut u2, mut count, mut eps, mut tke) = (0.0, 0usize, vec![], 0.0);
    for k in 0..actions.max(1) {
        let r = super::family::uncontrolled_step(&mut env, &spec.id, &zero)?;
        u2 += r.obs.iter().map(|v| v * v).sum::<f64>();
        count += r.obs.len();
        eps.push(info_value(&r.info, "dissipation")?);
        tke += info_value(&r.info, "tke")?;
        progress(k + 1);
    }
    let n = eps.len() as f64;
    let mean = eps.iter().sum::<f64>() / n;
    let std = (eps.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
    Ok(FlowStatistics {
        spec_hash: spec.physics_hash(),
        level: level.name().into(),
        time: n * spec.control_interval,
        u_rms: (u2 / count.max(1) as f64).sqrt(),
        dissipation_mean: mean,
        dissipation_std: std,
        tke_mean: tke / n,
    })
}

impl super::clock::SolverTime for KolmogorovEnv {
    fn solver_seconds(&self) -> f64 {
        self.clock.seconds()
    }
}
