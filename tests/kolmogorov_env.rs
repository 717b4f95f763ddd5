//! The Kolmogorov environments against the Env contract, and their differentiable extension:
//! reward gradients from the discrete adjoint against central finite differences of the env
//! itself, for both objectives.

use hgym::env::kolmogorov::{self, KolmogorovEnv, KolmogorovSpec, Objective};
use hgym::flow::Level;
use hgym_agents::{DifferentiableEnv, Env, EnvError};

fn short(mut s: KolmogorovSpec, actions: usize) -> KolmogorovSpec {
    s.episode_actions = actions;
    s
}

#[test]
fn every_kolmogorov_id_honours_the_contract_at_coarse() {
    for spec in kolmogorov::all() {
        let id = spec.id.clone();
        assert!(
            spec.statistics.u_rms > 0.0,
            "{id}: statistics not calibrated (hgym envs calibrate {id})"
        );
        let mut env = KolmogorovEnv::new(short(spec.clone(), 6), Level::Coarse).unwrap();
        assert_eq!(env.observation_space().dim(), 128);
        assert_eq!(env.action_space().dim(), 4);
        let (o1, _) = env.reset(3).unwrap();
        let (o2, _) = env.reset(3).unwrap();
        assert_eq!(o1, o2, "{id}: same seed, same observation");
        let (o3, _) = env.reset(4).unwrap();
        assert_ne!(o1, o3, "{id}: another seed starts elsewhere on the attractor");
        assert!(matches!(
            env.step(&[f64::NAN, 0.0, 0.0, 0.0]),
            Err(EnvError::NonFiniteAction { index: 0, .. })
        ));
        assert!(matches!(env.step(&[0.0; 3]), Err(EnvError::ActionShape { .. })));
        let space = env.observation_space();
        for k in 0..6 {
            let r = env.step(&[1.5, -0.3, 0.2, -2.0]).unwrap();
            assert_eq!(r.info.get("clipped"), Some(2.0), "{id}: two components clipped");
            assert!(!r.terminated, "{id}: {:?}", r.info.text("reason"));
            assert_eq!(r.truncated, k == 5, "{id}: truncated exactly at the last action");
            assert!(space.contains(&r.obs), "{id}: observation outside [-5, 5]");
            let again = env.reward_from_info(&r.info).unwrap();
            assert!(
                (again - r.reward).abs() <= 1e-12 * (1.0 + r.reward.abs()),
                "{id}: reward {} vs from info {again}",
                r.reward
            );
            assert_eq!(r.info.get("actuation_0"), Some(0.5 * spec.max_amplitude * 2.0));
        }
        assert!(matches!(env.step(&[0.0; 4]), Err(EnvError::NeedsReset)));
    }
}

/// Same seed and actions: bitwise identical trajectories.
#[test]
fn kolmogorov_episodes_are_bitwise_repeatable() {
    let run = || {
        let mut env = KolmogorovEnv::new(short(kolmogorov::spec(40), 4), Level::Coarse).unwrap();
        let mut out = vec![env.reset(9).unwrap().0];
        for k in 0..4 {
            out.push(env.step(&[0.3 * k as f64, -0.2, 0.1, 0.0]).unwrap().obs);
        }
        out
    };
    assert_eq!(run(), run());
}

fn gradient_check(objective: Objective) {
    let mut spec = short(kolmogorov::spec(40), 10);
    spec.objective = objective.clone();
    let actions = [[0.4, -0.3, 0.2, 0.1], [-0.2, 0.5, -0.1, 0.3], [0.1, 0.1, -0.4, -0.2]];
    let total = |acts: &[[f64; 4]]| -> f64 {
        let mut env = KolmogorovEnv::new(spec.clone(), Level::Coarse).unwrap();
        env.reset(2).unwrap();
        acts.iter().map(|a| env.step(a).unwrap().reward).sum()
    };
    let mut env = KolmogorovEnv::new(spec.clone(), Level::Coarse).unwrap();
    env.reset(2).unwrap();
    for a in &actions {
        env.step(a).unwrap();
    }
    let g = env.reward_action_gradients(3).unwrap();
    // A second episode refills the first one's stored states: the same gradients, bitwise.
    env.reset(2).unwrap();
    for a in &actions {
        env.step(a).unwrap();
    }
    assert_eq!(env.reward_action_gradients(3).unwrap(), g, "a second episode's gradients");
    let h = 1e-5;
    let mut worst: f64 = 0.0;
    for j in 0..3 {
        for i in 0..4 {
            let (mut p, mut m) = (actions, actions);
            p[j][i] += h;
            m[j][i] -= h;
            let fd = (total(&p) - total(&m)) / (2.0 * h);
            worst = worst.max((fd - g[j][i]).abs() / (1e-8 + fd.abs()));
        }
    }
    println!("{objective:?}: worst relative error of the adjoint reward gradients {worst:.2e}");
    assert!(worst < 1e-6, "{objective:?}: {worst}");
}

#[test]
fn reward_gradients_match_finite_differences_for_mixing() {
    gradient_check(Objective::Mixing);
}

#[test]
fn reward_gradients_match_finite_differences_for_dissipation() {
    gradient_check(Objective::Dissipation { extreme_weight: 10.0 });
}
