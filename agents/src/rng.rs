//! The one random-number generator of the agents: xoshiro256++ (Blackman & Vigna 2021),
//! serialisable so that checkpoints resume the exact stream.

use rand::{Rng as _, SeedableRng};
use rand_distr::StandardNormal;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rng(Xoshiro256PlusPlus);

impl Rng {
    /// A generator from a 64-bit seed (expanded with SplitMix64 by `seed_from_u64`).
    pub fn seed(seed: u64) -> Self {
        Rng(Xoshiro256PlusPlus::seed_from_u64(seed))
    }

    /// An independent stream derived from this one (for sub-components).
    pub fn fork(&mut self) -> Self {
        Rng::seed(self.0.random::<u64>())
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0.random::<f64>()
    }

    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        self.0.sample(StandardNormal)
    }

    /// Uniform integer in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        self.0.random_range(0..n)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0.random::<u64>()
    }
}
