//! `hgym bench agents`: learner speed at the sizes the paper's baselines use. With a peer
//! (Stable-Baselines3, [`super::peer`]) its TD3 updates and batch-1 predictions are timed in the
//! same run, alternating with ours, and the ratios printed; without one, no ratio. Judged: batch-1
//! policy evaluation under 10 us. Shapes: observation 60 (the cylinder's 20 probes x (u, v, p)),
//! 1 action.

use std::time::Instant;

use hgym_agents::nn::{Activation, Init, Mlp};
use hgym_agents::policy::{ActorPolicy, Policy};
use hgym_agents::ppo::{Ppo, PpoConfig, Sample};
use hgym_agents::rng::Rng;
use hgym_agents::td3::{Td3, Td3Config};
use hgym_agents::Info;
use serde::{Deserialize, Serialize};

use super::peer::{Pairs, Peer, PeerError};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AgentsBench {
    pub obs_dim: usize,
    pub act_dim: usize,
    pub threads: usize,
    pub td3_updates_per_s: f64,
    /// PPO epochs per second over a 2048-sample rollout, minibatch 64, 64x64 networks.
    pub ppo_epochs_per_s: f64,
    pub ppo_minibatch_updates_per_s: f64,
    /// Deterministic action of a 256x256 actor (TD3's) and a 64x64 one (PPO's), batch 1.
    pub td3_policy_us: f64,
    pub ppo_policy_us: f64,
    /// The peer measured in the same run (`--peer`), alternating with ours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peer: Option<PeerRun>,
    pub pass: bool,
}

/// A peer's figures beside ours.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PeerRun {
    /// The peer's own description (name, versions, threads).
    pub about: serde_json::Value,
    pub pairs: Vec<Pairs>,
}

pub(crate) fn best_of<F: FnMut() -> f64>(n: usize, mut f: F) -> f64 {
    (0..n).map(|_| f()).fold(f64::INFINITY, f64::min)
}

/// Our figures, and with `peer` its figures in `pairs` alternating pairs.
pub fn bench_agents(quick: bool, mut peer: Option<&mut Peer>) -> Result<AgentsBench, PeerError> {
    let (o, a) = (60, 1);
    let mut rng = Rng::seed(1);
    let obs = |rng: &mut Rng| -> Vec<f64> { (0..o).map(|_| rng.normal()).collect() };

    // TD3: fill a buffer, warm up, time updates.
    let mut td3 = Td3::new("td3", Td3Config::default(), o, a, 0);
    for _ in 0..10_000 {
        let (s, s2) = (obs(&mut rng), obs(&mut rng));
        td3.remember(&s, &[2.0 * rng.uniform() - 1.0], rng.normal(), &s2, false);
    }
    for _ in 0..10 {
        td3.update();
    }
    let n = if quick { 40 } else { 200 };
    let mut time_td3 = || {
        let t = Instant::now();
        for _ in 0..n {
            td3.update();
        }
        t.elapsed().as_secs_f64() / n as f64
    };
    let td3_s = best_of(3, &mut time_td3);
    let pair_count = if quick { 2 } else { 5 };
    let mut pairs = vec![];
    if let Some(p) = peer.as_deref_mut() {
        let mut v = vec![];
        for _ in 0..pair_count {
            let ours = 1.0 / time_td3();
            v.push((ours, p.numbers(&format!("td3 {n}"), ["updates_per_s"])?[0]));
        }
        pairs.push(Pairs::new("TD3 256x256 batch 256", "updates/s", &v, true));
    }

    // PPO: 10 epochs over 2048 samples with minibatch 64.
    let mut ppo = Ppo::new(PpoConfig::default(), o, a, 0);
    let samples: Vec<Sample> = (0..2048)
        .map(|_| {
            let x = obs(&mut rng);
            Sample {
                obs: x.iter().map(|v| *v as f32).collect(),
                action: vec![rng.normal()],
                logp: -1.0,
                value: 0.0,
                reward: rng.normal(),
                advantage: rng.normal(),
                ret: rng.normal(),
                action_grad: None,
            }
        })
        .collect();
    let reps = if quick { 1 } else { 3 };
    let ppo_s = best_of(reps, || {
        let t = Instant::now();
        ppo.update(&samples);
        t.elapsed().as_secs_f64() / ppo.cfg.n_epochs as f64
    });
    let minibatches = 2048usize.div_ceil(ppo.cfg.minibatch_size) as f64;

    // Batch-1 deterministic actions.
    let reps = if quick { 2000 } else { 20_000 };
    let policy = |hidden: &[usize], rng: &mut Rng| {
        let mut sizes = vec![o];
        sizes.extend(hidden);
        sizes.push(a);
        let net = Mlp::new(&sizes, Activation::Relu, Activation::Tanh, Init::FanIn, Init::FanIn, rng);
        let mut p = ActorPolicy::new("bench", net, None, 10.0);
        let x = obs(rng);
        let info = Info::default();
        let mut act = vec![0.0; a];
        for _ in 0..100 {
            p.act(&x, &info, &mut act);
        }
        move || {
            let t = Instant::now();
            for _ in 0..reps {
                p.act(&x, &info, &mut act);
            }
            t.elapsed().as_secs_f64() * 1e6 / reps as f64
        }
    };
    let mut time_td3_policy = policy(&[256, 256], &mut rng);
    let td3_policy_us = best_of(3, &mut time_td3_policy);
    let ppo_policy_us = best_of(3, policy(&[64, 64], &mut rng));
    let td3_rate = 1.0 / td3_s;
    if let Some(p) = peer.as_deref_mut() {
        let mut v = vec![];
        for _ in 0..pair_count {
            let ours = time_td3_policy();
            v.push((ours, p.numbers(&format!("policy {}", reps / 10), ["us"])?[0]));
        }
        pairs.push(Pairs::new("policy 256x256, batch 1", "us", &v, false));
    }
    Ok(AgentsBench {
        obs_dim: o,
        act_dim: a,
        threads: rayon::current_num_threads(),
        td3_updates_per_s: td3_rate,
        ppo_epochs_per_s: 1.0 / ppo_s,
        ppo_minibatch_updates_per_s: minibatches / ppo_s,
        td3_policy_us,
        ppo_policy_us,
        peer: peer.map(|p| PeerRun {
            about: p.about.clone(),
            pairs,
        }),
        pass: td3_policy_us < 10.0 && ppo_policy_us < 10.0,
    })
}

pub fn table(b: &AgentsBench) -> String {
    let peer = match &b.peer {
        None => "(no peer measured in this run, so no ratio to SB3; --peer runs it)".to_string(),
        Some(_) => "(best of 3; the peer's pairs below)".to_string(),
    };
    let mut s = format!(
        "learner speed (obs {}, act {}, {} threads)\n\
         TD3 256x256, batch 256   {:8.1} updates/s   {peer}\n\
         PPO 64x64, 2048 x mb 64  {:8.2} epochs/s    ({:.0} minibatch updates/s)\n\
         policy, batch 1          {:8.2} us (256x256)  {:.2} us (64x64)   target < 10 us\n\
         {}\n",
        b.obs_dim,
        b.act_dim,
        b.threads,
        b.td3_updates_per_s,
        b.ppo_epochs_per_s,
        b.ppo_minibatch_updates_per_s,
        b.td3_policy_us,
        b.ppo_policy_us,
        if b.pass { "PASS" } else { "SHORT of target" }
    );
    if let Some(p) = &b.peer {
        s += &format!("against {} (same run, alternating pairs):\n", super::peer::describe(&p.about));
        for pair in &p.pairs {
            s += &format!("  {}\n", pair.line("SB3"));
        }
    }
    s
}
