//! Exact-solution and oracle tests of the 3D lattice-Boltzmann solver (D3Q19, D3Q27), coarse
//! and fast. Run with `--nocapture` to see the measured errors and orders; `make test` does.

use hgym_solvers::geometry::{Circle, Cuboid, Extruded, Solid, Sphere};
use hgym_solvers::lbm::d3::{D3Config, D3q19, D3q27, Face, Faces, Lattice3, Lbm3, Sponge3};
use hgym_solvers::lbm::Collision;

/// The inside of a box as the fluid: everything outside it is wall.
#[derive(Debug)]
struct Hollow(Cuboid);

impl Solid for Hollow {
    fn sdf(&self, p: [f64; 3]) -> f64 {
        -self.0.sdf(p)
    }
}

fn kinetic_energy<const Q: usize, L: Lattice3<Q>>(s: &Lbm3<Q, L>) -> f64 {
    let [nx, ny, nz] = s.config().n;
    let mut e = 0.0;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let (rho, u) = s.rho_u([x, y, z]);
                e += 0.5 * rho * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            }
        }
    }
    e
}

/// Viscosity measured from the decay of a Taylor-Green vortex: `u = u0 (sin kx cos ky cos kz,
/// -cos kx sin ky cos kz, 0)` at an amplitude low enough for the flow to be linear, so that
/// its energy decays as `exp(-2 nu 3 k^2 t)`; the measured `nu` against `(tau - 1/2) / 3`.
fn taylor_green_nu<const Q: usize, L: Lattice3<Q>>(n: usize, tau: f64, collision: Collision) -> f64 {
    let mut cfg = D3Config::new([n; 3], tau);
    cfg.collision = collision;
    let mut s = Lbm3::<Q, L>::new(cfg, &[]).unwrap();
    let k = 2.0 * std::f64::consts::PI / n as f64;
    let u0 = 2e-3;
    s.set_equilibrium(|x, y, z| {
        let (x, y, z) = (k * x as f64, k * y as f64, k * z as f64);
        (1.0, [u0 * x.sin() * y.cos() * z.cos(), -u0 * x.cos() * y.sin() * z.cos(), 0.0])
    });
    let (t0, t1) = (100u64, 300u64);
    for _ in 0..t0 {
        s.step().unwrap();
    }
    let e0 = kinetic_energy(&s);
    for _ in t0..t1 {
        s.step().unwrap();
    }
    let e1 = kinetic_energy(&s);
    (e0 / e1).ln() / (2.0 * 3.0 * k * k * (t1 - t0) as f64)
}

/// The error is the scheme's, second order in the wavenumber: D3Q19 BGK gives +0.94 % at 32^3
/// and +0.42 % at 48^3 (ratio 2.2, (48/32)^2 = 2.25), the same at a tenth of the amplitude.
#[test]
fn taylor_green_decays_with_the_set_viscosity() {
    let tau = 0.6;
    let nu = (tau - 0.5) / 3.0;
    for collision in [Collision::Bgk, Collision::Regularized] {
        for (name, measured) in [
            ("d3q19", taylor_green_nu::<19, D3q19>(48, tau, collision)),
            ("d3q27", taylor_green_nu::<27, D3q27>(48, tau, collision)),
        ] {
            let err = measured / nu - 1.0;
            println!(
                "taylor-green[{name}, {}] 48^3: nu {measured:.6} vs {nu:.6} ({:+.3} %)",
                collision.name(),
                100.0 * err
            );
            assert!(err.abs() < 0.01, "{name} {}: nu off by {:.3} %", collision.name(), 100.0 * err);
        }
    }
}

/// Plane Poiseuille flow along x between two walls normal to y, driven by a body force. The
/// walls sit at `y_lo = 1 - q_lo` and `y_hi = h + q_hi` (between nodes at any fraction, so both
/// branches of the interpolated bounce-back run): `u = F / (2 nu) (y - y_lo) (y_hi - y)`.
fn poiseuille_error<const Q: usize, L: Lattice3<Q>>(h: usize, q: [f64; 2], collision: Collision) -> f64 {
    let tau = 0.8;
    let nu = (tau - 0.5) / 3.0;
    let (y_lo, y_hi) = (1.0 - q[0], h as f64 + q[1]);
    let width = y_hi - y_lo;
    let force = 8.0 * nu * 0.01 / (width * width);
    let ny = h + 2;
    let mut cfg = D3Config::new([4, ny, 1], tau);
    cfg.collision = collision;
    cfg.body_force = [force, 0.0, 0.0];
    cfg.check_interval = 0;
    let huge = 1e6;
    let lower = Cuboid {
        center: [0.0, y_lo - 0.5 * huge, 0.0],
        size: [huge, huge, huge],
    };
    let upper = Cuboid {
        center: [0.0, y_hi + 0.5 * huge, 0.0],
        size: [huge, huge, huge],
    };
    let mut s = Lbm3::<Q, L>::new(cfg, &[&lower, &upper]).unwrap();
    let mut prev = vec![0.0; ny];
    for _ in 0..400_000 / 200 {
        for _ in 0..200 {
            s.step().unwrap();
        }
        let u: Vec<f64> = (0..ny).map(|y| s.rho_u([2, y, 0]).1[0]).collect();
        let change = u.iter().zip(&prev).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        prev = u;
        if change < 1e-9 * 0.01 {
            break;
        }
    }
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (y, u) in prev.iter().enumerate().take(h + 1).skip(1) {
        let yy = y as f64;
        let exact = force / (2.0 * nu) * (yy - y_lo) * (y_hi - yy);
        num += (u - exact).powi(2);
        den += exact * exact;
    }
    (num / den).sqrt()
}

#[test]
fn poiseuille_converges_at_second_order_with_walls_between_nodes() {
    for collision in [Collision::Bgk, Collision::Regularized] {
        for q in [[0.5, 0.5], [0.3, 0.7]] {
            let hs = [8usize, 16, 32];
            let errs: Vec<f64> = hs.iter().map(|&h| poiseuille_error::<19, D3q19>(h, q, collision)).collect();
            for w in 0..hs.len() - 1 {
                let order = (errs[w] / errs[w + 1]).log2();
                println!(
                    "poiseuille3d[{}, q {:?}] H {:>2} -> {:>2}: L2 error {:.3e} -> {:.3e}, order {:.2}",
                    collision.name(),
                    q,
                    hs[w],
                    hs[w + 1],
                    errs[w],
                    errs[w + 1],
                    order
                );
                assert!(order > 1.8, "{} q {q:?}: order {order:.2}", collision.name());
            }
        }
    }
}

#[test]
fn mass_is_conserved_in_a_closed_box() {
    // Walls half-way between nodes: fluid nodes 1..=10 along each axis of a 12^3 grid.
    let walls = Hollow(Cuboid {
        center: [5.5; 3],
        size: [10.0; 3],
    });
    let mut cfg = D3Config::new([12; 3], 0.55);
    cfg.collision = Collision::Regularized;
    let mut s = Lbm3::<19, D3q19>::new(cfg, &[&walls]).unwrap();
    // A swirl and a density bump, nothing symmetric about it.
    s.set_equilibrium(|x, y, z| {
        let (x, y, z) = (x as f64 / 10.0, y as f64 / 10.0, z as f64 / 10.0);
        let rho = 1.0 + 0.01 * (3.0 * x).sin() * (2.0 * z).cos();
        (rho, [0.05 * (y - 0.5), -0.04 * (x - 0.5) + 0.01 * z, 0.03 * (x * y).sin()])
    });
    let m0 = s.mass();
    for _ in 0..2000 {
        s.step().unwrap();
    }
    let drift = (s.mass() - m0) / m0;
    println!("closed box 10^3 fluid nodes, 2000 steps: relative mass drift {drift:.3e}");
    assert!(drift.abs() < 1e-6, "mass drift {drift:.3e}");
}

/// At steady state in a periodic box the force on the body balances the body force on the
/// fluid: `F_sphere = F N_fluid` (momentum exchange against the exact momentum budget).
#[test]
fn momentum_exchange_balances_the_driving_force() {
    let sphere = Sphere {
        center: [11.7, 12.2, 11.9],
        radius: 4.3,
    };
    let mut cfg = D3Config::new([24; 3], 0.8);
    let f = 2e-6;
    cfg.body_force = [f, 0.0, 0.0];
    let mut s = Lbm3::<19, D3q19>::new(cfg, &[&sphere]).unwrap();
    let fluid = (0..24usize.pow(3))
        .filter(|&n| !s.is_solid([n % 24, (n / 24) % 24, n / 576]))
        .count();
    for _ in 0..8000 {
        s.step().unwrap();
    }
    let drag = s.body_forces()[0];
    let budget = f * fluid as f64;
    let err = drag[0] / budget - 1.0;
    println!(
        "momentum exchange: F_x {:.6e} vs F N_fluid {budget:.6e} ({:+.3} %), F_y {:.1e}, F_z {:.1e}",
        drag[0],
        100.0 * err,
        drag[1],
        drag[2]
    );
    assert!(err.abs() < 0.01, "drag off the momentum budget by {:.3} %", 100.0 * err);
}

/// Plane Poiseuille flow between the box's own walls (faces y: half-way bounce-back at
/// `y = -1/2` and `y = h - 1/2`), along x, with the span (z) periodic.
#[test]
fn poiseuille_between_wall_faces_converges_at_second_order() {
    let error = |h: usize| {
        let tau = 0.8;
        let nu = (tau - 0.5) / 3.0;
        let force = 8.0 * nu * 0.01 / (h * h) as f64;
        let mut cfg = D3Config::new([4, h, 2], tau);
        cfg.faces.0[2] = Face::Wall;
        cfg.faces.0[3] = Face::Wall;
        cfg.body_force = [force, 0.0, 0.0];
        let mut s = Lbm3::<19, D3q19>::new(cfg, &[]).unwrap();
        for _ in 0..(40.0 * (h * h) as f64 / nu / 10.0) as usize {
            s.step().unwrap();
        }
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for y in 0..h {
            let yy = y as f64 + 0.5;
            let exact = force / (2.0 * nu) * yy * (h as f64 - yy);
            num += (s.rho_u([1, y, 1]).1[0] - exact).powi(2);
            den += exact * exact;
        }
        (num / den).sqrt()
    };
    let (e8, e16) = (error(8), error(16));
    let order = (e8 / e16).log2();
    println!("poiseuille3d[wall faces] H 8 -> 16: L2 error {e8:.3e} -> {e16:.3e}, order {order:.2}");
    assert!(order > 1.8, "order {order:.2}");
}

/// A uniform stream through a box with a velocity inlet, an outlet and free-slip side faces is
/// an exact steady solution: every node must carry the inlet velocity.
#[test]
fn uniform_stream_passes_inlet_outlet_and_free_slip_faces_unchanged() {
    let u_in = 0.05f32;
    let mut cfg = D3Config::new([24, 8, 6], 0.56);
    cfg.faces = Faces([
        Face::Velocity([u_in, 0.0, 0.0]),
        Face::Outlet,
        Face::FreeSlip,
        Face::FreeSlip,
        Face::FreeSlip,
        Face::FreeSlip,
    ]);
    let mut s = Lbm3::<27, D3q27>::new(cfg, &[]).unwrap();
    s.set_equilibrium(|_, _, _| (1.0, [u_in as f64, 0.0, 0.0]));
    for _ in 0..500 {
        s.step().unwrap();
    }
    let mut worst = 0.0f64;
    for z in 0..6 {
        for y in 0..8 {
            for x in 0..24 {
                let (rho, u) = s.rho_u([x, y, z]);
                worst = worst
                    .max((u[0] - u_in as f64).abs())
                    .max(u[1].abs())
                    .max(u[2].abs())
                    .max((rho - 1.0).abs());
            }
        }
    }
    println!("uniform stream through inlet/outlet/free-slip: largest deviation {worst:.2e}");
    assert!(worst < 1e-6, "{worst:.2e}");
}

/// A velocity face with a parabolic profile between two walls feeds plane Poiseuille flow: the
/// sections downstream of the inlet's corners carry the profile's shape (the pressure drop that drives the flow
/// compresses the fluid a little, so each section is compared with its own peak) and the
/// inflow's mass flux; a face that is not a velocity face refuses a profile.
#[test]
fn a_face_profile_feeds_its_shape_into_the_channel() {
    let (nx, ny) = (48, 12);
    let u_max = 0.04;
    let mut cfg = D3Config::new([nx, ny, 3], 0.8);
    cfg.faces = Faces([
        Face::Velocity([u_max as f32, 0.0, 0.0]),
        Face::Outlet,
        Face::Wall,
        Face::Wall,
        Face::Periodic,
        Face::Periodic,
    ]);
    let mut s = Lbm3::<19, D3q19>::new(cfg, &[]).unwrap();
    // Walls half-way outside the first and last nodes: y in (-1/2, ny - 1/2).
    let shape = |y: f64| {
        let eta = (y + 0.5) / ny as f64;
        4.0 * eta * (1.0 - eta)
    };
    s.set_face_profile(0, |p| shape(p[1])).unwrap();
    assert!(s
        .set_face_profile(1, |_| 1.0)
        .unwrap_err()
        .to_string()
        .contains("not a velocity face"));
    s.set_equilibrium(|_, y, _| (1.0, [u_max * shape(y as f64), 0.0, 0.0]));
    for _ in 0..8000 {
        s.step().unwrap();
    }
    let peak = (0..ny).map(|y| shape(y as f64)).fold(0.0, f64::max);
    let flux_at = |x: usize| -> f64 {
        (0..ny)
            .map(|y| {
                let (rho, u) = s.rho_u([x, y, 1]);
                rho * u[0]
            })
            .sum()
    };
    let inflow = flux_at(0);
    let (mut worst_shape, mut worst_flux) = (0.0f64, 0.0f64);
    // Sections past the few nodes where the inlet meets the walls.
    for x in [nx / 2, nx - 4] {
        let section: Vec<(f64, f64)> = (0..ny)
            .map(|y| {
                let (rho, u) = s.rho_u([x, y, 1]);
                (rho, u[0])
            })
            .collect();
        let top = section.iter().map(|v| v.1).fold(0.0, f64::max);
        for (y, (_, u)) in section.iter().enumerate() {
            worst_shape = worst_shape.max((u / top - shape(y as f64) / peak).abs());
        }
        worst_flux = worst_flux.max((flux_at(x) / inflow - 1.0).abs());
    }
    println!("parabolic inflow through a {nx}-node channel: shape within {worst_shape:.2e} of the peak, mass flux within {worst_flux:.2e}");
    assert!(
        worst_shape < 2e-3 && worst_flux < 1e-5,
        "shape {worst_shape:.3e}, flux {worst_flux:.3e}"
    );
}

fn oracle_case<const Q: usize, L: Lattice3<Q>>(collision: Collision, smagorinsky: f64) -> Lbm3<Q, L> {
    let mut cfg = D3Config::new([13, 11, 9], 0.52);
    cfg.collision = collision;
    cfg.smagorinsky = smagorinsky;
    cfg.body_force = [1e-5, -2e-6, 3e-6];
    let sphere = Sphere {
        center: [6.3, 5.1, 4.4],
        radius: 2.6,
    };
    let mut s = Lbm3::<Q, L>::new(cfg, &[&sphere]).unwrap();
    s.set_equilibrium(|x, y, z| {
        (
            1.0 + 0.001 * ((x + 2 * y) % 5) as f64,
            [0.04, 0.01 * (z as f64 - 4.0) / 4.0, 0.005 * (y % 3) as f64],
        )
    });
    s
}

/// The same case in a box with every kind of face, a moving (rotating) wall on the sphere,
/// three spanwise segments and an absorbing layer under the free-slip face.
fn oracle_case_with_faces<const Q: usize, L: Lattice3<Q>>(collision: Collision, smagorinsky: f64) -> Lbm3<Q, L> {
    let mut cfg = D3Config::new([13, 11, 9], 0.52);
    cfg.collision = collision;
    cfg.smagorinsky = smagorinsky;
    cfg.faces = Faces([
        Face::Velocity([0.04, 0.0, 0.01]),
        Face::Outlet,
        Face::Wall,
        Face::FreeSlip,
        Face::Periodic,
        Face::Periodic,
    ]);
    cfg.segments = 3;
    cfg.sponges = vec![Sponge3 {
        face: 3,
        width: 3,
        strength: 0.3,
        rho: 1.0,
        u: [0.04, 0.0, 0.0],
    }];
    let sphere = Sphere {
        center: [6.3, 5.1, 4.4],
        radius: 2.6,
    };
    let mut s = Lbm3::<Q, L>::new(cfg, &[&sphere]).unwrap();
    s.set_wall_velocity(0, |p| [0.0, -0.01 * (p[2] - 4.4), 0.01 * (p[1] - 5.1)]);
    s.set_velocity_scale(0.7);
    s.set_face_profile(0, |p| 1.0 - 0.01 * (p[1] - 5.0).powi(2) + 0.02 * p[2]).unwrap();
    s.set_equilibrium(|x, y, z| {
        (
            1.0 + 0.001 * ((x + 2 * y) % 5) as f64,
            [0.04, 0.01 * (z as f64 - 4.0) / 4.0, 0.005 * (y % 3) as f64],
        )
    });
    s
}

/// A case builder: (operator, Smagorinsky constant) to a solver.
type Case<const Q: usize, L> = fn(Collision, f64) -> Lbm3<Q, L>;

/// Rows a multiple of 8 long written with non-temporal stores, across several chunks of the
/// bulk loop, with absorbing layers across the rows (one ending inside the second chunk) and
/// along them (which the fast kernel applies chunk by chunk and node by node), and two spheres
/// whose solid and wall-link nodes (specials inside streamed rows) fall in the first and second
/// chunk and in the last, partial one.
fn oracle_case_streamed<const Q: usize, L: Lattice3<Q>>(collision: Collision, smagorinsky: f64) -> Lbm3<Q, L> {
    let mut cfg = D3Config::new([264, 6, 5], 0.52);
    cfg.collision = collision;
    cfg.smagorinsky = smagorinsky;
    cfg.stream_stores = Some(true);
    cfg.faces.0[2] = Face::Wall;
    cfg.faces.0[3] = Face::Wall;
    let layer = |face, width| Sponge3 {
        face,
        width,
        strength: 0.3,
        rho: 1.001,
        u: [0.03, 0.002, -0.001],
    };
    cfg.sponges = vec![layer(0, 140), layer(1, 20), layer(2, 2)];
    let across_chunks = Sphere {
        center: [127.6, 2.7, 2.2],
        radius: 1.9,
    };
    let in_last_chunk = Sphere {
        center: [259.5, 3.0, 2.5],
        radius: 1.5,
    };
    let mut s = Lbm3::<Q, L>::new(cfg, &[&across_chunks, &in_last_chunk]).unwrap();
    s.set_equilibrium(|x, y, z| {
        (
            1.0 + 0.001 * ((x + 2 * y) % 5) as f64,
            [0.04 * ((x % 7) as f64 / 7.0), 0.01 * (z as f64 - 2.0) / 2.0, 0.005 * (y % 3) as f64],
        )
    });
    s
}

/// Periodic rows shorter than one vector block: a row's first and last node, both wrapping, in
/// the same block.
fn oracle_case_short_rows<const Q: usize, L: Lattice3<Q>>(collision: Collision, smagorinsky: f64) -> Lbm3<Q, L> {
    let mut cfg = D3Config::new([5, 6, 7], 0.52);
    cfg.collision = collision;
    cfg.smagorinsky = smagorinsky;
    cfg.body_force = [1e-5, -2e-6, 3e-6];
    let mut s = Lbm3::<Q, L>::new(cfg, &[]).unwrap();
    s.set_equilibrium(|x, y, z| {
        (
            1.0 + 0.001 * ((x + 2 * y) % 5) as f64,
            [0.04 * (x as f64 - 2.0) / 2.0, 0.01 * (z as f64 - 3.0) / 3.0, 0.005 * (y % 3) as f64],
        )
    });
    s
}

fn oracle_matches<const Q: usize, L: Lattice3<Q>>() {
    let cases: [(Case<Q, L>, Collision, f64); 7] = [
        (oracle_case_short_rows::<Q, L>, Collision::Regularized, 0.0),
        (oracle_case_streamed::<Q, L>, Collision::Regularized, 0.1),
        (oracle_case::<Q, L>, Collision::Bgk, 0.0),
        (oracle_case::<Q, L>, Collision::Regularized, 0.0),
        (oracle_case::<Q, L>, Collision::Regularized, 0.17),
        (oracle_case_with_faces::<Q, L>, Collision::Bgk, 0.0),
        (oracle_case_with_faces::<Q, L>, Collision::Regularized, 0.17),
    ];
    for ((case, collision, smag), narrow) in cases.into_iter().flat_map(|c| [(c, false), (c, true)]) {
        let mut fast = case(collision, smag);
        if narrow {
            fast.use_narrow_blocks();
        }
        let mut slow = case(collision, smag);
        for step in 0..20 {
            fast.poison_scratch();
            fast.step().unwrap();
            slow.step_reference().unwrap();
            let same = fast
                .populations_raw()
                .iter()
                .zip(slow.populations_raw())
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(
                same,
                "{} {} C_s {smag} (narrow blocks: {narrow}): fast kernel differs from the oracle at step {step}",
                L::NAME,
                collision.name()
            );
            assert_eq!(fast.body_forces(), slow.body_forces());
            assert_eq!(fast.segment_forces(), slow.segment_forces());
        }
    }
}

#[test]
fn fast_kernel_matches_the_slow_oracle_bitwise() {
    oracle_matches::<19, D3q19>();
    oracle_matches::<27, D3q27>();
}

#[test]
fn bitwise_identical_across_thread_counts() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut s = oracle_case::<19, D3q19>(Collision::Regularized, 0.1);
            for _ in 0..30 {
                s.step().unwrap();
            }
            (s.populations_raw().to_vec(), s.body_forces().to_vec())
        })
    };
    let (f1, b1) = run(1);
    let (f2, b2) = run(2);
    assert!(f1.iter().zip(&f2).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(b1, b2);
}

/// A standing pressure wave between two free-slip faces barely decays at tau 0.51; an absorbing
/// layer on one face takes most of its energy within a few crossings, and leaves a fluid at its
/// target state as it is.
#[test]
fn an_absorbing_layer_damps_a_standing_pressure_wave() {
    let nz = 32;
    let run = |sponge: bool| {
        let mut cfg = D3Config::new([4, 4, nz], 0.51);
        cfg.faces.0[4] = Face::FreeSlip;
        cfg.faces.0[5] = Face::FreeSlip;
        if sponge {
            cfg.sponges = vec![Sponge3 {
                face: 5,
                width: 8,
                strength: 0.3,
                rho: 1.0,
                u: [0.0; 3],
            }];
        }
        let mut s = Lbm3::<19, D3q19>::new(cfg, &[]).unwrap();
        let wave = |z: usize| 0.01 * (std::f64::consts::PI * (z as f64 + 0.5) / nz as f64).cos();
        s.set_equilibrium(|_, _, z| (1.0 + wave(z), [0.0; 3]));
        let energy = |s: &Lbm3<19, D3q19>| (0..nz).map(|z| (s.rho_u([1, 1, z]).0 - 1.0).powi(2)).sum::<f64>();
        let e0 = energy(&s);
        let mut peak = 0.0f64;
        // Four crossings of the box at the speed of sound, the energy at its largest over the
        // last (pressure and velocity trade places every half period).
        let crossing = (nz as f64 * 3f64.sqrt()) as usize;
        for k in 0..4 * crossing {
            s.step().unwrap();
            if k >= 3 * crossing {
                peak = peak.max(energy(&s));
            }
        }
        peak / e0
    };
    let (free, damped) = (run(false), run(true));
    println!("pressure-wave energy left after four crossings: {free:.3} without a layer, {damped:.4} with one");
    assert!(free > 0.5, "the undamped wave lost {free}");
    assert!(damped < 0.05 * free, "the layer left {damped} of the energy");

    // At its target state the layer changes nothing.
    let mut cfg = D3Config::new([4, 4, 8], 0.6);
    cfg.sponges = vec![Sponge3 {
        face: 0,
        width: 3,
        strength: 0.5,
        rho: 1.0,
        u: [0.05, 0.0, 0.0],
    }];
    let mut s = Lbm3::<19, D3q19>::new(cfg, &[]).unwrap();
    s.set_equilibrium(|_, _, _| (1.0, [0.05, 0.0, 0.0]));
    let before = s.populations_raw().to_vec();
    s.step().unwrap();
    let diff = before
        .iter()
        .zip(s.populations_raw())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(diff < 1e-7, "a uniform stream at the target moved by {diff}");
}

/// An extruded section, hidden from the solver's shortcut for bodies the same at every z.
#[derive(Debug)]
struct PlaneByPlane(Extruded<Circle>);

impl Solid for PlaneByPlane {
    fn sdf(&self, p: [f64; 3]) -> f64 {
        self.0.sdf(p)
    }
}

/// The solid nodes of an extruded body planned from one plane are those planned plane by plane:
/// the same links and the same flow, bitwise.
#[test]
fn an_extruded_body_plans_from_one_plane() {
    let circle = || {
        Extruded(Circle {
            center: [6.3, 5.2],
            radius: 2.4,
        })
    };
    let build = |body: &dyn Solid| {
        let mut cfg = D3Config::new([14, 11, 6], 0.55);
        cfg.faces.0[0] = Face::Velocity([0.04, 0.0, 0.0]);
        cfg.faces.0[1] = Face::Outlet;
        let mut s = Lbm3::<19, D3q19>::new(cfg, &[body]).unwrap();
        s.set_equilibrium(|_, _, _| (1.0, [0.04, 0.0, 0.0]));
        for _ in 0..5 {
            s.step().unwrap();
        }
        (s.link_count(), s.populations_raw().to_vec(), s.body_forces().to_vec())
    };
    let (fast, slow) = (build(&circle()), build(&PlaneByPlane(circle())));
    assert!(fast.0 > 0);
    assert_eq!(fast.0, slow.0);
    assert!(fast.1.iter().zip(&slow.1).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(fast.2, slow.2);
}

#[test]
fn blow_up_names_step_cause_and_node() {
    // A body force with nothing to hold it back: the flow accelerates by 1e-3 per step and
    // passes u_max = 0.5 at step 500.
    let mut cfg = D3Config::new([8, 8, 8], 0.6);
    cfg.body_force = [1e-3, 0.0, 0.0];
    cfg.check_interval = 1;
    let mut s = Lbm3::<19, D3q19>::new(cfg, &[]).unwrap();
    let err = (0..1000).find_map(|_| s.step().err()).expect("the runaway flow is caught");
    let text = err.to_string();
    println!("{text}");
    assert!(
        text.contains("diverged at step 50") && text.contains("lattice speed") && text.contains("at node (0, 0, 0)"),
        "{text}"
    );
}

#[test]
fn refuses_configurations_that_cannot_run() {
    let bad = |cfg: D3Config| Lbm3::<19, D3q19>::new(cfg, &[]).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(bad(D3Config::new([8, 8, 8], 0.5)).contains("`tau`"));
    let mut cfg = D3Config::new([8, 8, 8], 0.6);
    cfg.collision = Collision::Recursive;
    assert!(bad(cfg).contains("`collision`"));
    let mut cfg = D3Config::new([8, 8, 8], 0.6);
    cfg.collision = Collision::Bgk;
    cfg.smagorinsky = 0.1;
    assert!(bad(cfg).contains("`smagorinsky`"));
    assert!(bad(D3Config::new([0, 8, 8], 0.6)).contains("`n`"));
    let mut cfg = D3Config::new([8, 8, 8], 0.6);
    cfg.segments = 3;
    assert!(bad(cfg).contains("`segments`"));
    let mut cfg = D3Config::new([8, 8, 8], 0.6);
    cfg.faces.0[0] = Face::Outlet;
    assert!(bad(cfg).contains("`faces`"));
}

/// The benchmark's free-streaming step (`step_streaming_only`, the kernel without its
/// collision) moves every population by exactly its velocity on a periodic grid: after one step
/// population `i` at `x` is the one that was at `x - c_i`. Rows of 43 run blocks of 16 and 8,
/// a partial block, and their periodic ends.
fn free_streaming_moves_each_population_by_its_velocity<const Q: usize, L: Lattice3<Q>>() {
    let n = [43, 5, 3];
    let mut s = Lbm3::<Q, L>::new(D3Config::new(n, 0.8), &[]).unwrap();
    // Storage: plane z, then direction i, then row y, then x.
    let at = |p: [usize; 3], i: usize| ((p[2] * Q + i) * n[1] + p[1]) * n[0] + p[0];
    let mut f = vec![0.0f32; s.populations_raw().len()];
    for (k, v) in f.iter_mut().enumerate() {
        *v = k as f32; // distinct and exact (below 2^24)
    }
    s.set_populations(&f, 0).unwrap();
    s.step_streaming_only().unwrap();
    let g = s.populations_raw();
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                for (i, c) in L::C.iter().enumerate() {
                    let from = [0, 1, 2].map(|a| ([x, y, z][a] as i64 - c[a] as i64).rem_euclid(n[a] as i64) as usize);
                    assert_eq!(g[at([x, y, z], i)], f[at(from, i)], "{}: direction {i} at {:?}", L::NAME, [x, y, z]);
                }
            }
        }
    }
}

#[test]
fn free_streaming_is_a_pure_shift() {
    free_streaming_moves_each_population_by_its_velocity::<19, D3q19>();
    free_streaming_moves_each_population_by_its_velocity::<27, D3q27>();
}
