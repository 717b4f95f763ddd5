//! Cube family (HydroGym "Flow around a cube"): `Cube_3D_Re{300,3700}`.
//!
//! Set-up from the paper: a cube of side H at (8, 8, 8) in [0, 32] x [0, 16] x [0, 16] H, as the
//! sphere (`super::sphere::in_box`: free-slip sides and 1 H absorbing layers along them and the
//! outlet, the wake rake in the mid-plane). Actuation:
//! independent slot jets along the leading and trailing edges of the four lateral faces (top,
//! bottom, and both sides), 0.2 H wide and 0.8 H long, centred 0.15 H from the edge, blowing
//! along the face's outward normal, one action each (8 actions, bound 1.0 U, parabolic
//! profile; the paper shows such jets but does not size them). Reward `-|C_D| - w |(C_L, C_S)|`
//! with w = 1. Control interval: a twentieth of the shedding period (St 0.095 at Re 300, Saha
//! 2004; about 0.12 at Re 3700): 0.5 and 0.4 H/U. Levels 6, 16 and 24 cells per H.

use super::spec3::{Actuation3Spec, Env3Spec, Jet3};
use super::sphere::{in_box, CENTER};
use crate::flow::{GeometrySpec, ResolutionSpec};

pub const REYNOLDS: [u32; 2] = [300, 3700];

pub struct Cube;

impl super::family::Family for Cube {
    fn specs(&self) -> Vec<super::family::Spec> {
        super::registry::lbm3(REYNOLDS.map(cube))
    }
}

const SIDE: f64 = 1.0;
const JET_WIDTH: f64 = 0.2;
const JET_LENGTH: f64 = 0.8;
const JET_FROM_EDGE: f64 = 0.15;

/// Leading-edge then trailing-edge slots on the faces +y, -y, +z, -z.
pub fn jets() -> Vec<Jet3> {
    let h = 0.5 * SIDE;
    let faces: [([f64; 3], [f64; 3]); 4] = [
        ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
    ];
    [-1.0, 1.0]
        .into_iter()
        .flat_map(|edge| {
            faces.into_iter().map(move |(normal, along)| Jet3 {
                center: [0, 1, 2].map(|a| CENTER[a] + h * normal[a] + if a == 0 { edge * (h - JET_FROM_EDGE) } else { 0.0 }),
                direction: normal,
                width: JET_WIDTH,
                length: JET_LENGTH,
                slot_axis: along,
            })
        })
        .collect()
}

/// `Cube_3D_Re{re}`.
pub fn cube(re: u32) -> Env3Spec {
    in_box(
        format!("Cube_3D_Re{re}"),
        "cube",
        format!("Cube at Re {re}, slot jets along the leading and trailing edges of the four lateral faces"),
        re,
        GeometrySpec::Cube {
            center: CENTER,
            side: SIDE,
        },
        Actuation3Spec::SurfaceJets {
            body: 0,
            jets: jets(),
            max_velocity: 1.0,
        },
        if re == 300 { 0.5 } else { 0.4 },
        ResolutionSpec {
            coarse: 6,
            default: 16,
            fine: 24,
        },
    )
}
