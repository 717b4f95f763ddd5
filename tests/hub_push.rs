//! `hgym push` against a local stand-in for the Hugging Face Hub on 127.0.0.1: it implements the
//! endpoints hgym calls (repo create, preupload, LFS batch + upload + verify, commit), checks
//! the token on every Hub call, and injects 429 / 503 / 500 answers to exercise retries.

use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Arc, Mutex};

use base64::Engine;
use sha2::{Digest, Sha256};

const TOKEN: &str = "hf_test_SECRET_4711";

#[derive(Clone, Debug)]
struct Request {
    method: String,
    path: String,
    auth: Option<String>,
    body: Vec<u8>,
}

#[derive(Default)]
struct Hub {
    requests: Vec<Request>,
    lfs: HashMap<String, Vec<u8>>,
    commits: Vec<String>,
    created: Vec<serde_json::Value>,
    /// Answer every commit with 500 (the retry limit test).
    commit_always_fails: bool,
    put_failed_once: bool,
}

fn respond(s: &mut TcpStream, status: u16, extra: &str, body: &str) {
    let reason = match status {
        200 => "OK",
        401 => "Unauthorized",
        409 => "Conflict",
        429 => "Too Many Requests",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        _ => "Other",
    };
    let _ = write!(
        s,
        "HTTP/1.1 {status} {reason}\r\nContent-Type: application/json\r\nContent-Length: {}\r\nConnection: close\r\n{extra}\r\n{body}",
        body.len()
    );
}

fn read_request(s: &mut TcpStream) -> Option<Request> {
    let mut r = BufReader::new(s);
    let mut line = String::new();
    r.read_line(&mut line).ok()?;
    let mut parts = line.split_whitespace();
    let (method, path) = (parts.next()?.to_string(), parts.next()?.to_string());
    let (mut len, mut auth) = (0usize, None);
    loop {
        let mut h = String::new();
        r.read_line(&mut h).ok()?;
        let h = h.trim_end();
        if h.is_empty() {
            break;
        }
        let (k, v) = h.split_once(':')?;
        match k.to_ascii_lowercase().as_str() {
            "content-length" => len = v.trim().parse().ok()?,
            "authorization" => auth = Some(v.trim().to_string()),
            _ => {}
        }
    }
    let mut body = vec![0; len];
    r.read_exact(&mut body).ok()?;
    Some(Request { method, path, auth, body })
}

fn handle(mut s: TcpStream, hub: &Arc<Mutex<Hub>>, port: u16) {
    let Some(req) = read_request(&mut s) else { return };
    let mut h = hub.lock().unwrap();
    h.requests.push(req.clone());
    let json = |b: &[u8]| serde_json::from_slice::<serde_json::Value>(b).unwrap_or_default();
    let hub_call = req.path.starts_with("/api/") || req.path.contains(".git/");
    if hub_call && req.auth.as_deref() != Some(&format!("Bearer {TOKEN}")) {
        return respond(&mut s, 401, "", r#"{"error":"Invalid credentials in Authorization header"}"#);
    }
    let creates = h.requests.iter().filter(|r| r.path == "/api/repos/create").count();
    match (req.method.as_str(), req.path.as_str()) {
        ("POST", "/api/repos/create") if creates == 1 => respond(&mut s, 429, "Retry-After: 0\r\n", r#"{"error":"slow down"}"#),
        ("POST", "/api/repos/create") => {
            h.created.push(json(&req.body));
            respond(&mut s, 200, "", r#"{"url":"http://hub/datasets/alice/flows"}"#)
        }
        ("POST", "/api/datasets/alice/flows/preupload/main") => {
            let files: Vec<serde_json::Value> = json(&req.body)["files"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| {
                    let p = f["path"].as_str().unwrap();
                    let mode = if p.ends_with(".parquet") { "lfs" } else { "regular" };
                    serde_json::json!({"path": p, "uploadMode": mode, "shouldIgnore": false})
                })
                .collect();
            respond(&mut s, 200, "", &serde_json::json!({ "files": files }).to_string())
        }
        ("POST", "/datasets/alice/flows.git/info/lfs/objects/batch") => {
            let objects: Vec<serde_json::Value> = json(&req.body)["objects"]
                .as_array()
                .unwrap()
                .iter()
                .map(|o| {
                    let oid = o["oid"].as_str().unwrap();
                    serde_json::json!({"oid": oid, "size": o["size"], "actions": {
                        "upload": {"href": format!("http://127.0.0.1:{port}/lfs/upload/{oid}"), "header": {"X-Test": "1"}},
                        "verify": {"href": format!("http://127.0.0.1:{port}/lfs/verify"), "header": {}}}})
                })
                .collect();
            respond(&mut s, 200, "", &serde_json::json!({ "objects": objects }).to_string())
        }
        ("PUT", p) if p.starts_with("/lfs/upload/") => {
            if !h.put_failed_once {
                h.put_failed_once = true;
                return respond(&mut s, 503, "", "busy");
            }
            let oid = p.trim_start_matches("/lfs/upload/").to_string();
            assert_eq!(format!("{:x}", Sha256::digest(&req.body)), oid, "uploaded bytes match their oid");
            h.lfs.insert(oid, req.body.clone());
            respond(&mut s, 200, "", "")
        }
        ("POST", "/lfs/verify") => respond(&mut s, 200, "", "{}"),
        ("POST", "/api/datasets/alice/flows/commit/main") => {
            if h.commit_always_fails {
                return respond(&mut s, 500, "", r#"{"error":"internal"}"#);
            }
            h.commits.push(String::from_utf8(req.body.clone()).unwrap());
            respond(&mut s, 200, "", r#"{"commitOid":"c0ffee","commitUrl":"http://hub/c0ffee"}"#)
        }
        _ => respond(&mut s, 404, "", r#"{"error":"no such endpoint"}"#),
    }
}

/// Starts the stand-in Hub; returns its endpoint and state.
fn serve(commit_always_fails: bool) -> (String, Arc<Mutex<Hub>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let hub = Arc::new(Mutex::new(Hub {
        commit_always_fails,
        ..Hub::default()
    }));
    let h = hub.clone();
    std::thread::spawn(move || {
        for s in listener.incoming().flatten() {
            handle(s, &h, port);
        }
    });
    (format!("http://127.0.0.1:{port}"), hub)
}

fn push(dir: &Path, endpoint: &str, token: Option<&str>, hf_home: &Path, extra: &[&str]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hgym"));
    c.arg("push").arg(dir).args(["--repo", "alice/flows"]).args(extra);
    c.env("HF_ENDPOINT", endpoint).env("HF_HOME", hf_home).env_remove("HF_TOKEN_PATH");
    c.env_remove("HUGGING_FACE_HUB_TOKEN");
    match token {
        Some(t) => c.env("HF_TOKEN", t),
        None => c.env_remove("HF_TOKEN"),
    };
    c.output().unwrap()
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A real dataset folder: one Kolmogorov evaluation episode, exported.
fn dataset(tmp: &Path) -> PathBuf {
    let runs = tmp.join("runs");
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args([
            "eval",
            "--policy",
            "zero",
            "--env",
            "Kolmogorov_2D_Re40",
            "--episodes",
            "1",
            "--out",
        ])
        .arg(&runs)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let ds = tmp.join("ds");
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["export", "--to", "hf"])
        .arg(&runs)
        .arg(&ds)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    ds
}

#[test]
fn push_uploads_through_lfs_and_commits_with_retries_and_auth_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let ds = dataset(tmp.path());
    let hf_home = tmp.path().join("hf_home");
    std::fs::create_dir_all(&hf_home).unwrap();

    // No token anywhere: a clear error before any request.
    let (endpoint, hub) = serve(false);
    let o = push(&ds, &endpoint, None, &hf_home, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("no Hugging Face token"), "{}", text(&o));
    assert!(hub.lock().unwrap().requests.is_empty());

    // The token file the Hugging Face tools write works like HF_TOKEN; a wrong one is refused
    // with what to do, and the token is not echoed.
    std::fs::write(hf_home.join("token"), "hf_wrong_SECRET_0000\n").unwrap();
    let o = push(&ds, &endpoint, None, &hf_home, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("refused the token (401)") && t.contains("HF_TOKEN"), "{t}");
    assert!(!t.contains("SECRET"), "the token never appears in output: {t}");
    assert!(hub.lock().unwrap().commits.is_empty());
    std::fs::remove_file(hf_home.join("token")).unwrap();

    // The real thing: 429 on create and 503 on the first LFS upload are retried.
    let o = push(&ds, &endpoint, Some(TOKEN), &hf_home, &["--private", "--json"]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains(TOKEN), "the token never appears in output");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let h = hub.lock().unwrap();
    assert_eq!(h.created.len(), 1);
    assert_eq!(h.created[0]["type"], "dataset");
    assert_eq!(h.created[0]["name"], "flows");
    assert_eq!(h.created[0]["organization"], "alice");
    assert_eq!(h.created[0]["private"], true);
    assert_eq!(
        h.requests.iter().filter(|r| r.path == "/api/repos/create").count(),
        2,
        "429 retried"
    );
    assert!(h.put_failed_once);
    assert!(
        h.requests.iter().filter(|r| r.method == "PUT").all(|r| r.auth.is_none()),
        "the token goes only to the Hub, not to the storage address"
    );
    assert_eq!(h.commits.len(), 1);
    let lines: Vec<serde_json::Value> = h.commits[0].lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines[0]["key"], "header");
    let mut local: Vec<PathBuf> = vec![];
    let mut stack = vec![ds.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            if e.path().is_dir() {
                stack.push(e.path())
            } else {
                local.push(e.path())
            }
        }
    }
    assert_eq!(lines.len() - 1, local.len(), "every file in one commit");
    assert_eq!(report["files"], local.len());
    let b64 = base64::engine::general_purpose::STANDARD;
    for f in &local {
        let rel = f.strip_prefix(&ds).unwrap().to_string_lossy().replace('\\', "/");
        let bytes = std::fs::read(f).unwrap();
        let line = lines
            .iter()
            .find(|l| l["value"]["path"] == rel.as_str())
            .unwrap_or_else(|| panic!("{rel} committed"));
        if rel.ends_with(".parquet") {
            assert_eq!(line["key"], "lfsFile");
            let oid = format!("{:x}", Sha256::digest(&bytes));
            assert_eq!(line["value"]["oid"], oid.as_str());
            assert_eq!(h.lfs.get(&oid), Some(&bytes), "{rel}: the uploaded bytes are the file");
        } else {
            assert_eq!(line["key"], "file");
            assert_eq!(b64.decode(line["value"]["content"].as_str().unwrap()).unwrap(), bytes, "{rel}");
        }
    }
    assert!(report["lfs_files"].as_u64().unwrap() >= 1);
    drop(h);

    // A server that keeps failing: the retries are bounded and the error says where it failed.
    let (endpoint, hub) = serve(true);
    let o = push(&ds, &endpoint, Some(TOKEN), &hf_home, &["--retries", "2"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("answered 500 while committing"), "{}", text(&o));
    let commits = hub
        .lock()
        .unwrap()
        .requests
        .iter()
        .filter(|r| r.path.ends_with("/commit/main"))
        .count();
    assert_eq!(commits, 3, "one attempt and two retries");

    // Input errors name the fix.
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["push", ds.to_str().unwrap(), "--repo", "no-slash"])
        .env("HF_TOKEN", TOKEN)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("user/name"), "{}", text(&o));
}
