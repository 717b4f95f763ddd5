//! Transplanting trained networks onto another environment's spaces (transfer learning).
//!
//! A [`SpaceMap`] says where each quantity of a source environment sits in a target environment
//! (which one is a flow question, answered outside this crate): every source observation is read
//! from one target observation, and every target action is driven by one source action, with a
//! sign, or by none (it stays at zero). The maps below rewrite only a network's first-layer
//! columns and last-layer rows, so the transplanted network on a target observation computes
//! the source network on the source observation it corresponds to:
//!
//! - actor `mu'(o_t)_k = s_k mu(P o_t)_{j(k)}` (exact for odd or identity output activations,
//!   which ours are: tanh, identity, and the final clip is odd too);
//! - critic `Q'(o_t, a_t) = Q(P o_t, A a_t)` with `(A a_t)_j` the mean of `s_k a_{t,k}` over the
//!   target actions driven by `j`, so that `A` inverts the actor's action map;
//! - observation statistics: each source input's mean and variance move to its target input;
//!   unread target inputs get mean 0 and variance 1 (their weights are zero).

use crate::learn::LearnError;
use crate::nn::Mlp;
use crate::normalize::RunningMeanStd;
use crate::policy::ActorPolicy;

/// Where a source environment's observations and actions sit in a target environment.
#[derive(Clone, Debug, PartialEq)]
pub struct SpaceMap {
    pub target_obs_dim: usize,
    /// For each source observation `i`, the target observation it is read from.
    pub obs: Vec<usize>,
    pub source_act_dim: usize,
    /// For each target action `k`, the source action and sign that drive it (`None`: zero).
    pub act: Vec<Option<(usize, f64)>>,
}

impl SpaceMap {
    /// The map between two environments of one layout.
    pub fn identity(obs_dim: usize, act_dim: usize) -> Self {
        SpaceMap {
            target_obs_dim: obs_dim,
            obs: (0..obs_dim).collect(),
            source_act_dim: act_dim,
            act: (0..act_dim).map(|k| Some((k, 1.0))).collect(),
        }
    }

    pub fn source_obs_dim(&self) -> usize {
        self.obs.len()
    }

    pub fn target_act_dim(&self) -> usize {
        self.act.len()
    }

    pub fn is_identity(&self) -> bool {
        *self == SpaceMap::identity(self.obs.len(), self.act.len())
    }

    /// Whether the map is usable: indices in range, no target observation read twice, signs of
    /// +-1, at least one target action driven. The message says what is wrong.
    pub fn check(&self) -> Result<(), String> {
        let mut read = vec![false; self.target_obs_dim];
        for (i, &t) in self.obs.iter().enumerate() {
            match read.get_mut(t) {
                None => {
                    return Err(format!(
                        "source observation {i} reads target observation {t} of {}",
                        self.target_obs_dim
                    ))
                }
                Some(true) => return Err(format!("target observation {t} feeds two source observations")),
                Some(r) => *r = true,
            }
        }
        for (k, a) in self.act.iter().enumerate() {
            if let Some((j, s)) = a {
                if *j >= self.source_act_dim || s.abs() != 1.0 {
                    return Err(format!(
                        "target action {k} is driven by source action {j} with sign {s}: need an index below {} and a sign of +-1",
                        self.source_act_dim
                    ));
                }
            }
        }
        if self.act.iter().all(Option::is_none) {
            return Err("no target action is driven by a source action".into());
        }
        Ok(())
    }

    /// First-layer columns of an observation input: target input `c` collects the source inputs
    /// read from it.
    fn obs_columns(&self) -> Vec<Vec<(usize, f32)>> {
        let mut cols = vec![vec![]; self.target_obs_dim];
        for (i, &t) in self.obs.iter().enumerate() {
            cols[t].push((i, 1.0));
        }
        cols
    }

    fn act_rows(&self) -> Vec<Option<(usize, f32)>> {
        self.act.iter().map(|a| a.map(|(j, s)| (j, s as f32))).collect()
    }

    /// The actor `o_s -> a_s` as an actor `o_t -> a_t`.
    pub fn actor(&self, net: &Mlp<f32>) -> Mlp<f32> {
        net.remapped(&self.obs_columns(), &self.act_rows())
    }

    /// The critic `(o_s, a_s) -> Q` as a critic `(o_t, a_t) -> Q` (input: observation, then action).
    pub fn critic(&self, net: &Mlp<f32>) -> Mlp<f32> {
        let (o, ns) = (self.source_obs_dim(), self.source_act_dim);
        let mut drives = vec![0usize; ns];
        for (j, _) in self.act.iter().flatten() {
            drives[*j] += 1;
        }
        let mut cols = self.obs_columns();
        cols.extend(self.act.iter().map(|a| match a {
            Some((j, s)) => vec![(o + j, (*s / drives[*j] as f64) as f32)],
            None => vec![],
        }));
        net.remapped(&cols, &(0..net.output_dim()).map(|k| Some((k, 1.0))).collect::<Vec<_>>())
    }

    /// Observation statistics of the source inputs, moved to the target inputs.
    pub fn obs_stats(&self, rms: &RunningMeanStd) -> RunningMeanStd {
        let mut out = RunningMeanStd::new(self.target_obs_dim);
        out.count = rms.count;
        for (i, &t) in self.obs.iter().enumerate() {
            out.mean[t] = rms.mean[i];
            out.var[t] = rms.var[i];
        }
        out
    }
}

/// What `--init-from` carries over besides the actor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Parts {
    /// The critics and their targets (off-policy learners).
    pub critics: bool,
    /// The replay buffer (off-policy learners; only between environments of one layout).
    pub buffer: bool,
}

/// Whether `policy` can replace a learner's `actor`: made by one of `algos`, with the same layer
/// sizes and activations. The message names both.
pub fn fits(policy: &ActorPolicy, actor: &Mlp<f32>, algos: &[&str]) -> Result<(), LearnError> {
    if !algos.contains(&policy.algo.as_str()) {
        return Err(LearnError::Init(format!(
            "the policy was trained by {}; this learner starts from {} policies (use --algo {})",
            policy.algo,
            algos.join(" or "),
            policy.algo
        )));
    }
    let (p, a) = (&policy.net, actor);
    if p.sizes != a.sizes || p.hidden != a.hidden || p.output != a.output {
        return Err(LearnError::Init(format!(
            "the policy's network has layers {:?} ({:?}/{:?}), this learner's actor {:?} ({:?}/{:?}): \
             give the learner the source run's hidden sizes and activation",
            p.sizes, p.hidden, p.output, a.sizes, a.hidden, a.output
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nn::{Activation, Init, Tape};
    use crate::rng::Rng;

    fn net(sizes: &[usize], out: Activation, seed: u64) -> Mlp<f32> {
        Mlp::new(sizes, Activation::Relu, out, Init::FanIn, Init::FanIn, &mut Rng::seed(seed))
    }

    /// A map that permutes, drops and adds observations and fans one action out to two with
    /// opposite signs (the cylinder's jet pair driving a square's top and bottom jets).
    fn map() -> SpaceMap {
        SpaceMap {
            target_obs_dim: 5,
            obs: vec![3, 0, 4],
            source_act_dim: 2,
            act: vec![Some((1, 1.0)), None, Some((1, -1.0)), Some((0, 1.0))],
        }
    }

    #[test]
    fn transplanted_actor_computes_the_source_actor_on_mapped_inputs() {
        let m = map();
        m.check().unwrap();
        for layers in [&[3usize, 2][..], &[3, 8, 8, 2]] {
            let src = net(layers, Activation::Tanh, 7);
            let dst = m.actor(&src);
            let mut rng = Rng::seed(3);
            for _ in 0..20 {
                let o_t: Vec<f32> = (0..5).map(|_| rng.normal() as f32).collect();
                let o_s: Vec<f32> = m.obs.iter().map(|&t| o_t[t]).collect();
                let a_s = src.forward(&o_s, 1, &mut Tape::new()).to_vec();
                let a_t = dst.forward(&o_t, 1, &mut Tape::new()).to_vec();
                let want = [a_s[1], 0.0, -a_s[1], a_s[0]];
                for (g, w) in a_t.iter().zip(want) {
                    assert!((g - w).abs() <= 1e-6 * (1.0 + w.abs()), "{a_t:?} vs {want:?}");
                }
            }
        }
    }

    #[test]
    fn identity_map_leaves_a_network_bitwise_unchanged() {
        let src = net(&[4, 6, 2], Activation::Tanh, 1);
        let id = SpaceMap::identity(4, 2);
        assert!(id.is_identity() && !map().is_identity());
        assert_eq!(id.actor(&src), src);
        let critic = net(&[6, 5, 1], Activation::Identity, 2);
        assert_eq!(id.critic(&critic), critic);
    }

    #[test]
    fn transplanted_critic_inverts_the_action_map() {
        let m = map();
        let src = net(&[5, 8, 1], Activation::Identity, 5);
        let dst = m.critic(&src);
        let mut rng = Rng::seed(9);
        for _ in 0..20 {
            let o_t: Vec<f32> = (0..5).map(|_| rng.normal() as f32).collect();
            let a_s: Vec<f32> = (0..2).map(|_| rng.normal() as f32).collect();
            // The target actions the transplanted actor would give for a_s (the unmapped one free).
            let a_t = [a_s[1], rng.normal() as f32, -a_s[1], a_s[0]];
            let mut x_s: Vec<f32> = m.obs.iter().map(|&t| o_t[t]).collect();
            x_s.extend(&a_s);
            let mut x_t = o_t.clone();
            x_t.extend(a_t);
            let q_s = src.forward(&x_s, 1, &mut Tape::new())[0];
            let q_t = dst.forward(&x_t, 1, &mut Tape::new())[0];
            assert!((q_s - q_t).abs() <= 1e-5 * (1.0 + q_s.abs()), "{q_s} vs {q_t}");
        }
    }

    #[test]
    fn statistics_move_with_their_observations_and_bad_maps_are_named() {
        let rms = RunningMeanStd {
            mean: vec![1.0, 2.0, 3.0],
            var: vec![4.0, 5.0, 6.0],
            count: 42.0,
        };
        let t = map().obs_stats(&rms);
        assert_eq!(t.mean, vec![2.0, 0.0, 0.0, 1.0, 3.0]);
        assert_eq!(t.var, vec![5.0, 1.0, 1.0, 4.0, 6.0]);
        assert_eq!(t.count, 42.0);
        let mut twice = map();
        twice.obs[1] = 3;
        assert!(twice.check().unwrap_err().contains("two source"));
        let mut none = map();
        none.act = vec![None; 4];
        assert!(none.check().unwrap_err().contains("no target action"));
        let mut gain = map();
        gain.act[0] = Some((1, 0.5));
        assert!(gain.check().unwrap_err().contains("sign"));
    }
}
