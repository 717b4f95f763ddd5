//! 2:1 grid refinement in 3D (one and two nested boxes): a uniform flow stays uniform, a
//! Taylor-Green vortex decays at the analytic rate through the interfaces, a sphere on a coarse
//! grid with a fine box around it feels the drag of the uniformly fine grid (and so does a
//! cylinder with a box that covers its periodic span), unusable patches are refused, and results
//! do not depend on the thread count or on how much is restricted.

use std::f64::consts::PI;

use hgym_solvers::geometry::{Circle, Extruded, Solid, Sphere};
use hgym_solvers::lbm::d3::{D3Config, D3q19, D3q27, Face, Faces, Lattice3, Lbm3, Patch3, Refined3, Sponge3};
use hgym_solvers::lbm::{Collision, LbmError};

#[test]
fn a_uniform_flow_crosses_the_interfaces_unchanged() {
    let u0 = [0.04, 0.015, -0.01];
    fn check<const Q: usize, L: Lattice3<Q>>(collision: Collision, patches: &[Patch3], u0: [f64; 3]) {
        let mut cfg = D3Config::new([24, 20, 20], 0.56);
        cfg.collision = collision;
        let mut r = Refined3::<Q, L>::new(cfg, patches, &[]).unwrap();
        r.init_with(|_| (1.0, u0));
        for _ in 0..40 {
            r.step().unwrap();
        }
        r.sync();
        assert_eq!(r.levels().len(), patches.len() + 1);
        for (l, grid) in r.levels().iter().enumerate() {
            let n = grid.config().n;
            for z in 0..n[2] {
                for y in 0..n[1] {
                    for x in 0..n[0] {
                        let (rho, u) = grid.rho_u([x, y, z]);
                        let worst = (0..3).map(|a| (u[a] - u0[a]).abs()).fold((rho - 1.0).abs(), f64::max);
                        assert!(
                            worst < 2e-6,
                            "{} {collision:?}: node ({x}, {y}, {z}) of level {l}: rho {rho}, u {u:?}",
                            L::NAME
                        );
                    }
                }
            }
        }
    }
    let two = [
        Patch3 {
            lo: [6, 5, 5],
            hi: [16, 14, 14],
        },
        Patch3 {
            lo: [4, 4, 4],
            hi: [14, 12, 12],
        },
    ];
    check::<19, D3q19>(Collision::Regularized, &two, u0);
    check::<19, D3q19>(Collision::Bgk, &two[..1], u0);
    check::<27, D3q27>(Collision::Regularized, &two[..1], u0);
}

/// Taylor-Green vortex in x-y, uniform along z, wavelength `n` coarse cells:
/// `u = -u0 cos(kx) sin(ky) e^{-2 nu k^2 t}`, `v = u0 sin(kx) cos(ky) e^{-2 nu k^2 t}`, with its
/// pressure (positions in coarse lattice units).
fn taylor_green(n: usize, u0: f64, nu: f64, t: f64, x: [f64; 3]) -> (f64, [f64; 3]) {
    let k = 2.0 * PI / n as f64;
    let d = (-2.0 * nu * k * k * t).exp();
    let p = -0.25 * u0 * u0 * ((2.0 * k * x[0]).cos() + (2.0 * k * x[1]).cos()) * d * d;
    (
        1.0 + 3.0 * p,
        [
            -u0 * (k * x[0]).cos() * (k * x[1]).sin() * d,
            u0 * (k * x[0]).sin() * (k * x[1]).cos() * d,
            0.0,
        ],
    )
}

/// The same vortex in the x-z plane, uniform along y.
fn taylor_green_xz(n: usize, u0: f64, nu: f64, t: f64, x: [f64; 3]) -> (f64, [f64; 3]) {
    let (rho, u) = taylor_green(n, u0, nu, t, [x[0], x[2], x[1]]);
    (rho, [u[0], 0.0, u[1]])
}

type Vortex = fn(usize, f64, f64, f64, [f64; 3]) -> (f64, [f64; 3]);

/// Relative L2 error of `grid`'s velocity against `vortex` at time `t`.
fn vortex_error<const Q: usize, L: Lattice3<Q>>(grid: &Lbm3<Q, L>, vortex: Vortex, n: usize, u0: f64, nu: f64, t: f64) -> f64 {
    let (mut e2, mut r2) = (0.0, 0.0);
    let c = grid.config();
    for z in 0..c.n[2] {
        for y in 0..c.n[1] {
            for x in 0..c.n[0] {
                let (_, u) = grid.rho_u([x, y, z]);
                let (_, ue) = vortex(n, u0, nu, t, c.grid.position([x, y, z]));
                e2 += (0..3).map(|a| (u[a] - ue[a]).powi(2)).sum::<f64>();
                r2 += ue.iter().map(|v| v * v).sum::<f64>();
            }
        }
    }
    (e2 / r2).sqrt()
}

/// The relative L2 errors of the uniform grid and of the refined run's coarse and fine grids,
/// the refined run's mass drift, and the fine grid's size.
struct Decay {
    errors: [f64; 3],
    drift: f64,
    fine_n: [usize; 3],
}

/// What a vortex of wavelength 32 coarse cells (u0 0.03, tau 0.56) does in 300 steps on the
/// periodic box of `n` nodes and on the same box with `patch`.
fn decay_through_a_box(vortex: Vortex, n: [usize; 3], patch: Patch3) -> Decay {
    let (wavelength, u0, tau, steps) = (32usize, 0.03, 0.56, 300);
    let nu = (tau - 0.5) / 3.0;
    let t = steps as f64;
    let cfg = D3Config::new(n, tau);
    let mut uniform = Lbm3::<19, D3q19>::new(cfg.clone(), &[]).unwrap();
    uniform.set_equilibrium(|x, y, z| vortex(wavelength, u0, nu, 0.0, [x as f64, y as f64, z as f64]));
    for _ in 0..steps {
        uniform.step().unwrap();
    }
    let mut r = Refined3::<19, D3q19>::new(cfg, &[patch], &[]).unwrap();
    r.init_with(|x| vortex(wavelength, u0, nu, 0.0, x));
    let m0 = r.coarse().mass();
    for _ in 0..steps {
        r.step().unwrap();
    }
    r.sync();
    let error = |grid: &Lbm3<19, D3q19>| vortex_error(grid, vortex, wavelength, u0, nu, t);
    Decay {
        errors: [error(&uniform), error(r.coarse()), error(&r.levels()[1])],
        drift: (r.coarse().mass() - m0) / m0,
        fine_n: r.levels()[1].config().n,
    }
}

#[test]
fn a_taylor_green_vortex_decays_through_the_interface() {
    let patch = Patch3 {
        lo: [7, 9, 3],
        hi: [23, 25, 9],
    };
    let Decay {
        errors: [e_uniform, e_coarse, e_fine],
        drift,
        ..
    } = decay_through_a_box(taylor_green, [32, 32, 12], patch);
    println!(
        "3D Taylor-Green after 300 steps: uniform error {e_uniform:.3e}; refined coarse {e_coarse:.3e}, fine {e_fine:.3e}; mass drift {drift:.2e}"
    );
    assert!(
        e_coarse < 1.3 * e_uniform,
        "coarse grid with the patch: {e_coarse} vs uniform {e_uniform}"
    );
    assert!(e_fine < e_uniform, "fine patch: {e_fine} vs uniform coarse {e_uniform}");
    assert!(drift.abs() < 1e-5, "relative mass drift {drift}");
}

#[test]
fn a_taylor_green_vortex_decays_through_a_box_that_covers_the_periodic_span() {
    // The vortex turns in x-z; the box covers z whole (0..=31), so its fine grid wraps along z
    // and the vortex crosses only its x faces, whose interpolation runs across the wrap.
    let patch = Patch3 {
        lo: [7, 3, 0],
        hi: [23, 9, 31],
    };
    let Decay {
        errors: [e_uniform, e_coarse, e_fine],
        drift,
        fine_n,
    } = decay_through_a_box(taylor_green_xz, [32, 12, 32], patch);
    assert_eq!(fine_n, [33, 13, 64]);
    println!(
        "x-z Taylor-Green, box over the whole periodic z, after 300 steps: uniform error {e_uniform:.3e}; \
         refined coarse {e_coarse:.3e}, fine {e_fine:.3e}; mass drift {drift:.2e}"
    );
    assert!(
        e_coarse < 1.3 * e_uniform,
        "coarse grid with the box: {e_coarse} vs uniform {e_uniform}"
    );
    assert!(e_fine < e_uniform, "fine box: {e_fine} vs uniform coarse {e_uniform}");
    assert!(drift.abs() < 1e-5, "relative mass drift {drift}");
}

/// A sphere (diameter `4 k` nodes) in a channel `48 k x 24 k x 24 k` with a velocity inlet, an
/// outlet and free-slip sides, at Re 20, `k` nodes per coarse cell.
fn sphere_channel(k: usize) -> (D3Config, Sphere) {
    let u = 0.05;
    let d = 4.0 * k as f64;
    let tau = 0.5 + 3.0 * u * d / 20.0;
    let mut cfg = D3Config::new([48 * k, 24 * k, 24 * k], tau);
    cfg.faces = Faces([
        Face::Velocity([u as f32, 0.0, 0.0]),
        Face::Outlet,
        Face::FreeSlip,
        Face::FreeSlip,
        Face::FreeSlip,
        Face::FreeSlip,
    ]);
    let s = k as f64;
    let sphere = Sphere {
        center: [14.3 * s, 12.1 * s, 11.9 * s],
        radius: 0.5 * d,
    };
    (cfg, sphere)
}

fn drag_coefficient(fx: f64, diameter: f64) -> f64 {
    fx / (0.5 * 0.05 * 0.05 * PI * 0.25 * diameter * diameter)
}

/// Drag coefficients (`c_d(f_x, k)` with `k` nodes per coarse cell) after `steps` coarse steps
/// from a uniform start at u 0.05: on the uniformly fine grid (`setup(2)`), the uniformly coarse
/// one (`setup(1)`) and the coarse one with `patch`; and the node updates per coarse step of the
/// refined and the fine grid.
fn drag_three_ways<S: Solid>(
    setup: impl Fn(usize) -> (D3Config, S),
    patch: Patch3,
    steps: usize,
    c_d: impl Fn(f64, usize) -> f64,
) -> ([f64; 3], [usize; 2]) {
    let start = |_, _, _| (1.0, [0.05, 0.0, 0.0]);
    let uniform = |k: usize| {
        let (cfg, body) = setup(k);
        let mut g = Lbm3::<19, D3q19>::new(cfg, &[&body]).unwrap();
        g.set_equilibrium(start);
        for _ in 0..k * steps {
            g.step().unwrap();
        }
        (c_d(g.body_forces()[0][0], k), g.config().n.iter().product::<usize>())
    };
    let ((c_fine, fine_nodes), (c_coarse, _)) = (uniform(2), uniform(1));
    let (cfg, body) = setup(1);
    let mut r = Refined3::<19, D3q19>::new(cfg, &[patch], &[&body]).unwrap();
    r.init_with(|_| (1.0, [0.05, 0.0, 0.0]));
    for _ in 0..steps {
        r.step().unwrap();
    }
    let c_refined = c_d(r.body_forces()[0][0], 1);
    ([c_fine, c_coarse, c_refined], [r.node_updates_per_step(), 2 * fine_nodes])
}

#[test]
fn a_sphere_on_a_coarse_grid_with_a_fine_box_feels_the_fine_grids_drag() {
    let coarse_steps = 800;
    // 4 nodes per diameter on the coarse grid, 8 on the fine one and in the box around the
    // sphere and its near wake.
    let patch = Patch3 {
        lo: [8, 6, 6],
        hi: [28, 18, 18],
    };
    let ([c_fine, c_coarse, c_refined], [updates, fine_updates]) =
        drag_three_ways(sphere_channel, patch, coarse_steps, |fx, k| drag_coefficient(fx, 4.0 * k as f64));
    let (e_refined, e_coarse) = ((c_refined / c_fine - 1.0).abs(), (c_coarse / c_fine - 1.0).abs());
    println!(
        "sphere at Re 20 after {coarse_steps} coarse steps: C_D uniform fine {c_fine:.4}, uniform coarse {c_coarse:.4} \
         ({:+.2} %), coarse with a fine box {c_refined:.4} ({:+.2} %); node updates per coarse step {updates} vs {fine_updates}",
        100.0 * (c_coarse / c_fine - 1.0),
        100.0 * (c_refined / c_fine - 1.0),
    );
    assert!(e_refined < 0.02, "refined C_D {c_refined} vs uniformly fine {c_fine}");
    assert!(
        e_refined < 0.5 * e_coarse,
        "the box must buy most of the fine grid's accuracy: {e_refined} vs {e_coarse}"
    );
}

/// A cylinder (diameter `4 k` nodes) across a channel `48 k x 24 k` with a periodic span of
/// `6 k` nodes, inlet, outlet and free-slip sides, at Re 20.
fn cylinder_channel(k: usize) -> (D3Config, Extruded<Circle>) {
    let (mut cfg, sphere) = sphere_channel(k);
    cfg.n[2] = 6 * k;
    cfg.faces.0[4] = Face::Periodic;
    cfg.faces.0[5] = Face::Periodic;
    let circle = Circle {
        center: [sphere.center[0], sphere.center[1]],
        radius: sphere.radius,
    };
    (cfg, Extruded(circle))
}

#[test]
fn a_cylinder_with_a_box_over_its_periodic_span_feels_the_fine_grids_drag() {
    let coarse_steps = 3000;
    let patch = Patch3 {
        lo: [8, 6, 0],
        hi: [28, 18, 5],
    };
    // Drag per unit span: C_D = F / (1/2 u^2 D span).
    let c_d = |fx: f64, k: usize| fx / (0.5 * 0.05 * 0.05 * 4.0 * k as f64 * 6.0 * k as f64);
    let ([c_fine, c_coarse, c_refined], _) = drag_three_ways(cylinder_channel, patch, coarse_steps, c_d);
    let (e_refined, e_coarse) = ((c_refined / c_fine - 1.0).abs(), (c_coarse / c_fine - 1.0).abs());
    println!(
        "cylinder over a periodic span at Re 20 after {coarse_steps} coarse steps: C_D uniform fine {c_fine:.4}, \
         uniform coarse {c_coarse:.4} ({:+.2} %), coarse with a box over the span {c_refined:.4} ({:+.2} %)",
        100.0 * (c_coarse / c_fine - 1.0),
        100.0 * (c_refined / c_fine - 1.0),
    );
    // Measured: 2.6895 fine, 2.9137 coarse (+8.3 %), 2.7410 refined (+1.9 %): the box removes
    // 77 % of the coarse grid's error. What is left is the 4-cells-per-D grid outside it (a
    // cylinder's disturbance decays as 1/r, a sphere's as 1/r^2): a box reaching 1 D from the
    // free-slip sides and 2.5 D from the inlet gives the same 1.9 %.
    assert!(
        e_refined < 0.35 * e_coarse,
        "the box must buy most of the fine grid's accuracy: {e_refined} vs {e_coarse}"
    );
}

/// A sphere in a channel with two nested boxes, stepped a little.
fn channel_with_two_boxes() -> Refined3<19, D3q19> {
    let (mut cfg, sphere) = sphere_channel(1);
    cfg.smagorinsky = 0.1;
    cfg.sponges = vec![Sponge3 {
        face: 1,
        width: 4,
        strength: 0.05,
        rho: 1.0,
        u: [0.05, 0.0, 0.0],
    }];
    let patches = [
        Patch3 {
            lo: [8, 6, 6],
            hi: [28, 18, 18],
        },
        Patch3 {
            lo: [6, 6, 6],
            hi: [26, 18, 18],
        },
    ];
    let solid: &dyn Solid = &sphere;
    let mut r = Refined3::<19, D3q19>::new(cfg, &patches, &[solid]).unwrap();
    r.init_with(|x| (1.0, [0.05, 0.002 * (0.3 * x[2]).sin(), 0.001 * (0.2 * x[1]).cos()]));
    r
}

fn fields(r: &Refined3<19, D3q19>) -> Vec<Vec<f32>> {
    r.levels().iter().map(|g| g.populations_raw().to_vec()).collect()
}

#[test]
fn restricting_only_the_ring_between_full_restrictions_changes_nothing_the_coupling_reads() {
    let (mut lazy, mut full) = (channel_with_two_boxes(), channel_with_two_boxes());
    let mut forces = (vec![], vec![]);
    for _ in 0..21 {
        lazy.step().unwrap();
        full.step().unwrap();
        full.sync();
        forces.0.push(lazy.body_forces().to_vec());
        forces.1.push(full.body_forces().to_vec());
    }
    assert!(forces.0 == forces.1, "the forces depend on how much is restricted");
    let finest = |r: &Refined3<19, D3q19>| r.levels()[2].populations_raw().to_vec();
    assert!(finest(&lazy) == finest(&full), "the finest grid depends on how much is restricted");
    let before = fields(&lazy);
    lazy.sync();
    assert!(
        before != fields(&lazy),
        "21 steps is not a multiple of the full-restriction interval"
    );
    assert!(fields(&lazy) == fields(&full), "after a sync every grid agrees to the bit");
}

#[test]
fn bitwise_identical_across_thread_counts() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut r = channel_with_two_boxes();
            let mut forces = vec![];
            for _ in 0..10 {
                r.step().unwrap();
                forces.push(r.body_forces().to_vec());
            }
            (fields(&r), forces)
        })
    };
    assert!(run(1) == run(2));
}

#[test]
fn refuses_patches_that_cannot_run() {
    let (cfg, sphere) = sphere_channel(1);
    let solid: &dyn Solid = &sphere;
    let refused =
        |cfg: D3Config, patches: &[Patch3], bodies: &[&dyn Solid], needle: &str| match Refined3::<19, D3q19>::new(cfg, patches, bodies) {
            Err(LbmError::Config {
                field: "refinement",
                message,
            }) => {
                assert!(message.contains(needle), "{message:?} lacks {needle:?}")
            }
            Err(e) => panic!("refused for another reason: {e}"),
            Ok(_) => panic!("accepted {patches:?}"),
        };
    refused(cfg.clone(), &[], &[solid], "at least one patch");
    refused(
        cfg.clone(),
        &[Patch3 {
            lo: [8, 6, 6],
            hi: [11, 18, 18],
        }],
        &[solid],
        "at least 4 cells",
    );
    refused(
        cfg.clone(),
        &[Patch3 {
            lo: [1, 6, 6],
            hi: [28, 18, 18],
        }],
        &[solid],
        "keep 2 nodes from the faces",
    );
    // The sphere (x 12.3-16.3) pokes out of a box ending at x = 15.
    refused(
        cfg.clone(),
        &[Patch3 {
            lo: [4, 6, 6],
            hi: [15, 18, 18],
        }],
        &[solid],
        "inside a body but outside patch 1",
    );
    // Inside the box on the coarse grid, but within 4 fine nodes of its face: a sphere reaching
    // to x = 16.8 has its last coarse node at 16 and its last fine node at 2 (16.8 - 4) = 25 of 29.
    let closer = Sphere {
        center: [14.8, 12.1, 11.9],
        radius: 2.0,
    };
    refused(
        cfg.clone(),
        &[Patch3 {
            lo: [4, 6, 6],
            hi: [18, 18, 18],
        }],
        &[&closer],
        "within 4 nodes",
    );
    let mut tau_one = cfg.clone();
    tau_one.tau = 0.76;
    refused(
        tau_one,
        &[Patch3 {
            lo: [8, 6, 6],
            hi: [28, 18, 18],
        }],
        &[solid],
        "away from 1",
    );
    let mut layer = cfg.clone();
    layer.sponges = vec![Sponge3 {
        face: 0,
        width: 8,
        strength: 0.05,
        rho: 1.0,
        u: [0.05, 0.0, 0.0],
    }];
    refused(
        layer,
        &[Patch3 {
            lo: [8, 6, 6],
            hi: [28, 18, 18],
        }],
        &[solid],
        "absorbing layer on face 0",
    );
    let mut segments = cfg;
    segments.segments = 2;
    refused(
        segments,
        &[Patch3 {
            lo: [8, 6, 6],
            hi: [28, 18, 18],
        }],
        &[solid],
        "segments",
    );
}
