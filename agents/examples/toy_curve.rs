//! Learning curve of an algorithm on the unstable oscillator:
//! `cargo run --release -p hgym-agents --example toy_curve -- td3 200`.

use hgym_agents::learn::{Algo, AlgoConfigs, Learner};
use hgym_agents::rollout::episode;
use hgym_agents::toy::Oscillator;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let algo = match args.get(1).map(|s| s.as_str()) {
        Some("ppo") => Algo::Ppo,
        Some("ddpg") => Algo::Ddpg,
        Some("gppo") => Algo::Gppo,
        _ => Algo::Td3,
    };
    let rounds: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(100);
    let mut cfg = AlgoConfigs::default();
    cfg.td3.hidden = vec![64, 64];
    cfg.td3.batch_size = 64;
    cfg.td3.learning_starts = 400;
    cfg.td3.actor_lr = 1e-3;
    cfg.td3.critic_lr = 1e-3;
    cfg.ddpg.hidden = vec![64, 64];
    cfg.ddpg.batch_size = 64;
    cfg.ddpg.learning_starts = 400;
    cfg.ppo.n_envs = 4;
    cfg.ppo.lr = 1e-3;
    let mut envs = vec![Oscillator::default(); cfg.n_envs(algo)];
    let mut learner = Learner::new(algo, &cfg, 2, 1, 7);
    for r in 0..rounds {
        learner.round(&mut envs).unwrap();
        if (r + 1) % 10 == 0 {
            let mut p = learner.policy();
            let mut env = Oscillator::default();
            let ret: f64 = (0..8)
                .map(|s| episode(&mut env, &mut p, 1001 + s, &mut |_, _| {}).unwrap().ret)
                .sum::<f64>()
                / 8.0;
            println!("round {} samples {} eval {ret:.3}", r + 1, learner.samples());
        }
    }
}
