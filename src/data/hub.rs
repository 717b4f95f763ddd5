//! `hgym push DIR --repo user/name`: uploads a dataset folder to the Hugging Face Hub through
//! its HTTP API (the calls `huggingface_hub.upload_folder` makes):
//!
//! 1. `POST {endpoint}/api/repos/create` (`type: dataset`); 409 means it exists already;
//! 2. `POST {endpoint}/api/datasets/{repo}/preupload/main`: the Hub says which files go through
//!    Git LFS (Parquet, anything binary or large) and which inline;
//! 3. for LFS files, `POST {endpoint}/datasets/{repo}.git/info/lfs/objects/batch` (basic
//!    transfer), `PUT` the bytes to the returned address, then its `verify` call;
//! 4. `POST {endpoint}/api/datasets/{repo}/commit/main` (NDJSON): a header, inline files as
//!    base64, LFS files by their SHA-256.
//!
//! The token comes from `HF_TOKEN` (or `HUGGING_FACE_HUB_TOKEN`), else the file the Hugging Face
//! tools write (`HF_TOKEN_PATH`, `$HF_HOME/token`, `~/.cache/huggingface/token`). It is sent
//! only as a sensitive `Authorization` header to the endpoint and never formatted into any
//! message. Requests are retried with exponential backoff (or the server's `Retry-After`) on
//! 429, 5xx and connection failures; 401/403 stop at once with what to do.

use std::path::{Path, PathBuf};
use std::time::Duration;

use base64::Engine;
use serde_json::{json, Value};
use sha2::{Digest, Sha256};

/// A Hub token. Its `Debug` does not show it.
#[derive(Clone)]
pub struct Token(String);

impl std::fmt::Debug for Token {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Token(<hidden>)")
    }
}

#[derive(Debug, thiserror::Error)]
pub enum HubError {
    #[error("no Hugging Face token: set HF_TOKEN, or log in with `huggingface-cli login` (which writes ~/.cache/huggingface/token); the token needs write access")]
    NoToken,
    #[error("'{0}' is not a repository ID: use user/name or org/name (letters, digits, '-', '_', '.')")]
    BadRepo(String),
    #[error("the Hub refused the token ({status}) while {what}: {message}. Check HF_TOKEN (or the token file) and that it has write access to the repository")]
    Auth { status: u16, what: String, message: String },
    #[error("the Hub answered {status} while {what}: {message}")]
    Http { status: u16, what: String, message: String },
    #[error("could not reach {endpoint} while {what}: {message} (set HF_ENDPOINT to use another server)")]
    Network { endpoint: String, what: String, message: String },
    #[error("{0}")]
    Io(String),
}

/// Where and how to upload.
#[derive(Clone, Debug)]
pub struct HubConfig {
    pub endpoint: String,
    pub token: Token,
    /// Retries per request after the first attempt.
    pub retries: u32,
    /// First backoff; doubles on every retry (capped at 30 s).
    pub backoff: Duration,
}

impl HubConfig {
    /// Endpoint from `HF_ENDPOINT` (default `https://huggingface.co`), token as described above.
    pub fn from_env(retries: u32) -> Result<HubConfig, HubError> {
        let endpoint = std::env::var("HF_ENDPOINT")
            .ok()
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "https://huggingface.co".into())
            .trim_end_matches('/')
            .to_string();
        Ok(HubConfig {
            endpoint,
            token: token_from_env()?,
            retries,
            backoff: Duration::from_millis(500),
        })
    }
}

fn token_file() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("HF_TOKEN_PATH") {
        return Some(PathBuf::from(p));
    }
    if let Some(h) = std::env::var_os("HF_HOME") {
        return Some(PathBuf::from(h).join("token"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/huggingface/token"))
}

/// `HF_TOKEN`, `HUGGING_FACE_HUB_TOKEN`, else the Hugging Face token file.
pub fn token_from_env() -> Result<Token, HubError> {
    for var in ["HF_TOKEN", "HUGGING_FACE_HUB_TOKEN"] {
        if let Ok(t) = std::env::var(var) {
            if !t.trim().is_empty() {
                return Ok(Token(t.trim().to_string()));
            }
        }
    }
    token_file()
        .and_then(|p| std::fs::read_to_string(p).ok())
        .map(|t| t.trim().to_string())
        .filter(|t| !t.is_empty())
        .map(Token)
        .ok_or(HubError::NoToken)
}

/// `user/name` with the Hub's characters.
pub fn check_repo(repo: &str) -> Result<(&str, &str), HubError> {
    let ok = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    match repo.split_once('/') {
        Some((user, name)) if ok(user) && ok(name) => Ok((user, name)),
        _ => Err(HubError::BadRepo(repo.to_string())),
    }
}

/// One file to upload.
struct Upload {
    path: String,
    bytes: Vec<u8>,
    sha256: String,
}

/// What `push` did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PushReport {
    pub repo: String,
    pub url: String,
    pub created: bool,
    pub files: usize,
    pub lfs_files: usize,
    pub lfs_uploaded: usize,
    pub bytes: u64,
    pub commit: Option<String>,
}

struct Client<'a> {
    http: reqwest::blocking::Client,
    cfg: &'a HubConfig,
}

impl Client<'_> {
    /// Sends `build()` until it succeeds, retrying on 429 / 5xx / network failures; 401/403 and
    /// other 4xx are returned at once. `auth`: send the token (only to the Hub itself).
    fn send(
        &self,
        what: &str,
        auth: bool,
        build: &dyn Fn(&reqwest::blocking::Client) -> reqwest::blocking::RequestBuilder,
        accept: &[u16],
    ) -> Result<(u16, Value), HubError> {
        let mut attempt = 0;
        loop {
            let mut req = build(&self.http);
            if auth {
                req = req.bearer_auth(&self.cfg.token.0);
            }
            let wait = match req.send() {
                Ok(resp) => {
                    let status = resp.status().as_u16();
                    let retry_after = resp
                        .headers()
                        .get("retry-after")
                        .and_then(|v| v.to_str().ok())
                        .and_then(|v| v.trim().parse::<f64>().ok());
                    let text = resp.text().unwrap_or_default();
                    let body: Value = serde_json::from_str(&text).unwrap_or(Value::Null);
                    if (200..300).contains(&status) || accept.contains(&status) {
                        return Ok((status, body));
                    }
                    let message = body["error"]
                        .as_str()
                        .map(|s| s.to_string())
                        .unwrap_or_else(|| text.chars().take(300).collect());
                    if status == 401 || status == 403 {
                        return Err(HubError::Auth {
                            status,
                            what: what.into(),
                            message,
                        });
                    }
                    if !(status == 429 || status >= 500) || attempt >= self.cfg.retries {
                        return Err(HubError::Http {
                            status,
                            what: what.into(),
                            message,
                        });
                    }
                    retry_after.map(|s| Duration::from_secs_f64(s.clamp(0.0, 60.0)))
                }
                Err(e) => {
                    if attempt >= self.cfg.retries {
                        return Err(HubError::Network {
                            endpoint: self.cfg.endpoint.clone(),
                            what: what.into(),
                            message: e.without_url().to_string(),
                        });
                    }
                    None
                }
            };
            let backoff = (self.cfg.backoff * 2u32.pow(attempt.min(6))).min(Duration::from_secs(30));
            std::thread::sleep(wait.unwrap_or(backoff));
            attempt += 1;
        }
    }
}

fn collect(dir: &Path) -> Result<Vec<Upload>, HubError> {
    let mut paths = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let rd = std::fs::read_dir(&d).map_err(|e| HubError::Io(format!("cannot list {}: {e}", d.display())))?;
        for e in rd.flatten() {
            let p = e.path();
            let hidden = p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with('.'));
            if hidden {
                continue;
            } else if p.is_dir() {
                stack.push(p);
            } else {
                paths.push(p);
            }
        }
    }
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let bytes = std::fs::read(&p).map_err(|e| HubError::Io(format!("cannot read {}: {e}", p.display())))?;
            let sha256 = format!("{:x}", Sha256::digest(&bytes));
            let path = p.strip_prefix(dir).unwrap_or(&p).to_string_lossy().replace('\\', "/");
            Ok(Upload { path, bytes, sha256 })
        })
        .collect()
}

/// Uploads every file under `dir` (hidden files skipped) to the dataset repo `repo` in one commit.
pub fn push(
    dir: &Path,
    repo: &str,
    private: bool,
    message: &str,
    cfg: &HubConfig,
    progress: &mut dyn FnMut(&str),
) -> Result<PushReport, HubError> {
    let (user, name) = check_repo(repo)?;
    if !dir.is_dir() {
        return Err(HubError::Io(format!(
            "{} is not a folder: push the OUT folder of `hgym export --to hf DIR OUT`",
            dir.display()
        )));
    }
    let files = collect(dir)?;
    if files.is_empty() {
        return Err(HubError::Io(format!("{} is empty: nothing to push", dir.display())));
    }
    let http = reqwest::blocking::Client::builder()
        .user_agent(concat!("hgym/", env!("CARGO_PKG_VERSION")))
        .timeout(Duration::from_secs(600))
        .build()
        .map_err(|e| HubError::Io(format!("cannot start the HTTP client: {e}")))?;
    let c = Client { http, cfg };
    let ep = cfg.endpoint.clone();

    progress(&format!("creating dataset repo {repo} (if needed)"));
    let body = json!({"type": "dataset", "name": name, "organization": user, "private": private});
    let (status, _) = c.send(
        "creating the repository",
        true,
        &|h| h.post(format!("{ep}/api/repos/create")).json(&body),
        &[409],
    )?;
    let created = status != 409;

    progress(&format!("asking the Hub how to upload {} files", files.len()));
    let b64 = base64::engine::general_purpose::STANDARD;
    let pre = json!({"files": files.iter().map(|f| json!({
        "path": f.path, "size": f.bytes.len(), "sample": b64.encode(&f.bytes[..f.bytes.len().min(512)])
    })).collect::<Vec<_>>()});
    let (_, modes) = c.send(
        "asking for upload modes",
        true,
        &|h| h.post(format!("{ep}/api/datasets/{repo}/preupload/main")).json(&pre),
        &[],
    )?;
    let is_lfs = |path: &str| {
        modes["files"]
            .as_array()
            .and_then(|a| a.iter().find(|m| m["path"] == path))
            .map(|m| m["uploadMode"] == "lfs")
            .unwrap_or(false)
    };
    let lfs: Vec<&Upload> = files.iter().filter(|f| is_lfs(&f.path)).collect();

    let mut lfs_uploaded = 0;
    if !lfs.is_empty() {
        let batch = json!({
            "operation": "upload", "transfers": ["basic"], "hash_algo": "sha256", "ref": {"name": "main"},
            "objects": lfs.iter().map(|f| json!({"oid": f.sha256, "size": f.bytes.len()})).collect::<Vec<_>>(),
        });
        let (_, answer) = c.send(
            "requesting LFS uploads",
            true,
            &|h| {
                h.post(format!("{ep}/datasets/{repo}.git/info/lfs/objects/batch"))
                    .header("Accept", "application/vnd.git-lfs+json")
                    .header("Content-Type", "application/vnd.git-lfs+json")
                    .body(batch.to_string())
            },
            &[],
        )?;
        for obj in answer["objects"].as_array().cloned().unwrap_or_default() {
            let oid = obj["oid"].as_str().unwrap_or("");
            let Some(f) = lfs.iter().find(|f| f.sha256 == oid) else {
                continue;
            };
            if let Some(e) = obj.get("error") {
                return Err(HubError::Http {
                    status: e["code"].as_u64().unwrap_or(0) as u16,
                    what: format!("uploading {}", f.path),
                    message: e["message"].as_str().unwrap_or("").to_string(),
                });
            }
            let Some(upload) = obj["actions"].get("upload") else {
                continue; // the Hub has these bytes already
            };
            if upload["header"].get("chunk_size").is_some() {
                return Err(HubError::Io(format!(
                    "{} needs a multipart upload, which hgym does not do; split it with --shard-rows",
                    f.path
                )));
            }
            progress(&format!("uploading {} ({} bytes)", f.path, f.bytes.len()));
            let href = upload["href"].as_str().unwrap_or("").to_string();
            let headers = upload["header"].as_object().cloned().unwrap_or_default();
            c.send(
                &format!("uploading {}", f.path),
                false,
                &|h| {
                    let mut r = h.put(&href).body(f.bytes.clone());
                    for (k, v) in &headers {
                        r = r.header(k.as_str(), v.as_str().unwrap_or(""));
                    }
                    r
                },
                &[],
            )?;
            if let Some(verify) = obj["actions"].get("verify") {
                let href = verify["href"].as_str().unwrap_or("").to_string();
                let body = json!({"oid": f.sha256, "size": f.bytes.len()});
                c.send(
                    &format!("verifying {}", f.path),
                    href.starts_with(&ep),
                    &|h| h.post(&href).json(&body),
                    &[],
                )?;
            }
            lfs_uploaded += 1;
        }
    }

    progress("committing");
    let mut ndjson = json!({"key": "header", "value": {"summary": message, "description": ""}}).to_string();
    for f in &files {
        let line = if is_lfs(&f.path) {
            json!({"key": "lfsFile", "value": {"path": f.path, "algo": "sha256", "oid": f.sha256, "size": f.bytes.len()}})
        } else {
            json!({"key": "file", "value": {"path": f.path, "encoding": "base64", "content": b64.encode(&f.bytes)}})
        };
        ndjson.push('\n');
        ndjson.push_str(&line.to_string());
    }
    let (_, commit) = c.send(
        "committing",
        true,
        &|h| {
            h.post(format!("{ep}/api/datasets/{repo}/commit/main"))
                .header("Content-Type", "application/x-ndjson")
                .body(ndjson.clone())
        },
        &[],
    )?;
    Ok(PushReport {
        repo: repo.to_string(),
        url: format!("{ep}/datasets/{repo}"),
        created,
        files: files.len(),
        lfs_files: lfs.len(),
        lfs_uploaded,
        bytes: files.iter().map(|f| f.bytes.len() as u64).sum(),
        commit: commit["commitOid"].as_str().map(|s| s.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repo_ids() {
        assert_eq!(check_repo("user/name-1.x").unwrap(), ("user", "name-1.x"));
        for bad in ["name", "/name", "user/", "a/b/c", "us er/x", "u/n?"] {
            assert!(check_repo(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn token_debug_is_hidden() {
        let t = Token("hf_secret_value".into());
        assert!(!format!("{t:?}").contains("secret"));
    }
}
