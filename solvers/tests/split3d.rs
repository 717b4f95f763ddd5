//! The 3D solver split over ranks (ranks as threads here, `comm::Local`; the same code runs over
//! MPI with the `mpi` feature) gives bitwise what one process gives: forces per body and segment
//! at every step, probes, mass, every owned node's populations, and the blow-up report. Run on
//! boxes split along y (inlet, outlet, free-slip sides, absorbing layers across and along the
//! split, a moving sphere; and between walls), along z (periodic, so the two ghosts of a rank come
//! from the same neighbour when there are two ranks) and along x (a line of nodes), with 2 and 3
//! ranks.

use hgym_solvers::comm::{Comm, Local, Solo};
use hgym_solvers::geometry::{Circle, Extruded, Solid, Sphere};
use hgym_solvers::lbm::d3::{split_axis, D3Config, D3q19, D3q27, Face, Faces, Lattice3, Lbm3, Sponge3};
use hgym_solvers::lbm::{Collision, LbmError};

/// What one run records: per step the segment forces; at the end the probes, the mass and the
/// populations of every node (as the owning rank holds them).
#[derive(Debug, PartialEq)]
struct Record {
    forces: Vec<Vec<[f64; 3]>>,
    probes: Vec<(f64, [f64; 3])>,
    mass: f64,
    nodes: Vec<([usize; 3], Vec<u32>)>,
}

#[derive(Clone, Copy)]
enum Case {
    /// 22 x 10 x 8, along y: inlet, outlet with a layer, free-slip sides (one with a layer), a
    /// spinning sphere.
    Channel,
    /// 10 x 8 x 18, along z, periodic everywhere with a body force: an extruded cylinder.
    Periodic,
    /// 6 x 14 x 6, along y: walls at both y ends, periodic x and z, D3Q27, lid-driven by a
    /// moving sphere.
    Walls,
    /// 24 x 1 x 1, along x, periodic, driven by a body force.
    Line,
}

fn config(case: Case) -> D3Config {
    match case {
        Case::Channel => {
            let mut cfg = D3Config::new([22, 10, 8], 0.56);
            cfg.smagorinsky = 0.1;
            cfg.faces = Faces([
                Face::Velocity([0.04, 0.0, 0.0]),
                Face::Outlet,
                Face::FreeSlip,
                Face::FreeSlip,
                Face::FreeSlip,
                Face::FreeSlip,
            ]);
            cfg.segments = 2;
            cfg.check_interval = 5;
            let layer = |face, width| Sponge3 {
                face,
                width,
                strength: 0.3,
                rho: 1.0,
                u: [0.04, 0.0, 0.0],
            };
            cfg.sponges = vec![layer(1, 6), layer(3, 4)];
            cfg
        }
        Case::Periodic => {
            let mut cfg = D3Config::new([10, 8, 18], 0.6);
            cfg.collision = Collision::Bgk;
            cfg.body_force = [2e-6, 0.0, 0.0];
            cfg.segments = 3;
            cfg.check_interval = 4;
            cfg
        }
        Case::Walls => {
            let mut cfg = D3Config::new([6, 14, 6], 0.7);
            cfg.faces.0[2] = Face::Wall;
            cfg.faces.0[3] = Face::Wall;
            cfg
        }
        Case::Line => {
            let mut cfg = D3Config::new([24, 1, 1], 0.8);
            cfg.body_force = [1e-5, 0.0, 0.0];
            cfg
        }
    }
}

fn bodies(case: Case) -> Vec<Box<dyn Solid>> {
    match case {
        Case::Channel => vec![Box::new(Sphere {
            center: [7.3, 4.6, 3.7],
            radius: 2.4,
        })],
        Case::Periodic => vec![Box::new(Extruded(Circle {
            center: [4.4, 3.6],
            radius: 1.9,
        }))],
        Case::Walls => vec![Box::new(Sphere {
            center: [2.5, 6.6, 2.4],
            radius: 1.7,
        })],
        Case::Line => vec![],
    }
}

const PROBES: [[f64; 3]; 4] = [[1.3, 2.2, 0.4], [10.5, 4.1, 3.5], [5.0, 7.7, 5.5], [3.2, 1.0, 2.6]];

fn run<const Q: usize, L: Lattice3<Q>>(case: Case, comm: Box<dyn Comm>, steps: usize) -> Record {
    let bodies = bodies(case);
    let refs: Vec<&dyn Solid> = bodies.iter().map(|b| b.as_ref()).collect();
    let mut s = Lbm3::<Q, L>::new_split(config(case), &refs, comm).unwrap();
    if !refs.is_empty() {
        s.set_wall_velocity(0, |p| [0.0, -0.02 * (p[2] - 3.0), 0.02 * (p[1] - 5.0)]);
    }
    s.set_equilibrium(|x, y, z| (1.0 + 1e-3 * ((x * 7 + y * 3 + z) % 5) as f64, [0.01, 0.002 * (z % 3) as f64, 0.0]));
    let mut forces = Vec::new();
    for _ in 0..steps {
        s.step().unwrap();
        forces.push(s.segment_forces().to_vec());
    }
    let n = s.config().n;
    let probes = PROBES
        .iter()
        .filter(|p| (0..3).all(|a| p[a] < n[a] as f64 - 1.0))
        .map(|p| s.probe(*p).unwrap())
        .collect();
    let mass = s.mass();
    let mut nodes = Vec::new();
    for z in 0..n[2] {
        for y in 0..n[1] {
            for x in 0..n[0] {
                if s.owns([x, y, z]) && !s.is_solid([x, y, z]) {
                    let (rho, u) = s.rho_u([x, y, z]);
                    nodes.push(([x, y, z], [rho, u[0], u[1], u[2]].map(|v| (v as f32).to_bits()).to_vec()));
                }
            }
        }
    }
    Record {
        forces,
        probes,
        mass,
        nodes,
    }
}

/// `ranks` threads each stepping its slab; their records merged (the forces, probes and mass
/// must agree across ranks; the nodes are each rank's own).
fn split<const Q: usize, L: Lattice3<Q>>(case: Case, ranks: usize, steps: usize) -> Record {
    let records: Vec<Record> = std::thread::scope(|scope| {
        let handles: Vec<_> = Local::group(ranks)
            .into_iter()
            .map(|c| scope.spawn(move || run::<Q, L>(case, Box::new(c), steps)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut merged = Record {
        forces: records[0].forces.clone(),
        probes: records[0].probes.clone(),
        mass: records[0].mass,
        nodes: Vec::new(),
    };
    for r in records {
        assert_eq!(r.forces, merged.forces, "ranks disagree on the forces");
        assert_eq!(r.probes, merged.probes, "ranks disagree on the probes");
        assert_eq!(r.mass.to_bits(), merged.mass.to_bits(), "ranks disagree on the mass");
        merged.nodes.extend(r.nodes);
    }
    merged.nodes.sort_by_key(|(p, _)| [p[2], p[1], p[0]]);
    merged
}

fn same_as_one_process<const Q: usize, L: Lattice3<Q>>(case: Case, expected_axis: usize) {
    assert_eq!(split_axis(config(case).n), expected_axis);
    let steps = 12;
    let one = run::<Q, L>(case, Box::new(Solo), steps);
    if !bodies(case).is_empty() {
        assert!(one.forces.last().unwrap().iter().any(|f| f[0] != 0.0), "the body feels no force");
    }
    for ranks in [2, 3] {
        let many = split::<Q, L>(case, ranks, steps);
        assert_eq!(many.nodes.len(), one.nodes.len(), "{ranks} ranks: nodes owned twice or not at all");
        for (step, (a, b)) in one.forces.iter().zip(&many.forces).enumerate() {
            let bits = |f: &Vec<[f64; 3]>| f.iter().flat_map(|v| v.map(f64::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(a), bits(b), "{ranks} ranks: forces differ at step {step}: {a:?} vs {b:?}");
        }
        assert_eq!(one, many, "{ranks} ranks");
    }
}

#[test]
fn split_along_y_with_inlet_outlet_layers_and_a_spinning_sphere_is_bitwise_one_process() {
    same_as_one_process::<19, D3q19>(Case::Channel, 1);
}

#[test]
fn split_along_a_periodic_z_is_bitwise_one_process() {
    same_as_one_process::<19, D3q19>(Case::Periodic, 2);
}

#[test]
fn split_along_y_between_walls_with_d3q27_is_bitwise_one_process() {
    same_as_one_process::<27, D3q27>(Case::Walls, 1);
}

#[test]
fn split_along_x_a_line_of_nodes_is_bitwise_one_process() {
    same_as_one_process::<19, D3q19>(Case::Line, 0);
}

/// A blow-up is reported by every rank with the node one process names.
#[test]
fn every_rank_reports_the_blow_up_one_process_reports() {
    let blow_up = |comm: Box<dyn Comm>| -> LbmError {
        let mut cfg = config(Case::Channel);
        cfg.u_max = 0.045;
        let sphere = Sphere {
            center: [7.3, 4.6, 3.7],
            radius: 2.4,
        };
        let mut s = Lbm3::<19, D3q19>::new_split(cfg, &[&sphere], comm).unwrap();
        s.set_equilibrium(|x, _, _| (1.0, [if x > 15 { 0.05 } else { 0.01 }, 0.0, 0.0]));
        (0..20).find_map(|_| s.step().err()).expect("no blow-up reported")
    };
    let one = blow_up(Box::new(Solo));
    assert!(
        matches!(&one, LbmError::Diverged3 { reason, .. } if reason.contains("lattice speed")),
        "{one}"
    );
    let errors: Vec<LbmError> = std::thread::scope(|scope| {
        let handles: Vec<_> = Local::group(3)
            .into_iter()
            .map(|c| scope.spawn(move || blow_up(Box::new(c))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for e in errors {
        assert_eq!(e, one);
    }
}

#[test]
fn more_ranks_than_nodes_along_the_split_axis_is_refused_naming_the_limit() {
    let groups = Local::group(9);
    let c = groups.into_iter().next().unwrap();
    let err = Lbm3::<19, D3q19>::new_split(D3Config::new([12, 8, 4], 0.6), &[], Box::new(c))
        .err()
        .unwrap();
    let msg = err.to_string();
    assert!(
        msg.contains("ranks") && msg.contains("at most 8") && msg.contains("along y"),
        "{msg}"
    );
}
