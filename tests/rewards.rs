//! Each reward kind against a value computed here, independently of the environment's own
//! reward function and force sums: the forces are summed by hand from the solver's lattice
//! forces over the interval, on a second solver built from the environment's flow set-up and
//! started from the environment's state after `reset`; the reward is the paper's formula written
//! out here. The `info` keys are read by name, so renaming one fails here.

use hgym::env::{lbm_spec as spec, LbmEnv};
use hgym::flow::{FlowSetup, Level};
use hgym_agents::Env;

/// Interval-averaged (C_D, C_L) of each body over the first action at rest after `reset(seed)`,
/// summed by hand on a twin solver.
fn forces_by_hand(env: &LbmEnv) -> Vec<[f64; 2]> {
    let setup: FlowSetup = env.spec().flow_setup();
    let plan = setup.plan(Level::Coarse).unwrap();
    let mut twin = setup.build(&plan).unwrap().into_uniform().unwrap();
    twin.set_populations(&env.solver().populations(), env.solver().time()).unwrap();
    let n = env.steps_per_action();
    let mut sum = vec![[0.0f64; 2]; setup.bodies.len()];
    for _ in 0..n {
        twin.step().unwrap();
        for (s, f) in sum.iter_mut().zip(twin.body_forces()) {
            s[0] += f[0];
            s[1] += f[1];
        }
    }
    // C = F / (rho U^2 L / 2) with rho = 1 and L = cells_per_length lattice units.
    let u = plan.units.u_lattice;
    let q = 0.5 * u * u * plan.units.cells_per_length;
    sum.iter().map(|s| [s[0] / n as f64 / q, s[1] / n as f64 / q]).collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

/// Runs one zero action of `id` at coarse and returns (forces by hand, the step's reward, info).
fn first_interval(id: &str) -> (Vec<[f64; 2]>, hgym_agents::StepResult) {
    let mut env = LbmEnv::new(spec(id).unwrap(), Level::Coarse, None).unwrap();
    env.reset(5).unwrap();
    let by_hand = forces_by_hand(&env);
    let dim = env.action_space().dim();
    let r = env.step(&vec![0.0; dim]).unwrap();
    (by_hand, r)
}

fn info(r: &hgym_agents::StepResult, key: &str) -> f64 {
    r.info.get(key).unwrap_or_else(|| panic!("info has no '{key}'"))
}

/// Cylinder: `r = -|C_D| - 0.1 |C_L|` (the paper's Re 100 weight).
#[test]
fn drag_lift_reward_of_the_cylinder() {
    let (f, r) = first_interval("Cylinder_2D_Re100");
    let [c_d, c_l] = f[0];
    assert!(c_d > 1.0 && c_d < 2.0, "C_D {c_d}");
    assert!(
        close(info(&r, "C_D_0"), c_d) && close(info(&r, "C_L_0"), c_l),
        "{:?} vs {f:?}",
        r.info
    );
    assert!(close(info(&r, "C_D"), c_d) && close(info(&r, "C_L"), c_l));
    let expected = -c_d.abs() - 0.1 * c_l.abs();
    assert!(close(r.reward, expected), "reward {} vs {expected}", r.reward);
}

/// Pinball: `r = -|sum_b C_D,b| - w |sum_b C_L,b|` over the three cylinders.
#[test]
fn total_drag_lift_reward_of_the_pinball() {
    let (f, r) = first_interval("Pinball_2D_Re100");
    assert_eq!(f.len(), 3);
    let (c_d, c_l) = (f.iter().map(|b| b[0]).sum::<f64>(), f.iter().map(|b| b[1]).sum::<f64>());
    for (b, fb) in f.iter().enumerate() {
        assert!(close(info(&r, &format!("C_D_{b}")), fb[0]), "body {b}");
        assert!(close(info(&r, &format!("C_L_{b}")), fb[1]), "body {b}");
    }
    assert!(close(info(&r, "C_D"), c_d) && close(info(&r, "C_L"), c_l));
    let hgym::env::spec::RewardSpec::TotalDragLift { lift_weight } = spec("Pinball_2D_Re100").unwrap().reward else {
        panic!("the pinball's reward kind changed");
    };
    let expected = -c_d.abs() - lift_weight * c_l.abs();
    assert!(close(r.reward, expected), "reward {} vs {expected}", r.reward);
}

/// Gust aerofoil: `r = -|C_L - C_L,ref| - w |C_D - C_D,ref|`, in the first interval (before the
/// gust reaches the inlet, so the twin's steady inlet is the environment's), with the references
/// of the level run: at coarse the spec's `coarse` pair, the undisturbed coarse flow's mean
/// forces. `info["dC_L"]` is `C_L - C_L,ref`.
#[test]
fn gust_loads_reward_of_the_aerofoil() {
    let id = "NACA0012Gust_2D_Re1000_AoA20";
    let (f, r) = first_interval(id);
    let [c_d, c_l] = f[0];
    assert!(close(info(&r, "C_D"), c_d) && close(info(&r, "C_L"), c_l));
    let hgym::env::spec::RewardSpec::GustLoads {
        drag_weight,
        coarse: Some([c_l_ref, c_d_ref]),
        ..
    } = spec(id).unwrap().reward
    else {
        panic!("the gust reward kind changed, or it lost its coarse references");
    };
    let expected = -(c_l - c_l_ref).abs() - drag_weight * (c_d - c_d_ref).abs();
    assert!(close(r.reward, expected), "reward {} vs {expected}", r.reward);
    assert!(close(info(&r, "dC_L"), c_l - c_l_ref));
}

/// Open cavity: `r = -sum_i ((o_i - mean_i) / std_i)^2`, i.e. `-9 sum obs^2` with the 3-std
/// scaling, recomputed from the raw probe values and the spec's normalisation.
#[test]
fn probe_deviation_reward_of_the_cavity() {
    let mut env = LbmEnv::new(spec("Cavity_2D_Re7500").unwrap(), Level::Coarse, None).unwrap();
    env.reset(5).unwrap();
    let dim = env.action_space().dim();
    let r = env.step(&vec![0.0; dim]).unwrap();
    let raw = env.raw_observation().unwrap();
    let norm = &env.spec().normalization;
    assert_eq!(norm.mean.len(), raw.len(), "the cavity is calibrated");
    let expected: f64 = -raw
        .iter()
        .zip(norm.mean.iter().zip(&norm.scale))
        .map(|(o, (m, s))| ((o - m) / (s / 3.0)).powi(2))
        .sum::<f64>();
    assert!(
        (r.reward - expected).abs() <= 1e-9 * (1.0 + expected.abs()),
        "reward {} vs {expected}",
        r.reward
    );
}

/// Stenotic pipe: `r = -w |T(probe) / T_wall - target|`, with `T` read by name from `info`.
#[test]
fn probe_temperature_reward_of_the_pipe() {
    let id = "StenoticPipe_2D_Re100";
    let mut env = LbmEnv::new(spec(id).unwrap(), Level::Coarse, None).unwrap();
    env.reset(5).unwrap();
    let r = env.step(&[0.0]).unwrap();
    let hgym::env::spec::RewardSpec::ProbeTemperature { target, weight, .. } = spec(id).unwrap().reward else {
        panic!("the pipe's reward kind changed");
    };
    let t = info(&r, "T_target");
    assert!(t > 0.5 && t < 1.5, "T {t}");
    let expected = -weight * (t - target).abs();
    assert!(close(r.reward, expected), "reward {} vs {expected}", r.reward);
}
