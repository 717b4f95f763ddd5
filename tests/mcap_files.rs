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

/// Found by `tests/fuzz.rs`: a record inside a zstd chunk whose length field claims 2^56 bytes
/// made the `mcap` crate's message stream reserve it whole and abort the process. Reading and
/// recovering such a file is an error, never an abort.
#[test]
fn a_huge_record_length_inside_a_chunk_is_an_error_not_an_abort() {
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .create(std::io::Cursor::new(Vec::new()))
        .unwrap();
    let meta = [("env_id".to_string(), "Cylinder_2D_Re100".to_string())].into_iter().collect();
    w.write_metadata(&mcap::records::Metadata {
        name: "manifest".into(),
        metadata: meta,
    })
    .unwrap();
    let ch = w.add_channel(0, "/obs", "json", &Default::default()).unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: ch,
        sequence: 0,
        log_time: 0,
        publish_time: 0,
    };
    w.write_to_known_channel(&header, br#"{"episode":0,"step":0,"obs":[1.0]}"#).unwrap();
    w.finish().unwrap();
    let plain = w.into_inner().into_inner();
    // The chunk (opcode 0x06): times (16), uncompressed size (8), CRC (4), the length of its
    // compression's name (4; "" here), records length (8), records. Its message record's length is damaged, then the records are
    // compressed with zstd into a new chunk that replaces it.
    let at = |i: usize| u64::from_le_bytes(plain[i..i + 8].try_into().unwrap()) as usize;
    let chunk = (8..plain.len() - 49)
        .find(|&i| plain[i] == 0x06 && at(i + 9 + 32) == at(i + 9 + 16) && at(i + 9 + 16) > 0)
        .unwrap();
    let (len, records_at) = (at(chunk + 1), chunk + 9 + 40);
    let mut records = plain[records_at..chunk + 9 + len].to_vec();
    let message = records.iter().position(|&b| b == 0x05).unwrap();
    records[message + 1..message + 9].copy_from_slice(&(1u64 << 56).to_le_bytes());
    let packed = zstd::encode_all(&records[..], 3).unwrap();
    let mut content = plain[chunk + 9..chunk + 9 + 16].to_vec();
    content.extend((records.len() as u64).to_le_bytes());
    content.extend(0u32.to_le_bytes());
    content.extend(4u32.to_le_bytes());
    content.extend(b"zstd");
    content.extend((packed.len() as u64).to_le_bytes());
    content.extend(&packed);
    let mut bytes = plain[..chunk].to_vec();
    bytes.push(0x06);
    bytes.extend((content.len() as u64).to_le_bytes());
    bytes.extend(content);
    bytes.extend(&plain[chunk + 9 + len..]);
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("trajectory.mcap");
    std::fs::write(&file, &bytes).unwrap();
    assert!(hgym::data::read::read(&file).is_err());
    let r = hgym::data::trajectory::recover(&file, &tmp.path().join("fixed.mcap")).unwrap();
    assert!(!r.complete && r.messages == 0, "{r:?}");
}
