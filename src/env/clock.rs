//! Wall time inside an environment's solver steps, so that `hgym bench envs` can state which
//! share of a control action goes elsewhere (actuation, gusts, probes, forces, observation,
//! reward, info).

use std::time::Instant;

/// Seconds spent inside the solver's steps by `step`, summed since the environment was made.
#[derive(Clone, Copy, Debug, Default)]
pub struct SolverClock(f64);

impl SolverClock {
    /// Adds the time since `start`.
    #[inline]
    pub fn stop(&mut self, start: Instant) {
        self.0 += start.elapsed().as_secs_f64();
    }

    pub fn seconds(&self) -> f64 {
        self.0
    }
}

/// An environment that keeps a [`SolverClock`].
pub trait SolverTime {
    /// Seconds spent inside the solver's steps by `step` since the environment was made (resets
    /// and spin-ups not counted).
    fn solver_seconds(&self) -> f64;
}

impl<E: SolverTime + ?Sized> SolverTime for Box<E> {
    fn solver_seconds(&self) -> f64 {
        (**self).solver_seconds()
    }
}
