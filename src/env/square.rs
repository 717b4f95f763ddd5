//! Square cylinder family (HydroGym "Square cylinder flow"): `SquareCylinder_2D_Re{200,1000,3900}`.
//!
//! Same set-up as the circular cylinder (`super::cylinder::bluff_body`): a square of side D at
//! (10, 0) in [0, 40] x [-10, 10], uniform inflow, periodic sides, reward `-|C_D| - w |C_L|` with
//! the cylinder's `w` (0.2 at Re 200, 1.0 at 1000 and 3900), 200 actions per episode.
//!
//! Actuation, as the paper describes it: individual (not zero-net-mass-flux) jets at four
//! locations, leading edge upper, leading edge lower, trailing edge upper, trailing edge lower,
//! one action each. The paper does not give their size; we place them on the top and bottom
//! faces, 0.2 D wide, centred 0.15 D from the front and rear corners, blowing normal to the face
//! (parabolic profile, peak bound 1.0 U each), so that every level resolves at least two wall
//! links per jet (coarse: 8 cells per D).
//!
//! Control interval: a twentieth of the shedding period, with St = 0.151, 0.121 and 0.13 (the
//! paper's 2D table; Re 3900 from the 3D literature): 0.33, 0.41 and 0.38 D/U. The paper's m-AIA
//! set-up uses 225, 750 and 375 CFD steps per action.

use super::actuation::Jet;
use super::cylinder::bluff_body;
use super::spec::{ActuationSpec, EnvSpec};
use crate::flow::GeometrySpec;

pub const REYNOLDS: [u32; 3] = [200, 1000, 3900];

/// The square cylinder family over [`REYNOLDS`], in 2D and in 3D (`super::cylinder::in_3d`).
pub struct Square;

impl super::family::Family for Square {
    fn specs(&self) -> Vec<super::family::Spec> {
        let mut specs = super::registry::lbm(REYNOLDS.map(square));
        specs.extend(super::registry::lbm3(REYNOLDS.map(|re| super::cylinder::in_3d(square(re)))));
        specs
    }
}

/// Centre and side of the square.
pub const CENTER: [f64; 2] = [10.0, 0.0];
pub const SIDE: f64 = 1.0;

/// Jet width and the distance of its centre from the nearest corner.
const JET_WIDTH: f64 = 0.2;
const JET_FROM_CORNER: f64 = 0.15;

fn control_interval(re: u32) -> f64 {
    match re {
        200 => 0.33,
        1000 => 0.41,
        _ => 0.38,
    }
}

/// The four jets: leading edge upper, leading edge lower, trailing edge upper, trailing edge lower.
pub fn jets() -> Vec<Jet> {
    let h = 0.5 * SIDE;
    let front = CENTER[0] - h + JET_FROM_CORNER;
    let rear = CENTER[0] + h - JET_FROM_CORNER;
    [(front, 1.0), (front, -1.0), (rear, 1.0), (rear, -1.0)]
        .into_iter()
        .map(|(x, side)| Jet {
            center: [x, CENTER[1] + side * h],
            angle_deg: if side > 0.0 { 90.0 } else { 270.0 },
            width: JET_WIDTH,
        })
        .collect()
}

/// `SquareCylinder_2D_Re{re}`.
pub fn square(re: u32) -> EnvSpec {
    bluff_body(
        format!("SquareCylinder_2D_Re{re}"),
        "square_cylinder",
        re,
        GeometrySpec::Square {
            center: CENTER,
            side: SIDE,
        },
        ActuationSpec::Jets {
            body: 0,
            jets: jets(),
            max_velocity: 1.0,
        },
        format!("2D square cylinder at Re {re}, four independent jets at the leading and trailing edges"),
        control_interval(re),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::LbmEnv;
    use crate::flow::Level;

    /// On the env's own grid at every level, each of the four jets reaches wall links: blowing
    /// injects mass, suction removes the same amount, and the mirror pairs (upper/lower) inject
    /// the same to round-off.
    #[test]
    fn every_jet_is_resolved_at_every_level_and_mirror_jets_agree() {
        for level in Level::ALL {
            let mut env = LbmEnv::new(square(200), level, None).unwrap();
            let blow = env.actuator_mass_sources(1.0);
            let suck = env.actuator_mass_sources(-1.0);
            println!("{level:?}: mass injected per step by each jet at full blowing {blow:?}");
            for k in 0..4 {
                assert!(blow[k] > 1e-4, "{level:?}: jet {k} reaches no wall link ({})", blow[k]);
                assert!(
                    (blow[k] + suck[k]).abs() < 1e-12,
                    "{level:?}: jet {k} suction is not the mirror of blowing"
                );
            }
            for (a, b) in [(0, 1), (2, 3)] {
                assert!((blow[a] - blow[b]).abs() < 1e-9 * blow[a], "{level:?}: jets {a} and {b} differ");
            }
        }
    }
}
