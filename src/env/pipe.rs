//! Stenotic pipe (HydroGym "Flow through a stenotic pipe"): `StenoticPipe_2D_Re100` and
//! `StenoticPipe_3D_Re100`.
//!
//! A straight channel of width D (the reference length) from `x = -4` to `x = 12` (the paper's
//! 16 D x D) between walls held at the wall temperature `T_wall = 1`, with a cosine stenosis
//! at `x = 0` that halves the width at its throat over a length 2 D (Varghese, Frankel & Fischer
//! 2007's profile, `s0 = 0.25`, used as a channel's half-width). Re = U D / nu = 100 with U the
//! amplitude of the mean inflow velocity.
//!
//! Flow: oscillatory (zero-mean) through the west side, a Poiseuille profile scaled by
//! `sin(omega t) + 0.05 xi_k` with Womersley number `alpha = (D/2) sqrt(omega / nu) = 4`, so
//! `omega = 4 alpha^2 / Re = 0.64 U/D` (period 9.8 D/U), and the paper's Gaussian noise of
//! amplitude 0.05 (`xi_k` standard normal, one value per control interval, from the episode's
//! seed). East: open outlet at the reference pressure. The fluid starts at rest (the
//! oscillation starts from zero).
//!
//! Temperature: a passive scalar (D2Q5, `Pr = 0.71`, air), walls and stenosis at `T_wall`, the
//! inlet at `T_inlet` (the actuator), zero gradient at the outlet; the fluid starts at 0.9.
//!
//! Control, as the paper's: the action changes the inlet temperature by at most
//! `|Delta T_inlet / T_wall| <= 0.05` per action, from `T_inlet / T_wall = 0.9` at every reset;
//! we keep it within [0.5, 1.5]. Observations: `(u, v, p, T)` at 10 centreline probes from
//! `x = -3.5` to `x = 1` (every 0.5 D). Reward: `-100 |T(x = D) / T_wall - 0.95|` on the centreline
//! (the last probe).
//!
//! Resolution: 28, 32 and 48 cells per D (the throat is half of that). Coarser grids are not
//! offered: at 24 cells per D (tau 0.514) the flow diverged at the inlet corner during the spin-up
//! (node (0, 3), step 126,500); with the old lattice velocity 0.05, 12-20 cells per D (tau
//! 0.518-0.53) diverged at the inlet during the back-flow half of the oscillation.
//!
//! Mach number: lattice velocity 0.02 (Ma 0.035), not the 0.05 of the external flows. The pipe is
//! a quarter-wave resonator (velocity inlet: a hard end; pressure outlet: a soft one) driven at the
//! acoustic Helmholtz number `omega L / c_s = (omega D/U)(L/D) Ma = 0.64 x 16 x Ma`, resonance at
//! pi/2, and it must stay small for the flow to be the incompressible one. At 0.05 (He 0.89) the
//! oscillation was nearly resonant: at coarse level, reset(5) and 20 actions, the outlet's mass
//! flux swung 1.75 times as far as the inlet's (RMS of inlet minus outlet 74 % of the inlet's),
//! the density between 0.86 and 1.16, and the temperature, carried in conservative form by that
//! compressible velocity, followed the density: from 0.460 to 1.168 with the walls at 1 and the
//! inlet in [0.5, 0.9]. At 0.02 (He 0.36): 23 %, density 0.978-1.018, temperature 0.498-1.026
//! under full cooling. The remaining difference between inlet and outlet flux is acoustic ringing
//! after the noise's steps (0.01 gave the same 20-25 % at the default level), and the remaining
//! temperature overshoot is the conservative transport (carrying `rho T` would remove it). The
//! price: 2.5 times more solver steps per action.
//!
//! Timing: the paper advances 4,000 solver steps per action (its step size is not given); we
//! take 0.5 D/U, a twentieth of the oscillation period, so the 200 actions of an episode cover
//! ten periods. Spin-up: 100 D/U (ten periods, and longer than the diffusive time across the
//! channel, `Re Pr D / U = 71 D/U`).

use super::actuation::Ramp;
use super::spec::{ActuationSpec, EnvSpec, InflowSpec, Normalization, RewardSpec, ThermalSpec};
use super::spec3::{Actuation3Spec, Env3Spec};
use crate::flow::{BoundaryKind, BoundarySpec, DomainSpec, GeometrySpec, ResolutionSpec, SpanSpec};

pub const REYNOLDS: [u32; 1] = [100];

/// The stenotic pipe family over [`REYNOLDS`].
pub struct Pipe;

impl super::family::Family for Pipe {
    fn specs(&self) -> Vec<super::family::Spec> {
        let mut specs = super::registry::lbm(REYNOLDS.map(stenotic_pipe));
        specs.extend(super::registry::lbm3(REYNOLDS.map(stenotic_pipe_3d)));
        specs
    }
}

/// The probes: the centreline from x = -3.5 to x = 1; the last one is the reward's.
fn probes() -> Vec<[f64; 2]> {
    (0..10).map(|k| [-3.5 + 0.5 * k as f64, 0.0]).collect()
}

/// `StenoticPipe_2D_Re{re}`.
pub fn stenotic_pipe(re: u32) -> EnvSpec {
    let probes = probes();
    EnvSpec {
        id: format!("StenoticPipe_2D_Re{re}"),
        family: "stenotic_pipe".into(),
        description: format!("2D channel with a cosine stenosis at Re {re}, oscillatory inflow (Womersley 4), inlet-temperature control"),
        reynolds: re as f64,
        bodies: vec![GeometrySpec::Stenosis {
            center: [0.0, 0.0],
            width: 1.0,
            length: 2.0,
            severity: 0.25,
        }],
        domain: DomainSpec {
            x: [-4.0, 12.0],
            y: [-0.5, 0.5],
        },
        boundaries: BoundarySpec {
            west: BoundaryKind::Inlet,
            east: BoundaryKind::Outlet,
            south: BoundaryKind::Wall,
            north: BoundaryKind::Wall,
        },
        resolution: ResolutionSpec {
            coarse: 28,
            default: 32,
            fine: 48,
        },
        lattice_velocity: 0.02,
        collision: hgym_solvers::lbm::Collision::Regularized,
        smagorinsky: 0.0,
        actuation: ActuationSpec::InletTemperature {
            max_change: 0.05,
            range: [0.5, 1.5],
        },
        ramp: Ramp::default(),
        reward: RewardSpec::ProbeTemperature {
            probe: probes.len() - 1,
            target: 0.95,
            weight: 100.0,
        },
        probes,
        control_interval: 0.5,
        episode_actions: 200,
        spin_up: 100.0,
        normalization: Normalization::default(),
        gust: None,
        sponge: None,
        thermal: Some(Box::new(ThermalSpec {
            prandtl: 0.71,
            wall_temperature: 1.0,
            inlet_temperature: 0.9,
            initial_temperature: 0.9,
        })),
        inflow: Some(Box::new(InflowSpec {
            womersley: 4.0,
            noise: 0.05,
        })),
    }
}

/// `StenoticPipe_3D_Re{re}`: the paper's 3D set-up, a round pipe of diameter D in the box
/// [-4, 12] x [-0.5, 0.5]^2 D (the paper's 16 D x D x D) whose radius narrows by the same
/// cosine law to D/4 at the throat (`x = 0`; 75 % area reduction, Varghese, Frankel & Fischer
/// 2007), with everything else as in 2D: the oscillatory Poiseuille inflow of Womersley number 4
/// (the pipe's `2 U s(t) (1 - (2 r / D)^2)`), the walls at `T_wall`, the inlet temperature as the
/// action, `(u, v, w, p, T)` at the 10 centreline probes and the reward at `x = D`. The box's
/// corners outside the pipe are solid. Lattice velocity 0.02 (the 2D study of the acoustic
/// resonance holds: the pipe has the same length). Levels: 16, 24 and 32 cells per D (the
/// throat gets half of that).
///
/// Subgrid viscosity: Smagorinsky, C_s = 0.1. The round throat passes four times the pipe's
/// flow rate per area (twice in 2D), a jet of about 8 U peak, a cell Reynolds number `8 Re / N`
/// of 50 at 16 cells per D; without the subgrid viscosity the 16 and the 24 cells per D grids
/// diverged at the inlet in the first back-flow (steps 5,387 and 8,200, about 6.8 D/U).
pub fn stenotic_pipe_3d(re: u32) -> Env3Spec {
    let base = stenotic_pipe(re);
    Env3Spec {
        id: format!("StenoticPipe_3D_Re{re}"),
        family: base.family,
        description: format!("Round pipe with a cosine stenosis at Re {re}, oscillatory inflow (Womersley 4), inlet-temperature control"),
        reynolds: base.reynolds,
        bodies: vec![GeometrySpec::Pipe {
            center: [0.0, 0.0, 0.0],
            diameter: 1.0,
            length: 2.0,
            severity: 0.25,
        }],
        domain: base.domain,
        boundaries: base.boundaries,
        span: SpanSpec {
            z: [-0.5, 0.5],
            boundary: BoundaryKind::Wall,
            segments: 1,
            lattice: Default::default(),
        },
        resolution: ResolutionSpec {
            coarse: 16,
            default: 24,
            fine: 32,
        },
        lattice_velocity: base.lattice_velocity,
        collision: base.collision,
        smagorinsky: 0.1,
        actuation: Actuation3Spec::Segments { actuator: base.actuation },
        ramp: base.ramp,
        probes: base.probes,
        reward: base.reward,
        agent_reward: Default::default(),
        control_interval: base.control_interval,
        episode_actions: base.episode_actions,
        spin_up: base.spin_up,
        normalization: Normalization::default(),
        sponges: vec![],
        gust: None,
        thermal: base.thermal,
        inflow: base.inflow,
    }
}
