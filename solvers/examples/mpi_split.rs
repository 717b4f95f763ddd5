//! The 3D and 2D solvers over MPI ranks against one process, bitwise, and their speed.
//!
//! `mpirun -np 2 mpi_split` (built with `--features mpi`; `make mpi` builds and runs it): every
//! rank steps its slab of a channel with an inlet, an outlet with an absorbing layer, free-slip
//! sides and a spinning sphere (3D), and of the same with a spinning cylinder (D2Q9); rank 0 also
//! steps each whole grid alone, and the forces of every step, probes and the mass must be bitwise
//! equal (exit 1 otherwise). With `--bench N` it then times `N` steps of a 192 x 96 x 96 D3Q19
//! box and of a 2048 x 1024 D2Q9 grid split over the ranks and prints MLUPS and the bytes each
//! rank exchanges per step.

use std::process::ExitCode;
use std::time::Instant;

use std::sync::Arc;

use hgym_solvers::comm::{Comm, MpiComm, Solo};
use hgym_solvers::geometry::{Circle, Shape, Solid, Sphere};
use hgym_solvers::lbm::d3::{split_axis, D3Config, D3q19, Face, Faces, Lbm3, Sponge3};
use hgym_solvers::lbm::{D2q9, D2q9Config, Edge, Side, Sides, Sponge};
use mpi::traits::Communicator;

fn channel(n: [usize; 3]) -> D3Config {
    let mut cfg = D3Config::new(n, 0.56);
    cfg.smagorinsky = 0.1;
    cfg.faces = Faces([
        Face::Velocity([0.04, 0.0, 0.0]),
        Face::Outlet,
        Face::FreeSlip,
        Face::FreeSlip,
        Face::Periodic,
        Face::Periodic,
    ]);
    cfg.segments = 2;
    cfg.sponges = vec![Sponge3 {
        face: 1,
        width: n[0] / 4,
        strength: 0.3,
        rho: 1.0,
        u: [0.04, 0.0, 0.0],
    }];
    cfg
}

struct Run {
    forces: Vec<u64>,
    probes: Vec<u64>,
    mass: u64,
    seconds: f64,
}

fn run(n: [usize; 3], steps: usize, comm: Box<dyn Comm>) -> Result<Run, String> {
    let sphere = Sphere {
        center: [0.3 * n[0] as f64, 0.47 * n[1] as f64, 0.5 * n[2] as f64],
        radius: 0.12 * n[1] as f64,
    };
    let bodies: [&dyn Solid; 1] = [&sphere];
    let mut s = Lbm3::<19, D3q19>::new_split(channel(n), &bodies, comm).map_err(|e| e.to_string())?;
    let c = sphere.center;
    s.set_wall_velocity(0, |p| [0.0, -0.01 * (p[2] - c[2]), 0.01 * (p[1] - c[1])]);
    s.set_equilibrium(|x, y, _| (1.0, [0.04, 1e-3 * ((x * 7 + y * 3) % 5) as f64, 0.0]));
    let mut forces = Vec::new();
    let t0 = Instant::now();
    for _ in 0..steps {
        s.step().map_err(|e| e.to_string())?;
        forces.extend(s.segment_forces().iter().flat_map(|f| f.map(f64::to_bits)));
    }
    let seconds = t0.elapsed().as_secs_f64();
    let mut probes = Vec::new();
    for p in [[0.1, 0.2, 0.3], [0.45, 0.5, 0.6], [0.8, 0.3, 0.1]] {
        let (rho, u) = s.probe([0, 1, 2].map(|a| p[a] * (n[a] - 1) as f64)).map_err(|e| e.to_string())?;
        probes.extend([rho, u[0], u[1], u[2]].map(f64::to_bits));
    }
    Ok(Run {
        forces,
        probes,
        mass: s.mass().to_bits(),
        seconds,
    })
}

/// The 2D channel: inlet, outlet with an absorbing layer, free-slip sides, a spinning cylinder.
fn run_2d([nx, ny]: [usize; 2], steps: usize, comm: Box<dyn Comm>) -> Result<Run, String> {
    let u = 0.04;
    let sides = Sides {
        west: Side::Velocity {
            profile: vec![[u as f32, 0.0]; ny],
        },
        east: Side::Outlet,
        south: Side::FreeSlip,
        north: Side::FreeSlip,
    };
    let mut cfg = D2q9Config::new(nx, ny, 0.56, sides);
    cfg.smagorinsky = 0.1;
    cfg.sponges = vec![Sponge {
        edge: Edge::East,
        width: nx / 4,
        strength: 0.3,
        rho: 1.0,
        u: [u, 0.0],
    }];
    let (center, radius) = ([0.3 * nx as f64, 0.47 * ny as f64], 0.12 * ny as f64);
    let cylinder: Arc<dyn Shape> = Arc::new(Circle { center, radius });
    let mut s = D2q9::new_split(cfg, vec![cylinder], comm).map_err(|e| e.to_string())?;
    // Spinning at a wall speed of 0.02 whatever the grid.
    let omega = 0.02 / radius;
    s.set_wall_velocity(0, |wp| {
        [-omega * (wp.position[1] - center[1]), omega * (wp.position[0] - center[0])]
    });
    s.init_with(|x, y| (1.0, u, 1e-3 * ((x as usize * 7 + y as usize * 3) % 5) as f64));
    let mut forces = Vec::new();
    let t0 = Instant::now();
    for _ in 0..steps {
        s.step().map_err(|e| e.to_string())?;
        forces.extend(s.body_forces().iter().flat_map(|f| f.map(f64::to_bits)));
    }
    let seconds = t0.elapsed().as_secs_f64();
    let points: Vec<[f64; 2]> = [[0.1, 0.2], [0.45, 0.5], [0.8, 0.3]]
        .iter()
        .map(|p| [p[0] * (nx - 1) as f64, p[1] * (ny - 1) as f64])
        .collect();
    let probes = s
        .probes(&points)
        .map_err(|e| e.to_string())?
        .iter()
        .flat_map(|p| p.map(f64::to_bits))
        .collect();
    Ok(Run {
        forces,
        probes,
        mass: s.total_mass().to_bits(),
        seconds,
    })
}

fn main() -> ExitCode {
    let Some(universe) = mpi::initialize() else {
        eprintln!("MPI was already initialised");
        return ExitCode::FAILURE;
    };
    let world = universe.world();
    match check(world.rank(), world.size() as usize) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("rank {}: {e}", world.rank());
            ExitCode::FAILURE
        }
    }
}

/// Names what differs between one process's run and the split one.
fn differences(one: &Run, split: &Run) -> Vec<&'static str> {
    [
        ("forces", one.forces != split.forces),
        ("probes", one.probes != split.probes),
        ("mass", one.mass != split.mass),
    ]
    .iter()
    .filter(|d| d.1)
    .map(|d| d.0)
    .collect()
}

/// The comparisons on every rank (judged on rank 0), then the benches if asked for.
fn check(rank: i32, size: usize) -> Result<bool, String> {
    let bench: Option<usize> = std::env::args().skip_while(|a| a != "--bench").nth(1).and_then(|v| v.parse().ok());
    let steps = 40;
    let n = [48, 20, 16];
    let split = run(n, steps, Box::new(MpiComm))?;
    let n2 = [96, 41];
    let split_2d = run_2d(n2, steps, Box::new(MpiComm))?;
    if rank == 0 {
        let one = run(n, steps, Box::new(Solo))?;
        let one_2d = run_2d(n2, steps, Box::new(Solo))?;
        let grids = [
            (
                format!("{n:?} D3Q19 box split along {}", ["x", "y", "z"][split_axis(n)]),
                differences(&one, &split),
            ),
            (format!("{n2:?} D2Q9 grid split along y"), differences(&one_2d, &split_2d)),
        ];
        for (grid, differ) in &grids {
            if differ.is_empty() {
                println!("{grid} over {size} ranks, {steps} steps: forces, probes and mass bitwise the same as one process");
            } else {
                println!(
                    "{grid} over {size} ranks, {steps} steps: {} DIFFER from one process",
                    differ.join(", ")
                );
            }
        }
        if grids.iter().any(|g| !g.1.is_empty()) {
            return Ok(false);
        }
    }

    if let Some(steps) = bench {
        let n = [192, 96, 96];
        let r = run(n, steps, Box::new(MpiComm))?;
        if rank == 0 {
            let cells = n.iter().product::<usize>();
            // A layer (all Q populations of one node plane across the split axis) each way across
            // each of the size - 1 boundaries between slabs (the split axis, y, is not periodic).
            let layer_bytes = 19 * 4 * cells / n[split_axis(n)];
            println!(
                "bench {n:?} D3Q19, {size} rank(s) x {} thread(s): {steps} steps in {:.2} s, {:.1} MLUPS; \
                 {:.2} MB sent per step in all ({} boundaries, one {:.2} MB layer each way)",
                rayon::current_num_threads(),
                r.seconds,
                cells as f64 * steps as f64 / r.seconds / 1e6,
                (2 * (size - 1) * layer_bytes) as f64 / 1e6,
                size - 1,
                layer_bytes as f64 / 1e6
            );
        }
        let n2 = [2048, 1024];
        let r = run_2d(n2, steps, Box::new(MpiComm))?;
        if rank == 0 {
            let cells = n2[0] * n2[1];
            let row_bytes = 9 * 4 * n2[0];
            println!(
                "bench {n2:?} D2Q9, {size} rank(s) x {} thread(s): {steps} steps in {:.2} s, {:.1} MLUPS; \
                 {:.3} MB sent per step in all ({} boundaries, one {:.3} MB row each way)",
                rayon::current_num_threads(),
                r.seconds,
                cells as f64 * steps as f64 / r.seconds / 1e6,
                (2 * (size - 1) * row_bytes) as f64 / 1e6,
                size - 1,
                row_bytes as f64 / 1e6
            );
        }
    }
    Ok(true)
}
