//! The D2Q9 solver split over ranks along y (ranks as threads here, `comm::Local`; the same code
//! runs over MPI with the `mpi` feature) gives bitwise what one process gives: body forces at
//! every step, probes, mass, the wall's mass source, the density and velocity fields, and the
//! blow-up report. Cases: a channel (velocity inlet with a profile, outlet, free-slip and wall
//! edges, absorbing layers across and along the split, a spinning cylinder and a square crossing
//! slab boundaries), and a box periodic in y with a body force (so a rank's two ghosts come from
//! the same neighbour when there are two ranks); 2, 3 and 5 ranks.

use std::sync::Arc;

use hgym_solvers::comm::{Comm, Local, Solo};
use hgym_solvers::geometry::{Circle, Rectangle, Shape};
use hgym_solvers::lbm::{Collision, D2q9, D2q9Config, Edge, LbmError, Side, Sides, Sponge};

#[derive(Clone, Copy)]
enum Case {
    /// 64 x 37: inlet, outlet with a layer, free-slip south with a layer, wall north; a spinning
    /// cylinder and a square.
    Channel,
    /// 24 x 30, periodic everywhere, BGK with a body force, a cylinder.
    Periodic,
}

fn config(case: Case) -> D2q9Config {
    match case {
        Case::Channel => {
            let ny = 37;
            let profile: Vec<[f32; 2]> = (0..ny).map(|y| [0.05 * (1.0 + 0.2 * (y as f32 * 0.3).sin()), 0.0]).collect();
            let sides = Sides {
                west: Side::Velocity { profile },
                east: Side::Outlet,
                south: Side::FreeSlip,
                north: Side::Wall,
            };
            let mut cfg = D2q9Config::new(64, ny, 0.56, sides);
            cfg.smagorinsky = 0.1;
            cfg.check_interval = 5;
            let layer = |edge, width| Sponge {
                edge,
                width,
                strength: 0.3,
                rho: 1.0,
                u: [0.05, 0.0],
            };
            cfg.sponges = vec![layer(Edge::East, 10), layer(Edge::South, 6)];
            cfg
        }
        Case::Periodic => {
            let mut cfg = D2q9Config::new(24, 30, 0.6, Sides::periodic());
            cfg.collision = Collision::Bgk;
            cfg.body_force = [2e-6, 0.0];
            cfg.check_interval = 4;
            cfg
        }
    }
}

fn bodies(case: Case) -> Vec<Arc<dyn Shape>> {
    match case {
        Case::Channel => vec![
            Arc::new(Circle {
                center: [15.3, 17.6],
                radius: 5.4,
            }),
            Arc::new(Rectangle {
                center: [38.0, 12.2],
                size: [5.0, 9.5],
            }),
        ],
        Case::Periodic => vec![Arc::new(Circle {
            center: [11.4, 14.6],
            radius: 4.1,
        })],
    }
}

const PROBES: [[f64; 2]; 4] = [[1.3, 2.2], [40.5, 24.1], [5.0, 13.5], [20.2, 29.0]];

/// What one run records: per step the body forces; at the end the probes, the mass, the mass
/// source of the moving wall and the fields.
#[derive(Debug, PartialEq)]
struct Record {
    forces: Vec<Vec<u64>>,
    probes: Vec<u64>,
    mass: u64,
    source: u64,
    fields: Vec<u32>,
}

fn run(case: Case, comm: Box<dyn Comm>, steps: usize) -> Record {
    let mut s = D2q9::new_split(config(case), bodies(case), comm).unwrap();
    s.set_wall_velocity(0, |wp| [-0.02 * wp.normal[1], 0.02 * wp.normal[0]]);
    s.init_with(|x, y| {
        (
            1.0 + 1e-3 * (x * 0.7 + y * 0.3).sin(),
            0.03,
            0.01 * (x * 0.2).sin() * (y * 0.1).cos(),
        )
    });
    let bits = |v: &[[f64; 2]]| v.iter().flat_map(|f| f.map(f64::to_bits)).collect::<Vec<_>>();
    let mut forces = Vec::new();
    for _ in 0..steps {
        s.step().unwrap();
        forces.push(bits(s.body_forces()));
    }
    let (nx, ny) = (s.nx(), s.ny());
    let inside: Vec<[f64; 2]> = PROBES
        .into_iter()
        .filter(|p| p[0] < (nx - 1) as f64 && p[1] < (ny - 1) as f64)
        .collect();
    let probes = s.probes(&inside).unwrap().iter().flat_map(|p| p.map(f64::to_bits)).collect();
    let mut fields = vec![vec![0.0f32; nx * ny]; 3];
    let [rho, ux, uy] = &mut fields[..] else { unreachable!() };
    s.macroscopic(rho, ux, uy);
    Record {
        forces,
        probes,
        mass: s.total_mass().to_bits(),
        source: s.wall_mass_source(0).to_bits(),
        fields: fields.iter().flatten().map(|v| v.to_bits()).collect(),
    }
}

/// `ranks` threads each stepping its slab; every rank must record the same.
fn split(case: Case, ranks: usize, steps: usize) -> Record {
    let mut records: Vec<Record> = std::thread::scope(|scope| {
        let handles: Vec<_> = Local::group(ranks)
            .into_iter()
            .map(|c| scope.spawn(move || run(case, Box::new(c), steps)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let first = records.remove(0);
    for (r, other) in records.iter().enumerate() {
        assert!(*other == first, "rank {} of {ranks} disagrees with rank 0", r + 1);
    }
    first
}

fn same_as_one_process(case: Case) {
    let steps = 30;
    let one = run(case, Box::new(Solo), steps);
    let last = one.forces.last().unwrap();
    assert!(last.iter().any(|&f| f64::from_bits(f) != 0.0), "the bodies feel no force");
    for ranks in [2, 3, 5] {
        let many = split(case, ranks, steps);
        for (step, (a, b)) in one.forces.iter().zip(&many.forces).enumerate() {
            assert_eq!(a, b, "{ranks} ranks: forces differ at step {step}");
        }
        assert_eq!(one.probes, many.probes, "{ranks} ranks: probes");
        assert_eq!(one.mass, many.mass, "{ranks} ranks: mass");
        assert_eq!(one.source, many.source, "{ranks} ranks: wall mass source");
        assert!(one.fields == many.fields, "{ranks} ranks: fields differ");
    }
}

#[test]
fn split_channel_with_inlet_outlet_layers_and_bodies_across_slabs_is_bitwise_one_process() {
    same_as_one_process(Case::Channel);
}

#[test]
fn split_along_a_periodic_y_is_bitwise_one_process() {
    same_as_one_process(Case::Periodic);
}

/// A blow-up is reported by every rank with the node one process names.
#[test]
fn every_rank_reports_the_blow_up_one_process_reports() {
    let blow_up = |comm: Box<dyn Comm>| -> LbmError {
        let mut cfg = config(Case::Channel);
        cfg.u_max = 0.09;
        let mut s = D2q9::new_split(cfg, bodies(Case::Channel), comm).unwrap();
        s.init_with(|x, y| (1.0, if x > 40.0 && y > 20.0 { 0.1 } else { 0.05 }, 0.0));
        (0..20).find_map(|_| s.step().err()).expect("no blow-up reported")
    };
    let one = blow_up(Box::new(Solo));
    assert!(
        matches!(&one, LbmError::Diverged { reason, y, .. } if reason.contains("lattice speed") && *y > 20),
        "{one}"
    );
    let errors: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = Local::group(3)
            .into_iter()
            .map(|c| scope.spawn(move || blow_up(Box::new(c)).to_string()))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for e in errors {
        assert_eq!(e, one.to_string());
    }
}

#[test]
fn more_ranks_than_rows_and_a_split_characteristic_inlet_are_refused_naming_the_field() {
    let mut groups = Local::group(40).into_iter();
    let err = D2q9::new_split(config(Case::Channel), vec![], Box::new(groups.next().unwrap()))
        .err()
        .unwrap();
    let msg = err.to_string();
    assert!(
        msg.contains("ranks") && msg.contains("at most 37") && msg.contains("along y"),
        "{msg}"
    );
    let mut cfg = config(Case::Channel);
    cfg.characteristic_inlet = Some(100.0);
    let mut pair = Local::group(2).into_iter();
    let err = D2q9::new_split(cfg, vec![], Box::new(pair.next().unwrap())).err().unwrap();
    assert!(err.to_string().contains("characteristic"), "{err}");
}
