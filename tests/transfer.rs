//! Transfer between flows on real environments (coarse, one round of small networks): a
//! cylinder policy evaluated zero-shot on the square cylinder through the protocol's mapping,
//! fine-tuned there with `--init-from` (its first evaluation is the zero-shot one, bitwise), a
//! whole one-seed protocol through `hgym transfer`, and the bad input the issue names.

use std::path::Path;
use std::process::{Command, Output};

fn hgym(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hgym")).args(args).output().expect("run hgym")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// Episodes of 50 actions, two rounds of two environments, small networks.
const CONFIG: &str = "[train]\nsteps = 200\neval_every = 1\neval_episodes = 1\nfinal_eval_episodes = 1\n\
                      [td3]\nhidden = [16, 16]\nbatch_size = 16\nlearning_starts = 100\n[env]\nepisode_actions = 50\n";

const SQUARE: &str = "benchmarks/protocols/transfer/cylinder_square_re200.toml";

#[test]
fn zero_shot_fine_tuning_and_a_protocol_from_the_cylinder_to_the_square() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("small.toml");
    std::fs::write(&cfg, CONFIG).unwrap();
    let (cfg_s, out) = (cfg.to_str().unwrap(), tmp.path().to_str().unwrap());
    let o = hgym(&["train", "--env", "Cylinder_2D_Re100", "--config", cfg_s, "--out", out]);
    assert!(o.status.success(), "{}", text(&o));
    let src = tmp.path().join("Cylinder_2D_Re100-td3-coarse/seed0");
    let src_s = src.to_str().unwrap();

    // Zero-shot: the jet pair has no namesake on the square; the protocol's mapping names it.
    let o = hgym(&["eval", "--policy", src_s, "--env", "SquareCylinder_2D_Re200", "--episodes", "1"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("actuators jet_pair") && text(&o).contains("jet_rear_bottom"),
        "{}",
        text(&o)
    );
    let o = hgym(&[
        "eval",
        "--policy",
        src_s,
        "--env",
        "SquareCylinder_2D_Re200",
        "--episodes",
        "1",
        "--mapping",
        SQUARE,
        "--config",
        cfg_s,
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let zero_shot: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();

    // Fine-tuning starts from exactly that policy: its curve's row 0 is the zero-shot evaluation.
    let ft = tmp.path().join("ft");
    let fine_tune = [
        "train",
        "--env",
        "SquareCylinder_2D_Re200",
        "--init-from",
        src_s,
        "--mapping",
        SQUARE,
    ];
    let o = hgym(&[&fine_tune[..], &["--config", cfg_s, "--out", ft.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let run = ft.join("SquareCylinder_2D_Re200-td3-coarse-from-Cylinder_2D_Re100-seed0/seed0");
    let curve = std::fs::read_to_string(run.join("curve.csv")).unwrap();
    let row0: Vec<&str> = curve.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(&row0[..3], ["0", "0", "0"], "{curve}");
    assert_eq!(
        row0[6].parse::<f64>().unwrap(),
        zero_shot["ret"]["mean"].as_f64().unwrap(),
        "{curve}"
    );
    let m = json(&run.join("manifest.json"));
    assert_eq!(m["init_from"]["env_id"], "Cylinder_2D_Re100");
    assert_eq!(m["init_from"]["mapping"]["actions"]["jet_front_bottom"], "-jet_pair");
    assert_eq!(m["init_from"]["identity"], false);
    // On the leaderboard it is named by its source and made again with its algorithm.
    let o = hgym(&["leaderboard", "--json", "--results", ft.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let lb: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let entry = &lb["entries"][0];
    assert_eq!(entry["policy"], "td3 fine-tuned from Cylinder_2D_Re100", "{lb:#}");
    assert!(entry["reproduce"].as_str().unwrap().contains(" --algo td3 --res coarse "), "{lb:#}");
    // Critics need the source's checkpoint and a learner with critics; PPO has none to take.
    let o = hgym(&[&fine_tune[..], &["--algo", "ppo", "--steps", "1", "--out", out]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("use --algo td3"), "{}", text(&o));

    // A one-seed protocol with this source: three arms, the comparison and its plot.
    let protocol = std::fs::read_to_string(SQUARE)
        .unwrap()
        .replace("seeds = [0, 1, 2, 3, 4]", "seeds = [0]")
        .replace("source = \"Cylinder_2D_Re200\"", "source = \"Cylinder_2D_Re100\"")
        .replace(
            "results/train/Cylinder_2D_Re200-td3-coarse/seed{seed}",
            &format!("{out}/Cylinder_2D_Re100-td3-coarse/seed{{seed}}"),
        )
        .replace(
            "[config.train]\nsteps = 20000\n",
            CONFIG
                .replace("[train]", "[config.train]")
                .replace("[td3]", "[config.td3]")
                .replace("[env]", "[config.env]")
                .as_str(),
        );
    let pfile = tmp.path().join("protocol.toml");
    let hash_line = protocol.lines().find(|l| l.starts_with("source_spec_hash")).unwrap().to_string();
    std::fs::write(&pfile, &protocol).unwrap();
    let tout = tmp.path().join("transfer");
    let args = [
        "transfer",
        "--protocol",
        pfile.to_str().unwrap(),
        "--out",
        tout.to_str().unwrap(),
        "--json",
    ];
    // The pinned hash is the Re 200 cylinder's: this source is refused, with the command to make one.
    let o = hgym(&args);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("hgym train --env Cylinder_2D_Re100"), "{}", text(&o));
    let hash = json(&src.join("manifest.json"))["spec_hash"].as_str().unwrap().to_string();
    std::fs::write(&pfile, protocol.replace(&hash_line, &format!("source_spec_hash = \"{hash}\""))).unwrap();
    let o = hgym(&args);
    assert!(o.status.success(), "{}", text(&o));
    let root = tout.join("cylinder_square_re200");
    let cmp = json(&root.join("comparison.json"));
    assert_eq!(cmp["schema"], "hgym/transfer/v1");
    assert!(root.join("transfer.png").exists());
    let arms: Vec<&str> = cmp["arms"].as_array().unwrap().iter().map(|a| a["arm"].as_str().unwrap()).collect();
    assert_eq!(arms, ["zeroshot", "finetune", "scratch"]);
    // The protocol's zero-shot arm and `hgym eval` agree (same policy, seeds, mapping).
    let zs = json(&root.join("zeroshot/seed0/metrics.json"));
    assert_eq!(zs["ret"]["mean"], zero_shot["ret"]["mean"]);
    // The threshold is 90 % of the from-scratch arm's gain over the uncontrolled flow; without a
    // gain there is none (null), and no arm reaches it.
    let (r0, rs) = (
        cmp["uncontrolled_return"].as_f64().unwrap(),
        cmp["scratch_final_return"].as_f64().unwrap(),
    );
    match cmp["threshold"].as_f64() {
        Some(th) => assert!(rs > r0 && (th - (r0 + 0.9 * (rs - r0))).abs() < 1e-9 * r0.abs(), "{cmp}"),
        None => {
            assert!(rs <= r0 && cmp["threshold"].is_null(), "{cmp}");
            assert!(cmp["arms"].as_array().unwrap().iter().all(|a| a["seeds_reaching"] == 0), "{cmp}");
        }
    }
    // A second call finds every arm done and only recomputes the comparison.
    let o = hgym(&args[..args.len() - 1]);
    assert!(o.status.success() && text(&o).matches("done already").count() == 3, "{}", text(&o));
    // The same protocol with another budget does not keep the runs of the old one: refused,
    // naming what differs, with the finished runs left as they were.
    let before = std::fs::read(root.join("finetune/seed0/metrics.json")).unwrap();
    let changed = std::fs::read_to_string(&pfile).unwrap().replace("steps = 200", "steps = 400");
    std::fs::write(&pfile, changed).unwrap();
    let o = hgym(&args);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("config_toml differ"), "{}", text(&o));
    assert_eq!(std::fs::read(root.join("finetune/seed0/metrics.json")).unwrap(), before);
}

#[test]
fn unknown_pairs_and_missing_sources_exit_2_saying_what_to_run() {
    let o = hgym(&["transfer", "channel", "cylinder"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("Cylinder_2D_Re200 Cylinder_2D_Re1000"), "{}", text(&o));
    let tmp = tempfile::tempdir().unwrap();
    // The channel -> wing protocol without its channel runs: the command that trains them.
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["transfer", "channel", "naca0012", "--out", "."])
        .current_dir(tmp.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).contains("hgym train --env TCFOpen_3D_Retau206 --algo td3 --res coarse --seeds 0,1,2"),
        "{}",
        text(&o)
    );
    // From an empty folder: the protocol's relative source paths name nothing there (in the
    // repository they name the committed Re 1000 runs, and the protocol would start training).
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["transfer", "re1000", "re3900", "--out", "."])
        .current_dir(tmp.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Its sources are another protocol's from-scratch arm: that protocol is the command.
    assert!(
        text(&o).contains("hgym transfer Cylinder_2D_Re200 Cylinder_2D_Re1000"),
        "{}",
        text(&o)
    );
    let o = hgym(&[
        "train",
        "--env",
        "Cylinder_2D_Re100",
        "--init-from",
        tmp.path().to_str().unwrap(),
        "--steps",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("holds no finished training run"), "{}", text(&o));
}

/// A zero-shot deployment protocol end to end on a tiny wing: the committed minimal-channel MARL
/// run (its shared actor sees 3 x 3 patches of u', v' and sets one, as the wing's agents do)
/// beside the uncontrolled flow, opposition control and net blowing; a second call reruns nothing.
#[test]
fn a_deployment_protocol_runs_every_arm_and_compares_them() {
    let tmp = tempfile::tempdir().unwrap();
    // The source run, copied so that the test can retrain it (below).
    let source = tmp.path().join("source/seed0");
    std::fs::create_dir_all(&source).unwrap();
    for f in ["policy.json", "manifest.json"] {
        std::fs::copy(
            Path::new("results/train/TCFMini_3D_Retau180-td3-default/seed0").join(f),
            source.join(f),
        )
        .unwrap();
    }
    let pfile = tmp.path().join("wing.toml");
    let protocol = r#"
name = "mini_wing"
description = "test"
source = "TCFMini_3D_Retau180"
target = "WingTBL_3D_Rec200000"
algo = "td3"
level = "coarse"
seeds = [0]
source_spec_hash = "23584c5aa36fc9675cf26cd72b2a2765426e94939f81069586fb297caf193118"
source_runs = "SOURCE/seed{seed}"
fraction = 0.9
[deployment]
episodes = 2
settle_actions = 2
env = { grid = { coarse = [96, 32, 8], default = [96, 32, 8], fine = [96, 32, 8] }, patch_cells = { coarse = [6, 2], default = [6, 2], fine = [6, 2] }, spin_up = 0.002, stretch = 3.2, episode_actions = 5 }
baselines = [
    { name = "opposition", policy = "wall-opposition" },
    { name = "blowing", policy = "constant=0.5", env = { zero_net_flux = false } },
]
"#;
    let protocol = protocol.replace("SOURCE", tmp.path().join("source").to_str().unwrap());
    std::fs::write(&pfile, &protocol).unwrap();
    let args = [
        "transfer",
        "--protocol",
        pfile.to_str().unwrap(),
        "--out",
        tmp.path().to_str().unwrap(),
    ];
    let o = hgym(&args);
    assert!(o.status.success(), "{}", text(&o));
    let root = tmp.path().join("mini_wing");
    let cmp = json(&root.join("comparison.json"));
    assert_eq!(cmp["schema"], "hgym/transfer-deployment/v1");
    let arms: Vec<&str> = cmp["arms"].as_array().unwrap().iter().map(|a| a["arm"].as_str().unwrap()).collect();
    assert_eq!(arms, ["uncontrolled", "opposition", "blowing", "zeroshot"]);
    assert_eq!(cmp["arms"][0]["local_friction_reduction_pct"]["mean"], 0.0);
    for dir in ["uncontrolled", "zeroshot/seed0", "opposition", "blowing"] {
        let rec = json(&root.join(dir).join("deployment.json"));
        assert_eq!(rec["episodes"].as_array().unwrap().len(), 2, "{dir}");
        assert!(rec["cpu_s_per_episode"].as_f64().unwrap() > 0.0, "{dir}");
        assert!(root.join(dir).join("tau_w.png").exists() && root.join(dir).join("metrics.json").exists());
    }
    // Net blowing thickens the layer: less friction under it than without.
    let blowing = json(&root.join("blowing/deployment.json"));
    assert!(blowing["local_friction_reduction_pct"]["mean"].as_f64().unwrap() > 0.0, "{blowing}");
    assert!(cmp["cost"]["target_core_hours_per_episode"].as_f64().unwrap() > 0.0);
    assert!(root.join("friction.png").exists() && root.join("reductions.png").exists());
    let o = hgym(&args);
    assert!(o.status.success() && text(&o).matches("done already").count() == 4, "{}", text(&o));
    // Another blowing amplitude does not reuse the old arm: refused, naming what differs.
    std::fs::write(&pfile, protocol.replace("constant=0.5", "constant=0.25")).unwrap();
    let o = hgym(&args);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("policy constant=0.5") && text(&o).contains("move it away"),
        "{}",
        text(&o)
    );
    // A source retrained in the same folder is not taken for the one deployed.
    std::fs::write(&pfile, &protocol).unwrap();
    let policy = source.join("policy.json");
    let retrained = std::fs::read_to_string(&policy).unwrap() + "\n";
    std::fs::write(&policy, retrained).unwrap();
    let o = hgym(&args);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("the source was retrained"), "{}", text(&o));
}
