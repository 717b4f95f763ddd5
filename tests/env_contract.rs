//! Gymnasium's contract, checked over every registered ID at the coarse level (the env checker
//! of Gymnasium, as a test): spaces, seeded reset determinism, NaN actions rejected, clipping
//! counted, `truncated` exactly at the last action, reward recomputable from `info`.

use hgym::env::lbm_env::reward;
use hgym::env::{registry, LbmEnv};
use hgym::validate::Level;
use hgym_agents::{Env, EnvError};

#[test]
fn every_registered_id_keeps_the_env_contract() {
    for mut spec in registry::all() {
        let id = spec.id.clone();
        spec.episode_actions = 4;
        let n_bodies = spec.bodies.len();
        let reward_spec = spec.reward.clone();
        let mut env = LbmEnv::new(spec.clone(), Level::Coarse, None).unwrap_or_else(|e| panic!("{id}: {e}"));
        let (act, obs_space) = (env.action_space(), env.observation_space());
        assert_eq!(act.dim(), spec.act_dim(), "{id}");
        assert!(
            act.low.iter().all(|v| *v == -1.0) && act.high.iter().all(|v| *v == 1.0),
            "{id}: actions must be in [-1, 1]"
        );
        assert_eq!(obs_space.dim(), spec.obs_dim(), "{id}");

        // Seeded reset is deterministic, bitwise; another seed starts elsewhere.
        let (o1, _) = env.reset(7).unwrap_or_else(|e| panic!("{id}: {e}"));
        let (o2, _) = env.reset(7).unwrap();
        assert_eq!(o1, o2, "{id}: reset(7) twice differs");
        assert!(o1.iter().all(|v| v.is_finite()), "{id}: non-finite observation");
        assert!(obs_space.contains(&o1), "{id}: observation outside its space");
        let (o3, _) = env.reset(8).unwrap();
        assert_ne!(o1, o3, "{id}: seeds 7 and 8 give the same start");

        // Bad actions.
        let nan = vec![f64::NAN; act.dim()];
        assert!(
            matches!(env.step(&nan), Err(EnvError::NonFiniteAction { .. })),
            "{id}: NaN accepted"
        );
        assert!(
            matches!(env.step(&vec![0.0; act.dim() + 1]), Err(EnvError::ActionShape { .. })),
            "{id}"
        );

        // An episode: clipping counted, reward from info, truncated exactly at the last action.
        env.reset(3).unwrap();
        let actions = [1.7, -0.4, 0.3, -1.0];
        for (k, a) in actions.iter().enumerate() {
            let r = env.step(&vec![*a; act.dim()]).unwrap_or_else(|e| panic!("{id}: step {k}: {e}"));
            assert!(!r.terminated, "{id}: terminated at step {k}: {:?}", r.info.text("reason"));
            assert_eq!(r.truncated, k == actions.len() - 1, "{id}: truncated wrong at step {k}");
            assert!(r.obs.iter().all(|v| v.is_finite()), "{id}: non-finite observation at step {k}");
            let clipped = if a.abs() > 1.0 { act.dim() as f64 } else { 0.0 };
            assert_eq!(r.info.get("clipped"), Some(clipped), "{id}: clipping not counted");
            for key in ["t", "C_D", "C_L", "actuation_0"] {
                assert!(r.info.get(key).is_some_and(|v| v.is_finite()), "{id}: info lacks {key}");
            }
            assert_eq!(
                r.reward,
                reward(&reward_spec, &r.info, n_bodies),
                "{id}: reward not recomputable from info"
            );
        }
        assert!(
            matches!(env.step(&vec![0.0; act.dim()]), Err(EnvError::NeedsReset)),
            "{id}: step after the last action"
        );
        println!("{id}: contract ok ({} solver steps per action at coarse)", env.steps_per_action());
    }
}

/// Same seed and same actions in two separately built envs: bitwise-identical trajectories.
#[test]
fn same_seed_same_actions_same_trajectory() {
    let spec = registry::get("Cylinder_2D_Re100").unwrap();
    let run = || {
        let mut env = LbmEnv::new(spec.clone(), Level::Coarse, None).unwrap();
        let (mut obs, _) = env.reset(11).unwrap();
        let mut rewards = Vec::new();
        for k in 0..5 {
            let r = env.step(&[0.5 * ((k as f64) * 0.7).sin()]).unwrap();
            obs.extend(r.obs);
            rewards.push(r.reward);
        }
        (obs, rewards)
    };
    assert_eq!(run(), run());
}
