//! Specs of the 3D lattice-Boltzmann environments (`*_3D_*`): the 2D spec's fields plus a span
//! cut into segments, actuators per segment or on a body's surface, and probes repeated in each
//! segment's mid-plane. [`super::lbm_env3::LbmEnv3`] runs them.
//!
//! Layout of the vectors (what multi-agent training splits, one agent per segment):
//! - observation: for segment `s`, probe `p`: `(u, v, w, p)` at `4 (s P + p)`, units of U and
//!   rho U^2, at `(x_p, y_p, z_s)` with `z_s` the segment's mid-plane; with a temperature field
//!   `(u, v, w, p, T)` at `5 (s P + p)`, T in units of the wall temperature;
//! - action: a section actuator (`segments`) acts on each segment separately, its `k`-th action of
//!   segment `s` at `s K + k`; surface jets (`surface_jets`) have one action each.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use hgym_agents::multi::AgentReward;
use hgym_solvers::lbm::Collision;

use super::actuation::Ramp;
use super::spec::{ActuationSpec, GustSpec, InflowSpec, Normalization, RewardSpec, SpongeSpec, ThermalSpec};
use crate::flow::{BoundarySpec, DomainSpec, FlowSetup, GeometrySpec, ResolutionSpec, SpanSpec};

/// The actuators of a 3D environment; actions in `[-1, 1]` are scaled by the bound given here.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Actuation3Spec {
    /// A 2D actuator (jets or rotation on an extruded section, as in the 2D environments)
    /// repeated on every spanwise segment, each segment with its own actions.
    Segments { actuator: ActuationSpec },
    /// Independent jets on the surface of one body (sphere, cube), one action each.
    /// Bound: `max_velocity` in units of U (peak of the parabolic jet profile).
    SurfaceJets { body: usize, jets: Vec<Jet3>, max_velocity: f64 },
}

/// A jet on a body's surface: round (`length` 0, diameter `width`) or a slot (`length` along
/// `slot_axis`, `width` across it). Profile `u_w = A (1 - (2 d / W)^2) n` with `d` the distance
/// from the jet's axis (round) or from its centre line (slot), for `d <= W / 2`, within the slot's
/// length, and within `W` of the exit plane along `n` (a jet stays on its own face).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Jet3 {
    /// Centre of the exit on the wall.
    #[serde(deserialize_with = "crate::flow::triple")]
    pub center: [f64; 3],
    /// Blowing direction (normalised when used).
    #[serde(deserialize_with = "crate::flow::triple")]
    pub direction: [f64; 3],
    pub width: f64,
    /// A slot's length along `slot_axis`; 0 for a round jet.
    #[serde(default)]
    pub length: f64,
    #[serde(default)]
    pub slot_axis: [f64; 3],
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / n)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Jet3 {
    /// A round jet on a sphere of `radius` about `center`, centred in the direction `axis`,
    /// blowing radially outward, `half_angle_deg` of arc from its axis to its rim.
    pub fn on_sphere(center: [f64; 3], radius: f64, axis: [f64; 3], half_angle_deg: f64) -> Self {
        let n = unit(axis);
        Jet3 {
            center: [0, 1, 2].map(|a| center[a] + radius * n[a]),
            direction: n,
            width: 2.0 * radius * half_angle_deg.to_radians().sin(),
            length: 0.0,
            slot_axis: [0.0; 3],
        }
    }

    /// The spatial profile (zero outside the jet).
    pub fn profile(&self, p: [f64; 3]) -> [f64; 3] {
        let n = unit(self.direction);
        let r = [0, 1, 2].map(|a| p[a] - self.center[a]);
        let along = dot(r, n);
        let mut perp = [0, 1, 2].map(|a| r[a] - along * n[a]);
        if along.abs() > self.width {
            return [0.0; 3];
        }
        if self.length > 0.0 {
            let s = unit(self.slot_axis);
            let on_axis = dot(perp, s);
            if on_axis.abs() > 0.5 * self.length {
                return [0.0; 3];
            }
            perp = [0, 1, 2].map(|a| perp[a] - on_axis * s[a]);
        }
        let d = dot(perp, perp).sqrt();
        let half = 0.5 * self.width;
        if d > half {
            return [0.0; 3];
        }
        let s = 1.0 - (d / half).powi(2);
        n.map(|c| s * c)
    }

    fn check(&self) -> Result<(), String> {
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        if !finite(&self.center) || !finite(&self.direction) || dot(self.direction, self.direction) == 0.0 {
            return Err("a jet needs a finite centre and a nonzero finite direction".into());
        }
        if !(self.width.is_finite() && self.width > 0.0) {
            return Err(format!("a jet's width must be a positive length, got {}", self.width));
        }
        if !(self.length.is_finite() && self.length >= 0.0) {
            return Err(format!("a slot's length must be zero (round) or positive, got {}", self.length));
        }
        if self.length > 0.0 && (!finite(&self.slot_axis) || dot(self.slot_axis, self.slot_axis) == 0.0) {
            return Err("a slot (length > 0) needs a nonzero slot_axis".into());
        }
        Ok(())
    }
}

impl Actuation3Spec {
    /// Actions per segment of a section actuator, or all of the surface jets'.
    pub fn dim(&self, segments: usize) -> usize {
        match self {
            Actuation3Spec::Segments { actuator } => actuator.dim() * segments,
            Actuation3Spec::SurfaceJets { jets, .. } => jets.len(),
        }
    }

    /// The bound of the physical actuation (units of U or U/D).
    pub fn bound(&self) -> f64 {
        match self {
            Actuation3Spec::Segments { actuator } => match actuator {
                ActuationSpec::ZnmfJets { max_velocity, .. }
                | ActuationSpec::ZnmfJetsPerBody { max_velocity, .. }
                | ActuationSpec::Jets { max_velocity, .. } => *max_velocity,
                ActuationSpec::Rotation { max_omega, .. } => *max_omega,
                ActuationSpec::InletTemperature { max_change, .. } => *max_change,
            },
            Actuation3Spec::SurfaceJets { max_velocity, .. } => *max_velocity,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Env3Spec {
    pub id: String,
    pub family: String,
    pub description: String,
    pub reynolds: f64,
    pub bodies: Vec<GeometrySpec>,
    pub domain: DomainSpec,
    pub boundaries: BoundarySpec,
    pub span: SpanSpec,
    /// Cells per reference length at each level.
    pub resolution: ResolutionSpec,
    pub lattice_velocity: f64,
    pub collision: Collision,
    pub smagorinsky: f64,
    pub actuation: Actuation3Spec,
    /// Smoothing of each action change over the control interval.
    pub ramp: Ramp,
    /// Probe positions `[x, y]`, observed in the mid-plane of every spanwise segment.
    #[serde(deserialize_with = "crate::flow::pairs")]
    pub probes: Vec<[f64; 2]>,
    /// `drag_lift` or `total_drag_lift`, with the lift the lateral force `(C_L, C_S)`'s magnitude,
    /// `gust_loads` (lift `C_L`, the y force), or `probe_deviation`.
    pub reward: RewardSpec,
    /// The reward each agent of multi-agent training (one per segment) learns from: the
    /// environment's, or its own segment's `-sum_b |C_D,b,s| - w sum_b |(C_L, C_S)_b,s|`.
    #[serde(default)]
    pub agent_reward: AgentReward,
    /// Physical time between actions (L/U).
    pub control_interval: f64,
    pub episode_actions: usize,
    /// Uncontrolled run before the first episode (L/U).
    pub spin_up: f64,
    #[serde(default)]
    pub normalization: Normalization,
    /// Absorbing layers along x or y faces (the open cavity's top; the sphere's and cube's sides
    /// and outlet).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sponges: Vec<SpongeSpec>,
    /// A transverse gust entering through the inlet during each episode (as in 2D).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gust: Option<GustSpec>,
    /// A passive temperature field (D3Q7, `hgym_solvers::lbm::d3::Thermal3`), as in 2D: walls
    /// at `wall_temperature`, the inlet at the inlet temperature, zero gradient at an outlet.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<Box<ThermalSpec>>,
    /// Oscillatory inflow (a pipe's Poiseuille profile whose scale oscillates), as in 2D.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inflow: Option<Box<InflowSpec>>,
}

impl Env3Spec {
    /// SHA-256 of the spec's JSON form.
    pub fn hash(&self) -> String {
        let json = serde_json::to_string(self).unwrap_or_default();
        format!("{:x}", Sha256::digest(json.as_bytes()))
    }

    pub fn segments(&self) -> usize {
        self.span.segments
    }

    /// `(u, v, w, p)`, and `T` with a temperature field, per probe and segment.
    pub fn obs_dim(&self) -> usize {
        self.per_probe() * self.probes.len() * self.segments()
    }

    /// Values observed at each probe: `(u, v, w, p)`, and `T` with a temperature field.
    pub fn per_probe(&self) -> usize {
        4 + usize::from(self.thermal.is_some())
    }

    pub fn act_dim(&self) -> usize {
        self.actuation.dim(self.segments())
    }

    /// The probes in 3D, segment by segment: `(x, y)` at each segment's mid-plane.
    pub fn probe_points(&self) -> Vec<[f64; 3]> {
        let (z0, seg) = (self.span.z[0], self.span.length() / self.segments() as f64);
        (0..self.segments())
            .flat_map(|s| self.probes.iter().map(move |p| [p[0], p[1], z0 + (s as f64 + 0.5) * seg]))
            .collect()
    }

    /// The bundled 3D validation case of this flow (`sphere_re300`, `cube_re300`): the bodies
    /// of their own, not the extruded 2D sections, whose cases are 2D.
    pub fn validation_case(&self) -> Option<String> {
        matches!(self.family.as_str(), "sphere" | "cube").then(|| format!("{}_re{}", self.family, self.reynolds.round() as i64))
    }

    /// The flow this environment runs: a uniform rigid inlet (with `inflow`, a pipe's
    /// Poiseuille profile of mean U whose scale oscillates) and the span.
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
            sponges: self.sponges.clone(),
            refinement: None,
            span: Some(self.span.clone()),
        }
    }

    /// Everything a `--config` can change, checked before anything is built: the flow, the
    /// episode, the probes, the actuators (a section actuator with its bodies, surface jets on an
    /// existing body) and a force reward.
    pub(crate) fn check(&self) -> Result<(), String> {
        self.flow_setup().check().map_err(|e| e.to_string())?;
        super::family::check_episode(self.control_interval, self.episode_actions, self.spin_up)?;
        super::spec::check_probes(&self.probes)?;
        match &self.actuation {
            Actuation3Spec::Segments { actuator } => {
                if let ActuationSpec::InletTemperature { range, .. } = actuator {
                    if self.thermal.is_none() {
                        return Err("actuation: an inlet-temperature actuator needs a [thermal] section".into());
                    }
                    if self.segments() != 1 {
                        return Err("actuation: the inlet temperature is one actuator; use one segment (span.segments = 1)".into());
                    }
                    if !(range[0].is_finite() && range[1].is_finite() && range[0] < range[1]) {
                        return Err(format!("actuation: range must be [low, high] with low < high, got {range:?}"));
                    }
                } else {
                    super::actuation::resolve(actuator, &self.bodies).map_err(|m| format!("actuation: {m}"))?;
                }
            }
            Actuation3Spec::SurfaceJets { body, jets, .. } => {
                if *body >= self.bodies.len() {
                    return Err(format!("actuation: jets on body {body}, which does not exist"));
                }
                if jets.is_empty() {
                    return Err("actuation: list at least one jet".into());
                }
                for (k, j) in jets.iter().enumerate() {
                    j.check().map_err(|m| format!("actuation: jet {k}: {m}"))?;
                }
            }
        }
        let b = self.actuation.bound();
        if !(b.is_finite() && b > 0.0) {
            return Err(format!("actuation: the bound must be a positive number, got {b}"));
        }
        match &self.reward {
            RewardSpec::DragLift { .. } | RewardSpec::TotalDragLift { .. } | RewardSpec::ProbeDeviation | RewardSpec::GustLoads { .. } => {}
            RewardSpec::ProbeTemperature { probe, .. } => {
                if self.thermal.is_none() {
                    return Err("reward: probe_temperature needs a [thermal] section".into());
                }
                if *probe >= self.probes.len() {
                    return Err(format!("reward: probe {probe} does not exist ({} probes)", self.probes.len()));
                }
            }
        }
        if let Some(th) = &self.thermal {
            let values = [th.prandtl, th.wall_temperature, th.inlet_temperature, th.initial_temperature];
            if !(values.iter().all(|v| v.is_finite()) && th.prandtl > 0.0) {
                return Err(format!("thermal: needs a positive prandtl and finite temperatures, got {th:?}"));
            }
        }
        if let Some(inflow) = &self.inflow {
            if self.boundaries.west != crate::flow::BoundaryKind::Inlet {
                return Err("inflow: an oscillatory inflow enters through the inlet; make the west boundary an inlet".into());
            }
            if !(inflow.womersley.is_finite() && inflow.womersley > 0.0 && inflow.noise.is_finite() && inflow.noise >= 0.0) {
                return Err(format!(
                    "inflow: needs a positive womersley number and a noise >= 0, got {inflow:?}"
                ));
            }
        }
        if self.gust.is_some() && self.boundaries.west != crate::flow::BoundaryKind::Inlet {
            return Err("gust: a gust enters through the inlet; make the west boundary an inlet".into());
        }
        Ok(())
    }

    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the spec as TOML: {e}\n"))
    }
}

/// The 3D version of a 2D environment: the same bodies (sections extruded along the span),
/// boundaries, flow numbers, actuator (on every segment separately), probes, reward and timing,
/// in the x-y box `domain` over `span`, at `resolution`. With more than one segment each agent
/// learns from its own segment's reward.
pub fn extrude(
    base: super::spec::EnvSpec,
    id: String,
    description: String,
    domain: DomainSpec,
    span: SpanSpec,
    resolution: ResolutionSpec,
) -> Env3Spec {
    let agent_reward = if span.segments > 1 {
        AgentReward::Local
    } else {
        AgentReward::Global
    };
    Env3Spec {
        id,
        family: base.family,
        description,
        reynolds: base.reynolds,
        bodies: base.bodies,
        domain,
        boundaries: base.boundaries,
        span,
        resolution,
        lattice_velocity: base.lattice_velocity,
        collision: base.collision,
        smagorinsky: base.smagorinsky,
        actuation: Actuation3Spec::Segments { actuator: base.actuation },
        ramp: base.ramp,
        probes: base.probes,
        reward: base.reward,
        agent_reward,
        control_interval: base.control_interval,
        episode_actions: base.episode_actions,
        spin_up: base.spin_up,
        normalization: Normalization::default(),
        sponges: base.sponge.into_iter().map(|s| *s).collect(),
        gust: base.gust,
        thermal: base.thermal,
        inflow: base.inflow,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_jet_is_parabolic_about_its_axis_and_local() {
        let j = Jet3::on_sphere([0.0; 3], 0.5, [1.0, 0.0, 0.0], 15.0);
        let peak = j.profile([0.5, 0.0, 0.0]);
        assert!((peak[0] - 1.0).abs() < 1e-12 && peak[1] == 0.0 && peak[2] == 0.0);
        let rim = 0.5 * 15f64.to_radians().sin();
        let edge = j.profile([0.5 * 15f64.to_radians().cos(), rim, 0.0]);
        assert!(edge[0].abs() < 1e-9, "{edge:?}");
        assert_eq!(j.profile([-0.5, 0.0, 0.0]), [0.0; 3], "the opposite side of the sphere");
        let half = j.profile([0.5, 0.5 * rim, 0.0]);
        assert!((half[0] - 0.75).abs() < 1e-12, "{half:?}");
    }

    #[test]
    fn slot_covers_its_length_and_not_beyond() {
        let j = Jet3 {
            center: [0.0, 0.5, 0.0],
            direction: [0.0, 1.0, 0.0],
            width: 0.2,
            length: 0.8,
            slot_axis: [0.0, 0.0, 1.0],
        };
        assert_eq!(j.profile([0.0, 0.5, 0.39]), [0.0, 1.0, 0.0]);
        assert_eq!(j.profile([0.0, 0.5, 0.41]), [0.0; 3]);
        assert!((j.profile([0.05, 0.5, 0.0])[1] - 0.75).abs() < 1e-12);
        assert_eq!(j.profile([0.0, -0.5, 0.0]), [0.0; 3]);
    }
}
