//! The zero-shot target of the channel -> wing transfer (`WingTBL_3D_Rec200000`): the turbulent
//! boundary layer of a NACA 0012's suction side at `Re_c = 2x10^5`, angle of attack 0, laid flat
//! (the paper's target is a 219-million-point LES of the wing; this is the flow this machine
//! runs in its place).
//!
//! The scaling chain, each link computed by hgym:
//! 1. The panel method gives the inviscid edge velocity `Ue(s)` along the upper surface's arc
//!    length; Thwaites' and Head's integral methods give the layer tripped at `trip_xc`
//!    ([`hgym_solvers::suction_side::SuctionSide`]).
//! 2. A flat plate from `plate_xc[0]` to `plate_xc[1]` (by arc length, chord 1, free stream 1,
//!    `nu = 1 / Re_c`) carries that `Ue(x)` as the outflow of a potential base flow through its
//!    free-slip top, starts from the estimated layer, and is tripped at `trip_xc`; a fringe after
//!    its end turns the outflow back into the inflow ([`hgym_solvers::channel::wing_plate`]).
//! 3. The control region `control_xc` (the paper's x/c 0.25-0.86) is tiled with actuator patches
//!    the size of the surrogate's (`TCFOpen_3D_Retau206`: about 67 x 37 wall units) in the
//!    region's mean viscous units, and sensed at `y+ = 15` in the local viscous units.
//!
//! - Actions: wall-normal blowing (+) and suction (-) per patch, normalised actions in [-1, 1]
//!   times the local friction velocity `u_tau(x)` of the patch's column; the mean of the
//!   velocities over the control region is removed (zero net mass flux, as in the surrogate).
//!   Held over a control interval `dt+ = 0.6` with `t* = nu / <u_tau>^2` of the region.
//! - Observations: `u'` and `v'` at the local `y+ = 15` (spanwise means removed), averaged over
//!   each patch and divided by the local `u_tau`: first over the actuated patches in the action's
//!   order (x fastest, then z), `[u'_0, v'_0, u'_1, v'_1, ...]` (so a baseline reading `v'` of
//!   action `j` at `2 j + 1` works as in the channel), then over the sensing patches of the
//!   `agents.window` columns beyond each end of the region (upstream columns first, rows in z):
//!   the agents at the ends see the flow that enters and leaves their region.
//! - Reward: `1 - tau_w / tau_w,ref` over the control region, `tau_w,ref` the uncontrolled one.
//!   `info`: `C_f` of the region (`2 tau_w / <Ue>^2`), and as `C_D` the friction drag coefficient
//!   of the whole plate upstream of the fringe (`2 / c` times the integral of `tau_w` over x),
//!   so `hgym eval` reports the plate's total friction-drag reduction.
//! - `u_tau(x)` is the integral estimate's until the ID is calibrated (`hgym envs calibrate`),
//!   then the measured uncontrolled one, with `Re_theta(x)` and `Ue(x)` kept beside it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use hgym_agents::multi::Agents;
use hgym_agents::{checked_action, BoxSpace, DifferentiableEnv, Env, EnvError, Info, StepResult};
use hgym_solvers::channel::plate::{plate, PlateSpec};
use hgym_solvers::channel::wing_plate::WingPlate;
use hgym_solvers::channel::{viscous_dt_limit, Channel, ChannelState as State, FringeSpec, Grid, LayerSums, Top};
use hgym_solvers::geometry::Naca4;
use hgym_solvers::suction_side::SuctionSide;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::channel::ChannelAgents;
use super::family::{merged, CalibrateError, Family, FamilySpec, FlowEnv, Spec};
use super::seeding::splitmix64;
use super::EnvInputError;
use crate::data::field::Snapshot;
use crate::flow::level::PerLevel;
use crate::flow::Level;

/// The uncontrolled layer (`hgym envs calibrate ID`), per `u` position upstream of the fringe.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct WingTblStatistics {
    pub spec_hash: String,
    pub level: String,
    pub time: f64,
    /// Span- and time-mean wall shear stress.
    pub tau_w: Vec<f64>,
    pub ue: Vec<f64>,
    pub re_theta: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WingTblSpec {
    pub id: String,
    pub family: String,
    pub description: String,
    /// NACA 4-digit designation, angle of attack (degrees), chord Reynolds number.
    pub naca: String,
    pub alpha_deg: f64,
    pub re_c: f64,
    /// Chordwise trip position and its amplitude (in `Ue^2 / delta*` of the laminar layer).
    pub trip_xc: f64,
    pub trip_amplitude: f64,
    /// Chordwise start and end of the plate.
    pub plate_xc: [f64; 2],
    /// Fringe length (chords) and its peak damping rate (`U / c`).
    pub fringe: f64,
    pub fringe_lambda: f64,
    /// Fourier modes of the potential base flow.
    pub modes: usize,
    /// Box height and span (chords).
    pub height: f64,
    pub span: f64,
    pub stretch: f64,
    /// Cells `[nx, ny, nz]` at each level.
    pub grid: PerLevel<[usize; 3]>,
    /// Chordwise extent of the actuated region.
    pub control_xc: [f64; 2],
    /// Cells per patch `[in x, in z]` at each level; must divide `nz`.
    pub patch_cells: PerLevel<[usize; 2]>,
    pub sensing_y_plus: f64,
    pub control_interval_plus: f64,
    /// Remove the mean blowing over the control region (the surrogate's constraint); `false`
    /// lets a net flux through (uniform blowing), which then leaves through the top.
    pub zero_net_flux: bool,
    pub episode_actions: usize,
    /// Uncontrolled time (c/U) from the base flow to the developed layer.
    pub spin_up: f64,
    #[serde(default)]
    pub agents: ChannelAgents,
    #[serde(default)]
    pub statistics: WingTblStatistics,
}

/// The paper's LES of the wing: the chord average of `Re_theta` over the control region (its SI).
pub const PAPER_MEAN_RE_THETA: f64 = 382.0;

/// The uncontrolled layer a level measured (`hgym envs calibrate`) against the integral estimate
/// it is built to match, at the control region's `u` positions.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TargetCheck {
    pub level: String,
    pub xc: Vec<f64>,
    pub u_tau: Vec<f64>,
    pub u_tau_estimate: Vec<f64>,
    pub re_theta: Vec<f64>,
    pub re_theta_estimate: Vec<f64>,
    /// Means over the region.
    pub mean_u_tau: f64,
    pub mean_u_tau_estimate: f64,
    pub mean_re_theta: f64,
    pub mean_re_theta_estimate: f64,
    /// [`PAPER_MEAN_RE_THETA`].
    pub mean_re_theta_paper: f64,
}

/// The wing's layer laid flat, with what a level makes of it.
struct Layout {
    plate: WingPlate,
    grid: Grid,
    /// First and last-plus-one `u` position of the control region, cells per patch, patches.
    i0: usize,
    bx: usize,
    bz: usize,
    px: usize,
    pz: usize,
    /// Sensing columns beyond each end of the control region.
    margin: usize,
    /// Friction velocity per `u` position upstream of the fringe (calibrated or estimated).
    u_tau: Vec<f64>,
}

impl Layout {
    /// Sensing columns (the control region's and `margin` beyond each end).
    fn columns(&self) -> usize {
        self.px + 2 * self.margin
    }
    /// First `u` position of sensing column `c`.
    fn column_start(&self, c: usize) -> usize {
        self.i0 + c * self.bx - self.margin * self.bx
    }
    /// Mean friction velocity over column `c`.
    fn column_u_tau(&self, c: usize) -> f64 {
        let i = self.column_start(c);
        self.u_tau[i..i + self.bx].iter().sum::<f64>() / self.bx as f64
    }
    /// Index of the `(u', v')` pair of sensing column `c`, patch row `qz` in the observation:
    /// the actuated patches first, in the action's order, then the columns beyond the ends.
    fn slot(&self, c: usize, qz: usize) -> usize {
        let m = self.margin;
        if (m..m + self.px).contains(&c) {
            qz * self.px + c - m
        } else {
            let e = if c < m { c } else { c - self.px };
            self.px * self.pz + qz * 2 * m + e
        }
    }

    /// Mean friction velocity over the control region.
    fn region_u_tau(&self) -> f64 {
        let r = &self.u_tau[self.i0..self.i0 + self.px * self.bx];
        r.iter().sum::<f64>() / r.len() as f64
    }
}

impl WingTblSpec {
    pub fn nu(&self) -> f64 {
        1.0 / self.re_c
    }

    pub fn n(&self, level: Level) -> [usize; 3] {
        *self.grid.at(level)
    }

    fn wing_plate(&self) -> Result<WingPlate, String> {
        let wing = Naca4::from_digits(&self.naca, 1.0, [0.0, 0.0], 0.0)
            .ok_or_else(|| format!("naca = {}: not a NACA 4-digit designation", self.naca))?;
        let side = SuctionSide::of(&wing, self.alpha_deg.to_radians(), self.re_c, self.trip_xc).map_err(|e| e.to_string())?;
        Ok(WingPlate::new(side, self.plate_xc[0]))
    }

    /// Box `[lx, ly, lz]`: the plate and the fringe, the height, the span.
    fn length(&self, p: &WingPlate) -> [f64; 3] {
        [p.x_of(self.plate_xc[1]) + self.fringe, self.height, self.span]
    }

    fn layout(&self, level: Level) -> Result<Layout, String> {
        let plate = self.wing_plate()?;
        let grid = Grid::new(self.n(level), self.length(&plate), self.stretch, Top::FreeSlip).map_err(|e| e.to_string())?;
        let [bx, bz] = *self.patch_cells.at(level);
        if bx == 0 || bz == 0 || !grid.nz.is_multiple_of(bz) {
            return Err(format!(
                "patch_cells = [{bx}, {bz}] at the {} level: both must be positive and {bz} must divide the {} cells in z",
                level.name(),
                grid.nz
            ));
        }
        let i0 = (plate.x_of(self.control_xc[0]) / grid.dx).round() as usize;
        let i1 = (plate.x_of(self.control_xc[1]) / grid.dx).round() as usize;
        let px = i1.saturating_sub(i0) / bx;
        let margin = self.agents.window;
        let plate_end = ((grid.lx - self.fringe) / grid.dx).floor() as usize;
        if px == 0 || i0 < margin * bx || i0 + (px + margin) * bx > plate_end {
            return Err(format!(
                "control_xc = {:?} holds {px} patch columns of {bx} cells at the {} level, with {margin} sensing column(s) \
                 beyond each end; it must hold one and lie inside the plate {:?} with that margin",
                self.control_xc,
                level.name(),
                self.plate_xc
            ));
        }
        let calibrated = self.calibrated_at(level, plate_end);
        let u_tau = (0..plate_end)
            .map(|i| match calibrated {
                true => self.statistics.tau_w[i].max(0.0).sqrt(),
                false => plate.station(i as f64 * grid.dx).u_tau(),
            })
            .collect();
        Ok(Layout {
            plate,
            i0,
            bx,
            bz,
            px,
            pz: grid.nz / bz,
            margin,
            u_tau,
            grid,
        })
    }

    fn calibrated_at(&self, level: Level, stations: usize) -> bool {
        self.statistics.level == level.name() && self.statistics.tau_w.len() == stations
    }

    /// The calibrated layer at `level` against the integral estimate (`None` until calibrated there).
    pub fn target_check(&self, level: Level) -> Result<Option<TargetCheck>, String> {
        let l = self.layout(level)?;
        if !self.calibrated_at(level, l.u_tau.len()) {
            return Ok(None);
        }
        let cols: Vec<usize> = (l.i0..l.i0 + l.px * l.bx).collect();
        let x = |i: usize| i as f64 * l.grid.dx;
        let est = |i: usize| l.plate.station(x(i));
        let nu = self.nu();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let u_tau: Vec<f64> = cols.iter().map(|&i| l.u_tau[i]).collect();
        let u_tau_estimate: Vec<f64> = cols.iter().map(|&i| est(i).u_tau()).collect();
        let re_theta: Vec<f64> = cols.iter().map(|&i| self.statistics.re_theta[i]).collect();
        let re_theta_estimate: Vec<f64> = cols.iter().map(|&i| est(i).ue * est(i).theta / nu).collect();
        Ok(Some(TargetCheck {
            level: level.name().into(),
            xc: cols.iter().map(|&i| l.plate.xc_of(x(i))).collect(),
            mean_u_tau: mean(&u_tau),
            mean_u_tau_estimate: mean(&u_tau_estimate),
            mean_re_theta: mean(&re_theta),
            mean_re_theta_estimate: mean(&re_theta_estimate),
            mean_re_theta_paper: PAPER_MEAN_RE_THETA,
            u_tau,
            u_tau_estimate,
            re_theta,
            re_theta_estimate,
        }))
    }

    /// The checks a spec must pass before it builds an environment; the message names the field.
    pub fn check(&self) -> Result<(), String> {
        for (key, v) in [
            ("re_c", self.re_c),
            ("sensing_y_plus", self.sensing_y_plus),
            ("control_interval_plus", self.control_interval_plus),
            ("fringe", self.fringe),
            ("height", self.height),
            ("span", self.span),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key} must be a positive number, got {v}"));
            }
        }
        let [a, b] = self.plate_xc;
        let [c0, c1] = self.control_xc;
        if !(0.0 < a && a < self.trip_xc && self.trip_xc < c0 && c0 < c1 && c1 < b && b < 1.0) {
            return Err(format!(
                "need 0 < plate_xc[0] < trip_xc < control_xc[0] < control_xc[1] < plate_xc[1] < 1, got plate_xc {:?}, trip_xc {}, control_xc {:?}",
                self.plate_xc, self.trip_xc, self.control_xc
            ));
        }
        for level in Level::ALL {
            let l = self.layout(level)?;
            let first = l.grid.yc[0] * l.u_tau.iter().copied().fold(0.0, f64::max) / self.nu();
            if first > 1.0 {
                return Err(format!(
                    "the {} grid puts its first cell centre at y+ = {first:.2}; a wall-resolved flow needs y+ <= 1",
                    level.name()
                ));
            }
            if 2 * self.agents.window + 1 > l.pz {
                return Err(format!(
                    "agents.window = {} sees more patches in z than the {} there are",
                    self.agents.window, l.pz
                ));
            }
        }
        super::family::check_episode(self.control_interval(), self.episode_actions, self.spin_up)
    }

    /// `<u_tau>` of the control region at the default level (calibrated or estimated).
    fn region_u_tau(&self) -> f64 {
        self.layout(Level::Default).map_or(f64::NAN, |l| l.region_u_tau())
    }

    /// Time between actions (c/U): `dt+ nu / <u_tau>^2` over the control region.
    pub fn control_interval(&self) -> f64 {
        self.control_interval_plus * self.nu() / self.region_u_tau().powi(2)
    }

    pub fn patches(&self, level: Level) -> Result<[usize; 2], String> {
        self.layout(level).map(|l| [l.px, l.pz])
    }

    /// Actions at the default level (the action layout is the default level's; other levels
    /// that tile the region differently are refused by `make`).
    pub fn act_dim(&self) -> usize {
        self.layout(Level::Default).map_or(0, |l| l.px * l.pz)
    }

    pub fn obs_dim(&self) -> usize {
        self.layout(Level::Default).map_or(0, |l| 2 * l.columns() * l.pz)
    }

    pub fn hash(&self) -> String {
        format!("{:x}", Sha256::digest(serde_json::to_string(self).unwrap_or_default().as_bytes()))
    }

    /// Hash of what shapes the uncontrolled flow (for the statistics and the state cache).
    pub fn physics_hash(&self) -> String {
        let physics = (
            (&self.naca, self.alpha_deg, self.re_c, self.trip_xc, self.trip_amplitude),
            (self.plate_xc, self.fringe, self.fringe_lambda, self.modes),
            (self.height, self.span, self.stretch, &self.grid),
            self.spin_up,
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

/// The committed statistics table.
pub const TABLE: &str = include_str!("../../benchmarks/envs/wing_tbl.toml");
pub const TABLE_PATH: &str = "benchmarks/envs/wing_tbl.toml";

pub struct WingTbls;

impl Family for WingTbls {
    fn specs(&self) -> Vec<Spec> {
        all().into_iter().map(Spec::new).collect()
    }
}

fn with_statistics(mut s: WingTblSpec) -> WingTblSpec {
    let hash = s.physics_hash();
    if let Some(st) = crate::report::table::committed(TABLE, &s.id, &hash, |st: &WingTblStatistics| &st.spec_hash) {
        s.statistics = st;
    }
    s
}

/// `WingTBL_3D_Rec200000`: the paper's wing target. The default grid has the surrogate's
/// resolution in the control region's wall units (dx+ about 16, dz+ about 9; `TCFOpen_3D_Retau206`
/// default: 16.7 and 9.3), its patches 4 x 4 cells like the surrogate's.
pub fn all() -> Vec<WingTblSpec> {
    let s = WingTblSpec {
        id: "WingTBL_3D_Rec200000".into(),
        family: "wing_tbl".into(),
        description: "NACA 0012 suction-side turbulent boundary layer laid flat (Re_c 2e5, AoA 0, Ue(x) from the panel method), control region x/c 0.25-0.86 (the channel -> wing zero-shot target)".into(),
        naca: "0012".into(),
        alpha_deg: 0.0,
        re_c: 2e5,
        trip_xc: 0.1,
        trip_amplitude: 0.12,
        plate_xc: [0.06, 0.95],
        fringe: 0.15,
        fringe_lambda: 600.0,
        modes: 10,
        height: 0.08,
        span: 0.06,
        stretch: 2.5,
        grid: PerLevel {
            coarse: [320, 64, 30],
            default: [640, 64, 60],
            fine: [960, 96, 90],
        },
        control_xc: [0.25, 0.86],
        patch_cells: PerLevel {
            coarse: [2, 2],
            default: [4, 4],
            fine: [6, 6],
        },
        sensing_y_plus: 15.0,
        control_interval_plus: 0.6,
        zero_net_flux: true,
        episode_actions: 1500,
        spin_up: 3.0,
        agents: ChannelAgents::default(),
        statistics: WingTblStatistics::default(),
    };
    vec![with_statistics(s)]
}

impl FamilySpec for WingTblSpec {
    fn id(&self) -> &str {
        &self.id
    }
    fn family(&self) -> &str {
        &self.family
    }
    fn reynolds(&self) -> f64 {
        self.re_c
    }
    fn solver(&self) -> &'static str {
        "channel-fd2"
    }
    fn dimension(&self) -> u8 {
        3
    }
    fn obs_dim(&self) -> usize {
        WingTblSpec::obs_dim(self)
    }
    fn act_dim(&self) -> usize {
        WingTblSpec::act_dim(self)
    }
    fn control_interval(&self) -> f64 {
        WingTblSpec::control_interval(self)
    }
    fn calibrated(&self) -> bool {
        !self.statistics.tau_w.is_empty()
    }
    /// One agent per patch: it sees the `(2 window + 1)^2` sensing patches centred on its own
    /// (periodic in z; in x the sensing columns reach `window` beyond the region), acts on its
    /// own patch and learns from the region's reward.
    fn decomposition(&self) -> Option<Agents> {
        let l = self.layout(Level::Default).ok()?;
        let w = self.agents.window as isize;
        let (mut obs, mut act) = (vec![], vec![]);
        for qz in 0..l.pz {
            for qx in 0..l.px {
                let mut seen = vec![];
                for dz in -w..=w {
                    for dx in -w..=w {
                        let z = (qz as isize + dz).rem_euclid(l.pz as isize) as usize;
                        let c = ((l.margin + qx) as isize + dx) as usize;
                        let o = 2 * l.slot(c, z);
                        seen.extend([o, o + 1]);
                    }
                }
                obs.push(seen);
                act.push(vec![qz * l.px + qx]);
            }
        }
        Agents::new(self.obs_dim(), self.act_dim(), obs, act, self.agents.reward).ok()
    }

    fn hash(&self) -> String {
        WingTblSpec::hash(self)
    }
    fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }
    fn to_toml(&self) -> String {
        WingTblSpec::to_toml(self)
    }
    fn with_overrides(&self, over: &toml::Table) -> Result<Spec, EnvInputError> {
        merged(self, over, &self.id, WingTblSpec::check)
    }
    fn make(&self, level: Level, cache: Option<PathBuf>) -> Result<Box<dyn FlowEnv>, EnvError> {
        Ok(Box::new(WingTblEnv::new(self.clone(), level, cache)?))
    }
    fn calibrate(
        &self,
        level: Level,
        actions: usize,
        cache: Option<PathBuf>,
        table: Option<&Path>,
        progress: &mut dyn FnMut(usize),
    ) -> Result<(String, PathBuf), CalibrateError> {
        let table = super::family::calibration_table::<WingTblStatistics>(actions, table, TABLE_PATH)?;
        let st = calibrate(self, level, actions, cache, progress)?;
        let mut env = self.clone();
        env.statistics = st.clone();
        let l = env.layout(level).map_err(backend)?;
        let summary = format!(
            "{}: <u_tau> {:.5} over x/c {:?} (Re_theta {:.0} to {:.0} there) over {:.3} c/U",
            self.id,
            l.region_u_tau(),
            self.control_xc,
            st.re_theta[l.i0],
            st.re_theta[l.i0 + l.px * l.bx - 1],
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

pub struct WingTblEnv {
    spec: WingTblSpec,
    level: Level,
    cache: Option<PathBuf>,
    solver: Channel,
    layout: Layout,
    substeps: usize,
    /// Time between actions.
    interval: f64,
    /// Sensing row of each sensing column.
    sensing: Vec<usize>,
    tau_ref: f64,
    drag_ref: f64,
    /// Mean edge velocity over the control region (calibrated or estimated).
    ue_region: f64,
    actions: usize,
    live: bool,
    clock: super::clock::SolverClock,
    /// Per wall cell: the bottom's blowing, the top's base outflow and the top's transpiration
    /// (the outflow plus the net blowing when the flux is not held at zero).
    blowing: Vec<f64>,
    outflow: Vec<f64>,
    top: Vec<f64>,
    /// Wall shear stress of the bottom and (unused) the top.
    shear: [Vec<f64>; 2],
    /// Each patch's wall shear stress, averaged over the last interval (the agents' rewards).
    patch_tau: Vec<f64>,
}

impl WingTblEnv {
    pub fn new(spec: WingTblSpec, level: Level, cache: Option<PathBuf>) -> Result<Self, EnvError> {
        spec.check().map_err(|m| EnvError::Backend(format!("{}: {m}", spec.id)))?;
        let layout = spec.layout(level).map_err(backend)?;
        if layout.px * layout.pz != spec.act_dim() {
            return Err(EnvError::Backend(format!(
                "{}: the {} level tiles the control region with {}x{} patches, the default level with another number; \
                 set patch_cells so that every level has the default's patches",
                spec.id,
                level.name(),
                layout.px,
                layout.pz
            )));
        }
        let g = &layout.grid;
        let nu = spec.nu();
        let wp = &layout.plate;
        let trip = wp.trip(spec.trip_xc, spec.trip_amplitude, g.dx, g.dz, 1);
        let fringe = FringeSpec {
            x_start: g.lx - spec.fringe,
            x_end: g.lx,
            rise: 0.4 * spec.fringe,
            fall: 0.3 * spec.fringe,
            lambda_max: spec.fringe_lambda,
        };
        let convective = 0.5 / (1.3 / g.dx + 0.5 / g.dz);
        let dt = convective.min(0.8 * viscous_dt_limit(g, nu));
        // The spec's sizes and interval solve the panel flow each time: computed once here.
        let interval = spec.control_interval();
        let substeps = (interval / dt).ceil().max(1.0) as usize;
        let pspec = PlateSpec {
            n: spec.n(level),
            length: [g.lx, g.ly, g.lz],
            stretch: spec.stretch,
            nu,
            dt: interval / substeps as f64,
            fringe,
            modes: spec.modes,
            trip: Some(trip),
        };
        let (solver, _) = plate(&pspec, |x| wp.ue(x), |x, y| wp.shape(x, y)).map_err(backend)?;
        let sensing = (0..layout.columns())
            .map(|c| {
                let y_s = spec.sensing_y_plus * nu / layout.column_u_tau(c);
                (0..g.ny)
                    .min_by(|&a, &b| (g.yc[a] - y_s).abs().total_cmp(&(g.yc[b] - y_s).abs()))
                    .unwrap_or(0)
            })
            .collect();
        let region = layout.i0..layout.i0 + layout.px * layout.bx;
        let tau_ref = layout.u_tau[region.clone()].iter().map(|u| u * u).sum::<f64>() / (layout.px * layout.bx) as f64;
        let drag_ref = 2.0 * layout.u_tau.iter().map(|u| u * u).sum::<f64>() * g.dx;
        let ue_region = region
            .clone()
            .map(|i| match spec.statistics.ue.get(i) {
                Some(&u) if spec.calibrated_at(level, layout.u_tau.len()) => u,
                _ => wp.ue(i as f64 * g.dx),
            })
            .sum::<f64>()
            / region.len() as f64;
        let wall_cells = g.nx * g.nz;
        let outflow: Vec<f64> = (0..wall_cells).map(|c| solver.v()[g.at_v(c % g.nx, g.ny, c / g.nx)]).collect();
        Ok(WingTblEnv {
            substeps,
            interval,
            sensing,
            tau_ref,
            drag_ref,
            ue_region,
            blowing: vec![0.0; wall_cells],
            top: outflow.clone(),
            outflow,
            shear: [vec![0.0; wall_cells], vec![0.0; wall_cells]],
            patch_tau: vec![0.0; layout.px * layout.pz],
            layout,
            spec,
            level,
            cache,
            solver,
            actions: 0,
            live: false,
            clock: Default::default(),
        })
    }

    pub fn spec(&self) -> &WingTblSpec {
        &self.spec
    }

    pub fn solver(&self) -> &Channel {
        &self.solver
    }

    fn cache_file(&self) -> Option<PathBuf> {
        let hash = self.spec.physics_hash();
        self.cache
            .as_ref()
            .map(|d| d.join(format!("{}-{}-{}.bin", self.spec.id, self.level.name(), &hash[..16])))
    }

    /// The developed flow: from the process cache, the disk cache, or spun up from the base flow.
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
                let steps = (self.spec.spin_up / self.solver.config().dt).round() as u64;
                let solver = &mut self.solver;
                super::spin_up::run_reported(&self.spec.id, steps, |k| (0..k).try_for_each(|_| solver.step()))
                    .map_err(|e| EnvError::Backend(format!("{}: spin-up failed: {e}", self.spec.id)))?;
                Ok(self.solver.state())
            },
        )
    }

    /// `u'` and `v'` (cell centres, spanwise means removed) at the sensing row of each sensing
    /// column, averaged over each patch, in the column's `u_tau`; and the rms of `u'+` over them.
    fn observation(&self) -> (Vec<f64>, f64) {
        let l = &self.layout;
        let (s, g) = (&self.solver, &l.grid);
        let mut obs = vec![0.0; 2 * l.columns() * l.pz];
        let mut u2 = 0.0;
        let mut cells = 0usize;
        for c in 0..l.columns() {
            let j = self.sensing[c];
            let t = (g.yc[j] - g.yf[j]) / g.dyf[j];
            let u_tau = l.column_u_tau(c);
            for i in l.column_start(c)..l.column_start(c) + l.bx {
                let uc = |k| 0.5 * (s.u()[g.at(i, j, k)] + s.u()[g.at(i + 1, j, k)]);
                let vc = |k| {
                    let (lo, hi) = (s.v()[g.at_v(i, j, k)], s.v()[g.at_v(i, j + 1, k)]);
                    lo + t * (hi - lo)
                };
                let (mu, mv) = (0..g.nz).fold((0.0, 0.0), |(a, b), k| (a + uc(k), b + vc(k)));
                let (mu, mv) = (mu / g.nz as f64, mv / g.nz as f64);
                for k in 0..g.nz {
                    let (du, dv) = ((uc(k) - mu) / u_tau, (vc(k) - mv) / u_tau);
                    let o = 2 * l.slot(c, k / l.bz);
                    obs[o] += du / (l.bx * l.bz) as f64;
                    obs[o + 1] += dv / (l.bx * l.bz) as f64;
                    u2 += du * du;
                    cells += 1;
                }
            }
        }
        (obs, (u2 / cells.max(1) as f64).sqrt())
    }

    /// The wall shear stress into `self.shear[0]`; its means over the control region and the
    /// plate upstream of the fringe (as `2 / c` times its integral, the friction drag coefficient).
    fn wall_shear(&mut self) -> (f64, f64) {
        let [tau, top] = &mut self.shear;
        self.solver.wall_shear(tau, top);
        let (l, tau) = (&self.layout, &self.shear[0]);
        let g = &l.grid;
        let column = |i: usize| (0..g.nz).map(|k| tau[k * g.nx + i]).sum::<f64>() / g.nz as f64;
        let region = (l.i0..l.i0 + l.px * l.bx).map(column).sum::<f64>() / (l.px * l.bx) as f64;
        let drag = 2.0 * (0..l.u_tau.len()).map(column).sum::<f64>() * g.dx;
        (region, drag)
    }
}

impl Env for WingTblEnv {
    fn observation_space(&self) -> BoxSpace {
        BoxSpace::uniform(2 * self.layout.columns() * self.layout.pz, -30.0, 30.0)
    }

    fn action_space(&self) -> BoxSpace {
        BoxSpace::unit(self.patch_tau.len())
    }

    fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
        let state = self.developed()?;
        self.blowing.fill(0.0);
        self.solver.restore(&state).map_err(backend)?;
        self.solver.set_transpiration(&self.blowing, &self.outflow).map_err(backend)?;
        // A seed-dependent start: 0-63 control intervals further on.
        let offset = (splitmix64(seed) % 64) as usize * self.substeps;
        for _ in 0..offset {
            self.solver.step().map_err(backend)?;
        }
        self.actions = 0;
        self.live = true;
        let (obs, u_rms) = self.observation();
        let (tau, drag) = self.wall_shear();
        let mut info = Info::default();
        info.set("t", 0.0);
        info.set("phase_steps", offset as f64);
        info.set("tau_w", tau);
        info.set("C_D", drag);
        info.set("u_rms_plus", u_rms);
        Ok((obs, info))
    }

    fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
        if !self.live {
            return Err(EnvError::NeedsReset);
        }
        let (a, clipped) = checked_action(&self.action_space(), action)?;
        let l = &self.layout;
        let g = &l.grid;
        // Each patch's velocity in its column's u_tau, then the mean over the region removed.
        for (q, v) in self.patch_tau.iter_mut().enumerate() {
            *v = a[q] * l.column_u_tau(l.margin + q % l.px);
        }
        let mean = self.patch_tau.iter().sum::<f64>() / self.patch_tau.len() as f64;
        let shift = if self.spec.zero_net_flux { mean } else { 0.0 };
        // A uniform action under zero net flux leaves only round-off: no actuation.
        let spread = self.patch_tau.iter().fold(0.0f64, |m, v| m.max((v - mean).abs()));
        let idle = self.spec.zero_net_flux && spread <= 8.0 * f64::EPSILON * mean.abs();
        self.blowing.fill(0.0);
        let mut rms = 0.0;
        for k in 0..g.nz {
            for i in l.i0..l.i0 + l.px * l.bx {
                let v = if idle {
                    0.0
                } else {
                    self.patch_tau[(k / l.bz) * l.px + (i - l.i0) / l.bx] - shift
                };
                self.blowing[k * g.nx + i] = v;
                rms += v * v;
            }
        }
        // Net blowing leaves through the top, spread uniformly.
        let net = self.blowing.iter().sum::<f64>() / self.blowing.len() as f64;
        for (t, o) in self.top.iter_mut().zip(&self.outflow) {
            *t = o + net;
        }
        self.solver.set_transpiration(&self.blowing, &self.top).map_err(backend)?;
        let (mut tau, mut drag) = (0.0, 0.0);
        let mut failure = None;
        self.patch_tau.fill(0.0);
        let w = 1.0 / self.substeps as f64;
        for _ in 0..self.substeps {
            let t = std::time::Instant::now();
            let stepped = self.solver.step();
            self.clock.stop(t);
            if let Err(e) = stepped {
                failure = Some(e.to_string());
                break;
            }
            let (t_region, d) = self.wall_shear();
            tau += w * t_region;
            drag += w * d;
            self.add_patch_shear(w);
        }
        self.actions += 1;
        let region_cells = (self.layout.px * self.layout.bx * self.layout.grid.nz) as f64;
        let mut info = Info::default();
        info.set("t", self.actions as f64 * self.interval);
        info.set("clipped", clipped as f64);
        info.set("actuation_rms_plus", (rms / region_cells).sqrt() / self.layout.region_u_tau());
        info.set(
            "actuation_mean_plus",
            net * self.blowing.len() as f64 / region_cells / self.layout.region_u_tau(),
        );
        if let Some(reason) = failure {
            self.live = false;
            info.set("diverged", 1.0);
            info.set_text("reason", reason);
            return Ok(StepResult {
                obs: vec![0.0; 2 * self.layout.columns() * self.layout.pz],
                reward: 0.0,
                terminated: true,
                truncated: false,
                info,
            });
        }
        let (obs, u_rms) = self.observation();
        let reward = 1.0 - tau / self.tau_ref;
        info.set("tau_w", tau);
        info.set("drag_reduction", reward);
        info.set("C_f", 2.0 * tau / self.ue_region.powi(2));
        // The plate's friction drag coefficient: `hgym eval` reports its reduction.
        info.set("C_D", drag);
        info.set("drag_reduction_plate", 1.0 - drag / self.drag_ref);
        info.set("u_rms_plus", u_rms);
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

    /// One agent per patch ([`WingTblSpec::decomposition`]).
    fn agents(&self) -> Option<Agents> {
        FamilySpec::decomposition(&self.spec)
    }

    /// `1 - tau_w,patch / tau_w,ref` per patch over the last interval.
    fn agent_rewards(&self) -> Vec<f64> {
        self.patch_tau.iter().map(|t| 1.0 - t / self.tau_ref).collect()
    }
}

impl WingTblEnv {
    /// Adds `weight` times each patch's mean wall shear stress (last computed) to `patch_tau`.
    fn add_patch_shear(&mut self, weight: f64) {
        let l = &self.layout;
        let nx = l.grid.nx;
        let w = weight / (l.bx * l.bz) as f64;
        for k in 0..l.grid.nz {
            for i in l.i0..l.i0 + l.px * l.bx {
                self.patch_tau[(k / l.bz) * l.px + (i - l.i0) / l.bx] += w * self.shear[0][k * nx + i];
            }
        }
    }
}

impl DifferentiableEnv for WingTblEnv {
    fn reward_action_gradients(&mut self, _k: usize) -> Result<Vec<Vec<f64>>, EnvError> {
        Err(EnvError::Backend(format!(
            "{} is not differentiable (the channel solver has no adjoint)",
            self.spec.id
        )))
    }
}

impl super::fields::FlowFields for WingTblEnv {
    /// On the wall plane `[0, lx] x [0, lz]`: the wall shear stress over its uncontrolled local
    /// value, `tau_w / tau_w,ref(x) - 1` (streaks of high and low friction; 0 in the fringe).
    fn snapshot(&mut self) -> Snapshot {
        self.wall_shear();
        let l = &self.layout;
        let g = &l.grid;
        let excess: Vec<f32> = (0..g.nx * g.nz)
            .map(|c| {
                let i = c % g.nx;
                match l.u_tau.get(i) {
                    Some(u) if *u > 0.0 => (self.shear[0][c] / (u * u) - 1.0) as f32,
                    _ => 0.0,
                }
            })
            .collect();
        Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx: g.nx,
            ny: g.nz,
            extent: [0.0, g.lx, 0.0, g.lz],
            fields: vec![("tau_w_excess".into(), excess)],
        }
    }
}

impl super::clock::SolverTime for WingTblEnv {
    fn solver_seconds(&self) -> f64 {
        self.clock.seconds()
    }
}

/// Runs `actions` uncontrolled intervals from `reset(0)` and measures the layer at every `u`
/// position upstream of the fringe: wall shear stress, edge velocity, `Re_theta`.
pub fn calibrate(
    spec: &WingTblSpec,
    level: Level,
    actions: usize,
    cache: Option<PathBuf>,
    progress: &mut dyn FnMut(usize),
) -> Result<WingTblStatistics, EnvError> {
    let mut raw = spec.clone();
    raw.statistics = WingTblStatistics::default();
    raw.episode_actions = actions.max(1);
    let mut env = WingTblEnv::new(raw, level, cache)?;
    env.reset(0)?;
    let zero = vec![0.0; spec.act_dim()];
    let g = env.layout.grid.clone();
    let mut sums = LayerSums::new(&g);
    for k in 0..actions.max(1) {
        super::family::uncontrolled_step(&mut env, &spec.id, &zero)?;
        sums.add(env.solver());
        progress(k + 1);
    }
    let stations: Vec<_> = (0..env.layout.u_tau.len()).map(|i| sums.station(&g, i)).collect();
    Ok(WingTblStatistics {
        spec_hash: spec.physics_hash(),
        level: level.name().into(),
        time: actions.max(1) as f64 * env.interval,
        tau_w: stations.iter().map(|s| s.tau_w).collect(),
        ue: stations.iter().map(|s| s.ue).collect(),
        re_theta: stations.iter().map(|s| s.ue * s.theta / spec.nu()).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target() -> WingTblSpec {
        all().remove(0)
    }

    /// The target on a tiny grid every level shares, with a spin-up of a few steps.
    fn tiny(zero_net_flux: bool) -> WingTblEnv {
        let mut s = target();
        s.grid = PerLevel {
            coarse: [96, 32, 8],
            default: [96, 32, 8],
            fine: [96, 32, 8],
        };
        s.patch_cells = PerLevel {
            coarse: [6, 2],
            default: [6, 2],
            fine: [6, 2],
        };
        s.spin_up = 0.002;
        s.stretch = 3.2;
        s.zero_net_flux = zero_net_flux;
        WingTblEnv::new(s, Level::Coarse, None).unwrap()
    }

    /// The check reads the calibrated level's table over the control region, and exists only
    /// where a level is calibrated.
    #[test]
    fn the_target_check_covers_the_control_region_of_the_calibrated_level() {
        let s = target();
        assert_eq!(s.target_check(Level::Default).unwrap(), None);
        let Some(t) = s.target_check(Level::Coarse).unwrap() else {
            panic!("the coarse level is calibrated (benchmarks/envs/wing_tbl.toml)")
        };
        let n = t.xc.len();
        assert!(n > 10 && [t.u_tau.len(), t.u_tau_estimate.len(), t.re_theta.len(), t.re_theta_estimate.len()] == [n; 4]);
        assert!((t.xc[0] - 0.25).abs() < 0.01 && (t.xc[n - 1] - 0.86).abs() < 0.03, "{:?}", t.xc);
        let l = s.layout(Level::Coarse).unwrap();
        assert_eq!(t.u_tau[0], s.statistics.tau_w[l.i0].sqrt());
        assert!(
            t.re_theta_estimate.windows(2).all(|w| w[1] > w[0]),
            "the layer grows along the region"
        );
    }

    #[test]
    fn the_target_passes_its_checks_and_has_the_surrogates_patches_in_wall_units() {
        let s = target();
        s.check().unwrap();
        for level in Level::ALL {
            assert_eq!(s.patches(level), s.patches(Level::Default), "{level:?}");
        }
        let open = super::super::channel::all()
            .into_iter()
            .find(|c| c.id == "TCFOpen_3D_Retau206")
            .unwrap();
        let re_tau = open.u_tau() / open.nu();
        let [px, pz] = open.patches;
        let surrogate = [open.length[0] / px as f64 * re_tau, open.length[2] / pz as f64 * re_tau];
        let l = s.layout(Level::Default).unwrap();
        let unit = s.nu() / l.region_u_tau();
        let ours = [(l.bx as f64) * l.grid.dx / unit, (l.bz as f64) * l.grid.dz / unit];
        for d in 0..2 {
            assert!(
                (ours[d] / surrogate[d] - 1.0).abs() < 0.15,
                "patch {ours:?} wall units, surrogate {surrogate:?}"
            );
        }
    }

    #[test]
    fn the_env_keeps_the_gymnasium_contract() {
        let mut env = tiny(true);
        env.spec.episode_actions = 3;
        let violations = hgym_agents::check_env(&mut env, 3, 7);
        assert!(violations.is_empty(), "{violations:#?}");
    }

    #[test]
    fn agents_see_what_the_surrogates_agents_see() {
        let env = tiny(true);
        let a = env.agents().unwrap();
        let l = &env.layout;
        assert_eq!(a.obs.len(), l.px * l.pz);
        // 3 x 3 patches of (u', v'), as in the channel with window 1.
        assert!(a.obs.iter().all(|o| o.len() == 18));
        // The first agent's upstream neighbours are the sensing column before the region; its
        // own patch is the first action's.
        let up = 2 * l.slot(0, l.pz - 1);
        assert_eq!(a.obs[0][..2], [up, up + 1]);
        assert!(up >= 2 * l.px * l.pz);
        assert_eq!(a.obs[0][8..10], [0, 1]);
        // Every observation slot is one sensing patch.
        let mut slots: Vec<usize> = (0..l.columns())
            .flat_map(|c| (0..l.pz).map(move |z| (c, z)))
            .map(|(c, z)| l.slot(c, z))
            .collect();
        slots.sort();
        assert_eq!(slots, (0..l.columns() * l.pz).collect::<Vec<_>>());
    }

    #[test]
    fn blowing_scales_with_the_local_friction_velocity_and_holds_zero_net_flux() {
        let mut env = tiny(true);
        env.reset(0).unwrap();
        let n = env.spec.act_dim();
        let a: Vec<f64> = (0..n).map(|q| if q % 2 == 0 { 1.0 } else { -1.0 }).collect();
        let r = env.step(&a).unwrap();
        assert!(!r.terminated && r.obs.iter().all(|x| x.is_finite()));
        let l = &env.layout;
        let g = &l.grid;
        assert!(env.blowing.iter().sum::<f64>().abs() < 1e-12);
        // Within the region every cell carries its patch's action in its column's u_tau, less
        // the region's mean; outside it nothing.
        let mean = (0..n).map(|q| a[q] * l.column_u_tau(l.margin + q % l.px)).sum::<f64>() / n as f64;
        for q in [0, 1, l.px + 2] {
            let (qx, qz) = (q % l.px, q / l.px);
            let cell = qz * l.bz * g.nx + l.i0 + qx * l.bx;
            let want = a[q] * l.column_u_tau(l.margin + qx) - mean;
            assert!((env.blowing[cell] - want).abs() < 1e-15, "patch {q}");
        }
        assert_eq!(env.blowing[l.i0 - 1], 0.0);
        // A uniform action blows in proportion to u_tau(x) less its mean: the action bound
        // follows the local scale, and the net flux stays zero.
        env.step(&vec![0.7; n]).unwrap();
        let l = &env.layout;
        let mean = (0..l.px).map(|qx| l.column_u_tau(l.margin + qx)).sum::<f64>() / l.px as f64;
        let want = 0.7 * (l.column_u_tau(l.margin) - mean);
        assert!(want.abs() > 1e-4 && (env.blowing[l.i0] - want).abs() < 1e-15);
    }

    #[test]
    fn uniform_blowing_leaves_through_the_top() {
        let mut env = tiny(false);
        env.reset(0).unwrap();
        let n = env.spec.act_dim();
        let r = env.step(&vec![0.5; n]).unwrap();
        assert!(!r.terminated, "{:?}", r.info.text("reason"));
        let net: f64 = env.blowing.iter().sum();
        let out: f64 = env.top.iter().zip(&env.outflow).map(|(t, o)| t - o).sum();
        assert!(net > 0.0 && (net - out).abs() < 1e-12 * net);
        assert!(r.info.get("actuation_mean_plus").unwrap() > 0.4);
    }
}
