//! The D2Q5 temperature scheme against exact solutions: diffusion of a Fourier mode, advection
//! with exact conservation, steady conduction between fixed-temperature walls, and a solid at
//! the wall temperature heating the fluid around it.

use hgym_solvers::lbm::thermal::{Thermal, ThermalSide};
use hgym_solvers::lbm::Edge;

const P: ThermalSide = ThermalSide::Periodic;

fn amplitude(t: &Thermal, nx: usize, k: f64) -> f64 {
    // Projection of the row y = 0 on sin(k x).
    let mut s = 0.0;
    for x in 0..nx {
        s += (t.temperature(x, 0) as f64 - 1.0) * (k * x as f64).sin();
    }
    2.0 * s / nx as f64
}

#[test]
fn a_fourier_mode_decays_at_the_diffusivity_rate() {
    let (nx, ny) = (64, 4);
    let tau = 0.8;
    let kappa = (tau - 0.5) / 3.0;
    let k = 2.0 * std::f64::consts::PI / nx as f64;
    let mut t = Thermal::new(nx, ny, tau, [P; 4], vec![false; nx * ny], 0.0).unwrap();
    t.init_with(|x, _| 1.0 + 0.1 * (k * x as f64).sin());
    let (u, v) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
    let steps = 1000;
    for _ in 0..steps {
        t.step(&u, &v);
    }
    let measured = amplitude(&t, nx, k) / 0.1;
    let exact = (-kappa * k * k * steps as f64).exp();
    assert!(
        (measured / exact - 1.0).abs() < 2e-3,
        "amplitude ratio {measured:.5}, exact exp(-kappa k^2 t) = {exact:.5}"
    );
}

#[test]
fn advection_conserves_heat_and_moves_the_blob_at_the_flow_speed() {
    let (nx, ny) = (80, 80);
    let mut t = Thermal::new(nx, ny, 0.6, [P; 4], vec![false; nx * ny], 0.0).unwrap();
    let (x0, y0) = (30.0, 40.0);
    t.init_with(|x, y| {
        let r2 = (x as f64 - x0).powi(2) + (y as f64 - y0).powi(2);
        (-r2 / 50.0).exp()
    });
    let (ux, uy) = (0.05f32, 0.02f32);
    let (u, v) = (vec![ux; nx * ny], vec![uy; nx * ny]);
    let total0 = t.total();
    let steps = 400;
    for _ in 0..steps {
        t.step(&u, &v);
    }
    // Exact in exact arithmetic; f32 populations round at ~1e-7 per node and step.
    assert!((t.total() / total0 - 1.0).abs() < 5e-5, "heat {} -> {}", total0, t.total());
    let (mut mx, mut my) = (0.0, 0.0);
    for y in 0..ny {
        for x in 0..nx {
            let th = t.temperature(x, y) as f64;
            mx += th * x as f64;
            my += th * y as f64;
        }
    }
    let (cx, cy) = (mx / t.total(), my / t.total());
    let (ex, ey) = (x0 + ux as f64 * steps as f64, y0 + uy as f64 * steps as f64);
    assert!(
        (cx - ex).abs() < 0.05 && (cy - ey).abs() < 0.05,
        "centroid ({cx:.3}, {cy:.3}), expected ({ex}, {ey})"
    );
}

#[test]
fn conduction_between_fixed_temperature_walls_is_linear() {
    let (nx, ny) = (4, 20);
    let sides = [P, P, ThermalSide::Temperature(1.0), ThermalSide::Temperature(0.0)];
    let mut t = Thermal::new(nx, ny, 1.0, sides, vec![false; nx * ny], 0.0).unwrap();
    let (u, v) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
    for _ in 0..20_000 {
        t.step(&u, &v);
    }
    // Walls half-way outside the first and last nodes: T(y) = 1 - (y + 1/2) / ny.
    let worst = (0..ny)
        .map(|y| (t.temperature(1, y) as f64 - (1.0 - (y as f64 + 0.5) / ny as f64)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-4, "largest deviation from the linear profile {worst}");
}

#[test]
fn a_solid_at_the_wall_temperature_heats_a_closed_box_to_it() {
    let (nx, ny) = (24, 24);
    let mut solid = vec![false; nx * ny];
    for y in 10..14 {
        for x in 10..14 {
            solid[y * nx + x] = true;
        }
    }
    let z = ThermalSide::ZeroGradient;
    let mut t = Thermal::new(nx, ny, 1.0, [z; 4], solid, 1.0).unwrap();
    let (u, v) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
    let mut last = 0.0;
    for k in 0..40_000 {
        t.step(&u, &v);
        if k == 100 {
            // Heat flows in monotonically from the block: near it first.
            assert!(t.temperature(9, 12) > t.temperature(0, 0));
        }
        last = t.temperature(0, 0);
    }
    assert!((last - 1.0).abs() < 1e-3, "far corner at {last}");
}

#[test]
fn the_inlet_temperature_can_be_changed_and_bad_settings_are_refused() {
    let sides = [ThermalSide::Temperature(0.9), ThermalSide::ZeroGradient, P, P];
    let mut t = Thermal::new(8, 4, 0.7, sides, vec![false; 32], 1.0).unwrap();
    t.set_side_temperature(Edge::West, 0.95).unwrap();
    assert!(t
        .set_side_temperature(Edge::East, 0.95)
        .unwrap_err()
        .to_string()
        .contains("not a fixed-temperature"));
    assert!(t.set_side_temperature(Edge::West, f64::NAN).is_err());
    assert!(Thermal::new(8, 4, 0.5, sides, vec![false; 32], 1.0)
        .unwrap_err()
        .to_string()
        .contains("1/2"));
    let mixed = [P, ThermalSide::ZeroGradient, P, P];
    assert!(Thermal::new(8, 4, 0.7, mixed, vec![false; 32], 1.0).is_err());
}
