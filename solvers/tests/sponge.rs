//! Absorbing layers: they damp the acoustic standing wave a closed direction traps, leave a flow
//! already at their target state alone, and the fast kernel applies them exactly like the slow
//! oracle. And the force on an open body excludes the reference pressure.

mod common;

use std::sync::Arc;

use common::acoustic_energy;
use hgym_solvers::geometry::{Rectangle, Shape};
use hgym_solvers::lbm::{D2q9, D2q9Config, Edge, Side, Sides, Sponge};

/// Periodic in x, `south` and `north` as given.
fn periodic_in_x(south: Side, north: Side) -> Sides {
    Sides {
        west: Side::Periodic,
        east: Side::Periodic,
        south,
        north,
    }
}

/// A channel periodic in x between a no-slip floor and a free-slip top: the set-up of the open
/// cavity's vertical direction.
fn channel(ny: usize, sponge: Option<Sponge>) -> D2q9 {
    let sides = periodic_in_x(Side::Wall, Side::FreeSlip);
    let mut cfg = D2q9Config::new(8, ny, 0.52, sides);
    cfg.sponges = sponge.into_iter().collect();
    D2q9::new(cfg, Vec::new()).unwrap()
}

fn top_sponge(ny: usize) -> Sponge {
    Sponge {
        edge: Edge::North,
        width: ny / 4,
        strength: 0.2,
        rho: 1.0,
        u: [0.0, 0.0],
    }
}

/// The lowest vertical mode between the floor and the top: `rho = 1 + a cos(pi (y + 1/2) / ny)`.
fn standing_wave(s: &mut D2q9) {
    let ny = s.ny() as f64;
    s.init_with(|_, y| (1.0 + 1e-3 * (std::f64::consts::PI * (y + 0.5) / ny).cos(), 0.0, 0.0));
}

#[test]
fn a_top_sponge_absorbs_the_standing_acoustic_wave_viscosity_alone_keeps() {
    let ny = 64;
    // A few periods of the mode (period 2 ny / c_s = 222 steps).
    let steps = 1200;
    let mut open = channel(ny, None);
    let mut damped = channel(ny, Some(top_sponge(ny)));
    standing_wave(&mut open);
    standing_wave(&mut damped);
    let e0 = acoustic_energy(&open);
    open.advance(steps).unwrap();
    damped.advance(steps).unwrap();
    let (e_open, e_damped) = (acoustic_energy(&open) / e0, acoustic_energy(&damped) / e0);
    eprintln!("acoustic energy after {steps} steps: {e_open:.3} without a layer, {e_damped:.2e} with one");
    // Viscous damping of the mode at nu = 0.0067: exp(-nu k^2 t) ~ 0.98 in amplitude, so the
    // energy stays within a factor ~2 (it also sloshes between density and velocity).
    assert!(e_open > 0.3, "without a layer the wave should survive, energy ratio {e_open}");
    assert!(
        e_damped < 0.01 * e_open,
        "the layer left {e_damped} of the energy, against {e_open} without it"
    );
}

#[test]
fn a_flow_at_the_target_state_is_left_exactly_alone() {
    let ny = 32;
    let mut sp = top_sponge(ny);
    sp.u = [0.05, 0.0];
    let sides = periodic_in_x(Side::FreeSlip, Side::FreeSlip);
    let mut cfg = D2q9Config::new(8, ny, 0.6, sides);
    cfg.sponges = vec![sp];
    let mut s = D2q9::new(cfg, Vec::new()).unwrap();
    s.init_with(|_, _| (1.0, 0.05, 0.0));
    let before = s.populations().to_vec();
    s.advance(50).unwrap();
    let drift = s
        .populations()
        .iter()
        .zip(&before)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(drift < 1e-6, "uniform flow at the target state drifted by {drift}");
}

#[test]
fn the_fast_kernel_applies_layers_as_the_oracle_does() {
    let ny = 48;
    let mut layers = vec![top_sponge(ny)];
    layers.push(Sponge {
        edge: Edge::East,
        width: 5,
        strength: 0.3,
        rho: 1.0,
        u: [0.02, 0.0],
    });
    let sides = Sides {
        west: Side::Velocity {
            profile: vec![[0.02, 0.0]; ny],
        },
        east: Side::Outlet,
        south: Side::Wall,
        north: Side::FreeSlip,
    };
    let mut cfg = D2q9Config::new(40, ny, 0.55, sides);
    cfg.sponges = layers;
    let mut fast = D2q9::new(cfg.clone(), Vec::new()).unwrap();
    let mut slow = D2q9::new(cfg, Vec::new()).unwrap();
    standing_wave(&mut fast);
    standing_wave(&mut slow);
    for _ in 0..30 {
        fast.step().unwrap();
        slow.step_reference().unwrap();
    }
    assert!(
        fast.populations() == slow.populations(),
        "fast and reference steps differ with sponges"
    );
}

#[test]
fn bad_layers_are_refused_naming_the_problem() {
    let cases = [
        (Edge::North, 0, 0.2, "thick"),
        (Edge::North, 64, 0.2, "thick"),
        (Edge::North, 8, 1.5, "strength"),
        (Edge::West, 8, 0.2, "periodic"),
    ];
    for (edge, width, strength, word) in cases {
        let sides = periodic_in_x(Side::Wall, Side::FreeSlip);
        let mut cfg = D2q9Config::new(16, 64, 0.6, sides);
        cfg.sponges = vec![Sponge {
            edge,
            width,
            strength,
            rho: 1.0,
            u: [0.0, 0.0],
        }];
        let err = D2q9::new(cfg, Vec::new()).unwrap_err().to_string();
        assert!(err.contains(word), "{err}");
    }
}

/// A plate through the whole domain (an open body) in fluid at rest at the reference pressure:
/// the uniform pressure acts on one face only, but the reported force is relative to the
/// reference pressure, so it is zero; a closed box in the same fluid also feels nothing.
#[test]
fn an_open_plate_in_fluid_at_rest_feels_no_force() {
    let sides = periodic_in_x(Side::Wall, Side::FreeSlip);
    let plate: Arc<dyn Shape> = Arc::new(Rectangle {
        center: [16.0, 0.0],
        size: [100.0, 7.2],
    });
    let bx: Arc<dyn Shape> = Arc::new(Rectangle {
        center: [12.45, 13.25],
        size: [4.5, 6.1],
    });
    let mut s = D2q9::new(D2q9Config::new(32, 24, 0.6, sides), vec![plate, bx]).unwrap();
    s.advance(20).unwrap();
    for (b, f) in s.body_forces().iter().enumerate() {
        assert!(f[0].abs() < 1e-9 && f[1].abs() < 1e-9, "body {b}: force {f:?} at rest");
    }
}
