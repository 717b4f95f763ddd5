//! `hgym train` / `hgym eval` on a real flow (Cylinder_2D_Re100 at the coarse level, a few
//! rounds with small networks): result folder, Ctrl-C leaves a checkpoint, `--resume` reaches the
//! uninterrupted result bitwise, baselines evaluate, size mismatches are refused clearly; the
//! final evaluation's trajectory opens in the Python `mcap` reader.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn hgym(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hgym")).args(args).output().expect("run hgym")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Small networks, early learning, one evaluation episode: ~2 s per round of 2 x 200 actions.
const CONFIG: &str = "[train]\neval_every = 2\neval_episodes = 1\nfinal_eval_episodes = 1\ncheckpoint_seconds = 1000.0\n\
                      [td3]\nhidden = [32, 32]\nbatch_size = 32\nlearning_starts = 200\n";

fn config(dir: &Path) -> PathBuf {
    let p = dir.join("small.toml");
    std::fs::write(&p, CONFIG).unwrap();
    p
}

/// `hgym train` of TD3 on the cylinder for 1600 samples (4 rounds) with the config `cfg`.
/// One worker thread, not the machine's default, so a resume must find the count in the checkpoint.
fn td3_args<'a>(cfg: &'a Path, out: &'a Path) -> [&'a str; 13] {
    let (cfg, out) = (cfg.to_str().unwrap(), out.to_str().unwrap());
    [
        "train",
        "--env",
        "Cylinder_2D_Re100",
        "--algo",
        "td3",
        "--steps",
        "1600",
        "--config",
        cfg,
        "--out",
        out,
        "--threads",
        "1",
    ]
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn train_writes_a_result_folder_and_resume_after_ctrl_c_is_bitwise_identical() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = config(tmp.path());
    // Uninterrupted: 4 rounds (1600 samples).
    let full = tmp.path().join("full");
    let o = hgym(&td3_args(&cfg, &full));
    assert!(o.status.success(), "{}", text(&o));
    let run = full.join("Cylinder_2D_Re100-td3-coarse/seed0");
    for f in [
        "manifest.json",
        "metrics.json",
        "policy.json",
        "curve.csv",
        "curve.png",
        "drag_reduction.png",
        "vorticity.png",
        "checkpoint.bin",
    ] {
        assert!(run.join(f).exists(), "missing {f}");
    }
    let curve = read(&run.join("curve.csv"));
    assert_eq!(curve.lines().count(), 5, "{curve}");
    let metrics: serde_json::Value = serde_json::from_str(&read(&run.join("metrics.json"))).unwrap();
    assert!(metrics["drag_reduction_pct"]["mean"].as_f64().unwrap().is_finite());
    let manifest: serde_json::Value = serde_json::from_str(&read(&run.join("manifest.json"))).unwrap();
    assert_eq!(manifest["samples"], 1600);
    assert_eq!(manifest["algo"], "td3");
    // The final evaluation (one episode of 200 actions) as a trajectory people can open.
    let s = common::read_mcap(&run.join("trajectory.mcap")).unwrap();
    assert_eq!(s["counts"]["/reward"], 200, "{s}");
    assert_eq!(s["counts"]["/obs"], 201, "reset observation + 200: {s}");
    assert_eq!(s["episodes"], serde_json::json!([0]));
    assert_eq!(s["env_id"], "Cylinder_2D_Re100");

    // The same command again keeps the finished run (no retraining, nothing rewritten); with
    // another budget it refuses to overwrite the run, naming what differs.
    let before = read(&run.join("metrics.json"));
    let o = hgym(&td3_args(&cfg, &full));
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("finished already"), "{}", text(&o));
    assert_eq!(read(&run.join("metrics.json")), before);
    // A run recorded before a configuration field existed (the field at its default) is the
    // same set-up, kept too.
    let manifest_path = run.join("manifest.json");
    let recorded = read(&manifest_path);
    let mut older: serde_json::Value = serde_json::from_str(&recorded).unwrap();
    let toml = older["config_toml"].as_str().unwrap().replace("fields_every = 0\n", "");
    assert_ne!(Some(toml.as_str()), older["config_toml"].as_str());
    older["config_toml"] = toml.into();
    std::fs::write(&manifest_path, older.to_string()).unwrap();
    let o = hgym(&td3_args(&cfg, &full));
    assert!(text(&o).contains("finished already"), "{}", text(&o));
    // A recorded configuration that no longer parses is named as such, with the manifest.
    older["config_toml"] = "[train]\nno_such_field = 1\n".into();
    std::fs::write(&manifest_path, older.to_string()).unwrap();
    let o = hgym(&td3_args(&cfg, &full));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("no longer parses"), "{}", text(&o));
    assert!(text(&o).contains("manifest.json"), "{}", text(&o));
    std::fs::write(&manifest_path, recorded).unwrap();
    let mut other = td3_args(&cfg, &full);
    other[6] = "2000";
    let o = hgym(&other);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("config_toml differ"), "{}", text(&o));
    assert_eq!(read(&run.join("metrics.json")), before);

    // Interrupted with SIGINT (Ctrl-C) during the run, then resumed.
    let cut = tmp.path().join("cut");
    let mut child = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(td3_args(&cfg, &cut))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(3500));
    let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let t0 = Instant::now();
    let status = child.wait().unwrap();
    let cut_run = cut.join("Cylinder_2D_Re100-td3-coarse/seed0");
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    if status.code() == Some(130) {
        assert!(err.contains("--resume"), "the interrupt message names the way back: {err}");
        assert!(cut_run.join("checkpoint.bin").exists());
        assert!(!cut_run.join("policy.json").exists(), "an interrupted run has no final policy");
        println!("interrupted after {:.1} s, stopped {:.1} s later", 3.5, t0.elapsed().as_secs_f64());
        let o = hgym(&["train", "--resume", cut_run.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
    } else {
        // The machine was fast enough to finish before the signal: still a complete result.
        assert!(status.success(), "{err}");
    }
    assert_eq!(
        read(&cut_run.join("policy.json")),
        read(&run.join("policy.json")),
        "resumed policy differs"
    );
    assert_eq!(
        read(&cut_run.join("metrics.json")),
        read(&run.join("metrics.json")),
        "resumed metrics differ"
    );
    assert_eq!(read(&cut_run.join("curve.csv")).lines().count(), 5);
    let resumed: serde_json::Value = serde_json::from_str(&read(&cut_run.join("manifest.json"))).unwrap();
    assert_eq!(resumed["manifest"]["threads"], 1, "a resume keeps the run's thread count");

    // The trained policy evaluates through `hgym eval`, and is refused on a flow of another shape.
    let o = hgym(&[
        "eval",
        "--policy",
        run.to_str().unwrap(),
        "--env",
        "Cylinder_2D_Re100",
        "--episodes",
        "1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        r["mean_c_d"]["mean"], metrics["mean_c_d"]["mean"],
        "eval reproduces train's final evaluation"
    );
    let o = hgym(&[
        "eval",
        "--policy",
        run.to_str().unwrap(),
        "--env",
        "Pinball_2D_Re30",
        "--episodes",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let t = text(&o);
    // The layouts differ (probe positions, actuators): both are named.
    assert!(
        t.contains("actuators jet_pair") && t.contains("actuators rotation0, rotation1, rotation2"),
        "{t}"
    );
}

#[test]
fn baselines_evaluate_against_the_uncontrolled_flow() {
    let tmp = tempfile::tempdir().unwrap();
    // One episode of `policy` on the cylinder, with `extra` arguments.
    let eval = |policy: &str, extra: &[&str]| {
        hgym(
            &[
                &["eval", "--policy", policy, "--env", "Cylinder_2D_Re100", "--episodes", "1"],
                extra,
            ]
            .concat(),
        )
    };
    let o = eval("zero", &["--json", "--out", tmp.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        r["drag_reduction_pct"]["mean"].as_f64(),
        Some(0.0),
        "zero control is the reference itself"
    );
    // Beside the numbers, the flow the policy leaves, as images.
    let dir = tmp.path().join("Cylinder_2D_Re100-zero-coarse");
    for name in ["metrics.json", "trajectory.mcap", "vorticity.png", "u.png"] {
        assert!(dir.join(name).is_file(), "{name} missing in {}", dir.display());
    }
    let png = std::fs::read(dir.join("vorticity.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"), "vorticity.png is not a PNG");
    assert_eq!(r["actuation_cost"]["mean"].as_f64(), Some(0.0));
    // The manifest records an [env] override, so the leaderboard can tell its spec from the
    // registered one (and give the command with it); without one there is nothing to record.
    let manifest = |d: &Path| -> serde_json::Value { serde_json::from_str(&read(&d.join("manifest.json"))).unwrap() };
    assert!(manifest(&dir).get("config_toml").is_none());
    let cfg = tmp.path().join("short.toml");
    std::fs::write(&cfg, "[env]\nepisode_actions = 20\n").unwrap();
    let out = tmp.path().join("short");
    let o = eval("zero", &["--config", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let m = manifest(&out.join("Cylinder_2D_Re100-zero-coarse"));
    assert!(m["config_toml"].as_str().unwrap().contains("episode_actions = 20"), "{m}");
    assert_eq!(m["spec"]["episode_actions"], 20);
    let o = eval("opposition=2", &["--json"]);
    assert!(o.status.success(), "{}", text(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(r["actuation_cost"]["mean"].as_f64().unwrap() > 0.0);
    assert!(r.get("lift_deviation").is_none(), "the cylinder's reward has no reference lift");
}

/// On a gust flow an evaluation says how far the lift strays from the undisturbed flow's mean,
/// mean |C_L - C_L,ref| (info dC_L), under the policy and uncontrolled from the same states; a
/// proportional controller on dC_L changes it, zero control is the reference itself.
#[test]
fn gust_evaluations_report_the_lift_deviation_against_the_uncontrolled_gust() {
    let tmp = tempfile::tempdir().unwrap();
    // 100 actions = 10 c/U: the gust reaches the leading edge after about 8.5.
    let cfg = tmp.path().join("short.toml");
    std::fs::write(&cfg, "[env]\nepisode_actions = 100\n").unwrap();
    let eval = |policy: &str| -> serde_json::Value {
        let o = hgym(&[
            "eval",
            "--policy",
            policy,
            "--env",
            "NACA0012Gust_2D_Re1000_AoA20",
            "--episodes",
            "1",
            "--config",
            cfg.to_str().unwrap(),
            "--json",
        ]);
        assert!(o.status.success(), "{}", text(&o));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let zero = eval("zero");
    let l = &zero["lift_deviation"];
    let d0 = l["uncontrolled_abs_dc_l"]["mean"].as_f64().unwrap();
    assert!(d0 > 0.05, "the gust moves the lift: {l}");
    assert_eq!(l["mean_abs_dc_l"]["mean"].as_f64(), Some(d0));
    assert_eq!(l["reduction_pct"]["mean"].as_f64(), Some(0.0));
    let pd = eval("pd=dC_L,-0.6,0");
    let l = &pd["lift_deviation"];
    let (d, pct) = (
        l["mean_abs_dc_l"]["mean"].as_f64().unwrap(),
        l["reduction_pct"]["mean"].as_f64().unwrap(),
    );
    assert_eq!(
        l["uncontrolled_abs_dc_l"]["mean"].as_f64(),
        Some(d0),
        "the same uncontrolled episode"
    );
    assert!(d != d0 && (pct - 100.0 * (1.0 - d / d0)).abs() < 1e-9, "{l}");
    assert_eq!(pd["episodes"][0]["lift_deviation"]["reduction_pct"].as_f64(), Some(pct));
}

/// Hostile overrides and arguments (issue 36): each is refused at once with exit 2, naming the
/// field or flag; none runs, hangs, wraps or allocates.
#[test]
fn hostile_overrides_and_arguments_exit_2_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("runs");
    let cfg = tmp.path().join("c.toml");
    let overrides: &[(&str, &str, &str)] = &[
        ("Cylinder_2D_Re100", "control_interval = 1e300", "control_interval"),
        ("Cylinder_2D_Re100", "control_interval = 0.0", "control_interval"),
        ("Cylinder_2D_Re100", "control_interval = -1.0", "control_interval"),
        ("Cylinder_2D_Re100", "control_interval = nan", "control_interval"),
        ("Cylinder_2D_Re100", "episode_actions = 0", "episode_actions"),
        ("Cylinder_2D_Re100", "probes = []", "probes"),
        ("Cylinder_2D_Re100", "probes = [[1.0, 2.0, 3.0]]", "two numbers"),
        ("Cylinder_2D_Re100", "spin_up = -5.0", "spin_up"),
        ("Kolmogorov_2D_Re40", "control_interval = nan", "control_interval"),
        ("Kolmogorov_2D_Re40", "probes_per_side = 7", "probes_per_side"),
        ("Kolmogorov_2D_Re40", "control_wavenumbers = [0]", "control_wavenumbers"),
        (
            "NACA0012_2D_Re100_AoA20",
            "[[env.bodies]]\nshape = \"naca\"\ndigits = \"0012\"\nchord = 1.0\nleading_edge = [6.5, 0.0]\naoa_deg = nan",
            "aoa_deg",
        ),
        (
            "NACA0012_2D_Re100_AoA20",
            "[[env.bodies]]\nshape = \"naca\"\ndigits = \"0000\"\nchord = 1.0\nleading_edge = [6.5, 0.0]\naoa_deg = 20.0",
            "thickness",
        ),
    ];
    for (id, line, words) in overrides {
        std::fs::write(&cfg, format!("[env]\n{line}\n")).unwrap();
        let t0 = std::time::Instant::now();
        let o = hgym(&[
            "train",
            "--env",
            id,
            "--config",
            cfg.to_str().unwrap(),
            "--steps",
            "10",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{id} {line}: {}", text(&o));
        assert!(text(&o).contains(words), "{id} {line}: {}", text(&o));
        assert!(t0.elapsed().as_secs() < 10, "{id} {line}: refused before running");
    }
    assert!(!out.exists(), "no run folder for a refused override");
    let missing = tmp.path().join("missing.toml");
    let args: &[(&[&str], &str)] = &[
        (
            &["train", "--env", "Cylinder_2D_Re100", "--seeds", "0..18446744073709551615"],
            "--seeds",
        ),
        (&["train", "--env", "Cylinder_2D_Re100", "--seeds", "0..1000000000"], "--seeds"),
        (
            &["train", "--env", "Cylinder_2D_Re100", "--seeds", "5..=18446744073709551615"],
            "--seeds",
        ),
        (&["train", "--env", "Cylinder_2D_Re100", "--steps", "0"], "--steps"),
        (
            &["train", "--env", "Cylinder_2D_Re100", "--config", missing.to_str().unwrap()],
            "missing.toml",
        ),
        (
            &[
                "eval",
                "--policy",
                "zero",
                "--env",
                "Cylinder_2D_Re100",
                "--eval-seed",
                "18446744073709551615",
            ],
            "--eval-seed",
        ),
        (
            &["eval", "--policy", "zero", "--env", "Cylinder_2D_Re100", "--episodes", "0"],
            "--episodes",
        ),
        (
            &["eval", "--policy", "zero", "--env", "Cylinder_2D_Re100", "--episodes", "100001"],
            "--episodes",
        ),
    ];
    for (a, words) in args {
        let o = hgym(a);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {}", text(&o));
        assert!(text(&o).contains(words), "{a:?}: {}", text(&o));
    }
    std::fs::write(&cfg, "[train]\nsteps = 0\n").unwrap();
    let o = hgym(&["train", "--env", "Cylinder_2D_Re100", "--config", cfg.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("steps must be at least 1"), "{}", text(&o));
}

/// Hostile policies and baselines (issue 36): a policy file with empty sizes, short or extra
/// parameters, a zero width, NaN weights or an `obs_norm` of the wrong length, and baselines
/// with infinite, NaN or out-of-range numbers or signals the flow does not have: exit 2 at once,
/// naming the problem, never a panic and never a silent zero.
#[test]
fn hostile_policies_and_baselines_exit_2_naming_the_problem() {
    let tmp = tempfile::tempdir().unwrap();
    let good = common::repo().join("results/train/Cylinder_2D_Re100-ppo-coarse/seed1/policy.json");
    let base: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(good).unwrap()).unwrap();
    type Edit = Box<dyn Fn(&mut serde_json::Value)>;
    let edits: Vec<(&str, Edit, &str)> = vec![
        (
            "empty_sizes",
            Box::new(|p| p["net"]["sizes"] = serde_json::json!([])),
            "input and an output size",
        ),
        ("zero_width", Box::new(|p| p["net"]["sizes"][1] = 0.into()), "a width of 0"),
        (
            "short_params",
            Box::new(|p| {
                p["net"]["params"].as_array_mut().unwrap().pop();
            }),
            "parameters",
        ),
        (
            "extra_params",
            Box::new(|p| p["net"]["params"].as_array_mut().unwrap().push(0.5.into())),
            "parameters",
        ),
        (
            "short_obs_norm",
            Box::new(|p| {
                p["obs_norm"]["mean"].as_array_mut().unwrap().pop();
            }),
            "obs_norm",
        ),
        (
            "huge_width",
            Box::new(|p| p["net"]["sizes"][1] = 4_000_000_000_000u64.into()),
            "a width of",
        ),
    ];
    for (name, edit, words) in &edits {
        let mut p = base.clone();
        edit(&mut p);
        let file = tmp.path().join(format!("{name}.json"));
        std::fs::write(&file, p.to_string()).unwrap();
        let o = hgym(&[
            "eval",
            "--policy",
            file.to_str().unwrap(),
            "--env",
            "Cylinder_2D_Re100",
            "--episodes",
            "1",
        ]);
        assert_eq!(o.status.code(), Some(2), "{name}: {}", text(&o));
        assert!(text(&o).contains(words) && !text(&o).contains("panicked"), "{name}: {}", text(&o));
    }
    for (policy, words) in [
        ("constant=inf", "not a finite number"),
        ("constant=1e308", "outside the normalised action range"),
        ("constant=nan", "not a finite number"),
        ("constant=0,2", "2 is outside the normalised action range"),
        ("constant=0.5,-0.5", "2 constant values for 1 actuators"),
        ("sine=nan", "not a finite number"),
        ("sine=0", "must be positive"),
        ("pd=obs:999,1,0", "obs:999 does not exist"),
        ("pd=NOPE,1,0", "'NOPE' is not in the environment's info"),
    ] {
        let t0 = std::time::Instant::now();
        let o = hgym(&["eval", "--policy", policy, "--env", "Cylinder_2D_Re100", "--episodes", "1"]);
        assert_eq!(o.status.code(), Some(2), "{policy}: {}", text(&o));
        assert!(text(&o).contains(words), "{policy}: {}", text(&o));
        assert!(t0.elapsed().as_secs() < 60, "{policy}: refused before the reference episode");
    }
}

/// Killed with SIGKILL (no chance to save) after its first round, a run still resumes: the
/// first checkpoint comes after the first round, not after `checkpoint_seconds`; and every resume
/// is counted, even one killed at once.
#[test]
fn a_run_killed_after_its_first_round_resumes_and_counts_every_resume() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = config(tmp.path());
    let out = tmp.path().join("runs");
    let run = out.join("Cylinder_2D_Re100-td3-coarse/seed0");
    let ck = run.join("checkpoint.bin");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    // Spawns `args`, waits until the checkpoint is (re)written, and kills the process with -9.
    let kill_after_checkpoint = |args: &[&str]| {
        let before = modified(&ck);
        let mut child = Command::new(env!("CARGO_BIN_EXE_hgym"))
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        while modified(&ck) == before || modified(&ck).is_none() {
            assert!(
                t0.elapsed().as_secs() < 120,
                "no checkpoint within 120 s (checkpoint_seconds is 1000)"
            );
            assert!(child.try_wait().unwrap().is_none(), "the run ended before it was killed");
            std::thread::sleep(Duration::from_millis(20));
        }
        child.kill().unwrap();
        child.wait().unwrap();
    };
    kill_after_checkpoint(&td3_args(&cfg, &out));
    kill_after_checkpoint(&["train", "--resume", run.to_str().unwrap()]);
    let o = hgym(&["train", "--resume", run.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let manifest: serde_json::Value = serde_json::from_str(&read(&run.join("manifest.json"))).unwrap();
    assert_eq!(manifest["resumed"], 2, "two resumes, both counted: {manifest}");
    assert_eq!(manifest["samples"], 1600);
}

#[test]
fn bad_training_input_is_named() {
    let o = hgym(&["train", "--env", "Cylindre_2D_Re100", "--steps", "10"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("Cylinder_2D_Re100"), "{}", text(&o));
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("bad.toml");
    std::fs::write(&p, "[td3]\nbatchsize = 3\n").unwrap();
    let o = hgym(&["train", "--env", "Cylinder_2D_Re100", "--config", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("batchsize"), "{}", text(&o));
    // An override that parses but cannot run is bad input too (exit 2), named.
    std::fs::write(&p, "[env]\nreynolds = -5.0\n[train]\nsteps = 10\n").unwrap();
    let out = tmp.path().join("runs");
    let o = hgym(&[
        "train",
        "--env",
        "Cylinder_2D_Re100",
        "--config",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("reynolds"), "{}", text(&o));
    let o = hgym(&["train", "--env", "Cylinder_2D_Re100", "--seeds", "3..1"]);
    assert_eq!(o.status.code(), Some(2));
    let o = hgym(&["eval", "--policy", "bogus", "--env", "Cylinder_2D_Re100"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("opposition"), "{}", text(&o));
    let o = hgym(&["train", "--resume", tmp.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("checkpoint"), "{}", text(&o));
    let o = hgym(&["train", "--print-config"]);
    assert!(o.status.success());
    assert!(text(&o).contains("[td3]") && text(&o).contains("policy_delay"));
}

#[test]
fn plot_draws_several_committed_runs_and_names_bad_folders() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("c.png");
    let repo = common::repo();
    let a = repo.join("results/train/Cylinder_2D_Re100-td3-coarse/seed0");
    let b = repo.join("results/train/Cylinder_2D_Re100-ppo-coarse/seed0");
    let o = hgym(&[
        "plot",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--drag",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(std::fs::metadata(&out).unwrap().len() > 10_000);
    let o = hgym(&["plot", tmp.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("curve.csv"), "{}", text(&o));
}
