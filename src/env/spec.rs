//! Environment specs: plain serialisable values (`hgym envs show ID` prints one as TOML). A spec
//! fixes the physics, the actuators, the probes, the reward and the timing; its hash goes into
//! every result and keys the cache of developed-flow states. `build()` makes the running env.
//!
//! Units: lengths in the body's reference length (diameter), velocities in U, times in L/U.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use hgym_solvers::lbm::Collision;

use super::actuation::{Jet, Ramp};
use crate::flow::{BoundarySpec, DomainSpec, FlowSetup, GeometrySpec, InletSpec, Level, Profile, ResolutionSpec, VelocityReference};
pub use crate::flow::{EdgeName, SpongeSpec};

/// The actuators of an environment; actions in `[-1, 1]` are scaled by the bound given here.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ActuationSpec {
    /// Zero-net-mass-flux jet pair on a circular body: one action `a`; the jet at
    /// `angles_deg[0]` blows with `a * max_velocity`, the one at `angles_deg[1]` sucks the same.
    /// Bound: `max_velocity` in units of U (peak of the parabolic jet profile).
    ZnmfJets {
        body: usize,
        #[serde(deserialize_with = "crate::flow::pair")]
        angles_deg: [f64; 2],
        span_deg: f64,
        max_velocity: f64,
    },
    /// A zero-net-mass-flux jet pair on each of the listed circular bodies, as in `ZnmfJets`,
    /// one action per body. Bound: `max_velocity` in units of U.
    ZnmfJetsPerBody {
        bodies: Vec<usize>,
        #[serde(deserialize_with = "crate::flow::pair")]
        angles_deg: [f64; 2],
        span_deg: f64,
        max_velocity: f64,
    },
    /// Independent jets on one body (any shape), one action each: jet `k` blows with
    /// `a_k * max_velocity` (negative: suction). Net mass flux is not zero.
    /// Bound: `max_velocity` in units of U (peak of the parabolic jet profile).
    Jets { body: usize, jets: Vec<Jet>, max_velocity: f64 },
    /// Surface rotation of the listed circular bodies, one action each.
    /// Bound: `max_omega` in units of U/D.
    Rotation { bodies: Vec<usize>, max_omega: f64 },
    /// The inlet temperature (needs `thermal`): each action changes it by at most `max_change`
    /// (units of T_wall), kept within `range`; it starts at `thermal.inlet_temperature`.
    InletTemperature { max_change: f64, range: [f64; 2] },
}

impl ActuationSpec {
    pub fn dim(&self) -> usize {
        match self {
            ActuationSpec::ZnmfJets { .. } => 1,
            ActuationSpec::Jets { jets, .. } => jets.len(),
            ActuationSpec::ZnmfJetsPerBody { bodies, .. } => bodies.len(),
            ActuationSpec::Rotation { bodies, .. } => bodies.len(),
            ActuationSpec::InletTemperature { .. } => 1,
        }
    }
}

/// Reward of one control interval, from the interval-averaged force coefficients.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RewardSpec {
    /// `r = -sum_b |C_D,b| - w sum_b |C_L,b|` (cylinder, square cylinder, pinball).
    DragLift { lift_weight: f64 },
    /// `r = -|sum_b C_D,b| - w |sum_b C_L,b|` (the paper's fluidic pinball).
    TotalDragLift { lift_weight: f64 },
    /// `r = -sum_i ((o_i - mean_i) / std_i)^2` over every observation (the paper's open cavity):
    /// the deviation of the probes from the uncontrolled flow's mean, in units of its standard
    /// deviation. Mean and std are the calibrated normalisation (`scale` = 3 std), so this is
    /// `-9 sum_i obs_i^2` of the normalised observation at the end of the interval.
    ProbeDeviation,
    /// `r = -|C_L - c_l_ref| - w |C_D - c_d_ref|` (the paper's gust mitigation): force deviation
    /// from the time-averaged coefficients of the undisturbed flow, with `w = drag_weight`.
    /// `coarse` holds the undisturbed flow's `[C_L, C_D]` at the coarse level where its
    /// under-resolved flow has other mean forces: the references there (see [`Self::at_level`]).
    GustLoads {
        c_l_ref: f64,
        c_d_ref: f64,
        drag_weight: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        coarse: Option<[f64; 2]>,
    },
    /// `-weight |T(probe) / T_wall - target|` (the stenotic pipe; `T_target` in info).
    ProbeTemperature { probe: usize, target: f64, weight: f64 },
}

impl RewardSpec {
    /// The reward as an environment at `level` computes it: the gust reward takes its
    /// references from the undisturbed flow at the same level (its `coarse` pair at coarse), so
    /// that `C_L - C_L,ref` measures the gust and the control, not the grid's offset.
    pub fn at_level(&self, level: Level) -> RewardSpec {
        match self {
            RewardSpec::GustLoads {
                drag_weight,
                coarse: Some([c_l, c_d]),
                ..
            } if level == Level::Coarse => RewardSpec::GustLoads {
                c_l_ref: *c_l,
                c_d_ref: *c_d,
                drag_weight: *drag_weight,
                coarse: None,
            },
            other => other.clone(),
        }
    }

    /// `C_L - c_l_ref`, the lift's deviation from the undisturbed flow's mean (info `dC_L`), for
    /// the gust reward; `None` for the rewards without a reference lift.
    pub fn lift_deviation(&self, c_l: f64) -> Option<f64> {
        match self {
            RewardSpec::GustLoads { c_l_ref, .. } => Some(c_l - c_l_ref),
            _ => None,
        }
    }
}

/// Observation normalisation `obs = (raw - mean) / scale`, computed by `hgym envs calibrate`
/// from an uncontrolled run (`scale` = 3 standard deviations, so values fall in about [-1, 1]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Normalization {
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
}

impl Normalization {
    /// `obs = (raw - mean) / scale` in place, when calibrated for this many observations (raw
    /// values otherwise).
    pub fn apply(&self, obs: &mut [f64]) {
        if self.mean.len() == obs.len() && self.scale.len() == obs.len() {
            for ((o, m), s) in obs.iter_mut().zip(&self.mean).zip(&self.scale) {
                *o = (*o - m) / s;
            }
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvSpec {
    pub id: String,
    pub family: String,
    pub description: String,
    pub reynolds: f64,
    pub bodies: Vec<GeometrySpec>,
    pub domain: DomainSpec,
    pub boundaries: BoundarySpec,
    /// Cells per reference length at each level.
    pub resolution: ResolutionSpec,
    pub lattice_velocity: f64,
    pub collision: Collision,
    pub smagorinsky: f64,
    pub actuation: ActuationSpec,
    /// Smoothing of each action change over the control interval.
    pub ramp: Ramp,
    /// Point probes of (u, v, p); the observation is their values in this order.
    #[serde(deserialize_with = "crate::flow::pairs")]
    pub probes: Vec<[f64; 2]>,
    pub reward: RewardSpec,
    /// Physical time between actions (L/U); the solver steps per action follow from it.
    pub control_interval: f64,
    /// Actions per episode; `truncated` is true on the last one.
    pub episode_actions: usize,
    /// Uncontrolled run before the first episode (L/U), to reach the attractor.
    pub spin_up: f64,
    /// Empty until calibrated.
    #[serde(default)]
    pub normalization: Normalization,
    /// A transverse gust entering through the inlet during each episode (none: steady inflow).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust: Option<GustSpec>,
    /// An absorbing layer along one edge (the open cavity's top), relaxing to the free stream.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sponge: Option<Box<SpongeSpec>>,
    /// Temperature carried by the flow (observed as a fourth value per probe).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<Box<ThermalSpec>>,
    /// Oscillatory inflow instead of a steady one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inflow: Option<Box<InflowSpec>>,
}

/// A passive temperature field (D2Q5, `hgym_solvers::lbm::thermal`): diffusivity `nu / Pr`;
/// temperatures in units of the wall temperature, which bodies and the north and south sides
/// hold; the west side holds the inlet temperature (the actuator), the east side is open.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    pub prandtl: f64,
    pub wall_temperature: f64,
    /// The inlet temperature at the start of every episode (and during the spin-up).
    pub inlet_temperature: f64,
    /// The fluid's temperature when the spin-up starts.
    pub initial_temperature: f64,
}

/// Oscillatory inflow through the west side: a Poiseuille profile of mean velocity `U s(t)`,
/// `s(t) = sin(omega t) + noise xi_k`, with `omega` from the Womersley number
/// `alpha = (D / 2) sqrt(omega / nu)`, i.e. `omega = 4 alpha^2 / Re` in units of U / D, and
/// `xi_k` a standard normal number drawn once per control interval `k` from the episode's seed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InflowSpec {
    pub womersley: f64,
    pub noise: f64,
}

impl InflowSpec {
    /// Angular frequency in units of U / D at Reynolds number `re`.
    pub fn omega(&self, re: f64) -> f64 {
        4.0 * self.womersley * self.womersley / re
    }

    /// The inflow's scale `s(t)` at time `t` (D/U) of a run seeded `seed` at Reynolds number
    /// `re`, its noise drawn once per control interval `interval`.
    pub fn scale(&self, re: f64, t: f64, interval: f64, seed: u64) -> f64 {
        let k = (t / interval).floor().max(0.0) as u64;
        (self.omega(re) * t).sin() + self.noise * super::seeding::gaussian(seed, k)
    }

    /// The inlet an oscillatory inflow needs (Poiseuille of mean U), or the uniform one.
    pub fn inlet(inflow: Option<&InflowSpec>) -> InletSpec {
        match inflow {
            None => InletSpec::default(),
            Some(_) => InletSpec {
                profile: Profile::Parabolic,
                reference_velocity: VelocityReference::Mean,
                ..InletSpec::default()
            },
        }
    }
}

/// A "1 - cos" transverse gust imposed at the inflow (the paper's gust-airfoil set-up): the
/// inlet's transverse velocity is `v(t) = (G / 2) (1 - cos(2 pi (t - start) / duration)) U` for
/// `start <= t <= start + duration` (episode time, L/U) and zero otherwise; `G = ratio` is the
/// peak gust velocity over U. The gust then convects with the flow towards the body.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GustSpec {
    pub ratio: f64,
    pub start: f64,
    pub duration: f64,
}

impl GustSpec {
    /// Transverse inlet velocity (units of U) at episode time `t`.
    pub fn velocity(&self, t: f64) -> f64 {
        let s = (t - self.start) / self.duration;
        if (0.0..=1.0).contains(&s) {
            0.5 * self.ratio * (1.0 - (2.0 * std::f64::consts::PI * s).cos())
        } else {
            0.0
        }
    }
}

impl EnvSpec {
    /// SHA-256 of the spec's JSON form (what changes the physics changes the hash).
    pub fn hash(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        format!("{:x}", Sha256::digest(json.as_bytes()))
    }

    /// `(u, v, p)` per probe, and `T` with a temperature field.
    pub fn obs_dim(&self) -> usize {
        (3 + usize::from(self.thermal.is_some())) * self.probes.len()
    }

    pub fn act_dim(&self) -> usize {
        self.actuation.dim()
    }

    pub fn cells_per_length(&self, level: Level) -> u32 {
        self.resolution.at(level)
    }

    /// The bundled validation case whose literature references this environment's uncontrolled
    /// flow is compared with (`hgym validate --env ID`), by family and Reynolds number, e.g.
    /// `cylinder_re100`; none for families without 2D references here (cavity, aerofoil, pipe).
    pub fn validation_case(&self) -> Option<String> {
        let base = match self.family.as_str() {
            "cylinder" | "rotary_cylinder" => "cylinder",
            "pinball" | "jet_pinball" => "pinball",
            "square_cylinder" => "square",
            _ => return None,
        };
        Some(format!("{base}_re{}", self.reynolds.round() as i64))
    }

    /// Every field a `--config` can change, checked before anything is built: the flow (as
    /// validation checks it), the episode, and probes (at least one, at finite positions).
    pub(crate) fn check(&self) -> Result<(), String> {
        self.flow_setup().check().map_err(|e| e.to_string())?;
        super::family::check_episode(self.control_interval, self.episode_actions, self.spin_up)?;
        check_probes(&self.probes)
    }

    /// The flow this environment runs (what `FlowSetup::build` makes its solver from): a
    /// uniform inlet, or with `inflow` a Poiseuille profile of mean U whose scale oscillates.
    pub fn flow_setup(&self) -> FlowSetup {
        let inlet = InflowSpec::inlet(self.inflow.as_deref());
        FlowSetup {
            bodies: self.bodies.clone(),
            domain: self.domain.clone(),
            boundaries: self.boundaries.clone(),
            inlet,
            reynolds: self.reynolds,
            lattice_velocity: self.lattice_velocity,
            collision: self.collision,
            smagorinsky: self.smagorinsky,
            resolution: self.resolution.clone(),
            sponges: self.sponge.iter().map(|s| (**s).clone()).collect(),
            refinement: None,
            span: None,
        }
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the spec as TOML: {e}\n"))
    }
}

/// At least one probe, every one at a finite position.
pub(crate) fn check_probes(probes: &[[f64; 2]]) -> Result<(), String> {
    if probes.is_empty() {
        return Err("probes must list at least one [x, y] position (the observation)".into());
    }
    if let Some(p) = probes.iter().find(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(format!("probe {p:?} is not a finite position"));
    }
    Ok(())
}

/// Probes on the grid `xs x ys` (x-major), the usual wake rake.
pub fn probe_grid(xs: &[f64], ys: &[f64]) -> Vec<[f64; 2]> {
    xs.iter().flat_map(|&x| ys.iter().map(move |&y| [x, y])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's 1 - cos gust: zero before and after, peak G at mid-duration, continuous.
    #[test]
    fn gust_is_one_minus_cosine_with_peak_ratio() {
        let g = GustSpec {
            ratio: 2.0,
            start: 2.0,
            duration: 2.0,
        };
        assert_eq!(g.velocity(1.99), 0.0);
        assert_eq!(g.velocity(4.01), 0.0);
        assert!((g.velocity(3.0) - 2.0).abs() < 1e-12);
        assert!((g.velocity(2.5) - 1.0).abs() < 1e-12);
        assert!(g.velocity(2.0).abs() < 1e-12 && g.velocity(4.0).abs() < 1e-12);
        let mut t = 1.5;
        while t < 4.5 {
            assert!((g.velocity(t + 1e-4) - g.velocity(t)).abs() < 1e-3, "jump at t = {t}");
            t += 1e-3;
        }
    }
}
