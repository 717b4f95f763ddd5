//! Trajectory files open in the tool people use: every check reads them with the Python `mcap`
//! reader (installed by `make setup` into ~/.cache/hgym-venv, or `$HGYM_PYTHON`). Ctrl-C leaves a
//! valid file; `hgym data recover` salvages a truncated one.

mod common;

use std::process::{Command, Output, Stdio};
use std::time::Duration;

use common::read_mcap;

fn hgym(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hgym")).args(args).output().expect("run hgym")
}

#[test]
fn eval_trajectories_read_back_with_python_and_recover_after_truncation() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().to_str().unwrap();
    let o = hgym(&[
        "eval",
        "--policy",
        "random",
        "--env",
        "Cylinder_2D_Re100",
        "--episodes",
        "3",
        "--out",
        out,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = tmp.path().join("Cylinder_2D_Re100-random-coarse/trajectory.mcap");
    let s = read_mcap(&file).unwrap();
    assert_eq!(s["counts"]["/reward"], 600, "{s}");
    assert_eq!(s["counts"]["/obs"], 603, "reset observation + 200 per episode: {s}");
    assert_eq!(s["episodes"], serde_json::json!([0, 1, 2]));
    assert_eq!(s["env_id"], "Cylinder_2D_Re100");
    assert_eq!(s["encodings"]["/obs"], serde_json::json!(["jsonschema", "json"]));
    for k in ["spec", "spec_hash", "code_version", "seeds", "policy"] {
        assert!(
            s["manifest_keys"].as_array().unwrap().iter().any(|v| v == k),
            "manifest lacks {k}: {s}"
        );
    }

    // A kill mid-write: keep 60 % of the bytes. Readers fail on it; recover keeps every complete
    // chunk.
    let bytes = std::fs::read(&file).unwrap();
    let cut = tmp.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    assert!(read_mcap(&cut).map(|s| s["counts"]["/reward"] != 600).unwrap_or(true));
    let fixed = tmp.path().join("fixed.mcap");
    let o = hgym(&["data", "recover", cut.to_str().unwrap(), "--out", fixed.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(text.contains("lost"), "recover says what was lost: {text}");
    let r = read_mcap(&fixed).unwrap();
    let steps = r["counts"]["/reward"].as_u64().unwrap();
    assert!((200..600).contains(&steps), "whole episodes before the cut survive: {r}");
    // Every episode finished before the cut is whole (a chunk closes at each episode's end);
    // full chunks of the episode in progress survive too.
    assert_eq!(r["steps_per_episode"]["0"], 200, "{r}");
    assert_eq!(r["env_id"], "Cylinder_2D_Re100", "the manifest survives: {r}");
    // The report is truthful: a complete file loses nothing; a file one byte short, or only its
    // magic bytes, is not complete, and --json's byte counts say how much was whole.
    let recover_json = |f: &std::path::Path| -> serde_json::Value {
        let o = hgym(&[
            "data",
            "recover",
            f.to_str().unwrap(),
            "--out",
            tmp.path().join("r.mcap").to_str().unwrap(),
            "--json",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let whole = recover_json(&file);
    assert_eq!(whole["complete"], true, "{whole}");
    assert_eq!(whole["bytes_read"], whole["bytes_total"], "{whole}");
    assert_eq!(
        whole["messages"].as_u64(),
        Some(603 + 600 + 600 + 603),
        "obs, action, reward, info: {whole}"
    );
    let short = tmp.path().join("short.mcap");
    std::fs::write(&short, &bytes[..bytes.len() - 1]).unwrap();
    let r = recover_json(&short);
    assert_eq!(r["complete"], false, "one byte short is not complete: {r}");
    let magic = tmp.path().join("magic.mcap");
    std::fs::write(&magic, &bytes[..8]).unwrap();
    let r = recover_json(&magic);
    assert_eq!((r["complete"].clone(), r["messages"].clone()), (false.into(), 0.into()), "{r}");
    let r = recover_json(&cut);
    assert_eq!(r["complete"], false, "{r}");
    assert!(r["bytes_read"].as_u64() < r["bytes_total"].as_u64(), "{r}");
    // Not an MCAP file: a clear error, exit 2.
    let junk = tmp.path().join("junk.mcap");
    std::fs::write(&junk, b"hello").unwrap();
    let o = hgym(&["data", "recover", junk.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not an MCAP file"));
}

#[test]
fn ctrl_c_during_a_run_leaves_a_valid_trajectory() {
    let tmp = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args([
            "run",
            "--env",
            "Cylinder_2D_Re100",
            "--res",
            "coarse",
            "--steps",
            "2000",
            "--out",
            tmp.path().to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(2500));
    let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "interrupted runs exit 130");
    let file = tmp.path().join("Cylinder_2D_Re100-zero-seed0/trajectory.mcap");
    let s = read_mcap(&file).unwrap_or_else(|e| panic!("the interrupted file must be valid: {e}"));
    let steps = s["counts"]["/reward"].as_u64().unwrap();
    assert!(steps > 0 && steps < 2000, "{s}");
    assert!(tmp.path().join("Cylinder_2D_Re100-zero-seed0/metrics.json").exists());
}
