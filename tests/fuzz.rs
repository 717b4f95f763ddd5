//! Fuzzing the readers of hostile input with proptest: the case-file reader (and the plan of
//! every level), the train config reader (and the `[env]` overrides it applies), the policy
//! loader (and one action of a policy it accepts), and the MCAP reader and `recover`. Each target
//! mutates a corpus of the repository's own files (bundled cases, the default config, committed
//! policies, a trajectory written here) and asserts that no input panics: every one is either
//! accepted or refused with an error. The fifth target, the Hub's replies, lives beside the
//! Hub stand-in in `tests/hub_push.rs`.
//!
//! Why proptest, not `cargo fuzz`: cargo-fuzz needs a nightly toolchain and libFuzzer, and this
//! project builds with the one stable toolchain its machines have; proptest runs inside `cargo
//! test` and shrinks a failure to a small input, which becomes a regression test beside the
//! reader's other tests (the MCAP chunk abort: `tests/mcap_files.rs`). `make test` runs 64 inputs per target (`PROPTEST_CASES` unset); `make
//! nightly` runs 10^4 (`PROPTEST_CASES=10000`).

mod common;
#[path = "common/mutate.rs"]
mod mutate;

use std::path::PathBuf;

use mutate::{apply, cases, edits};
use proptest::prelude::*;

fn files(dir: &str, ext: &str) -> Vec<Vec<u8>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(common::repo().join(dir))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == ext))
        .collect();
    paths.sort();
    paths.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    /// Case files: parse and check, then plan every level (where sizes and step counts could
    /// wrap or allocate).
    #[test]
    fn case_reader_never_panics(pick in any::<usize>(), e in edits()) {
        let corpus = files("benchmarks/validation", "toml");
        let text = apply(&corpus[pick % corpus.len()], &e, &[]);
        if let Ok(c) = hgym::validate::LoadedCase::parse(&String::from_utf8_lossy(&text), "fuzz.toml") {
            for level in [hgym::flow::Level::Coarse, hgym::flow::Level::Default, hgym::flow::Level::Fine] {
                let _ = hgym::validate::run::Plan::new(&c, level);
            }
        }
    }

    /// Train configs with `[env]` overrides, applied to a lattice-Boltzmann and a spectral flow.
    #[test]
    fn config_reader_never_panics(id in prop::sample::select(vec!["Cylinder_2D_Re100", "Pinball_2D_Re100", "Kolmogorov_2D_Re40"]), e in edits()) {
        let spec = hgym::env::lookup(id).unwrap();
        let base = format!("{}[env]\n{}", hgym::train::config::TrainConfig::default().to_toml(), env_table(&spec.to_toml()));
        let text = apply(base.as_bytes(), &e, &[]);
        if let Ok(c) = hgym::train::config::TrainConfig::parse(&String::from_utf8_lossy(&text), "fuzz.toml") {
            if let Ok(s) = hgym::train::resolve_spec(id, &c) {
                let _ = (s.obs_dim(), s.act_dim(), s.hash());
            }
        }
    }

    /// Policy files (a PPO and a TD3 actor of the cylinder, a GPPO actor of the Kolmogorov
    /// flow): a policy that is accepted must act without a panic.
    #[test]
    fn policy_loader_never_panics(pick in any::<usize>(), e in edits()) {
        let corpus = policies();
        let text = apply(&corpus[pick % corpus.len()], &e, &[]);
        if let Ok(mut p) = serde_json::from_slice::<hgym_agents::policy::ActorPolicy>(&text) {
            if p.validate().is_ok() {
                use hgym_agents::policy::Policy;
                let obs = vec![0.1; p.obs_dim()];
                let mut a = vec![0.0; p.act_dim()];
                p.act(&obs, &hgym_agents::Info::default(), &mut a);
            }
        }
    }

    /// Trajectory files: reading and `recover` on damaged MCAP bytes.
    #[test]
    fn mcap_reader_and_recover_never_panic(e in edits()) {
        let dir = tempfile::tempdir().unwrap();
        let bytes = apply(&trajectory(), &e, &[]);
        let input = dir.path().join("in.mcap");
        std::fs::write(&input, &bytes).unwrap();
        let _ = hgym::data::read::read(&input);
        if let Ok(r) = hgym::data::trajectory::recover(&input, &dir.path().join("out.mcap")) {
            prop_assert!(r.bytes_read <= r.bytes_total);
            prop_assert!(!r.complete || r.bytes_read == r.bytes_total);
        }
    }
}

/// The committed policies the policy target mutates, read once.
fn policies() -> &'static [Vec<u8>] {
    static BYTES: std::sync::OnceLock<Vec<Vec<u8>>> = std::sync::OnceLock::new();
    BYTES.get_or_init(|| {
        [
            "results/train/Cylinder_2D_Re100-ppo-coarse/seed1/policy.json",
            "results/train/Cylinder_2D_Re100-td3-coarse/seed0/policy.json",
            "results/compare/kolmogorov_gppo/gppo/seed0/policy.json",
        ]
        .iter()
        .map(|p| std::fs::read(common::repo().join(p)).unwrap())
        .collect()
    })
}

/// `hgym envs show` output's fields as the body of an `[env]` table (the comment line dropped).
fn env_table(toml: &str) -> String {
    toml.lines().filter(|l| !l.starts_with('#')).collect::<Vec<_>>().join("\n") + "\n"
}

/// A small trajectory (two episodes of three steps, a flow-field snapshot at each reset), written once.
fn trajectory() -> Vec<u8> {
    static BYTES: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    BYTES
        .get_or_init(|| {
            use hgym_agents::{Info, StepResult};
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("t.mcap");
            let manifest = [("env_id".to_string(), "Cylinder_2D_Re100".to_string())].into_iter().collect();
            let mut w = hgym::data::trajectory::TrajectoryWriter::create(&path, 0.5, manifest).unwrap();
            let mut info = Info::default();
            info.set("C_D", 1.3);
            for _ in 0..2 {
                w.reset(&[0.1, 0.2], &info).unwrap();
                w.field(hgym::data::field::Snapshot {
                    episode: 0,
                    step: 0,
                    t: 0.0,
                    nx: 3,
                    ny: 2,
                    extent: [0.0, 3.0, 0.0, 2.0],
                    fields: vec![("u".into(), vec![1.0; 6]), ("vorticity".into(), vec![0.5; 6])],
                })
                .unwrap();
                for k in 0..3 {
                    let r = StepResult {
                        obs: vec![0.1 * k as f64, 0.2],
                        reward: -1.0,
                        terminated: false,
                        truncated: k == 2,
                        info: info.clone(),
                    };
                    w.step(&[0.5], &r).unwrap();
                }
                w.end_episode().unwrap();
            }
            w.finish().unwrap();
            std::fs::read(&path).unwrap()
        })
        .clone()
}
