//! Policies: anything that maps an observation (and the step's info) to an action in [-1, 1].
//! Learned actors and the classical controllers share this trait, so they are evaluated and
//! ranked the same way.

use serde::{Deserialize, Serialize};

use crate::env::Info;
use crate::multi::Agents;
use crate::nn::{Mlp, Tape};
use crate::normalize::RunningMeanStd;

pub trait Policy {
    /// Whether the policy can act on an environment whose step gave `obs` and `info` (the
    /// observation indices and info keys it reads exist, and it has an action for each of the
    /// `act_dim` actuators); the message names what is missing.
    fn check(&self, _obs: &[f64], _info: &Info, _act_dim: usize) -> Result<(), String> {
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
    /// A policy shared by agents ([`crate::multi`]): the network maps one agent's local
    /// observation to its local action and acts for every agent of the global environment.
    #[serde(default)]
    pub agents: Option<Agents>,
    #[serde(skip)]
    scratch: Scratch,
}

#[derive(Clone, Debug, Default)]
struct Scratch {
    local: Vec<f64>,
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
            agents: None,
            scratch: Scratch::default(),
        }
    }

    /// This (local) actor acting for every agent of `agents`.
    pub fn with_agents(mut self, agents: Agents) -> Self {
        self.agents = Some(agents);
        self
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
        if let Some(a) = &self.agents {
            a.check().map_err(|m| format!("agents: {m}"))?;
            if (a.local_obs_dim(), a.local_act_dim()) != (self.net.input_dim(), self.net.output_dim()) {
                return Err(format!(
                    "agents see {} observations and set {} actions each, but the network maps {} to {}",
                    a.local_obs_dim(),
                    a.local_act_dim(),
                    self.net.input_dim(),
                    self.net.output_dim()
                ));
            }
        }
        Ok(())
    }

    /// The global observation dimension it acts on.
    pub fn obs_dim(&self) -> usize {
        self.agents.as_ref().map_or(self.net.input_dim(), |a| a.obs_dim)
    }

    pub fn act_dim(&self) -> usize {
        self.agents.as_ref().map_or(self.net.output_dim(), |a| a.act_dim)
    }
}

impl Policy for ActorPolicy {
    /// One forward pass; with agents, one batch row per agent (its local observation), each
    /// row's output scattered into the agent's actions.
    fn act(&mut self, obs: &[f64], _info: &Info, action: &mut [f64]) {
        let s = &mut self.scratch;
        s.x32.clear();
        let rows = match &self.agents {
            None => {
                s.local.clear();
                s.local.extend_from_slice(obs);
                push_row(&mut s.x32, &mut s.local, self.obs_norm.as_ref(), self.obs_clip);
                1
            }
            Some(agents) => {
                for i in 0..agents.len() {
                    agents.gather(i, obs, &mut s.local);
                    push_row(&mut s.x32, &mut s.local, self.obs_norm.as_ref(), self.obs_clip);
                }
                agents.len()
            }
        };
        let y = self.net.forward(&s.x32, rows, &mut s.tape);
        match &self.agents {
            None => {
                for (a, y) in action.iter_mut().zip(y) {
                    *a = (*y as f64).clamp(-1.0, 1.0);
                }
            }
            Some(agents) => {
                let m = agents.local_act_dim();
                for (i, row) in y.chunks(m).enumerate() {
                    s.local.clear();
                    s.local.extend(row.iter().map(|y| (*y as f64).clamp(-1.0, 1.0)));
                    agents.scatter(i, &s.local, action);
                }
            }
        }
    }
}

/// Appends `x`, normalised, to the network's f32 input.
fn push_row(input: &mut Vec<f32>, x: &mut [f64], norm: Option<&RunningMeanStd>, clip: f64) {
    if let Some(n) = norm {
        n.normalize(x, clip);
    }
    input.extend(x.iter().map(|v| *v as f32));
}
