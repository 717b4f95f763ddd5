//! The 3D lattice-Boltzmann environments (`*_3D_*`): Gymnasium's contract for each family at the
//! coarse level (the real coarse grids; spin-up and control interval shortened so the suite
//! stays short; `hgym eval --policy random` runs full episodes, and the Python tests run
//! Gymnasium's own checker over every ID), per-segment forces that
//! add up to the body's, one agent per segment for multi-agent training, and bitwise-repeatable
//! trajectories.

use hgym::env::spec::ActuationSpec;
use hgym::env::spec3::{Actuation3Spec, Env3Spec};
use hgym::env::{registry, LbmEnv3};
use hgym::flow::Level;
use hgym_agents::multi::pseudo_envs;
use hgym_agents::{check_env, Env, EnvError};

/// `spec` with a short spin-up and control interval, `actions` per episode.
fn short(spec: &Env3Spec, actions: usize) -> Env3Spec {
    let mut s = spec.clone();
    s.spin_up = 0.5;
    s.control_interval = 0.02;
    s.episode_actions = actions;
    s
}

/// `spec` with a spin-up and control interval of a few lattice steps: the contract's checks
/// (spaces, seeding, determinism, truncation) on the real grid at the least cost.
fn shortest(spec: &Env3Spec, actions: usize) -> Env3Spec {
    let mut s = short(spec, actions);
    s.spin_up = 0.1;
    s.control_interval = 0.005;
    s
}

fn specs3() -> Vec<Env3Spec> {
    registry::all().iter().filter_map(|s| s.downcast::<Env3Spec>().cloned()).collect()
}

/// The first 3D ID of each family (every 3D ID: the ignored test below, which `make nightly`
/// runs; Python's `test_gymnasium.py` runs Gymnasium's own checker on these first IDs).
#[test]
fn each_3d_family_keeps_the_env_contract_at_coarse() {
    let specs = specs3();
    let mut seen = std::collections::BTreeSet::new();
    for family in [
        "cylinder",
        "rotary_cylinder",
        "pinball",
        "square_cylinder",
        "sphere",
        "cube",
        "naca0012",
        "cavity",
        "stenotic_pipe",
    ] {
        assert!(specs.iter().any(|s| s.family == family), "no 3D {family} ID registered");
    }
    for spec in specs.into_iter().filter(|s| seen.insert(s.family.clone())) {
        keeps_the_contract(&spec);
    }
}

/// Every 3D ID, not only each family's first (about 4 minutes here; `make nightly` runs it:
/// `cargo test --release --test env3_contract -- --ignored`).
#[test]
#[ignore]
fn every_3d_id_keeps_the_env_contract_at_coarse() {
    for spec in specs3() {
        keeps_the_contract(&spec);
    }
}

/// Gymnasium's contract (`check_env`), three steps with clipping, finite observations, the
/// force keys in `info` and a negative reward, on `spec` at coarse with the shortest timing.
fn keeps_the_contract(spec: &Env3Spec) {
    let id = spec.id.clone();
    let spec = shortest(spec, 3);
    let start = std::time::Instant::now();
    let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap_or_else(|e| panic!("{id}: {e}"));
    let built = start.elapsed().as_secs_f64();
    let violations = check_env(&mut env, spec.episode_actions, 7);
    assert!(violations.is_empty(), "{id}: {violations:#?}");
    assert_eq!(env.observation_space().dim(), spec.obs_dim(), "{id}");
    let act = env.action_space().dim();
    env.reset(3).unwrap();
    for (k, a) in [1.7, -0.4, 0.3].iter().enumerate() {
        let r = env.step(&vec![*a; act]).unwrap_or_else(|e| panic!("{id}: step {k}: {e}"));
        assert!(!r.terminated, "{id}: terminated at step {k}: {:?}", r.info.text("reason"));
        assert!(r.obs.iter().all(|v| v.is_finite()), "{id}: non-finite observation");
        let clipped = if a.abs() > 1.0 { act as f64 } else { 0.0 };
        assert_eq!(r.info.get("clipped"), Some(clipped), "{id}: clipping not counted");
        for key in ["t", "C_D", "C_L", "C_S", "C_D_0", "C_D_seg0", "actuation_0"] {
            assert!(r.info.get(key).is_some_and(|v| v.is_finite()), "{id}: info lacks {key}");
        }
        assert!(r.reward.is_finite() && r.reward < 0.0, "{id}: reward {}", r.reward);
    }
    assert!(matches!(env.step(&vec![0.0; act]), Err(EnvError::NeedsReset)), "{id}");
    println!(
        "{id}: contract ok, {} obs, {act} actions (built in {built:.1} s, checked in {:.1} s)",
        spec.obs_dim(),
        start.elapsed().as_secs_f64() - built
    );
}

/// The segments of a span split the body's force: the mean of the segments' coefficients (each
/// over its share of the area) is the body's; each segment is one agent seeing its own probes
/// and setting its own jet pair, and the pseudo-environments step the one flow together.
#[test]
fn segments_split_forces_and_agents() {
    let spec = short(
        &registry::lookup("Cylinder_3D_Re1000")
            .unwrap()
            .downcast::<Env3Spec>()
            .unwrap()
            .clone(),
        4,
    );
    let segments = spec.span.segments;
    assert_eq!(segments, 4);
    let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap();
    env.reset(0).unwrap();
    let r = env.step(&[0.8, -0.3, 0.0, 1.0]).unwrap();
    let c_d = r.info.get("C_D").unwrap();
    let c_l = r.info.get("C_L").unwrap();
    let mean = |key: &str| (0..segments).map(|s| r.info.get(&format!("{key}_seg{s}")).unwrap()).sum::<f64>() / segments as f64;
    println!(
        "C_D {c_d:.6} vs segment mean {:.6}; C_L {c_l:.6} vs {:.6}",
        mean("C_D"),
        mean("C_L")
    );
    assert!((mean("C_D") - c_d).abs() < 1e-9 * c_d.abs().max(1.0));
    assert!((mean("C_L") - c_l).abs() < 1e-9);
    let rewards = env.agent_rewards();
    assert_eq!(rewards.len(), segments);
    assert!(rewards.iter().all(|r| r.is_finite() && *r < 0.0), "{rewards:?}");

    let agents = env.agents().expect("a segmented span declares agents");
    assert_eq!(agents.len(), segments);
    let per = 4 * spec.probes.len();
    for s in 0..segments {
        assert_eq!(agents.act[s], vec![s], "agent {s} sets its segment's jet pair");
        assert_eq!(
            agents.obs[s],
            (s * per..(s + 1) * per).collect::<Vec<_>>(),
            "agent {s} sees its segment's probes"
        );
    }
    let mut pseudo = pseudo_envs(env).unwrap();
    assert_eq!(pseudo.len(), segments);
    for (k, p) in pseudo.iter_mut().enumerate() {
        assert_eq!(p.action_space().dim(), 1);
        assert_eq!(p.observation_space().dim(), per);
        p.submit_reset(5 + k as u64).unwrap();
    }
    for p in pseudo.iter_mut() {
        let (obs, _) = p.reset(0).unwrap();
        assert_eq!(obs.len(), per);
    }
    for p in pseudo.iter_mut() {
        p.submit(&[0.5]).unwrap();
    }
    for p in pseudo.iter_mut() {
        let r = p.step(&[0.5]).unwrap();
        assert!(r.reward.is_finite() && !r.terminated);
    }

    // A body without segments (the sphere's surface jets) has no agents.
    let sphere = registry::lookup("Sphere_3D_Re300").unwrap().downcast::<Env3Spec>().unwrap().clone();
    let env = LbmEnv3::new(short(&sphere, 2), Level::Coarse, None).unwrap();
    assert!(env.agents().is_none());
}

/// Turning segment 0 alone changes its lift far more than that of the segment across the span:
/// the actuators act on their own segment.
#[test]
fn a_segment_actuator_acts_on_its_own_segment() {
    let spec = short(
        &registry::lookup("RotaryCylinder_3D_Re1000")
            .unwrap()
            .downcast::<Env3Spec>()
            .unwrap()
            .clone(),
        8,
    );
    let run = |action: [f64; 4]| {
        let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap();
        env.reset(0).unwrap();
        let mut r = None;
        for _ in 0..8 {
            r = Some(env.step(&action).unwrap());
        }
        let r = r.unwrap();
        (0..4).map(|s| r.info.get(&format!("C_L_seg{s}")).unwrap()).collect::<Vec<_>>()
    };
    let rest = run([0.0; 4]);
    let turn = run([1.0, 0.0, 0.0, 0.0]);
    let change: Vec<f64> = rest.iter().zip(&turn).map(|(a, b)| (b - a).abs()).collect();
    println!("|change of C_L| per segment: {change:?}");
    assert!(change[0] > 10.0 * change[2], "segment 0 {} vs segment 2 {}", change[0], change[2]);
}

/// Same seed and actions in two separately built environments: the same trajectory, bitwise.
#[test]
fn same_seed_same_actions_same_trajectory() {
    let spec = short(
        &registry::lookup("Pinball_3D_Re30").unwrap().downcast::<Env3Spec>().unwrap().clone(),
        3,
    );
    let run = || {
        let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap();
        let (mut obs, _) = env.reset(11).unwrap();
        for k in 0..3 {
            obs.extend(env.step(&[0.5, -0.2 * k as f64, 0.1]).unwrap().obs);
        }
        obs
    };
    assert_eq!(run(), run());
}

/// Every surface jet (sphere, cube) reaches wall links at the coarse level: alone at its bound
/// it injects mass. A zero-net-mass-flux pair of a segment injects none; a segment's section
/// jets (the square's) inject mass of their own.
#[test]
fn every_3d_jet_reaches_the_wall_at_coarse() {
    for spec in specs3() {
        let id = spec.id.clone();
        let znmf = matches!(
            &spec.actuation,
            Actuation3Spec::Segments {
                actuator: ActuationSpec::ZnmfJets { .. }
            }
        );
        if !(znmf
            || matches!(
                &spec.actuation,
                Actuation3Spec::SurfaceJets { .. }
                    | Actuation3Spec::Segments {
                        actuator: ActuationSpec::Jets { .. }
                    }
            ))
        {
            continue;
        }
        let mut env = LbmEnv3::new(short(&spec, 1), Level::Coarse, None).unwrap();
        let m = env.actuator_mass_sources(1.0);
        println!("{id}: mass per step by each action at its bound {m:?}");
        if let (true, Actuation3Spec::Segments { actuator }) = (znmf, &spec.actuation) {
            // The pair's first jet alone.
            let (jets, _) = hgym::env::actuation::resolve(actuator, &spec.bodies).unwrap();
            let mut one = short(&spec, 1);
            one.actuation = Actuation3Spec::Segments {
                actuator: ActuationSpec::Jets {
                    body: 0,
                    jets: jets[..1].to_vec(),
                    max_velocity: 1.0,
                },
            };
            let alone = LbmEnv3::new(one, Level::Coarse, None).unwrap().actuator_mass_sources(1.0);
            println!("{id}: the blowing jet of each pair alone {alone:?}");
            assert!(
                alone.iter().all(|v| *v > 1e-5),
                "{id}: a jet of the pair reaches no wall link at coarse"
            );
        }
        for (k, v) in m.iter().enumerate() {
            if znmf {
                assert!(v.abs() < 1e-9, "{id}: jet pair {k} injects net mass {v:e}");
            } else {
                assert!(*v > 1e-5, "{id}: jet {k} reaches no wall link at coarse ({v:e})");
            }
        }
    }
}

/// The 3D gust enters through the inlet with the paper's 1 - cos shape, uniformly across the
/// span: the transverse velocity half a cell inside the inlet peaks at G at mid-gust, equal at two
/// spanwise positions, and is gone after it (coarse grid over a short span, gust moved to the
/// start of the episode).
#[test]
fn a_3d_gust_enters_through_the_inlet_across_the_span() {
    let mut spec = hgym::env::naca::steady_3d(1000, 20);
    spec.span.z = [-0.25, 0.25];
    spec.spin_up = 0.5;
    spec.episode_actions = 35;
    spec.gust = hgym::env::naca::gust(1000, 20).unwrap().gust;
    let g = spec.gust.as_mut().unwrap();
    g.start = 0.0;
    let g = g.clone();
    let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap();
    env.reset(0).unwrap();
    let (mut v, mut spread) = (vec![], 0.0f64);
    for _ in 0..spec.episode_actions {
        let r = env.step(&[0.0; 3]).unwrap();
        assert!(!r.terminated, "{:?}", r.info.text("reason"));
        let at = |z: f64| env.units().velocity(env.solver().probe([0.05, 0.0, z]).unwrap().1[1]);
        spread = spread.max((at(-0.2) - at(0.2)).abs());
        v.push(at(0.0));
    }
    let dt = spec.control_interval;
    let (k, peak) = v
        .iter()
        .enumerate()
        .fold((0, f64::MIN), |(kb, vb), (k, x)| if *x > vb { (k, *x) } else { (kb, vb) });
    let t_peak = (k + 1) as f64 * dt;
    println!(
        "inlet gust peak {peak:.4} at t = {t_peak:.2} (G = {}), spanwise spread {spread:.2e}",
        g.ratio
    );
    assert!((peak - g.ratio).abs() < 0.05 * g.ratio, "peak {peak}");
    assert!((t_peak - (g.start + 0.5 * g.duration)).abs() <= 0.3, "peak at t = {t_peak}");
    assert!(spread < 1e-6 * g.ratio, "the gust varies across the span by {spread}");
    let after = ((g.start + g.duration + 0.5) / dt) as usize;
    assert!(v[after..].iter().all(|x| x.abs() < 0.01), "transverse velocity left after the gust");
}

/// `hgym train --env Cylinder_3D_Re1000 --algo td3` trains one actor shared by the four segments'
/// agents, and `hgym eval --policy DIR` runs it on the whole span.
#[test]
fn multi_agent_td3_trains_on_the_segmented_cylinder_through_the_cli() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("marl.toml");
    std::fs::write(
        &cfg,
        "[train]\neval_every = 1\nfinal_eval_episodes = 1\n[env]\nspin_up = 0.2\ncontrol_interval = 0.02\nepisode_actions = 4\n\
         [td3]\nhidden = [16, 16]\nbatch_size = 8\nlearning_starts = 8\n",
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
    // Two rounds of one 4-action episode of 4 agents.
    let args = [
        "train",
        "--env",
        "Cylinder_3D_Re1000",
        "--algo",
        "td3",
        "--steps",
        "32",
        "--config",
        cfg,
        "--out",
        out_s,
    ];
    run(&args);
    let dir = out.join("Cylinder_3D_Re1000-td3-coarse/seed0");
    let policy: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("policy.json")).unwrap()).unwrap();
    assert_eq!(policy["agents"]["act"], serde_json::json!([[0], [1], [2], [3]]));
    assert_eq!(policy["net"]["sizes"][0], 80, "each agent sees its segment's 20 probes");
    let dir_s = dir.to_str().unwrap();
    let text = run(&[
        "eval",
        "--env",
        "Cylinder_3D_Re1000",
        "--policy",
        dir_s,
        "--episodes",
        "1",
        "--config",
        cfg,
        "--json",
    ]);
    assert!(text.contains("drag_reduction_pct"), "{text}");
}

/// The 3D stenotic pipe carries a temperature: `(u, v, w, p, T)` at each probe, the action moves
/// the inlet temperature by at most its bound per action within its range, the reward is the
/// target probe's temperature error, and the field stays between the coldest inlet and the wall
/// temperature.
#[test]
fn the_3d_pipe_observes_and_sets_the_temperature() {
    let spec = specs3()
        .into_iter()
        .find(|s| s.id == "StenoticPipe_3D_Re100")
        .expect("the 3D pipe is registered");
    let spec = short(&spec, 4);
    let mut env = LbmEnv3::new(spec.clone(), Level::Coarse, None).unwrap();
    assert_eq!(spec.obs_dim(), 5 * 10);
    let (obs, _) = env.reset(1).unwrap();
    let temperatures: Vec<f64> = obs.chunks(5).map(|p| p[4]).collect();
    assert!(temperatures.iter().all(|t| (0.85..=1.0 + 1e-6).contains(t)), "{temperatures:?}");
    let mut inlet = 0.9;
    for a in [1.0, 1.0, -1.0, 0.5] {
        let r = env.step(&[a]).unwrap();
        assert!(!r.terminated, "{:?}", r.info.text("reason"));
        let set = r.info.get("actuation_0").unwrap();
        assert!((set - (inlet + 0.05 * a)).abs() < 1e-12, "inlet {inlet} + 0.05 x {a} gave {set}");
        inlet = set;
        let t = r.info.get("T_target").unwrap();
        assert!((r.reward + 100.0 * (t - 0.95).abs()).abs() < 1e-9, "reward {} at T {t}", r.reward);
        assert!(r.obs.chunks(5).all(|p| (0.85..=1.0 + 1e-6).contains(&p[4])), "{:?}", r.obs);
    }
}
