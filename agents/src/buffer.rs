//! Replay buffer: a ring of transitions `(s, a, r, s', terminated)` in flat `f32` arrays.

use serde::{Deserialize, Serialize};

use crate::rng::Rng;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReplayBuffer {
    capacity: usize,
    obs_dim: usize,
    act_dim: usize,
    len: usize,
    next: usize,
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    act: Vec<f32>,
    reward: Vec<f32>,
    /// 1 for a real terminal state (no bootstrapping), 0 otherwise (including truncation).
    terminal: Vec<f32>,
}

/// A sampled minibatch, row-major, reused between samples.
#[derive(Clone, Debug, Default)]
pub struct Batch {
    pub size: usize,
    pub obs: Vec<f32>,
    pub next_obs: Vec<f32>,
    pub act: Vec<f32>,
    pub reward: Vec<f32>,
    pub terminal: Vec<f32>,
}

impl ReplayBuffer {
    pub fn new(capacity: usize, obs_dim: usize, act_dim: usize) -> Self {
        ReplayBuffer {
            capacity,
            obs_dim,
            act_dim,
            len: 0,
            next: 0,
            obs: vec![0.0; capacity * obs_dim],
            next_obs: vec![0.0; capacity * obs_dim],
            act: vec![0.0; capacity * act_dim],
            reward: vec![0.0; capacity],
            terminal: vec![0.0; capacity],
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Stores one transition, overwriting the oldest when full.
    pub fn push(&mut self, obs: &[f64], act: &[f64], reward: f64, next_obs: &[f64], terminal: bool) {
        let (i, o, a) = (self.next, self.obs_dim, self.act_dim);
        self.obs[i * o..(i + 1) * o].iter_mut().zip(obs).for_each(|(d, s)| *d = *s as f32);
        self.next_obs[i * o..(i + 1) * o]
            .iter_mut()
            .zip(next_obs)
            .for_each(|(d, s)| *d = *s as f32);
        self.act[i * a..(i + 1) * a].iter_mut().zip(act).for_each(|(d, s)| *d = *s as f32);
        self.reward[i] = reward as f32;
        self.terminal[i] = if terminal { 1.0 } else { 0.0 };
        self.next = (self.next + 1) % self.capacity;
        self.len = (self.len + 1).min(self.capacity);
    }

    /// Samples `size` transitions uniformly with replacement into `batch`.
    pub fn sample(&self, size: usize, rng: &mut Rng, batch: &mut Batch) {
        assert!(self.len > 0, "sampling from an empty replay buffer");
        let (o, a) = (self.obs_dim, self.act_dim);
        batch.size = size;
        batch.obs.resize(size * o, 0.0);
        batch.next_obs.resize(size * o, 0.0);
        batch.act.resize(size * a, 0.0);
        batch.reward.resize(size, 0.0);
        batch.terminal.resize(size, 0.0);
        for k in 0..size {
            let i = rng.below(self.len);
            batch.obs[k * o..(k + 1) * o].copy_from_slice(&self.obs[i * o..(i + 1) * o]);
            batch.next_obs[k * o..(k + 1) * o].copy_from_slice(&self.next_obs[i * o..(i + 1) * o]);
            batch.act[k * a..(k + 1) * a].copy_from_slice(&self.act[i * a..(i + 1) * a]);
            batch.reward[k] = self.reward[i];
            batch.terminal[k] = self.terminal[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ring_overwrites_oldest() {
        let mut b = ReplayBuffer::new(3, 1, 1);
        for i in 0..5 {
            b.push(&[i as f64], &[0.0], i as f64, &[i as f64 + 1.0], false);
        }
        assert_eq!(b.len(), 3);
        let mut batch = Batch::default();
        let mut rng = Rng::seed(0);
        b.sample(64, &mut rng, &mut batch);
        assert!(batch.reward.iter().all(|r| *r >= 2.0));
        assert!(batch.obs.iter().zip(&batch.next_obs).all(|(o, n)| n - o == 1.0));
    }
}
