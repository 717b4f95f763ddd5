//! The channel environments: the contract at coarse (with a short spin-up), zero-net-mass-flux
//! actuation, observations that see the flow, reproducibility, and the refusals.

use hgym::env::channel::{self, ChannelEnv, ChannelSpec};
use hgym::env::registry;
use hgym::flow::Level;
use hgym_agents::{check_env, Env, EnvError};

/// A spec with a short spin-up (the flow is still transitional: enough for the contract).
fn short(mut s: ChannelSpec, actions: usize) -> ChannelSpec {
    s.spin_up = 4.0;
    s.episode_actions = actions;
    s
}

#[test]
fn the_three_ids_are_registered_and_keep_the_contract() {
    let ids: Vec<String> = channel::all().iter().map(|s| s.id.clone()).collect();
    assert_eq!(ids, ["TCF_3D_Retau180", "TCFMini_3D_Retau180", "TCFOpen_3D_Retau206"]);
    for spec in channel::all() {
        assert!(registry::lookup(&spec.id).is_ok());
        let mut env = ChannelEnv::new(short(spec.clone(), 3), Level::Coarse, None).unwrap();
        let violations = check_env(&mut env, 3, 7);
        assert!(violations.is_empty(), "{}: {violations:#?}", spec.id);
        assert_eq!(env.observation_space().dim(), 2 * env.action_space().dim());
    }
}

#[test]
fn actuation_is_zero_net_mass_flux_per_wall_and_bounded_by_u_tau() {
    let spec = short(channel::all().remove(1), 5);
    let mut env = ChannelEnv::new(spec.clone(), Level::Coarse, None).unwrap();
    env.reset(1).unwrap();
    let n = env.action_space().dim();
    let action: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 4.0).collect();
    let r = env.step(&action).unwrap();
    assert!(r.info.get("clipped").unwrap() > 0.0);
    let s = env.solver();
    let g = s.grid();
    for (j, sign) in [(0, 1.0), (g.ny, -1.0)] {
        let row: Vec<f64> = (0..g.nz)
            .flat_map(|k| (0..g.nx).map(move |i| (i, k)))
            .map(|(i, k)| sign * s.v()[g.at_v(i, j, k)])
            .collect();
        let mean = row.iter().sum::<f64>() / row.len() as f64;
        let max = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(mean.abs() < 1e-15, "wall row {j}: net flux {mean:e}");
        assert!(
            max > 0.0 && max <= 2.0 * spec.u_tau() + 1e-12,
            "wall row {j}: {max} against u_tau {}",
            spec.u_tau()
        );
    }
    assert!(s.max_divergence() < 1e-12);
}

#[test]
fn episodes_are_bitwise_repeatable_and_seeds_differ() {
    let spec = short(channel::all().remove(1), 3);
    let run = |seed: u64| {
        let mut env = ChannelEnv::new(spec.clone(), Level::Coarse, None).unwrap();
        let (mut obs, _) = env.reset(seed).unwrap();
        let mut out = obs.clone();
        for _ in 0..3 {
            let a: Vec<f64> = obs.iter().skip(1).step_by(2).map(|v| -v.clamp(-1.0, 1.0)).collect();
            let r = env.step(&a).unwrap();
            out.push(r.reward);
            obs = r.obs;
            out.extend(&obs);
        }
        out
    };
    let (a, b) = (run(4), run(4));
    assert!(a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
    assert_ne!(run(4)[..8], run(5)[..8]);
}

#[test]
fn bad_specs_and_actions_are_refused_naming_the_field() {
    let mut spec = channel::all().remove(0);
    spec.patches = [7, 32];
    assert!(spec.check().unwrap_err().contains("patches"));
    let mut spec = channel::all().remove(0);
    spec.grid.coarse[1] = 16;
    let e = spec.check().unwrap_err();
    assert!(e.contains("y+") && e.contains("coarse"), "{e}");
    let mut env = ChannelEnv::new(short(channel::all().remove(1), 2), Level::Coarse, None).unwrap();
    env.reset(0).unwrap();
    let mut a = vec![0.0; env.action_space().dim()];
    a[3] = f64::NAN;
    assert!(matches!(env.step(&a), Err(EnvError::NonFiniteAction { index: 3, .. })));
}
