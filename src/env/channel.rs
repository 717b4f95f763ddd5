//! Turbulent channel flows (`TCF_3D_Retau180`, `TCFMini_3D_Retau180`, `TCFOpen_3D_Retau206`) on the
//! channel DNS of `hgym_solvers::channel`, after the paper's Nek5000 channel ("Turbulent channel
//! flow" appendix) and Guastoni et al. (2023). Outer units: half-height (open channel: height) h,
//! bulk velocity U_b, time h/U_b; the flow rate is held constant.
//!
//! - Actions: zero-net-mass-flux wall-normal blowing (+) and suction (-) per actuator patch (a
//!   block of wall cells), each wall its own set; normalised actions in [-1, 1] times the friction
//!   velocity `u_tau`; the mean over each wall is removed after clipping. Held over a control
//!   interval `dt+ = 0.6` (`t* = nu / u_tau^2`).
//! - Observations per actuator: `u'` and `v'` at `y+ = 15` above it (the sensing plane's cell row
//!   nearest to it; homogeneous-plane means removed; averaged over the patch), in units of `u_tau`,
//!   with `v'` positive away from its wall. Bottom-wall actuators first, then the top wall's, each
//!   in x-fastest order; `[u'_0, v'_0, u'_1, v'_1, ...]`.
//! - Reward: `1 - tau_w / tau_w,ref` with `tau_w` the mean wall shear stress of the actuated
//!   walls over the interval and `tau_w,ref` the uncontrolled one (calibrated). `info` carries
//!   `C_f = 2 tau_w` also as `C_D`, the drag coefficient `hgym eval` compares.
//! - Agents (multi-agent training, `hgym_agents::multi`): one per patch, seeing the patches
//!   around its own, rewarded by the global reward ([`ChannelAgents`]).
//! - `u_tau` is the nominal `Re_tau nu / h` until the ID is calibrated (`hgym envs calibrate`),
//!   then the measured uncontrolled one.
//!
//! Relaminarisation is reported in `info` (`relaminarised` = 1 when `u'_rms+` at the sensing plane
//! falls below 0.5, a fifth of its turbulent value), not hidden.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use hgym_agents::multi::{AgentReward, Agents};
use hgym_agents::{checked_action, BoxSpace, DifferentiableEnv, Env, EnvError, Info, StepResult};
use hgym_solvers::channel::{viscous_dt_limit, Channel, ChannelConfig, ChannelState as State, Drive, Grid, Top};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::family::{merged, CalibrateError, Family, FamilySpec, FlowEnv, Spec};
use super::seeding::splitmix64;
use super::EnvInputError;
use crate::data::field::Snapshot;
use crate::flow::level::PerLevel;
use crate::flow::Level;

/// Statistics of the uncontrolled flow (`hgym envs calibrate ID`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ChannelStatistics {
    pub spec_hash: String,
    pub level: String,
    pub time: f64,
    /// Mean wall shear stress of the actuated walls (`u_tau^2`, outer units).
    pub tau_w: f64,
    /// `u'_rms+` and `v'_rms+` at the sensing plane (nominal viscous units).
    pub u_rms_plus: f64,
    pub v_rms_plus: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ChannelSpec {
    pub id: String,
    pub family: String,
    pub description: String,
    /// Nominal friction Reynolds number (sets the viscous scales until calibrated).
    pub re_tau: f64,
    /// `U_b h / nu`, held by the flow rate.
    pub reynolds_bulk: f64,
    /// Box `[lx, ly, lz]` in h.
    pub length: [f64; 3],
    pub top: Top,
    /// tanh stretching of the wall-normal grid.
    pub stretch: f64,
    /// Cells `[nx, ny, nz]` at each level.
    pub grid: PerLevel<[usize; 3]>,
    /// Actuator patches per wall `[in x, in z]`; each must divide the cells of every level.
    pub patches: [usize; 2],
    pub sensing_y_plus: f64,
    /// Time between actions in viscous units.
    pub control_interval_plus: f64,
    pub episode_actions: usize,
    /// Uncontrolled time (h/U_b) from the disturbed laminar flow to developed turbulence.
    pub spin_up: f64,
    /// The agents of multi-agent training: one per patch.
    #[serde(default)]
    pub agents: ChannelAgents,
    #[serde(default)]
    pub statistics: ChannelStatistics,
}

/// One agent per actuator patch (`hgym train` trains one policy they share, `hgym_agents::multi`).
/// An agent sees `u'` and `v'` above the `(2 window + 1)^2` patches centred on its own, on its
/// own wall (periodic in x and z), rows in z, x fastest, and learns from the global reward (the
/// paper's: the wall shear stress is a global invariant of the developed channel) or its own
/// `1 - tau_w,patch / tau_w,ref` (the patches tile the wall without overlap). The local reward
/// pays each agent for blowing, which lowers the shear under its own patch while the
/// zero-net-mass-flux suction that balances it raises the shear under the others: every agent
/// learns to blow, and the mean removal leaves no actuation at all.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ChannelAgents {
    pub window: usize,
    pub reward: AgentReward,
}

impl Default for ChannelAgents {
    fn default() -> Self {
        ChannelAgents {
            window: 1,
            reward: AgentReward::Global,
        }
    }
}

impl ChannelSpec {
    /// The checks a spec must pass before it builds an environment; the message names the field.
    pub fn check(&self) -> Result<(), String> {
        super::family::check_episode(self.control_interval(), self.episode_actions, self.spin_up)?;
        for (key, v) in [
            ("re_tau", self.re_tau),
            ("reynolds_bulk", self.reynolds_bulk),
            ("sensing_y_plus", self.sensing_y_plus),
            ("control_interval_plus", self.control_interval_plus),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key} must be a positive number, got {v}"));
            }
        }
        for level in Level::ALL {
            let n = self.n(level);
            if self.patches[0] == 0
                || self.patches[1] == 0
                || !n[0].is_multiple_of(self.patches[0])
                || !n[2].is_multiple_of(self.patches[1])
            {
                return Err(format!(
                    "patches = {:?} must divide the {}x{} wall cells of the {} level",
                    self.patches,
                    n[0],
                    n[2],
                    level.name()
                ));
            }
            let g = self.grid_of(level)?;
            let first = g.yc[0] * self.re_tau;
            if first > 1.0 {
                return Err(format!(
                    "the {} grid puts its first cell centre at y+ = {first:.2}; a wall-resolved flow needs y+ <= 1 \
                     (more cells in y or a larger `stretch`)",
                    level.name()
                ));
            }
            let side = 2 * self.agents.window + 1;
            if side > self.patches[0] || side > self.patches[1] {
                return Err(format!(
                    "agents.window = {} sees {side}x{side} patches, more than the {:?} patches of a wall: \
                     take a smaller window",
                    self.agents.window, self.patches
                ));
            }
            if self.sensing_y_plus / self.re_tau >= g.ly * 0.5 {
                return Err(format!("sensing_y_plus = {} lies beyond the channel's centre", self.sensing_y_plus));
            }
        }
        Ok(())
    }

    pub fn n(&self, level: Level) -> [usize; 3] {
        *self.grid.at(level)
    }

    fn grid_of(&self, level: Level) -> Result<Grid, String> {
        Grid::new(self.n(level), self.length, self.stretch, self.top).map_err(|e| e.to_string())
    }

    pub fn nu(&self) -> f64 {
        1.0 / self.reynolds_bulk
    }

    /// Nominal friction velocity `Re_tau nu / h` (h = 1).
    pub fn u_tau_nominal(&self) -> f64 {
        self.re_tau * self.nu()
    }

    /// The friction velocity the environment scales by: calibrated, else nominal.
    pub fn u_tau(&self) -> f64 {
        if self.statistics.tau_w > 0.0 {
            self.statistics.tau_w.sqrt()
        } else {
            self.u_tau_nominal()
        }
    }

    /// Time between actions in h/U_b: `dt+ nu / u_tau^2` with the nominal scales.
    pub fn control_interval(&self) -> f64 {
        self.control_interval_plus * self.nu() / self.u_tau_nominal().powi(2)
    }

    /// Solver steps per action and the step: about half the RK3 Courant limit for the bulk flow
    /// and inside the viscous limit, dividing the control interval exactly.
    pub fn steps(&self, level: Level) -> Result<(usize, f64), String> {
        let g = self.grid_of(level)?;
        let dy_max = g.dyf.iter().copied().fold(0.0, f64::max);
        let convective = 0.5 / (1.5 / g.dx + 0.5 / dy_max + 0.5 / g.dz);
        let dt = convective.min(0.8 * viscous_dt_limit(&g, self.nu()));
        let n = (self.control_interval() / dt).ceil().max(1.0) as usize;
        Ok((n, self.control_interval() / n as f64))
    }

    pub fn walls(&self) -> usize {
        match self.top {
            Top::Wall => 2,
            Top::FreeSlip => 1,
        }
    }

    pub fn act_dim(&self) -> usize {
        self.walls() * self.patches[0] * self.patches[1]
    }

    pub fn obs_dim(&self) -> usize {
        2 * self.act_dim()
    }

    pub fn hash(&self) -> String {
        format!("{:x}", Sha256::digest(serde_json::to_string(self).unwrap_or_default().as_bytes()))
    }

    /// Hash of what shapes the uncontrolled flow (for the statistics and the state cache).
    pub fn physics_hash(&self) -> String {
        let physics = (
            self.reynolds_bulk,
            self.length,
            self.top,
            self.stretch,
            &self.grid,
            self.spin_up,
            self.control_interval_plus,
            self.re_tau,
        );
        format!(
            "{:x}",
            Sha256::digest(serde_json::to_string(&physics).unwrap_or_default().as_bytes())
        )
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the spec as TOML: {e}\n"))
    }
}

/// The smallest box `[Lx+, Lz+]` that sustains channel turbulence (Jimenez & Moin 1991).
pub const MINIMAL_UNIT_PLUS: [f64; 2] = [250.0, 100.0];

/// The committed statistics table.
pub const TABLE: &str = include_str!("../../benchmarks/envs/channel.toml");
pub const TABLE_PATH: &str = "benchmarks/envs/channel.toml";

pub struct Channels;

impl Family for Channels {
    fn specs(&self) -> Vec<Spec> {
        all().into_iter().map(Spec::new).collect()
    }
}

fn with_statistics(mut s: ChannelSpec) -> ChannelSpec {
    let hash = s.physics_hash();
    if let Some(st) = crate::report::table::committed(TABLE, &s.id, &hash, |st: &ChannelStatistics| &st.spec_hash) {
        s.statistics = st;
    }
    s
}

/// `TCF_3D_Retau180`: full channel `2 pi x 2 x pi` (HydroGym's JAX box), both walls actuated.
/// `TCFMini_3D_Retau180`: the minimal channel `2.67 x 2 x 0.8` (Lx+ 480, Lz+ 144) Guastoni et al.
/// (2023) train in, after Jimenez & Moin (1991). `TCFOpen_3D_Retau206`: the open channel
/// `2 pi x 1 x pi` with a free-slip top, the paper's zero-shot surrogate (Re_theta 365 against the
/// wing's 382), Re_b from Dean's correlation `Re_tau = 0.09 (2 Re_b)^0.88`.
pub fn all() -> Vec<ChannelSpec> {
    let pi = std::f64::consts::PI;
    let base = |id: &str, description: &str| ChannelSpec {
        id: id.into(),
        family: "channel".into(),
        description: description.into(),
        re_tau: 180.0,
        reynolds_bulk: 2800.0,
        length: [2.0 * pi, 2.0, pi],
        top: Top::Wall,
        stretch: 1.8,
        grid: PerLevel {
            coarse: [32, 64, 32],
            default: [64, 96, 64],
            fine: [128, 128, 128],
        },
        patches: [32, 32],
        sensing_y_plus: 15.0,
        control_interval_plus: 0.6,
        episode_actions: 2500,
        spin_up: 150.0,
        agents: ChannelAgents::default(),
        statistics: ChannelStatistics::default(),
    };
    let full = base(
        "TCF_3D_Retau180",
        "Turbulent channel, Re_tau 180, 2 pi x 2 x pi, blowing/suction on both walls",
    );
    let mini = ChannelSpec {
        length: [2.67, 2.0, 0.8],
        grid: PerLevel {
            coarse: [24, 64, 16],
            default: [32, 64, 24],
            fine: [48, 96, 32],
        },
        patches: [8, 8],
        ..base(
            "TCFMini_3D_Retau180",
            "Minimal turbulent channel, Re_tau 180, 2.67 x 2 x 0.8 (Guastoni et al. 2023), blowing/suction on both walls",
        )
    };
    let open = ChannelSpec {
        re_tau: 206.0,
        reynolds_bulk: 3275.0,
        length: [2.0 * pi, 1.0, pi],
        top: Top::FreeSlip,
        grid: PerLevel {
            coarse: [40, 48, 36],
            default: [80, 64, 72],
            fine: [120, 96, 108],
        },
        patches: [20, 18],
        ..base(
            "TCFOpen_3D_Retau206",
            "Open channel, Re_tau 206, 2 pi x 1 x pi, free-slip top, blowing/suction on the wall (the wing surrogate)",
        )
    };
    vec![full, mini, open].into_iter().map(with_statistics).collect()
}

impl FamilySpec for ChannelSpec {
    fn id(&self) -> &str {
        &self.id
    }
    fn family(&self) -> &str {
        &self.family
    }
    fn reynolds(&self) -> f64 {
        self.re_tau
    }
    fn solver(&self) -> &'static str {
        "channel-fd2"
    }
    fn dimension(&self) -> u8 {
        3
    }
    fn obs_dim(&self) -> usize {
        ChannelSpec::obs_dim(self)
    }
    fn act_dim(&self) -> usize {
        ChannelSpec::act_dim(self)
    }
    fn control_interval(&self) -> f64 {
        ChannelSpec::control_interval(self)
    }
    fn calibrated(&self) -> bool {
        self.statistics.tau_w > 0.0
    }
    /// One agent per patch ([`ChannelAgents`]); the patch numbering is the action's.
    fn decomposition(&self) -> Option<Agents> {
        let [px, pz] = self.patches;
        let w = self.agents.window as isize;
        let (mut obs, mut act) = (vec![], vec![]);
        for wall in 0..self.walls() {
            for qz in 0..pz {
                for qx in 0..px {
                    let mut seen = vec![];
                    for dz in -w..=w {
                        for dx in -w..=w {
                            let z = (qz as isize + dz).rem_euclid(pz as isize) as usize;
                            let x = (qx as isize + dx).rem_euclid(px as isize) as usize;
                            let q = wall * px * pz + z * px + x;
                            seen.extend([2 * q, 2 * q + 1]);
                        }
                    }
                    obs.push(seen);
                    act.push(vec![wall * px * pz + qz * px + qx]);
                }
            }
        }
        Agents::new(self.obs_dim(), self.act_dim(), obs, act, self.agents.reward).ok()
    }

    /// A box smaller than the minimal flow unit in viscous units (Jimenez & Moin 1991: about
    /// `Lx+ 250-350` by `Lz+ 100`) may not sustain turbulence at this Re_tau.
    fn warnings(&self) -> Vec<String> {
        let (lx, lz) = (self.length[0] * self.re_tau, self.length[2] * self.re_tau);
        if lx >= MINIMAL_UNIT_PLUS[0] && lz >= MINIMAL_UNIT_PLUS[1] {
            return vec![];
        }
        vec![format!(
            "{}: the box is Lx+ {lx:.0} by Lz+ {lz:.0} at Re_tau {}, smaller than the minimal flow unit \
             (Jimenez & Moin 1991: Lx+ about 250-350, Lz+ about 100); turbulence may not be sustained \
             (info `relaminarised` reports it): make length[0] >= {:.2} and length[2] >= {:.2}",
            self.id,
            self.re_tau,
            MINIMAL_UNIT_PLUS[0] / self.re_tau,
            MINIMAL_UNIT_PLUS[1] / self.re_tau
        )]
    }
    fn hash(&self) -> String {
        ChannelSpec::hash(self)
    }
    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }
    fn to_toml(&self) -> String {
        ChannelSpec::to_toml(self)
    }
    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError> {
        merged(self, over, &self.id, ChannelSpec::check)
    }
    fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError> {
        Ok(Box::new(ChannelEnv::new(self.clone(), level, cache)?))
    }
    fn calibrate(
        &self,
        level: Level,
        actions: usize,
        cache: Option<PathBuf>,
        table: Option<&Path>,
        progress: &mut dyn FnMut(usize),
    ) -> Result<(String, PathBuf), CalibrateError> {
        let table = super::family::calibration_table::<ChannelStatistics>(actions, table, TABLE_PATH)?;
        let st = calibrate(self, level, actions, cache, progress)?;
        let summary = format!(
            "{}: tau_w {:.5e} (Re_tau {:.1}), u'_rms+ {:.3}, v'_rms+ {:.3} at y+ {} over {:.1} h/U_b",
            self.id,
            st.tau_w,
            st.tau_w.sqrt() / self.nu(),
            st.u_rms_plus,
            st.v_rms_plus,
            self.sensing_y_plus,
            st.time
        );
        crate::report::table::record(&table, &[(self.id.clone(), st)])?;
        Ok((summary, table))
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

/// Developed states shared by every environment of the process, keyed by physics hash and level.
fn developed() -> &'static Mutex<HashMap<String, Arc<State>>> {
    static CACHE: OnceLock<Mutex<HashMap<String, Arc<State>>>> = OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(HashMap::new()))
}

fn backend(e: impl std::fmt::Display) -> EnvError {
    EnvError::Backend(e.to_string())
}

pub struct ChannelEnv {
    spec: ChannelSpec,
    level: Level,
    cache: Option<PathBuf>,
    solver: Channel,
    substeps: usize,
    /// Sensing rows of the bottom and the top wall.
    sensing: [usize; 2],
    u_tau: f64,
    tau_ref: f64,
    actions: usize,
    live: bool,
    clock: super::clock::SolverClock,
    /// Per-wall-cell scratch: the transpiration of each wall, then the sensing plane's u' and v'.
    plane: [Vec<f64>; 2],
    shear: [Vec<f64>; 2],
    /// Each patch's wall shear stress, averaged over the last interval (the agents' rewards).
    patch_tau: Vec<f64>,
}

impl ChannelEnv {
    pub fn new(spec: ChannelSpec, level: Level, cache: Option<PathBuf>) -> Result<Self, EnvError> {
        spec.check().map_err(|m| EnvError::Backend(format!("{}: {m}", spec.id)))?;
        let (substeps, dt) = spec.steps(level).map_err(backend)?;
        let cfg = ChannelConfig {
            n: spec.n(level),
            length: spec.length,
            stretch: spec.stretch,
            top: spec.top,
            nu: spec.nu(),
            dt,
            drive: Drive::FlowRate(1.0),
            check_interval: 1,
        };
        let solver = Channel::new(cfg).map_err(backend)?;
        let g = solver.grid();
        let y_s = spec.sensing_y_plus * spec.nu() / spec.u_tau();
        let j = (0..g.ny)
            .min_by(|&a, &b| (g.yc[a] - y_s).abs().total_cmp(&(g.yc[b] - y_s).abs()))
            .unwrap_or(0);
        let wall_cells = g.nx * g.nz;
        let u_tau = spec.u_tau();
        Ok(ChannelEnv {
            sensing: [j, g.ny - 1 - j],
            tau_ref: if spec.statistics.tau_w > 0.0 {
                spec.statistics.tau_w
            } else {
                u_tau * u_tau
            },
            u_tau,
            substeps,
            plane: [vec![0.0; wall_cells], vec![0.0; wall_cells]],
            shear: [vec![0.0; wall_cells], vec![0.0; wall_cells]],
            patch_tau: vec![0.0; spec.act_dim()],
            spec,
            level,
            cache,
            solver,
            actions: 0,
            live: false,
            clock: Default::default(),
        })
    }

    pub fn spec(&self) -> &ChannelSpec {
        &self.spec
    }

    pub fn solver(&self) -> &Channel {
        &self.solver
    }

    pub fn substeps(&self) -> usize {
        self.substeps
    }

    fn cache_file(&self) -> Option<PathBuf> {
        self.cache.as_ref().map(|d| {
            d.join(format!(
                "{}-{}-{}.bin",
                self.spec.id,
                self.level.name(),
                &self.spec.physics_hash()[..16]
            ))
        })
    }

    /// The developed flow: from the process cache, the disk cache, or spun up from a seeded
    /// disturbed laminar flow.
    fn developed(&mut self) -> Result<Arc<State>, EnvError> {
        let key = format!("{}-{}", self.spec.physics_hash(), self.level.name());
        let n = self.spec.n(self.level);
        let file = self.cache_file();
        super::spin_up::developed(
            developed(),
            key,
            file,
            |s: &State| s.n == n,
            || {
                let mut rng = hgym_agents::rng::Rng::seed(splitmix64(0x5eed));
                self.solver.set_disturbed_laminar(0.3, || 2.0 * rng.uniform() - 1.0);
                let steps = (self.spec.spin_up / self.solver.config().dt).round() as u64;
                let solver = &mut self.solver;
                super::spin_up::run_reported(&self.spec.id, steps, |k| (0..k).try_for_each(|_| solver.step()))
                    .map_err(|e| EnvError::Backend(format!("{}: spin-up failed: {e}", self.spec.id)))?;
                Ok(self.solver.state())
            },
        )
    }

    /// Plane-mean-free `u` and `v` (cell centres) on the sensing row of `wall`, per wall cell.
    fn sensing_plane(&self, wall: usize, u: &mut [f64], v: &mut [f64]) {
        let s = &self.solver;
        let g = s.grid();
        let j = self.sensing[wall];
        let t = (g.yc[j] - g.yf[j]) / g.dyf[j];
        let sign = if wall == 0 { 1.0 } else { -1.0 };
        for k in 0..g.nz {
            for i in 0..g.nx {
                let ip = (i + 1) % g.nx;
                let c = k * g.nx + i;
                u[c] = 0.5 * (s.u()[g.at(i, j, k)] + s.u()[g.at(ip, j, k)]);
                let (vl, vh) = (s.v()[g.at_v(i, j, k)], s.v()[g.at_v(i, j + 1, k)]);
                v[c] = sign * (vl + t * (vh - vl));
            }
        }
        for a in [u, v] {
            let mean = a.iter().sum::<f64>() / a.len() as f64;
            a.iter_mut().for_each(|x| *x -= mean);
        }
    }

    /// Observations and the sensing-plane rms `(u'_rms+, v'_rms+)` of the actuated walls.
    fn observation(&mut self) -> (Vec<f64>, f64, f64) {
        let (nx, nz) = (self.solver.grid().nx, self.solver.grid().nz);
        let [px, pz] = self.spec.patches;
        let (bx, bz) = (nx / px, nz / pz);
        let mut obs = Vec::with_capacity(self.spec.obs_dim());
        let (mut u2, mut v2) = (0.0, 0.0);
        let [mut u, mut v] = std::mem::take(&mut self.plane);
        for wall in 0..self.spec.walls() {
            self.sensing_plane(wall, &mut u, &mut v);
            u2 += u.iter().map(|x| x * x).sum::<f64>();
            v2 += v.iter().map(|x| x * x).sum::<f64>();
            for qz in 0..pz {
                for qx in 0..px {
                    let (mut su, mut sv) = (0.0, 0.0);
                    for k in qz * bz..(qz + 1) * bz {
                        for i in qx * bx..(qx + 1) * bx {
                            su += u[k * nx + i];
                            sv += v[k * nx + i];
                        }
                    }
                    let m = (bx * bz) as f64 * self.u_tau;
                    obs.push(su / m);
                    obs.push(sv / m);
                }
            }
        }
        self.plane = [u, v];
        let cells = (nx * nz * self.spec.walls()) as f64;
        (obs, (u2 / cells).sqrt() / self.u_tau, (v2 / cells).sqrt() / self.u_tau)
    }

    /// Mean wall shear stress of the actuated walls.
    fn tau_w(&mut self) -> f64 {
        let [b, t] = &mut self.shear;
        self.solver.wall_shear(b, t);
        let walls = self.spec.walls();
        let sum: f64 = b.iter().sum::<f64>() + if walls == 2 { t.iter().sum::<f64>() } else { 0.0 };
        sum / (b.len() * walls) as f64
    }

    /// Adds `weight` times each patch's mean of the wall shear stress [`ChannelEnv::tau_w`]
    /// last computed to `patch_tau`.
    fn add_patch_shear(&mut self, weight: f64) {
        let (nx, nz) = (self.solver.grid().nx, self.solver.grid().nz);
        let [px, pz] = self.spec.patches;
        let (bx, bz) = (nx / px, nz / pz);
        let w = weight / (bx * bz) as f64;
        for wall in 0..self.spec.walls() {
            let patches = &mut self.patch_tau[wall * px * pz..(wall + 1) * px * pz];
            for k in 0..nz {
                for i in 0..nx {
                    patches[(k / bz) * px + i / bx] += w * self.shear[wall][k * nx + i];
                }
            }
        }
    }
}

impl Env for ChannelEnv {
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(self.spec.obs_dim(), -30.0, 30.0)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.spec.act_dim())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        let state = self.developed()?;
        let [bottom, top] = &mut self.plane;
        bottom.fill(0.0);
        top.fill(0.0);
        self.solver.set_transpiration(bottom, top).map_err(backend)?;
        self.solver.restore(&state).map_err(backend)?;
        // A seed-dependent start: 0-63 control intervals further on.
        let offset = (splitmix64(seed) % 64) as usize * self.substeps;
        for _ in 0..offset {
            self.solver.step().map_err(backend)?;
        }
        self.actions = 0;
        self.live = true;
        let (obs, u_rms, v_rms) = self.observation();
        let mut info = Info::default();
        info.set("t", 0.0);
        info.set("phase_steps", offset as f64);
        info.set("tau_w", self.tau_w());
        info.set("u_rms_plus", u_rms);
        info.set("v_rms_plus", v_rms);
        Ok((obs, info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let (nx, nz) = (self.solver.grid().nx, self.solver.grid().nz);
        let [px, pz] = self.spec.patches;
        let (bx, bz) = (nx / px, nz / pz);
        let per_wall = px * pz;
        let mut rms = 0.0;
        for wall in 0..self.spec.walls() {
            let acts = &a[wall * per_wall..(wall + 1) * per_wall];
            let mean = acts.iter().sum::<f64>() / per_wall as f64;
            // A uniform action leaves only the round-off of the mean: no actuation (the solver
            // would otherwise see a net flux of the size of the values themselves).
            let spread = acts.iter().fold(0.0f64, |m, x| m.max((x - mean).abs()));
            let uniform = spread <= 8.0 * f64::EPSILON * mean.abs();
            let out = &mut self.plane[wall];
            for k in 0..nz {
                for i in 0..nx {
                    let q = (k / bz) * px + i / bx;
                    let blowing = if uniform { 0.0 } else { (acts[q] - mean) * self.u_tau };
                    rms += blowing * blowing;
                    // v on the top wall points out of the fluid.
                    out[k * nx + i] = if wall == 0 { blowing } else { -blowing };
                }
            }
        }
        if self.spec.walls() == 1 {
            self.plane[1].fill(0.0);
        }
        let [bottom, top] = &self.plane;
        self.solver.set_transpiration(bottom, top).map_err(backend)?;
        let mut tau = 0.0;
        let mut failure = None;
        self.patch_tau.fill(0.0);
        for _ in 0..self.substeps {
            let t = std::time::Instant::now();
            let stepped = self.solver.step();
            self.clock.stop(t);
            if let Err(e) = stepped {
                failure = Some(e.to_string());
                break;
            }
            tau += self.tau_w() / self.substeps as f64;
            self.add_patch_shear(1.0 / self.substeps as f64);
        }
        self.actions += 1;
        let mut info = Info::default();
        info.set("t", self.actions as f64 * self.spec.control_interval());
        info.set("clipped", clipped as f64);
        info.set(
            "actuation_rms_plus",
            (rms / (nx * nz * self.spec.walls()) as f64).sqrt() / self.u_tau,
        );
        info.set("actuation_0", a[0]);
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
        let (obs, u_rms, v_rms) = self.observation();
        let reward = 1.0 - tau / self.tau_ref;
        info.set("tau_w", tau);
        info.set("drag_reduction", reward);
        // The skin-friction coefficient 2 tau_w / U_b^2 is the channel's drag coefficient: as C_D
        // it gives `hgym eval` its drag reduction against the uncontrolled flow.
        info.set("C_f", 2.0 * tau);
        info.set("C_D", 2.0 * tau);
        info.set("re_tau", tau.sqrt() / self.spec.nu());
        info.set("u_rms_plus", u_rms);
        info.set("v_rms_plus", v_rms);
        info.set("relaminarised", if u_rms < 0.5 { 1.0 } else { 0.0 });
        let truncated = self.actions >= self.spec.episode_actions;
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

    /// One agent per patch ([`ChannelAgents`]); the patch numbering is the action's.
    fn agents(&self) -> Option<Agents> {
        FamilySpec::decomposition(&self.spec)
    }

    /// `1 - tau_w,patch / tau_w,ref` per patch over the last interval.
    fn agent_rewards(&self) -> Vec<f64> {
        self.patch_tau.iter().map(|t| 1.0 - t / self.tau_ref).collect()
    }
}

impl DifferentiableEnv for ChannelEnv {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend(format!(
            "{} is not differentiable (the channel has no adjoint yet); the Kolmogorov flows are",
            self.spec.id
        )))
    }
}

impl super::fields::FlowFields for ChannelEnv {
    /// On the wall plane `[0, lx] x [0, lz]`: the bottom wall's shear stress excess
    /// `tau_w / tau_w,ref - 1` (streaks of high and low friction), and `u'`, `v'` at the sensing
    /// plane in units of `u_tau`.
    fn snapshot(&mut self) -> Snapshot {
        let g = self.solver.grid().clone();
        let n = g.nx * g.nz;
        let (mut u, mut v) = (vec![0.0; n], vec![0.0; n]);
        self.sensing_plane(0, &mut u, &mut v);
        let [b, t] = &mut self.shear;
        self.solver.wall_shear(b, t);
        let f32s = |x: &[f64], s: f64, shift: f64| x.iter().map(|v| (v / s - shift) as f32).collect::<Vec<f32>>();
        Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx: g.nx,
            ny: g.nz,
            extent: [0.0, g.lx, 0.0, g.lz],
            fields: vec![
                ("tau_w_excess".into(), f32s(&self.shear[0], self.tau_ref, 1.0)),
                ("u_sensing".into(), f32s(&u, self.u_tau, 0.0)),
                ("v_sensing".into(), f32s(&v, self.u_tau, 0.0)),
            ],
        }
    }
}

/// Runs `actions` uncontrolled intervals from `reset(0)` and measures the flow's statistics.
pub fn calibrate(
    spec: &ChannelSpec,
    level: Level,
    actions: usize,
    cache: Option<PathBuf>,
    progress: &mut dyn FnMut(usize),
) -> Result<ChannelStatistics, EnvError> {
    let mut raw = spec.clone();
    raw.statistics = ChannelStatistics::default();
    raw.episode_actions = actions.max(1);
    let mut env = ChannelEnv::new(raw, level, cache)?;
    env.reset(0)?;
    let zero = vec![0.0; spec.act_dim()];
    let (mut tau, mut u2, mut v2) = (0.0, 0.0, 0.0);
    for k in 0..actions.max(1) {
        let r = super::family::uncontrolled_step(&mut env, &spec.id, &zero)?;
        tau += super::info_value(&r.info, "tau_w")?;
        u2 += super::info_value(&r.info, "u_rms_plus")?.powi(2);
        v2 += super::info_value(&r.info, "v_rms_plus")?.powi(2);
        progress(k + 1);
    }
    let n = actions.max(1) as f64;
    Ok(ChannelStatistics {
        spec_hash: spec.physics_hash(),
        level: level.name().into(),
        time: n * spec.control_interval(),
        tau_w: tau / n,
        u_rms_plus: (u2 / n).sqrt(),
        v_rms_plus: (v2 / n).sqrt(),
    })
}

impl super::clock::SolverTime for ChannelEnv {
    fn solver_seconds(&self) -> f64 {
        self.clock.seconds()
    }
}
