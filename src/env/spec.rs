//! Environment specs: plain serialisable values (`hgym envs show ID` prints one as TOML). A spec
//! fixes the physics, the actuators, the probes, the reward and the timing; its hash goes into
//! every result and keys the cache of developed-flow states. `build()` makes the running env.
//!
//! Units: lengths in the body's reference length (diameter), velocities in U, times in L/U.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use hgym_solvers::lbm::Collision;

use super::actuation::{Jet, Ramp};
use crate::validate::case::{BoundarySpec, DomainSpec, GeometrySpec, Level, ResolutionSpec};

/// The actuators of an environment; actions in `[-1, 1]` are scaled by the bound given here.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ActuationSpec {
    /// Zero-net-mass-flux jet pair on a circular body: one action `a`; the jet at
    /// `angles_deg[0]` blows with `a * max_velocity`, the one at `angles_deg[1]` sucks the same.
    /// Bound: `max_velocity` in units of U (peak of the parabolic jet profile).
    ZnmfJets {
        body: usize,
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
}

impl ActuationSpec {
    pub fn dim(&self) -> usize {
        match self {
            ActuationSpec::ZnmfJets { .. } => 1,
            ActuationSpec::Jets { jets, .. } => jets.len(),
            ActuationSpec::Rotation { bodies, .. } => bodies.len(),
        }
    }
}

/// Reward of one control interval, from the interval-averaged force coefficients.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RewardSpec {
    /// `r = -sum_b |C_D,b| - w sum_b |C_L,b|` (cylinder, square cylinder, pinball).
    DragLift { lift_weight: f64 },
}

/// Observation normalisation `obs = (raw - mean) / scale`, computed by `hgym envs calibrate`
/// from an uncontrolled run (`scale` = 3 standard deviations, so values fall in about [-1, 1]).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct Normalization {
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
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
}

impl EnvSpec {
    /// SHA-256 of the spec's JSON form (what changes the physics changes the hash).
    pub fn hash(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        format!("{:x}", Sha256::digest(json.as_bytes()))
    }

    pub fn obs_dim(&self) -> usize {
        3 * self.probes.len()
    }

    pub fn act_dim(&self) -> usize {
        self.actuation.dim()
    }

    pub fn cells_per_length(&self, level: Level) -> u32 {
        match level {
            Level::Coarse => self.resolution.coarse,
            Level::Default => self.resolution.default,
            Level::Fine => self.resolution.fine,
        }
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the spec as TOML: {e}\n"))
    }
}

/// Probes on the grid `xs x ys` (x-major), the usual wake rake.
pub fn probe_grid(xs: &[f64], ys: &[f64]) -> Vec<[f64; 2]> {
    xs.iter().flat_map(|&x| ys.iter().map(move |&y| [x, y])).collect()
}
