//! Classical controllers as policies, on the same footing as the learners: zero, constant,
//! uniform random, open-loop sine, and proportional-derivative feedback on an observation
//! component or on an info value (e.g. the lift coefficient, "opposition control"), and local
//! feedback of every actuator on its own observations (opposition control of wall turbulence).

use serde::{Deserialize, Serialize};

use crate::env::Info;
use crate::policy::Policy;
use crate::rng::Rng;

/// Which measured signal a feedback controller uses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Signal {
    /// Component `i` of the observation.
    Obs(usize),
    /// A value of the step's info, e.g. `"C_L"`.
    Info(String),
}

/// The classical baselines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Baseline {
    /// No actuation.
    Zero,
    /// The same action every step: one value for every actuator, or one per actuator (e.g. the
    /// pinball's boat-tailing `[0, -1, 1]`: front still, rear cylinders counter-rotating).
    Constant { values: Vec<f64> },
    /// Uniform in [-1, 1].
    Random,
    /// `amplitude sin(2 pi k / period + phase)` at action k, on every actuator.
    Sine { amplitude: f64, period: f64 },
    /// `a = clip(-(kp e + kd (e - e_prev)))` with `e = signal - target`, on every actuator
    /// (signs per actuator in `signs`, default all +1).
    Pd {
        signal: Signal,
        kp: f64,
        kd: f64,
        target: f64,
        signs: Vec<f64>,
    },
    /// Actuator `i` fed back from its own observation: `a_i = clip(-gain obs[i stride + offset])`
    /// (opposition control of wall turbulence, Choi, Moin & Kim 1994: the wall velocity opposes
    /// the wall-normal velocity at the sensing plane; stride 2, offset 1 in the channel flows).
    Local { stride: usize, offset: usize, gain: f64 },
}

/// A baseline with its running state.
#[derive(Clone, Debug)]
pub struct BaselinePolicy {
    pub baseline: Baseline,
    rng: Rng,
    k: u64,
    prev: Option<f64>,
}

impl BaselinePolicy {
    pub fn new(baseline: Baseline, seed: u64) -> Self {
        BaselinePolicy {
            baseline,
            rng: Rng::seed(seed),
            k: 0,
            prev: None,
        }
    }
}

impl Policy for BaselinePolicy {
    fn check(&self, obs: &[f64], info: &Info, act_dim: usize) -> Result<(), String> {
        match &self.baseline {
            Baseline::Constant { values } if values.len() != 1 && values.len() != act_dim => Err(format!(
                "{} constant values for {act_dim} actuators: give one value for all, or one per actuator",
                values.len()
            )),
            Baseline::Pd {
                signal: Signal::Obs(i), ..
            } if *i >= obs.len() => Err(format!(
                "the signal obs:{i} does not exist: the observation has {} values (obs:0 to obs:{})",
                obs.len(),
                obs.len().saturating_sub(1)
            )),
            Baseline::Pd {
                signal: Signal::Info(key), ..
            } if info.get(key).is_none() => {
                let keys: Vec<&str> = info.values.keys().map(String::as_str).collect();
                Err(format!(
                    "the signal '{key}' is not in the environment's info; it has: {}",
                    keys.join(", ")
                ))
            }
            Baseline::Local { stride, offset, .. } if *offset >= *stride || !obs.len().is_multiple_of(*stride) => Err(format!(
                "local feedback reads observation {offset} of each group of {stride}, but the observation has {} values",
                obs.len()
            )),
            _ => Ok(()),
        }
    }

    fn reset(&mut self) {
        self.k = 0;
        self.prev = None;
    }

    fn act(&mut self, obs: &[f64], info: &Info, action: &mut [f64]) {
        let k = self.k as f64;
        self.k += 1;
        match &self.baseline {
            Baseline::Zero => action.iter_mut().for_each(|a| *a = 0.0),
            Baseline::Constant { values } => {
                // `check` refuses a list of another length than the action's.
                for (j, a) in action.iter_mut().enumerate() {
                    let v = if values.len() == 1 {
                        values[0]
                    } else {
                        values.get(j).copied().unwrap_or(0.0)
                    };
                    *a = v.clamp(-1.0, 1.0);
                }
            }
            Baseline::Random => action.iter_mut().for_each(|a| *a = 2.0 * self.rng.uniform() - 1.0),
            Baseline::Sine { amplitude, period } => {
                let v = amplitude * (2.0 * std::f64::consts::PI * k / period.max(1e-9)).sin();
                action.iter_mut().for_each(|a| *a = v.clamp(-1.0, 1.0));
            }
            Baseline::Pd {
                signal,
                kp,
                kd,
                target,
                signs,
            } => {
                let s = match signal {
                    Signal::Obs(i) => obs.get(*i).copied().unwrap_or(0.0),
                    Signal::Info(key) => info.get(key).unwrap_or(0.0),
                };
                let e = s - target;
                let de = self.prev.map(|p| e - p).unwrap_or(0.0);
                self.prev = Some(e);
                let u = -(kp * e + kd * de);
                for (j, a) in action.iter_mut().enumerate() {
                    *a = (u * signs.get(j).copied().unwrap_or(1.0)).clamp(-1.0, 1.0);
                }
            }
            Baseline::Local { stride, offset, gain } => {
                for (j, a) in action.iter_mut().enumerate() {
                    let s = obs.get(j * stride + offset).copied().unwrap_or(0.0);
                    *a = (-gain * s).clamp(-1.0, 1.0);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One constant value drives every actuator; a list gives each its own, clipped to [-1, 1];
    /// a list of the wrong length is refused before the first action.
    #[test]
    fn constant_values_per_actuator() {
        let info = Info::default();
        let mut a = [9.0; 3];
        BaselinePolicy::new(Baseline::Constant { values: vec![0.25] }, 0).act(&[], &info, &mut a);
        assert_eq!(a, [0.25; 3]);
        let boat_tailing = BaselinePolicy::new(
            Baseline::Constant {
                values: vec![0.0, -1.0, 1.0],
            },
            0,
        );
        let mut p = boat_tailing.clone();
        p.act(&[], &info, &mut a);
        assert_eq!(a, [0.0, -1.0, 1.0]);
        assert!(boat_tailing.check(&[], &info, 3).is_ok());
        let e = boat_tailing.check(&[], &info, 2).unwrap_err();
        assert!(e.contains("3 constant values for 2 actuators"), "{e}");
    }
}
