//! Exploration noise for deterministic policies.

use serde::{Deserialize, Serialize};

use crate::rng::Rng;

/// Ornstein-Uhlenbeck process `x <- x + theta (mu - x) dt + sigma sqrt(dt) N(0, 1)`
/// (Uhlenbeck & Ornstein 1930; DDPG's exploration, Lillicrap et al. 2016), one per action.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrnsteinUhlenbeck {
    pub theta: f64,
    pub sigma: f64,
    pub dt: f64,
    pub x: Vec<f64>,
}

impl OrnsteinUhlenbeck {
    pub fn new(dim: usize, theta: f64, sigma: f64) -> Self {
        OrnsteinUhlenbeck {
            theta,
            sigma,
            dt: 1e-2,
            x: vec![0.0; dim],
        }
    }

    pub fn reset(&mut self) {
        self.x.iter_mut().for_each(|x| *x = 0.0);
    }

    /// Advances the process and returns the current sample.
    pub fn sample(&mut self, rng: &mut Rng) -> &[f64] {
        let (theta, sigma, dt) = (self.theta, self.sigma, self.dt);
        for x in &mut self.x {
            *x += -theta * *x * dt + sigma * dt.sqrt() * rng.normal();
        }
        &self.x
    }
}
