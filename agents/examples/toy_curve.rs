//! Learning curve of an algorithm on the unstable oscillator:
//! `cargo run --release -p hgym-agents --example toy_curve -- td3 200`.

use hgym_agents::learn::{algorithm, AlgoConfigs};
use hgym_agents::rollout::episode;
use hgym_agents::toy::Oscillator;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let algo = algorithm(args.get(1).map_or("td3", |s| s.as_str()))?;
    let rounds: u64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(100);
    // Small networks and an early start suit the two-dimensional oscillator.
    let mut cfg = AlgoConfigs::default();
    let small = serde_json::json!({"hidden": [64, 64], "batch_size": 64, "learning_starts": 400, "actor_lr": 1e-3, "critic_lr": 1e-3});
    cfg.0.insert("td3".into(), small.clone());
    cfg.0.insert("ddpg".into(), small);
    cfg.0.insert("ppo".into(), serde_json::json!({"n_envs": 4, "lr": 1e-3}));
    let cfg = cfg.complete()?;
    let mut envs = vec![Oscillator::default(); algo.n_envs(&cfg)?];
    let mut learner = algo.learner(&cfg, 2, 1, 7)?;
    for r in 0..rounds {
        learner.round_on(&mut envs)?;
        if (r + 1) % 10 == 0 {
            let mut p = learner.policy();
            let mut env = Oscillator::default();
            let ret: f64 = (0..8)
                .map(|s| episode(&mut env, &mut p, 1001 + s, &mut |_, _| {}).map(|e| e.ret))
                .sum::<Result<f64, _>>()?
                / 8.0;
            println!("round {} samples {} eval {ret:.3}", r + 1, learner.samples());
        }
    }
    Ok(())
}
