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
    // A uniform action (the sine baseline's) is no actuation, not a round-off net flux.
    let r = env.step(&vec![0.3; n]).unwrap();
    assert!(r.obs.iter().all(|v| v.is_finite()));
    let s = env.solver();
    let g = s.grid();
    assert!((0..g.nz).all(|k| (0..g.nx).all(|i| s.v()[g.at_v(i, 0, k)] == 0.0)));
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

/// One agent per patch: the agents' actions tile both walls, each sees its own patch at the
/// centre of its window, and the local rewards (patches of equal area) average to the reward.
#[test]
fn agents_tile_the_walls_and_local_rewards_average_to_the_reward() {
    let spec = short(channel::all().remove(1), 3);
    let mut env = ChannelEnv::new(spec.clone(), Level::Coarse, None).unwrap();
    let agents = env.agents().expect("the channel declares agents");
    assert_eq!(agents.len(), spec.act_dim());
    assert_eq!((agents.local_obs_dim(), agents.local_act_dim()), (18, 1));
    for (i, (obs, act)) in agents.obs.iter().zip(&agents.act).enumerate() {
        assert_eq!(act, &vec![i]);
        assert_eq!(obs[8..10], [2 * i, 2 * i + 1], "agent {i}: its own patch is the window's centre");
    }
    env.reset(2).unwrap();
    let a: Vec<f64> = (0..spec.act_dim()).map(|i| ((i * 13 % 7) as f64 - 3.0) / 3.0).collect();
    let r = env.step(&a).unwrap();
    let local = env.agent_rewards();
    let mean = local.iter().sum::<f64>() / local.len() as f64;
    assert!((mean - r.reward).abs() < 1e-12, "{mean} against {}", r.reward);
    assert!(
        local.iter().any(|l| (l - r.reward).abs() > 1e-3),
        "local rewards differ between patches"
    );
    let mut bad = spec.clone();
    bad.agents.window = 4;
    assert!(bad.check().unwrap_err().contains("agents.window"));
}

/// `hgym train --env TCFMini_3D_Retau180 --algo td3` trains the agents through pseudo-environments
/// and writes a shared policy that `hgym eval --policy DIR` runs on the whole channel.
#[test]
fn multi_agent_td3_trains_through_the_cli_and_evaluates() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("marl.toml");
    std::fs::write(
        &cfg,
        "[train]\neval_every = 1\nfinal_eval_episodes = 1\n[env]\nspin_up = 4.0\nepisode_actions = 4\n\
         [td3]\nhidden = [16, 16]\nbatch_size = 32\nlearning_starts = 256\ngradient_steps = 2\nn_envs = 1\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_hgym"))
            .args(args)
            .env("HGYM_CACHE", tmp.path().join("cache"))
            .output()
            .unwrap();
        let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert!(o.status.success(), "{args:?}: {text}");
        text
    };
    let (cfg, out_s) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    // Two rounds of one 4-action episode of 128 agents.
    run(&[
        "train",
        "--env",
        "TCFMini_3D_Retau180",
        "--algo",
        "td3",
        "--steps",
        "1024",
        "--config",
        cfg,
        "--out",
        out_s,
    ]);
    let dir = out.join("TCFMini_3D_Retau180-td3-coarse/seed0");
    let policy: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("policy.json")).unwrap()).unwrap();
    assert_eq!(policy["agents"]["obs"].as_array().unwrap().len(), 128);
    assert_eq!(policy["net"]["sizes"][0], 18);
    let manifest: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["samples"], 1024);
    let curve = std::fs::read_to_string(dir.join("curve.csv")).unwrap();
    assert_eq!(curve.lines().count(), 3, "{curve}");
    let text = run(&[
        "eval",
        "--env",
        "TCFMini_3D_Retau180",
        "--policy",
        dir.to_str().unwrap(),
        "--episodes",
        "1",
        "--config",
        cfg,
        "--json",
    ]);
    assert!(text.contains("drag_reduction_pct"), "{text}");
}

/// `hgym run` on a channel: the wall shear stress map and the sensing-plane fields as images;
/// a box below the minimal flow unit runs with a warning that names the sizes.
#[test]
fn run_draws_the_wall_shear_stress() {
    use hgym::env::family::FamilySpec;
    assert!(channel::all().iter().all(|s| s.warnings().is_empty()));
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("short.toml");
    std::fs::write(&cfg, "[env]\nspin_up = 4.0\nlength = [1.2, 2.0, 0.4]\n").unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args([
            "run",
            "--env",
            "TCFMini_3D_Retau180",
            "--res",
            "coarse",
            "--steps",
            "3",
            "--policy",
            "random",
        ])
        .arg("--config")
        .arg(&cfg)
        .arg("--out")
        .arg(tmp.path())
        .env("HGYM_CACHE", tmp.path().join("cache"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: TCFMini_3D_Retau180: the box is Lx+ 216 by Lz+ 72"),
        "{stderr}"
    );
    assert!(stderr.contains("length[0] >= 1.39"), "{stderr}");
    let dir = tmp.path().join("TCFMini_3D_Retau180-random-seed0");
    for f in [
        "manifest.json",
        "metrics.json",
        "rollout.png",
        "tau_w_excess.png",
        "u_sensing.png",
        "trajectory.mcap",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap();
    assert_eq!((m["actions_run"].as_u64(), m["spec"]["re_tau"].as_f64()), (Some(3), Some(180.0)));
}
