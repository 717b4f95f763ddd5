//! `check_env`: the environment checker of Gymnasium (`gymnasium/utils/env_checker.py`) for this
//! crate's [`Env`] contract. It checks what Gymnasium's does that applies to a `Box`-space env,
//! and the semantics `Env` adds:
//!
//! - spaces: bounds with `low <= high` (infinite allowed), actions exactly `[-1, 1]`;
//! - `reset(seed)`: an observation of the space's length, finite and inside the space;
//!   the same seed twice gives the same observation bitwise (Gymnasium's
//!   `check_reset_seed_determinism`), another seed a different one;
//! - `step`: a wrong action length and a NaN component are refused; a component outside
//!   `[-1, 1]` is clipped, not refused; observations finite and inside the space, rewards finite;
//! - the same seed and the same actions give bitwise-equal transitions (Gymnasium's
//!   `check_step_determinism`);
//! - `truncated` is false until the episode's last action and true on it, after
//!   `episode_actions` steps; `step` after it is refused until the next `reset`;
//! - `terminated` never comes without a reason: a healthy episode here has none.
//!
//! Each finding is a [`Violation`] naming the check, so one run reports every problem.

use crate::{Env, EnvError, StepResult};

/// One broken rule of the contract.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    pub check: &'static str,
    pub message: String,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.check, self.message)
    }
}

/// Runs every check on `env`, whose episodes last `episode_actions` actions, with `seed` (and
/// `seed + 1` for the different-start check). Returns the violations (empty: the env keeps the
/// contract). Errors of the env itself end the check with a violation naming the call.
pub fn check_env(env: &mut dyn Env, episode_actions: usize, seed: u64) -> Vec<Violation> {
    let mut v = Vec::new();
    let mut fail = |check: &'static str, message: String| v.push(Violation { check, message });
    let (obs_space, act_space) = (env.observation_space(), env.action_space());

    // Spaces.
    for (name, space) in [("observation_space", &obs_space), ("action_space", &act_space)] {
        if space.low.len() != space.high.len() {
            fail(
                "spaces",
                format!("{name}: {} lower and {} upper bounds", space.low.len(), space.high.len()),
            );
        }
        // Infinite bounds are allowed (Gymnasium's Box takes them); NaN and low > high are not.
        if space.low.iter().zip(&space.high).any(|(l, h)| !(l <= h)) {
            fail("spaces", format!("{name}: bounds must be numbers with low <= high"));
        }
    }
    if act_space.low.iter().any(|l| *l != -1.0) || act_space.high.iter().any(|h| *h != 1.0) {
        fail(
            "spaces",
            "actions must be exactly in [-1, 1] (mapped to physical bounds inside the env)".into(),
        );
    }
    if act_space.dim() == 0 {
        fail("spaces", "the action space is empty".into());
    }

    // Reset.
    let observation = |check: &'static str, obs: &[f64], fail: &mut dyn FnMut(&'static str, String)| {
        if obs.len() != obs_space.dim() {
            fail(
                check,
                format!("observation has {} values, the space {}", obs.len(), obs_space.dim()),
            );
        } else if !obs.iter().all(|x| x.is_finite()) {
            fail(check, "observation has non-finite values".into());
        } else if !obs_space.contains(obs) {
            fail(check, "observation lies outside the observation space".into());
        }
    };
    let first = match env.reset(seed) {
        Ok((o, _)) => o,
        Err(e) => {
            fail("reset", format!("reset({seed}) failed: {e}"));
            return v;
        }
    };
    observation("reset", &first, &mut fail);
    match (env.reset(seed), env.reset(seed.wrapping_add(1))) {
        (Ok((again, _)), Ok((other, _))) => {
            if again != first {
                fail("reset determinism", format!("reset({seed}) twice gives different observations"));
            }
            if other == first {
                fail(
                    "reset seeding",
                    format!("reset({seed}) and reset({}) start from the same state", seed.wrapping_add(1)),
                );
            }
        }
        (Err(e), _) | (_, Err(e)) => fail("reset", format!("a second reset failed: {e}")),
    }

    // Bad actions, after a fresh reset.
    if let Err(e) = env.reset(seed) {
        fail("reset", format!("reset({seed}) failed: {e}"));
        return v;
    }
    let n = act_space.dim();
    match env.step(&vec![0.0; n + 1]) {
        Err(EnvError::ActionShape { .. }) => {}
        other => fail("action shape", format!("an action of {} components gave {other:?}", n + 1)),
    }
    let mut nan = vec![0.0; n];
    if let Some(a) = nan.last_mut() {
        *a = f64::NAN;
    }
    match env.step(&nan) {
        Err(EnvError::NonFiniteAction { .. }) => {}
        other => fail("non-finite action", format!("a NaN component gave {other:?}")),
    }

    // Two episodes with the same seed and actions: bitwise equal, truncated exactly at the end.
    let actions: Vec<Vec<f64>> = (0..episode_actions)
        .map(|k| (0..n).map(|i| [1.7, -0.4, 0.3, -1.0, 0.9][(k + i) % 5]).collect())
        .collect();
    let mut episodes: Vec<Vec<StepResult>> = Vec::new();
    for _ in 0..2 {
        if let Err(e) = env.reset(seed) {
            fail("reset", format!("reset({seed}) failed: {e}"));
            return v;
        }
        let mut steps = Vec::with_capacity(episode_actions);
        for (k, a) in actions.iter().enumerate() {
            match env.step(a) {
                Ok(r) => {
                    observation("step", &r.obs, &mut fail);
                    if !r.reward.is_finite() {
                        fail("step", format!("reward {} at step {k}", r.reward));
                    }
                    if r.terminated {
                        fail("terminated", format!("a healthy episode terminated at step {k}"));
                    }
                    if r.truncated != (k + 1 == episode_actions) {
                        fail(
                            "truncated",
                            format!("truncated = {} at step {k} of an episode of {episode_actions}", r.truncated),
                        );
                    }
                    steps.push(r);
                }
                Err(e) => {
                    fail("step", format!("step {k} failed: {e} (components outside [-1, 1] must be clipped)"));
                    return v;
                }
            }
        }
        match env.step(&actions[0]) {
            Err(EnvError::NeedsReset) => {}
            other => fail("step after the end", format!("a step after the last action gave {other:?}")),
        }
        episodes.push(steps);
    }
    if episodes[0] != episodes[1] {
        let k = episodes[0].iter().zip(&episodes[1]).position(|(a, b)| a != b).unwrap_or(0);
        fail("step determinism", format!("the same seed and actions differ at step {k}"));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BoxSpace, Info};

    /// A toy env that keeps the contract unless told to break one rule.
    struct Toy {
        t: usize,
        x: f64,
        live: bool,
        bug: Option<&'static str>,
    }

    impl Env for Toy {
        fn observation_space(&self) -> BoxSpace {
            BoxSpace::uniform(1, -10.0, 10.0)
        }
        fn action_space(&self) -> BoxSpace {
            BoxSpace::unit(1)
        }
        fn reset(&mut self, seed: u64) -> Result<(Vec<f64>, Info), EnvError> {
            self.t = 0;
            self.live = true;
            self.x = if self.bug == Some("seed") { 0.5 } else { (seed % 7) as f64 * 0.1 };
            Ok((vec![self.x], Info::default()))
        }
        fn step(&mut self, action: &[f64]) -> Result<StepResult, EnvError> {
            if !self.live {
                return Err(EnvError::NeedsReset);
            }
            let (a, _) = crate::checked_action(&self.action_space(), action)?;
            self.t += 1;
            self.x += 0.1 * a[0];
            let truncated = self.t == if self.bug == Some("late") { 4 } else { 3 };
            self.live = !truncated;
            Ok(StepResult {
                obs: vec![if self.bug == Some("nan") { f64::NAN } else { self.x }],
                reward: -self.x.abs(),
                terminated: false,
                truncated,
                info: Info::default(),
            })
        }
    }

    fn toy(bug: Option<&'static str>) -> Toy {
        Toy {
            t: 0,
            x: 0.0,
            live: false,
            bug,
        }
    }

    #[test]
    fn a_correct_env_passes_and_each_planted_bug_is_named() {
        assert_eq!(check_env(&mut toy(None), 3, 1), vec![]);
        for (bug, check) in [("seed", "reset seeding"), ("late", "truncated"), ("nan", "step")] {
            let found = check_env(&mut toy(Some(bug)), 3, 1);
            assert!(found.iter().any(|v| v.check == check), "{bug}: {found:?}");
        }
    }
}
