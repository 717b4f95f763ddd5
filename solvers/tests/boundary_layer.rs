//! The spatially developing boundary layer of the channel solver: a fringe region recycles the
//! periodic box into an inflow, the outflow through the free-slip top sets the free stream. The
//! laminar case has an exact answer, the Blasius layer: its skin friction against its momentum
//! thickness and its shape factor downstream of the inflow. A trip forces where it is placed.

use hgym_solvers::blasius::Blasius;
use hgym_solvers::channel::plate::{plate as plate_flow, PlateSpec};
use hgym_solvers::channel::{Channel, ChannelConfig, Drive, FringeSpec, Top, TripSpec};

/// A Blasius layer entering at displacement thickness 1 (the length unit) with `Re_delta* = re`;
/// `n` cells over the box `[lx, ly]`, the fringe over its last `fringe` lengths.
struct Plate {
    c: Channel,
    b: Blasius,
    nu: f64,
    fringe: FringeSpec,
}

fn plate(n: [usize; 2], lx: f64, ly: f64, fringe: f64, re: f64, dt: f64) -> Plate {
    let nu = 1.0 / re;
    let b = Blasius::solve();
    let x0 = b.x_of_displacement(1.0, 1.0, nu);
    let spec = PlateSpec {
        n: [n[0], n[1], 1],
        length: [lx, ly, 1.0],
        stretch: 1.5,
        nu,
        dt,
        fringe: FringeSpec {
            x_start: lx - fringe,
            x_end: lx,
            rise: 0.3 * fringe,
            fall: 0.3 * fringe,
            lambda_max: 1.0,
        },
        modes: 4,
        trip: None,
    };
    let (c, misfit) = plate_flow(&spec, |_| 1.0, |x, y| b.velocity(x0 + x, y, 1.0, nu).0).unwrap();
    assert!(misfit < 1e-12, "a uniform free stream is one mode: {misfit}");
    Plate {
        c,
        b,
        nu,
        fringe: spec.fringe,
    }
}

/// At every `u` position upstream of the fringe: `x`, `C_f Re_theta` and the shape factor
/// `H = delta* / theta`, each divided by Blasius' value (`2 f''(0) theta_hat` and
/// `delta*_hat / theta_hat`; both hold at every `x`, whatever the virtual origin).
fn against_blasius(p: &Plate) -> Vec<(f64, f64, f64)> {
    let g = p.c.grid();
    let (mut tau, mut top) = (vec![0.0; g.nx], vec![0.0; g.nx]);
    p.c.wall_shear(&mut tau, &mut top);
    let u = p.c.u();
    let (cf_re, shape) = (2.0 * p.b.wall_curvature * p.b.momentum, p.b.displacement / p.b.momentum);
    (0..g.nx)
        .map(|i| (i, i as f64 * g.dx))
        .filter(|&(_, x)| x < p.fringe.x_start)
        .map(|(i, x)| {
            // The edge: the first maximum of u above the wall.
            let edge = (1..g.ny).find(|&j| u[g.at(i, j, 0)] < u[g.at(i, j - 1, 0)]).unwrap_or(g.ny);
            let ue = u[g.at(i, edge - 1, 0)];
            let r = |j| u[g.at(i, j, 0)] / ue;
            let delta_star: f64 = (0..edge).map(|j| g.dyf[j] * (1.0 - r(j))).sum();
            let theta: f64 = (0..edge).map(|j| g.dyf[j] * r(j) * (1.0 - r(j))).sum();
            let c_f = 2.0 * tau[i] / (ue * ue);
            (x, c_f * ue * theta / p.nu / cf_re, delta_star / theta / shape)
        })
        .collect()
}

/// Downstream of the inflow's adjustment (40 inflow displacement thicknesses; the fringe's
/// forcing leaves the near-wall profile slightly off Blasius) and upstream of the fringe's own
/// reach, the layer is Blasius': `C_f Re_theta` within 1 % and `H` within 0.5 %, steady, the edge
/// velocity within 0.5 % of 1, and the adjustment shrinking downstream.
#[test]
fn a_laminar_plate_with_a_fringe_is_the_blasius_layer() {
    let mut p = plate([128, 48], 130.0, 12.0, 40.0, 400.0, 0.2);
    for _ in 0..3000 {
        p.c.step().unwrap();
    }
    let before = against_blasius(&p);
    for _ in 0..250 {
        p.c.step().unwrap();
    }
    let after = against_blasius(&p);
    for ((x, cf, h), (_, cf0, h0)) in after.iter().zip(&before) {
        assert!((cf - cf0).abs() < 1e-4 && (h - h0).abs() < 1e-4, "not steady at x = {x}");
        if (40.0..80.0).contains(x) {
            assert!((cf - 1.0).abs() < 0.01, "C_f Re_theta / Blasius = {cf} at x = {x}");
            assert!((h - 1.0).abs() < 0.005, "H / Blasius = {h} at x = {x}");
        }
    }
    let err_at = |x: f64| after.iter().find(|r| r.0 >= x).map(|r| (r.1 - 1.0).abs()).unwrap();
    assert!(err_at(40.0) < 0.5 * err_at(10.0), "the inflow's adjustment decays");
    let g = p.c.grid();
    for i in 0..g.nx {
        let ue = (0..g.ny).map(|j| p.c.u()[g.at(i, j, 0)]).fold(0.0, f64::max);
        assert!((ue - 1.0).abs() < 0.005, "edge velocity {ue} at x = {}", i as f64 * g.dx);
    }
}

/// A trip pushes the fluid up and down at its own place: one step from rest moves `v` most at
/// `x0` near the wall, barely far downstream, and the same seed pushes the same way.
#[test]
fn a_trip_acts_where_it_is() {
    let cfg = ChannelConfig {
        n: [64, 32, 16],
        length: [8.0, 2.0, 2.0],
        stretch: 1.5,
        top: Top::FreeSlip,
        nu: 0.01,
        dt: 0.01,
        drive: Drive::PressureGradient(0.0),
        check_interval: 0,
    };
    let trip = TripSpec {
        x0: 2.0,
        lx: 0.3,
        ly: 0.2,
        z_s: 0.5,
        t_s: 1.0,
        a_steady: 0.5,
        a_time: 1.0,
        seed: 3,
    };
    let run = || {
        let mut c = Channel::new(cfg.clone()).unwrap();
        c.set_trip(trip).unwrap();
        c.step().unwrap();
        c.v().to_vec()
    };
    let v = run();
    let c = Channel::new(cfg.clone()).unwrap();
    let g = c.grid();
    let largest = |i0: usize, i1: usize| {
        let mut m = 0.0f64;
        for k in 0..g.nz {
            for j in 1..g.ny {
                for i in i0..i1 {
                    m = m.max(v[g.at_v(i, j, k)].abs());
                }
            }
        }
        m
    };
    let near = largest(14, 18); // x in [1.75, 2.25)
    let far = largest(40, 56); // x in [5, 7)
    assert!(near > 1e-3, "{near}");
    assert!(far < 0.05 * near, "{far} against {near}");
    assert_eq!(v, run(), "the same seed pushes the same way");
}

/// A tripped flow continued from a saved state is the flow that saved it, bit for bit: the
/// state carries the clock the trip's forcing reads.
#[test]
fn a_tripped_flow_continues_from_its_state() {
    let cfg = ChannelConfig {
        n: [32, 16, 8],
        length: [8.0, 2.0, 2.0],
        stretch: 1.5,
        top: Top::FreeSlip,
        nu: 0.01,
        dt: 0.05,
        drive: Drive::PressureGradient(0.0),
        check_interval: 0,
    };
    let trip = TripSpec {
        x0: 2.0,
        lx: 0.5,
        ly: 0.3,
        z_s: 1.0,
        t_s: 0.3,
        a_steady: 0.0,
        a_time: 1.0,
        seed: 5,
    };
    let tripped = || {
        let mut c = Channel::new(cfg.clone()).unwrap();
        c.set_trip(trip).unwrap();
        c
    };
    let mut a = tripped();
    (0..10).for_each(|_| a.step().unwrap());
    let saved = a.state();
    (0..10).for_each(|_| a.step().unwrap());
    let mut b = tripped();
    b.restore(&saved).unwrap();
    assert_eq!((b.steps(), b.time()), (10, saved.time));
    (0..10).for_each(|_| b.step().unwrap());
    assert_eq!(a.state(), b.state());
}
