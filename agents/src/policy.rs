//! Policies: anything that maps an observation (and the step's info) to an action in [-1, 1].
//! Learned actors and the classical controllers share this trait, so they are evaluated and
//! ranked the same way.

use serde::{Deserialize, Serialize};

use crate::env::Info;
use crate::nn::{Mlp, Tape};
use crate::normalize::RunningMeanStd;

pub trait Policy {
    /// Whether the policy can act on an environment whose step gave `obs` and `info` (the
    /// observation indices and info keys it reads exist); the message names what is missing.
    fn check(&self, _obs: &[f64], _info: &Info) -> Result<(), String> {
        Ok(())
    }
    /// Called at every reset (feedback controllers clear their memory here).
    fn reset(&mut self) {}
    /// Writes the action for `obs` into `action` (length = the action space's dimension).
    fn act(&mut self, obs: &[f64], info: &Info, action: &mut [f64]);
}

/// A trained deterministic actor: optional observation normalisation, an MLP, clipping to
/// [-1, 1]. This is what `train` saves and `eval` loads.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ActorPolicy {
    pub algo: String,
    pub net: Mlp<f32>,
    pub obs_norm: Option<RunningMeanStd>,
    pub obs_clip: f64,
    #[serde(skip)]
    scratch: Scratch,
}

#[derive(Clone, Debug, Default)]
struct Scratch {
    x: Vec<f64>,
    x32: Vec<f32>,
    tape: Tape<f32>,
}

impl ActorPolicy {
    pub fn new(algo: &str, net: Mlp<f32>, obs_norm: Option<RunningMeanStd>, obs_clip: f64) -> Self {
        ActorPolicy {
            algo: algo.to_string(),
            net,
            obs_norm,
            obs_clip,
            scratch: Scratch::default(),
        }
    }

    /// Whether a policy read from a file is whole: its network ([`Mlp::check`]), an observation
    /// normalisation of the network's input size with finite statistics, a positive clip.
    pub fn validate(&self) -> Result<(), String> {
        self.net.check()?;
        if let Some(n) = &self.obs_norm {
            let dim = self.net.input_dim();
            if n.mean.len() != dim || n.var.len() != dim {
                return Err(format!(
                    "obs_norm has {} means and {} variances for a network of {dim} inputs",
                    n.mean.len(),
                    n.var.len()
                ));
            }
            if n.mean.iter().chain(&n.var).any(|v| !v.is_finite()) || n.var.iter().any(|v| *v < 0.0) {
                return Err("obs_norm holds a value that is not finite, or a negative variance".into());
            }
        }
        if !(self.obs_clip.is_finite() && self.obs_clip > 0.0) {
            return Err(format!("obs_clip must be positive, got {}", self.obs_clip));
        }
        Ok(())
    }

    pub fn obs_dim(&self) -> usize {
        self.net.input_dim()
    }

    pub fn act_dim(&self) -> usize {
        self.net.output_dim()
    }
}

impl Policy for ActorPolicy {
    fn act(&mut self, obs: &[f64], _info: &Info, action: &mut [f64]) {
        let s = &mut self.scratch;
        s.x.clear();
        s.x.extend_from_slice(obs);
        if let Some(n) = &self.obs_norm {
            n.normalize(&mut s.x, self.obs_clip);
        }
        s.x32.clear();
        s.x32.extend(s.x.iter().map(|v| *v as f32));
        let y = self.net.forward(&s.x32, 1, &mut s.tape);
        for (a, y) in action.iter_mut().zip(y) {
            *a = (*y as f64).clamp(-1.0, 1.0);
        }
    }
}
