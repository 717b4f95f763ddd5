//! What a solver split over processes needs from them: its rank, a shift of values to one
//! neighbour while receiving from the other, and an element-wise sum. [`Solo`] is one process;
//! [`Local`] runs ranks as threads of one process (tests, and a check of the decomposition without
//! MPI); with the `mpi` feature, `MpiComm` runs them as MPI ranks (rsmpi).
//!
//! The solvers only ever sum arrays in which every element has exactly one rank that holds a
//! value and zeros elsewhere, so the sum is exact whatever order a library reduces in, and a split
//! solver's forces are bitwise those of one process.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Barrier, Condvar, Mutex};

/// A group of processes working on one solver.
pub trait Comm: Send + Sync {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// Sends `send.0` to rank `send.1` and receives `recv.0.len()` values from rank `recv.1`
    /// (either may be absent), without deadlock when every rank shifts at once.
    fn shift(&self, send: Option<(&[f32], usize)>, recv: Option<(&mut [f32], usize)>);
    /// `out` becomes the element-wise sum over ranks of `v`, on every rank (same lengths).
    fn sum(&self, v: &[f64], out: &mut [f64]);

    /// Whether `yes` holds on every rank.
    fn all(&self, yes: bool) -> bool {
        let mut count = [0.0];
        self.sum(&[f64::from(u8::from(yes))], &mut count);
        count[0] == self.size() as f64
    }

    /// The `width` values of the lowest rank that has any, on every rank: each rank's in slots of
    /// its own in one sum (exact: every slot holds one rank's values).
    fn lowest_rank(&self, mine: Option<&[f64]>, width: usize) -> Option<Vec<f64>> {
        if self.size() == 1 {
            return mine.map(<[f64]>::to_vec); // no allocation on the way that finds nothing
        }
        let (rank, w) = (self.rank(), width + 1);
        let mut slots = vec![0.0; w * self.size()];
        if let Some(v) = mine {
            slots[w * rank] = 1.0;
            slots[w * rank + 1..w * (rank + 1)].copy_from_slice(v);
        }
        let mut all = vec![0.0; slots.len()];
        self.sum(&slots, &mut all);
        all.chunks(w).find(|c| c[0] == 1.0).map(|c| c[1..].to_vec())
    }
}

/// One process: nothing to exchange.
#[derive(Clone, Copy, Debug, Default)]
pub struct Solo;

impl Comm for Solo {
    fn rank(&self) -> usize {
        0
    }
    fn size(&self) -> usize {
        1
    }
    fn shift(&self, send: Option<(&[f32], usize)>, recv: Option<(&mut [f32], usize)>) {
        // A one-rank ring only ever talks to itself (a periodic axis that is not split).
        if let (Some((s, _)), Some((r, _))) = (send, recv) {
            r.copy_from_slice(s);
        }
    }
    fn sum(&self, v: &[f64], out: &mut [f64]) {
        out.copy_from_slice(v);
    }
}

/// Ranks as threads of one process, talking through shared memory (for tests: it allocates a
/// message per shift).
pub struct Local {
    rank: usize,
    shared: Arc<Shared>,
}

/// Messages in flight, per (from, to), in the order sent.
type Mailbox = HashMap<(usize, usize), VecDeque<Vec<f32>>>;

struct Shared {
    size: usize,
    mail: Mutex<Mailbox>,
    arrived: Condvar,
    /// Each rank's contribution to the current sum.
    terms: Mutex<Vec<Vec<f64>>>,
    barrier: Barrier,
}

impl Local {
    /// `size` ranks; give one to each thread.
    pub fn group(size: usize) -> Vec<Local> {
        let shared = Arc::new(Shared {
            size,
            mail: Mutex::new(HashMap::new()),
            arrived: Condvar::new(),
            terms: Mutex::new(vec![Vec::new(); size]),
            barrier: Barrier::new(size),
        });
        (0..size)
            .map(|rank| Local {
                rank,
                shared: shared.clone(),
            })
            .collect()
    }
}

impl Comm for Local {
    fn rank(&self) -> usize {
        self.rank
    }
    fn size(&self) -> usize {
        self.shared.size
    }
    fn shift(&self, send: Option<(&[f32], usize)>, recv: Option<(&mut [f32], usize)>) {
        // A poisoned lock means another rank panicked; this one cannot go on either.
        if let Some((s, to)) = send {
            let mut mail = self.shared.mail.lock().expect("a rank panicked");
            mail.entry((self.rank, to)).or_default().push_back(s.to_vec());
            self.shared.arrived.notify_all();
        }
        if let Some((r, from)) = recv {
            let mut mail = self.shared.mail.lock().expect("a rank panicked");
            loop {
                if let Some(m) = mail.get_mut(&(from, self.rank)).and_then(VecDeque::pop_front) {
                    r.copy_from_slice(&m);
                    break;
                }
                mail = self.shared.arrived.wait(mail).expect("a rank panicked");
            }
        }
    }
    fn sum(&self, v: &[f64], out: &mut [f64]) {
        self.shared.terms.lock().expect("a rank panicked")[self.rank] = v.to_vec();
        self.shared.barrier.wait();
        {
            let terms = self.shared.terms.lock().expect("a rank panicked");
            out.iter_mut().for_each(|x| *x = 0.0);
            for t in terms.iter() {
                for (x, y) in out.iter_mut().zip(t) {
                    *x += y;
                }
            }
        }
        self.shared.barrier.wait();
    }
}

#[cfg(feature = "mpi")]
pub use self::mpi_comm::MpiComm;

#[cfg(feature = "mpi")]
mod mpi_comm {
    use mpi::collective::SystemOperation;
    use mpi::topology::SimpleCommunicator;
    use mpi::traits::*;

    /// The ranks of `MPI_COMM_WORLD` (rsmpi). MPI must be initialised (its `Universe` kept
    /// alive) while this is used, with `Threading::Serialized` if it is called from another
    /// thread than the one that initialised it, and from one thread at a time: one solver per
    /// process, stepped by one thread at a time.
    #[derive(Clone, Copy, Debug, Default)]
    pub struct MpiComm;

    impl MpiComm {
        fn world(&self) -> SimpleCommunicator {
            SimpleCommunicator::world()
        }
    }

    impl super::Comm for MpiComm {
        fn rank(&self) -> usize {
            self.world().rank() as usize
        }
        fn size(&self) -> usize {
            self.world().size() as usize
        }
        fn shift(&self, send: Option<(&[f32], usize)>, recv: Option<(&mut [f32], usize)>) {
            let world = self.world();
            mpi::request::scope(|scope| {
                let r = recv.map(|(buf, from)| world.process_at_rank(from as i32).immediate_receive_into(scope, buf));
                let s = send.map(|(buf, to)| world.process_at_rank(to as i32).immediate_send(scope, buf));
                if let Some(r) = r {
                    r.wait();
                }
                if let Some(s) = s {
                    s.wait();
                }
            });
        }
        fn sum(&self, v: &[f64], out: &mut [f64]) {
            self.world().all_reduce_into(v, out, SystemOperation::sum());
        }
    }
}
