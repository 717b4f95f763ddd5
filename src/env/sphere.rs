//! Sphere family (HydroGym "Flow around a sphere"): `Sphere_3D_Re{300,3700}`.
//!
//! Set-up from the paper: a sphere of diameter D at (8, 8, 8) in [0, 32] x [0, 16] x [0, 16] D,
//! uniform inflow, open outlet; the paper's lateral outlets are free-slip walls here (a 16 D
//! wide box blocks 0.3 % of it), with 1 D absorbing layers along them and the outlet, as in the
//! validation cases (`sphere_re300.toml`). Actuation: eight round jets on the rear half, on the circle
//! 60 degrees from the rear stagnation point (the +x axis), 45 degrees apart around it, blowing
//! along the normal, one action each (bound 1.0 U, parabolic profile). The paper does not give
//! their size: 15 degrees of arc from axis to rim, so the coarse level resolves a few links per
//! jet. Reward as for the cylinder, `-|C_D| - w |(C_L, C_S)|`; probes: the cylinder's wake rake
//! (1 to 5 D behind the centre, within 1 D of the axis) in the mid-plane z = 8, as in the paper's
//! figure. Control interval: a twentieth of the shedding period (St 0.137 at Re 300, Johnson &
//! Patel 1999; about 0.2 at Re 3700): 0.36 and 0.25 D/U. Re 3700 runs with the Smagorinsky
//! subgrid viscosity (C_s = 0.1). Levels: 6, 16 and 24 cells per D (the coarse grid, 1.8 million
//! nodes, keeps an action under 2 s on two cores).

use hgym_solvers::lbm::Collision;

use super::actuation::Ramp;
use super::spec::{probe_grid, Normalization, RewardSpec};
use super::spec3::{Actuation3Spec, Env3Spec, Jet3};
use crate::flow::{BoundaryKind, BoundarySpec, DomainSpec, EdgeName, GeometrySpec, ResolutionSpec, SpanSpec, SpongeSpec};

pub const REYNOLDS: [u32; 2] = [300, 3700];

/// Centre of the sphere (and of the cube, which shares the box).
pub const CENTER: [f64; 3] = [8.0, 8.0, 8.0];

pub struct Sphere;

impl super::family::Family for Sphere {
    fn specs(&self) -> Vec<super::family::Spec> {
        super::registry::lbm3(REYNOLDS.map(sphere))
    }
}

/// The eight rear jets.
pub fn jets() -> Vec<Jet3> {
    let polar = 60f64.to_radians();
    (0..8)
        .map(|k| {
            let phi = (45.0 * k as f64).to_radians();
            let axis = [polar.cos(), polar.sin() * phi.cos(), polar.sin() * phi.sin()];
            Jet3::on_sphere(CENTER, 0.5, axis, 15.0)
        })
        .collect()
}

/// The paper's 3D box around a body at [`CENTER`] (shared with the cube): inflow at x = 0, open
/// outlet at x = 32, free-slip walls on the four sides, the wake rake in the mid-plane.
#[allow(clippy::too_many_arguments)]
pub(super) fn in_box(
    id: String,
    family: &str,
    description: String,
    re: u32,
    body: GeometrySpec,
    actuation: Actuation3Spec,
    control_interval: f64,
    resolution: ResolutionSpec,
) -> Env3Spec {
    let c = CENTER;
    Env3Spec {
        id,
        family: family.into(),
        description,
        reynolds: re as f64,
        bodies: vec![body],
        domain: DomainSpec {
            x: [0.0, 32.0],
            y: [0.0, 16.0],
        },
        boundaries: BoundarySpec {
            west: BoundaryKind::Inlet,
            east: BoundaryKind::Outlet,
            south: BoundaryKind::FreeSlip,
            north: BoundaryKind::FreeSlip,
        },
        span: SpanSpec {
            z: [0.0, 16.0],
            boundary: BoundaryKind::FreeSlip,
            segments: 1,
            lattice: Default::default(),
        },
        resolution,
        lattice_velocity: 0.05,
        collision: Collision::Regularized,
        smagorinsky: if re >= 1000 { 0.1 } else { 0.0 },
        actuation,
        ramp: Ramp::default(),
        probes: probe_grid(
            &[c[0] + 1.0, c[0] + 2.0, c[0] + 3.5, c[0] + 5.0],
            &[c[1] - 1.0, c[1] - 0.5, c[1], c[1] + 0.5, c[1] + 1.0],
        ),
        reward: RewardSpec::DragLift { lift_weight: 1.0 },
        agent_reward: Default::default(),
        control_interval,
        episode_actions: 200,
        spin_up: 60.0,
        normalization: Normalization::default(),
        // The validation cases' layers: without them the box's acoustic mode between the
        // free-slip sides rings in the lift (St 0.31 in sphere_re300 at coarse).
        sponges: [EdgeName::South, EdgeName::North, EdgeName::East]
            .map(|edge| SpongeSpec {
                edge,
                thickness: 1.0,
                strength: 0.05,
            })
            .into(),
        gust: None,
        thermal: None,
        inflow: None,
    }
}

/// `Sphere_3D_Re{re}`.
pub fn sphere(re: u32) -> Env3Spec {
    in_box(
        format!("Sphere_3D_Re{re}"),
        "sphere",
        format!("Sphere at Re {re}, eight independent jets on the rear half"),
        re,
        GeometrySpec::Sphere {
            center: CENTER,
            diameter: 1.0,
        },
        Actuation3Spec::SurfaceJets {
            body: 0,
            jets: jets(),
            max_velocity: 1.0,
        },
        if re == 300 { 0.36 } else { 0.25 },
        ResolutionSpec {
            coarse: 6,
            default: 16,
            fine: 24,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every jet sits on the sphere's surface, 60 degrees from the rear axis, blowing outward.
    #[test]
    fn jets_ring_the_rear_half() {
        for j in jets() {
            let r: Vec<f64> = (0..3).map(|a| j.center[a] - CENTER[a]).collect();
            let dist = r.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!((dist - 0.5).abs() < 1e-12);
            assert!((r[0] / dist - 0.5).abs() < 1e-12, "60 degrees from +x");
            let n = j.direction;
            assert!((n[0] * r[0] + n[1] * r[1] + n[2] * r[2]) / dist > 0.999, "blows outward");
        }
    }
}
