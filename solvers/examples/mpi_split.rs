//! The 3D solver over MPI ranks against one process, bitwise, and its speed.
//!
//! `mpirun -np 2 mpi_split` (built with `--features mpi`; `make mpi` builds and runs it): every
//! rank steps its slab of a channel with an inlet, an outlet with an absorbing layer, free-slip
//! sides and a spinning sphere; rank 0 also steps the whole box alone, and the forces of every
//! step, probes and the mass must be bitwise equal (exit 1 otherwise). With `--bench N` it then
//! times `N` steps of a 192 x 96 x 96 D3Q19 box split over the ranks and prints MLUPS and the
//! bytes each rank exchanges per step.

use std::process::ExitCode;
use std::time::Instant;

use hgym_solvers::comm::{Comm, MpiComm, Solo};
use hgym_solvers::geometry::{Solid, Sphere};
use hgym_solvers::lbm::d3::{split_axis, D3Config, D3q19, Face, Faces, Lbm3, Sponge3};
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

/// The comparison on every rank (judged on rank 0), then the bench if asked for.
fn check(rank: i32, size: usize) -> Result<bool, String> {
    let bench: Option<usize> = std::env::args().skip_while(|a| a != "--bench").nth(1).and_then(|v| v.parse().ok());
    let n = [48, 20, 16];
    let steps = 40;
    let split = run(n, steps, Box::new(MpiComm))?;
    if rank == 0 {
        let one = run(n, steps, Box::new(Solo))?;
        let differ: Vec<&str> = [
            ("forces", one.forces != split.forces),
            ("probes", one.probes != split.probes),
            ("mass", one.mass != split.mass),
        ]
        .iter()
        .filter(|d| d.1)
        .map(|d| d.0)
        .collect();
        let axis = ["x", "y", "z"][split_axis(n)];
        if !differ.is_empty() {
            println!(
                "{n:?} box split along {axis} over {size} ranks, {steps} steps: {} DIFFER from one process",
                differ.join(", ")
            );
            return Ok(false);
        }
        println!("{n:?} box split along {axis} over {size} ranks, {steps} steps: forces, probes and mass bitwise the same as one process");
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
    }
    Ok(true)
}
