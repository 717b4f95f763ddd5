//! The D3Q7 temperature scheme against exact solutions: diffusion of a Fourier mode along each
//! axis, advection with exact conservation, steady conduction between fixed-temperature faces,
//! and the flow's velocity field as the solver reports it node by node.

use hgym_solvers::lbm::d3::{D3Config, D3q19, Lbm3, Thermal3};
use hgym_solvers::lbm::thermal::ThermalSide;

const P: ThermalSide = ThermalSide::Periodic;

fn still(cells: usize) -> [Vec<f32>; 3] {
    std::array::from_fn(|_| vec![0.0; cells])
}

fn step(t: &mut Thermal3, u: &[Vec<f32>; 3]) {
    t.step([&u[0], &u[1], &u[2]]).unwrap();
}

#[test]
fn a_fourier_mode_decays_at_the_diffusivity_rate_along_every_axis() {
    let tau = 0.8;
    let kappa = (tau - 0.5) / 4.0;
    for axis in 0..3 {
        let mut n = [4, 4, 4];
        n[axis] = 48;
        let k = 2.0 * std::f64::consts::PI / n[axis] as f64;
        let cells = n.iter().product();
        let mut t = Thermal3::new(n, tau, [P; 6], vec![false; cells], 0.0).unwrap();
        t.init_with(|p| 1.0 + 0.1 * (k * p[axis] as f64).sin());
        let u = still(cells);
        let steps = 600;
        for _ in 0..steps {
            step(&mut t, &u);
        }
        let mut proj = 0.0;
        for i in 0..n[axis] {
            let mut p = [1, 1, 1];
            p[axis] = i;
            proj += (t.temperature(p) as f64 - 1.0) * (k * i as f64).sin();
        }
        let measured = 2.0 * proj / n[axis] as f64 / 0.1;
        let exact = (-kappa * k * k * steps as f64).exp();
        assert!(
            (measured / exact - 1.0).abs() < 2e-3,
            "axis {axis}: amplitude ratio {measured:.5}, exact exp(-kappa k^2 t) = {exact:.5}"
        );
    }
}

#[test]
fn advection_conserves_heat_and_moves_the_blob_at_the_flow_speed() {
    let n = [40, 40, 40];
    let cells: usize = n.iter().product();
    let mut t = Thermal3::new(n, 0.6, [P; 6], vec![false; cells], 0.0).unwrap();
    // Narrow enough that its tails stay clear of the periodic wrap (they would shift the
    // centroid computed over the box).
    let c0 = [15.0, 18.0, 23.0];
    t.init_with(|p| {
        let r2: f64 = (0..3).map(|a| (p[a] as f64 - c0[a]).powi(2)).sum();
        (-r2 / 8.0).exp()
    });
    let v = [0.05f32, 0.02, -0.03];
    let u: [Vec<f32>; 3] = std::array::from_fn(|a| vec![v[a]; cells]);
    let total0 = t.total();
    let steps = 200;
    for _ in 0..steps {
        step(&mut t, &u);
    }
    assert!((t.total() / total0 - 1.0).abs() < 5e-5, "heat {total0} -> {}", t.total());
    let mut m = [0.0f64; 3];
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                let th = t.temperature([x, y, z]) as f64;
                m[0] += th * x as f64;
                m[1] += th * y as f64;
                m[2] += th * z as f64;
            }
        }
    }
    for a in 0..3 {
        let (c, e) = (m[a] / t.total(), c0[a] + v[a] as f64 * steps as f64);
        // The populations start at rest equilibrium: the flux lags `u` for a few steps.
        assert!((c - e).abs() < 0.05, "axis {a}: centroid {c:.3}, expected {e}");
    }
}

#[test]
fn conduction_between_fixed_temperature_faces_is_linear() {
    let n = [3, 3, 20];
    let faces = [P, P, P, P, ThermalSide::Temperature(1.0), ThermalSide::Temperature(0.0)];
    let cells = n.iter().product();
    let mut t = Thermal3::new(n, 1.0, faces, vec![false; cells], 0.0).unwrap();
    let u = still(cells);
    for _ in 0..20_000 {
        step(&mut t, &u);
    }
    // Faces half-way outside the first and last nodes: T(z) = 1 - (z + 1/2) / nz.
    let worst = (0..n[2])
        .map(|z| (t.temperature([1, 1, z]) as f64 - (1.0 - (z as f64 + 0.5) / n[2] as f64)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-4, "largest deviation from the linear profile {worst}");
}

#[test]
fn a_solid_at_the_wall_temperature_heats_a_closed_box_to_it() {
    let n = [12, 12, 12];
    let solid: Vec<bool> = (0..1728)
        .map(|c| {
            let p = [c % 12, (c / 12) % 12, c / 144];
            p.iter().all(|&v| (5..7).contains(&v))
        })
        .collect();
    let zero = ThermalSide::ZeroGradient;
    let mut t = Thermal3::new(n, 1.0, [zero; 6], solid, 1.0).unwrap();
    let u = still(1728);
    let mut far = 0.0;
    for k in 0..20_000 {
        step(&mut t, &u);
        if k == 50 {
            assert!(t.temperature([4, 5, 5]) > t.temperature([0, 0, 0]), "heat flows out from the block");
        }
        far = t.temperature([0, 0, 0]);
    }
    assert!((far - 1.0).abs() < 1e-3, "far corner at {far}");
}

#[test]
fn the_inlet_temperature_can_be_changed_and_bad_settings_are_refused() {
    let faces = [ThermalSide::Temperature(0.9), ThermalSide::ZeroGradient, P, P, P, P];
    let mut t = Thermal3::new([6, 4, 4], 0.7, faces, vec![false; 96], 1.0).unwrap();
    t.set_face_temperature(0, 0.95).unwrap();
    assert!(t
        .set_face_temperature(1, 0.95)
        .unwrap_err()
        .to_string()
        .contains("not a fixed-temperature"));
    assert!(t.set_face_temperature(0, f64::NAN).is_err());
    assert!(
        t.step([&[0.0; 95], &[0.0; 96], &[0.0; 96]]).is_err(),
        "a velocity of the wrong size"
    );
    assert!(Thermal3::new([6, 4, 4], 0.5, faces, vec![false; 96], 1.0)
        .unwrap_err()
        .to_string()
        .contains("1/2"));
    let mixed = [P, ThermalSide::ZeroGradient, P, P, P, P];
    assert!(Thermal3::new([6, 4, 4], 0.7, mixed, vec![false; 96], 1.0).is_err());
}

#[test]
fn the_velocity_field_is_the_solvers_node_velocity() {
    let n = [9, 7, 5];
    let mut s = Lbm3::<19, D3q19>::new(D3Config::new(n, 0.7), &[]).unwrap();
    s.set_equilibrium(|x, y, z| {
        (
            1.0 + 0.001 * x as f64,
            [0.01 * y as f64, -0.02 + 0.003 * z as f64, 0.004 * x as f64],
        )
    });
    s.step().unwrap();
    let cells = n.iter().product();
    let mut u = still(cells);
    let [a, b, c] = &mut u;
    s.velocity_field([a, b, c]).unwrap();
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                let (_, v) = s.rho_u([x, y, z]);
                let k = (z * n[1] + y) * n[0] + x;
                for d in 0..3 {
                    assert!(
                        (u[d][k] as f64 - v[d]).abs() < 1e-6,
                        "node {:?} axis {d}: {} vs {}",
                        [x, y, z],
                        u[d][k],
                        v[d]
                    );
                }
            }
        }
    }
}
