//! Running statistics for observation and reward normalisation (as Gymnasium's
//! `NormalizeObservation` / `NormalizeReward` and SB3's `VecNormalize` do).

use serde::{Deserialize, Serialize};

/// Mean and variance of a stream of vectors, merged batch by batch (Chan et al. 1979).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningMeanStd {
    pub mean: Vec<f64>,
    pub var: Vec<f64>,
    pub count: f64,
}

impl RunningMeanStd {
    pub fn new(dim: usize) -> Self {
        RunningMeanStd {
            mean: vec![0.0; dim],
            var: vec![1.0; dim],
            count: 1e-4,
        }
    }

    /// Merges one sample.
    pub fn update(&mut self, x: &[f64]) {
        let n = self.count + 1.0;
        for ((m, v), x) in self.mean.iter_mut().zip(&mut self.var).zip(x) {
            let delta = x - *m;
            let mean = *m + delta / n;
            let m2 = *v * self.count + delta * delta * self.count / n;
            *m = mean;
            *v = m2 / n;
        }
        self.count = n;
    }

    /// `clip((x - mean) / sqrt(var + eps), -clip, clip)` in place.
    pub fn normalize(&self, x: &mut [f64], clip: f64) {
        for ((x, m), v) in x.iter_mut().zip(&self.mean).zip(&self.var) {
            *x = ((*x - m) / (v + 1e-8).sqrt()).clamp(-clip, clip);
        }
    }
}

/// Scales rewards by the standard deviation of the discounted return (not centred), as
/// Gymnasium's `NormalizeReward` does; one return accumulator per environment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RewardScaler {
    pub stats: RunningMeanStd,
    pub returns: Vec<f64>,
    pub gamma: f64,
}

impl RewardScaler {
    pub fn new(n_envs: usize, gamma: f64) -> Self {
        RewardScaler {
            stats: RunningMeanStd::new(1),
            returns: vec![0.0; n_envs],
            gamma,
        }
    }

    /// Feeds the reward of environment `env` and returns it scaled; `done` restarts its return.
    pub fn scale(&mut self, env: usize, reward: f64, done: bool) -> f64 {
        self.returns[env] = self.returns[env] * self.gamma + reward;
        self.stats.update(&[self.returns[env]]);
        if done {
            self.returns[env] = 0.0;
        }
        (reward / (self.stats.var[0] + 1e-8).sqrt()).clamp(-10.0, 10.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_stats_match_two_pass() {
        let xs: Vec<[f64; 2]> = (0..500).map(|i| [(i as f64 * 0.3).sin() * 3.0 + 1.0, i as f64 * 0.01]).collect();
        let mut r = RunningMeanStd::new(2);
        xs.iter().for_each(|x| r.update(x));
        for d in 0..2 {
            let mean = xs.iter().map(|x| x[d]).sum::<f64>() / 500.0;
            let var = xs.iter().map(|x| (x[d] - mean).powi(2)).sum::<f64>() / 500.0;
            assert!(
                (r.mean[d] - mean).abs() < 1e-5 && (r.var[d] - var).abs() < 1e-3 * var.max(1.0),
                "{d}"
            );
        }
    }
}
