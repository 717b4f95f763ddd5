//! Fluidic pinball (HydroGym "Fluidic pinball"; Noack et al. 2017; Deng et al. 2020):
//! `Pinball_2D_Re{30,75,100,150}`, three cylinders of diameter D on an equilateral triangle
//! pointing upstream, centres at (-1.299, 0), (0, 0.75), (0, -0.75) relative to the pinball centre
//! (10, 0), in the cylinder's domain [0, 40] x [-10, 10]. Actions: surface rotation of the three
//! cylinders, bound 2.0 U/D each (surface speed U).
//!
//! Reward, as the paper writes it: `r = -sum_i |C_D,i| - w sum_i |C_L,i|`. The paper gives no
//! value for `w`; we take `w = 0.2` (the cylinder's value at Re 200): large enough that rotating
//! for Magnus lift does not pay, small enough that the rear cylinders' natural mean lift (up to
//! 0.36 at Re 30) does not dominate the drag term.
//!
//! Control interval: a twentieth of the natural period (200 actions ~ 10 periods), with
//! f0 = 0.065, 0.08, 0.090, 0.118 (Wang et al. 2023; Re 75 interpolated): 0.77, 0.62, 0.56 and
//! 0.42 D/U. Spin-up 150 D/U: the asymmetric (pitchfork) states above Re ~ 68 take long to settle.

use super::actuation::Ramp;
use super::spec::{probe_grid, ActuationSpec, EnvSpec, Normalization, RewardSpec};
use crate::validate::case::{BoundaryKind, BoundarySpec, DomainSpec, GeometrySpec, ResolutionSpec};

pub const REYNOLDS: [u32; 4] = [30, 75, 100, 150];

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
        reward: RewardSpec::DragLift { lift_weight: 0.2 },
        control_interval: control_interval(re),
        episode_actions: 200,
        spin_up: 150.0,
        normalization: Normalization::default(),
    }
}
