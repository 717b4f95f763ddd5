//! Fluidic pinball (HydroGym "Fluidic pinball"; Noack et al. 2017; Deng et al. 2020):
//! `Pinball_2D_Re{30,75,100,150}`, three cylinders of diameter D on an equilateral triangle
//! pointing upstream, centres at (-1.299, 0), (0, 0.75), (0, -0.75) relative to the pinball centre
//! (10, 0), in the cylinder's domain [0, 40] x [-10, 10]. Actions: surface rotation of the three
//! cylinders, bound 2.0 U/D each (surface speed U). `JetPinball_2D_Re{...}`: a jet pair on each
//! cylinder instead (see [`jets`]).
//!
//! Reward, as the paper's environment appendix writes it: `r = -|sum_i C_D,i| - w |sum_i C_L,i|`
//! with `w = 1.0` at every Re (to keep policies from generating lift). The rear cylinders'
//! natural mean lifts (about +-0.36 at Re 30) cancel in the sum, so they do not enter the reward.
//! (Until this change the spec used `-sum_i |C_D,i| - 0.2 sum_i |C_L,i|`; results trained with
//! it carry the old spec hash.)
//!
//! Control interval: a twentieth of the natural period (200 actions ~ 10 periods), with
//! f0 = 0.065, 0.08, 0.090, 0.118 (Wang et al. 2023; Re 75 interpolated): 0.77, 0.62, 0.56 and
//! 0.42 D/U. Spin-up 150 D/U: the asymmetric (pitchfork) states above Re ~ 68 take long to settle.

use super::actuation::Ramp;
use super::spec::{probe_grid, ActuationSpec, EnvSpec, Normalization, RewardSpec};
use crate::flow::{BoundaryKind, BoundarySpec, DomainSpec, GeometrySpec, ResolutionSpec};

pub const REYNOLDS: [u32; 4] = [30, 75, 100, 150];

/// The fluidic pinball family: rotation, then jets, each over [`REYNOLDS`], then rotation in 3D
/// (`Pinball_3D_Re{...}`, `super::cylinder::in_3d`: span 4 D, one segment).
pub struct Pinball;

impl super::family::Family for Pinball {
    fn specs(&self) -> Vec<super::family::Spec> {
        let mut specs = super::registry::lbm(REYNOLDS.map(rotary).into_iter().chain(REYNOLDS.map(jets)));
        specs.extend(super::registry::lbm3(REYNOLDS.map(|re| super::cylinder::in_3d(rotary(re)))));
        specs
    }
}

/// Centre of the pinball (the triangle's reference point).
pub const CENTER: [f64; 2] = [10.0, 0.0];

fn control_interval(re: u32) -> f64 {
    match re {
        30 => 0.77,
        75 => 0.62,
        100 => 0.56,
        _ => 0.42,
    }
}

fn probes() -> Vec<[f64; 2]> {
    probe_grid(&[11.5, 12.5, 14.0, 16.0], &[-1.5, -0.75, 0.0, 0.75, 1.5])
}

/// The three cylinders: front, top rear, bottom rear.
pub fn bodies() -> Vec<GeometrySpec> {
    [[-1.299, 0.0], [0.0, 0.75], [0.0, -0.75]]
        .iter()
        .map(|o| GeometrySpec::Circle {
            center: [CENTER[0] + o[0], CENTER[1] + o[1]],
            diameter: 1.0,
        })
        .collect()
}

/// `JetPinball_2D_Re{re}`: the pinball with a zero-net-mass-flux jet pair at 90 and 270 degrees
/// on each cylinder (10 degrees wide, peak bound 1.0 U, as the cylinder family's), one action per
/// cylinder. The paper's standard pinball uses rotation and leaves jets to users; this is that
/// variant with HydroGym's name. Same flow, reward and timing as `Pinball_2D_Re{re}`, so the two
/// share the developed-flow state (the cache key leaves the actuators out); each is calibrated on
/// its own (its observation statistics are keyed on the whole spec).
pub fn jets(re: u32) -> EnvSpec {
    let mut s = rotary(re);
    s.id = format!("JetPinball_2D_Re{re}");
    s.family = "jet_pinball".into();
    s.description = format!("2D fluidic pinball at Re {re}, a zero-net-mass-flux jet pair on each cylinder");
    s.actuation = ActuationSpec::ZnmfJetsPerBody {
        bodies: vec![0, 1, 2],
        angles_deg: [90.0, 270.0],
        span_deg: 10.0,
        max_velocity: 1.0,
    };
    s
}

/// `Pinball_2D_Re{re}`.
pub fn rotary(re: u32) -> EnvSpec {
    EnvSpec {
        id: format!("Pinball_2D_Re{re}"),
        family: "pinball".into(),
        description: format!("2D fluidic pinball at Re {re}, rotation of the three cylinders"),
        reynolds: re as f64,
        bodies: bodies(),
        domain: DomainSpec {
            x: [0.0, 40.0],
            y: [-10.0, 10.0],
        },
        boundaries: BoundarySpec {
            west: BoundaryKind::Inlet,
            east: BoundaryKind::Outlet,
            south: BoundaryKind::Periodic,
            north: BoundaryKind::Periodic,
        },
        resolution: ResolutionSpec {
            coarse: 8,
            default: 24,
            fine: 40,
        },
        lattice_velocity: 0.05,
        collision: hgym_solvers::lbm::Collision::Regularized,
        smagorinsky: 0.0,
        actuation: ActuationSpec::Rotation {
            bodies: vec![0, 1, 2],
            max_omega: 2.0,
        },
        ramp: Ramp::default(),
        probes: probes(),
        reward: RewardSpec::TotalDragLift { lift_weight: 1.0 },
        control_interval: control_interval(re),
        episode_actions: 200,
        spin_up: 150.0,
        normalization: Normalization::default(),
        gust: None,
        sponge: None,
        thermal: None,
        inflow: None,
    }
}
