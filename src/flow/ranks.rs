//! hgym over MPI ranks, the single-program way: `mpirun -np N hgym-mpi COMMAND` runs the same
//! command on every rank. The lattice-Boltzmann flows split their grids over the ranks
//! ([`hgym_solvers::lbm::d3::Lbm3::new_split`], [`hgym_solvers::lbm::D2q9::new_split`]);
//! everything they report (forces, probes, fields, slices, the blow-up scan) is summed over the
//! ranks bitwise as one process would compute it, so every rank takes the same decisions
//! (agents, seeds, episode ends) without talking about them. Only rank 0 prints and writes
//! files. What is not split runs whole on every rank: 2D grids with refined patches, the
//! temperature fields, the spectral solvers.
//!
//! The binary that starts MPI is `hgym-mpi` (the `mpi` feature, `make mpi`); `hgym` is one
//! process and needs no MPI library.

use std::sync::atomic::{AtomicUsize, Ordering};

use hgym_solvers::comm::{Comm, Solo};

static RANK: AtomicUsize = AtomicUsize::new(0);
static SIZE: AtomicUsize = AtomicUsize::new(1);

/// Records this process's rank among `size` (called once by the binary after starting MPI).
pub fn set(rank: usize, size: usize) {
    RANK.store(rank, Ordering::Relaxed);
    SIZE.store(size.max(1), Ordering::Relaxed);
}

/// `(rank, size)`; `(0, 1)` without MPI.
pub fn rank() -> (usize, usize) {
    (RANK.load(Ordering::Relaxed), SIZE.load(Ordering::Relaxed))
}

/// Whether this process prints and writes files (rank 0, or the only process).
pub fn leader() -> bool {
    rank().0 == 0
}

/// The ranks a solver splits its grid over: all of them under MPI, this process otherwise.
pub fn comm() -> Box<dyn Comm> {
    #[cfg(feature = "mpi")]
    if rank().1 > 1 {
        return Box::new(hgym_solvers::comm::MpiComm);
    }
    Box::new(Solo)
}

/// Whether `yes` holds on any rank. A collective: every rank calls it at the same point of the
/// same program (a Ctrl-C reaches the ranks at different moments; deciding on `any` of them
/// keeps them stepping together).
pub fn any(yes: bool) -> bool {
    if rank().1 == 1 {
        return yes;
    }
    let mut count = [0.0];
    comm().sum(&[f64::from(u8::from(yes))], &mut count);
    count[0] > 0.0
}

/// Waits until every rank gets here.
pub fn barrier() {
    any(false);
}
