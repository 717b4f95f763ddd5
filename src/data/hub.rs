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
//! as a sensitive `Authorization` header only to the endpoint's exact origin (scheme, host and
//! port, compared on parsed URLs), whatever address a reply names; redirects are followed only
//! within a request's own origin; the endpoint must be `https://` (plain `http://` only on a
//! loopback host); server text in messages is cut to 300 characters with token-shaped words
//! redacted. Replies are parsed strictly: an answer without what the API returns (upload modes,
//! LFS objects, the commit's ID) is an error, never a success. Requests are retried with
//! exponential backoff (or the server's `Retry-After`, in whole seconds up to 60) on 429, 5xx,
//! connection failures and time-outs; 401/403 stop at once with what to do.

use std::path::{Path, PathBuf};
use std::time::Duration;

use base64::Engine;
use reqwest::Url;
use serde_json::{json, Value};
use sha2::{Digest, Sha256};
use url::Origin;

/// A Hub token. Its `Debug` does not show it.
#[derive(Clone)]
pub struct Token(String);

impl Token {
    /// A token given by the caller (the CLI reads it with [`token_from_env`]).
    pub fn new(token: impl Into<String>) -> Token {
        Token(token.into())
    }
}

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
    #[error("HF_ENDPOINT '{endpoint}' {problem}")]
    Endpoint { endpoint: String, problem: String },
    #[error("the Hub refused the token ({status}) while {what}: {message}. Check HF_TOKEN (or the token file) and that it has write access to the repository")]
    Auth { status: u16, what: String, message: String },
    #[error("the Hub answered {status} while {what}: {message}")]
    Http { status: u16, what: String, message: String },
    #[error("the Hub's answer while {what} is not what its API returns ({problem}), so the push is not confirmed; check the repository on the Hub before pushing again. The answer began: {body}")]
    Reply { what: String, problem: String, body: String },
    #[error("the server redirected to {to} while {what}: not followed, because it is not {origin} (hgym follows redirects only within one origin, so the token never leaves the endpoint)")]
    Redirect { what: String, origin: String, to: String },
    #[error("timed out while {what}: no complete answer from {endpoint} within {seconds} s, {attempts} attempt(s) (a slow server: try again later, or raise --timeout)")]
    TimedOut {
        endpoint: String,
        what: String,
        seconds: u64,
        attempts: u32,
    },
    #[error("could not reach {endpoint} while {what}: {message} (set HF_ENDPOINT to use another server)")]
    Network { endpoint: String, what: String, message: String },
    #[error("{0}")]
    Io(String),
}

impl HubError {
    /// Token, endpoint, repository and folder problems are the user's to fix (exit 2); the
    /// server's are not.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            HubError::NoToken | HubError::BadRepo(_) | HubError::Endpoint { .. } | HubError::Auth { .. } | HubError::Io(_)
        )
    }
}

/// Where and how to upload.
#[derive(Clone, Debug)]
pub struct HubConfig {
    /// The endpoint without a trailing '/', e.g. `https://huggingface.co`.
    pub endpoint: String,
    /// Its scheme, host and port: the only origin the token is sent to.
    origin: Origin,
    pub token: Token,
    /// Retries per request after the first attempt.
    pub retries: u32,
    /// First backoff; doubles on every retry (capped at 30 s).
    pub backoff: Duration,
    /// How long one request may take, plus one second per MB it uploads.
    pub timeout: Duration,
}

impl HubConfig {
    /// The endpoint `endpoint` with `token`: `https://`, or plain `http://` on a loopback host
    /// only (a local test server), since the token would otherwise cross the network in clear.
    pub fn new(endpoint: &str, token: Token, retries: u32, timeout: Duration) -> Result<HubConfig, HubError> {
        let endpoint = endpoint.trim_end_matches('/').to_string();
        let refuse = |problem: &str| HubError::Endpoint {
            endpoint: endpoint.clone(),
            problem: problem.to_string(),
        };
        let url = Url::parse(&endpoint).map_err(|e| refuse(&format!("is not a URL ({e}): use e.g. https://huggingface.co")))?;
        let loopback = match url.host() {
            Some(url::Host::Domain(d)) => d.eq_ignore_ascii_case("localhost"),
            Some(url::Host::Ipv4(a)) => a.is_loopback(),
            Some(url::Host::Ipv6(a)) => a.is_loopback(),
            None => false,
        };
        match url.scheme() {
            "https" if url.host().is_some() => {}
            "http" if loopback => {}
            "http" => {
                return Err(refuse(
                    "is plain http: the token would cross the network unencrypted. Use https:// (plain http is accepted only for a server on this machine: localhost, 127.0.0.1, ::1)",
                ))
            }
            _ => return Err(refuse("is not an https:// address with a host: use e.g. https://huggingface.co")),
        }
        if !url.username().is_empty() || url.password().is_some() || url.query().is_some() {
            return Err(refuse("carries credentials or a query: give the bare server address"));
        }
        Ok(HubConfig {
            origin: url.origin(),
            endpoint,
            token,
            retries,
            backoff: Duration::from_millis(500),
            timeout,
        })
    }

    /// Endpoint from `HF_ENDPOINT` (default `https://huggingface.co`), token as described above.
    pub fn from_env(retries: u32, timeout: Duration) -> Result<HubConfig, HubError> {
        let endpoint = std::env::var("HF_ENDPOINT")
            .ok()
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "https://huggingface.co".into());
        HubConfig::new(&endpoint, token_from_env()?, retries, timeout)
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

/// `text` (a server's words) for a message: at most 300 characters, with the token, any piece
/// of it of 8 or more characters, and anything shaped like a Hugging Face token (`hf_` and 8 or
/// more letters or digits) replaced by `hf_***`.
pub fn redact(text: &str, token: &Token) -> String {
    // Mask a bounded head (bodies can be large); the 300 characters shown lie inside it.
    let head: String = text.chars().take(4096).collect();
    let text = mask_fragments(&head, token.0.as_bytes());
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(i) = rest.find("hf_") {
        out.push_str(&rest[..i]);
        let tail = &rest[i + 3..];
        let n = tail.find(|c: char| !c.is_ascii_alphanumeric()).unwrap_or(tail.len());
        out.push_str(if n >= 8 { "hf_***" } else { &rest[i..i + 3 + n] });
        rest = &tail[n..];
    }
    out.push_str(rest);
    out.chars().take(300).collect()
}

/// `text` with every run of at least 8 bytes that also occurs in `token` (the whole token, or
/// any piece an echo or a cut left) replaced by `hf_***`. Tokens are ASCII (an HTTP header
/// carries them), so a matched run never splits a character.
fn mask_fragments(text: &str, token: &[u8]) -> String {
    const MIN: usize = 8;
    let t = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let (mut i, mut copied) = (0, 0);
    while i < t.len() {
        let longest = (0..token.len())
            .map(|j| t[i..].iter().zip(&token[j..]).take_while(|(a, b)| a == b).count())
            .max()
            .unwrap_or(0);
        if longest >= MIN && token.is_ascii() {
            out.push_str(&text[copied..i]);
            out.push_str("hf_***");
            i += longest;
            copied = i;
        } else {
            i += 1;
        }
    }
    out.push_str(&text[copied..]);
    out
}

/// The `Retry-After` header's delay in seconds (RFC 9110: a non-negative integer), capped at
/// 60 s; `None` for anything else (an HTTP date, garbage), which falls back to the backoff.
pub fn retry_after(value: &str) -> Option<Duration> {
    let v = value.trim();
    if v.is_empty() || !v.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(Duration::from_secs(v.parse::<u64>().unwrap_or(u64::MAX).min(60)))
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
    pub commit: String,
}

struct Client<'a> {
    http: reqwest::blocking::Client,
    cfg: &'a HubConfig,
}

impl Client<'_> {
    /// Sends `build()` until it succeeds, retrying on 429 / 5xx / network failures and time-outs;
    /// 401/403 and other 4xx are returned at once. `auth`: the call carries the token, which is
    /// attached only if the request's origin is the endpoint's. Returns the status and the body.
    fn send(
        &self,
        what: &str,
        auth: bool,
        build: &dyn Fn(&reqwest::blocking::Client) -> reqwest::blocking::RequestBuilder,
        accept: &[u16],
    ) -> Result<(u16, String), HubError> {
        let mut attempt = 0;
        loop {
            let mut req = build(&self.http).build().map_err(|e| HubError::Reply {
                what: what.into(),
                problem: "it names an address that is not a URL".into(),
                body: redact(&e.without_url().to_string(), &self.cfg.token),
            })?;
            if auth && req.url().origin() == self.cfg.origin {
                let mut value = reqwest::header::HeaderValue::from_str(&format!("Bearer {}", self.cfg.token.0))
                    .map_err(|_| HubError::Io("the token has characters an HTTP header cannot carry".into()))?;
                value.set_sensitive(true);
                req.headers_mut().insert(reqwest::header::AUTHORIZATION, value);
            }
            let wait = match self.http.execute(req) {
                Ok(resp) => {
                    let status = resp.status().as_u16();
                    let header = |name: &str| resp.headers().get(name).and_then(|v| v.to_str().ok()).map(str::to_string);
                    let (wait, location) = (header("retry-after").and_then(|v| retry_after(&v)), header("location"));
                    let text = match resp.text() {
                        Ok(t) => t,
                        Err(e) if e.is_timeout() => return Err(self.timed_out(what, attempt)),
                        Err(e) => return Err(self.network(what, e)),
                    };
                    if (200..300).contains(&status) || accept.contains(&status) {
                        return Ok((status, text));
                    }
                    let message = serde_json::from_str::<Value>(&text)
                        .ok()
                        .and_then(|b| b["error"].as_str().map(str::to_string))
                        .unwrap_or_else(|| text.clone());
                    let message = redact(&message, &self.cfg.token);
                    if (300..400).contains(&status) {
                        return Err(HubError::Redirect {
                            what: what.into(),
                            origin: self.cfg.endpoint.clone(),
                            to: redact(location.as_deref().unwrap_or("(no Location)"), &self.cfg.token),
                        });
                    }
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
                    wait
                }
                Err(e) if attempt >= self.cfg.retries => {
                    return Err(if e.is_timeout() {
                        self.timed_out(what, attempt)
                    } else {
                        self.network(what, e)
                    })
                }
                Err(_) => None,
            };
            let backoff = (self.cfg.backoff * 2u32.pow(attempt.min(6))).min(Duration::from_secs(30));
            std::thread::sleep(wait.unwrap_or(backoff));
            attempt += 1;
        }
    }

    fn timed_out(&self, what: &str, attempt: u32) -> HubError {
        HubError::TimedOut {
            endpoint: self.cfg.endpoint.clone(),
            what: what.into(),
            seconds: self.cfg.timeout.as_secs(),
            attempts: attempt + 1,
        }
    }

    fn network(&self, what: &str, e: reqwest::Error) -> HubError {
        HubError::Network {
            endpoint: self.cfg.endpoint.clone(),
            what: what.into(),
            message: redact(&e.without_url().to_string(), &self.cfg.token),
        }
    }

    /// A JSON object answer, or the error that says it is not one.
    fn object(&self, what: &str, text: &str) -> Result<serde_json::Map<String, Value>, HubError> {
        match serde_json::from_str::<Value>(text) {
            Ok(Value::Object(m)) => Ok(m),
            _ => Err(self.reply(what, "not a JSON object", text)),
        }
    }

    fn reply(&self, what: &str, problem: &str, text: &str) -> HubError {
        HubError::Reply {
            what: what.into(),
            problem: problem.into(),
            body: if text.is_empty() {
                "(empty)".into()
            } else {
                redact(text, &self.cfg.token)
            },
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
        .connect_timeout(Duration::from_secs(10).min(cfg.timeout))
        .timeout(cfg.timeout)
        // Redirects within the request's own origin only: a reply never sends a request (and
        // with it the token) somewhere else.
        .redirect(reqwest::redirect::Policy::custom(|a| {
            let same = a.previous().first().is_some_and(|first| first.origin() == a.url().origin());
            if same && a.previous().len() <= 5 {
                a.follow()
            } else {
                a.stop()
            }
        }))
        .build()
        .map_err(|e| HubError::Io(format!("cannot start the HTTP client: {e}")))?;
    let c = Client { http, cfg };
    let ep = cfg.endpoint.clone();

    let what = "creating the repository";
    progress(&format!("creating dataset repo {repo} (if needed)"));
    let body = json!({"type": "dataset", "name": name, "organization": user, "private": private});
    let (status, text) = c.send(what, true, &|h| h.post(format!("{ep}/api/repos/create")).json(&body), &[409])?;
    let created = status != 409;
    if created {
        c.object(what, &text)?;
    }

    let what = "asking for upload modes";
    progress(&format!("asking the Hub how to upload {} files", files.len()));
    let b64 = base64::engine::general_purpose::STANDARD;
    let pre = json!({"files": files.iter().map(|f| json!({
        "path": f.path, "size": f.bytes.len(), "sample": b64.encode(&f.bytes[..f.bytes.len().min(512)])
    })).collect::<Vec<_>>()});
    let (_, text) = c.send(
        what,
        true,
        &|h| h.post(format!("{ep}/api/datasets/{repo}/preupload/main")).json(&pre),
        &[],
    )?;
    let modes = c.object(what, &text)?;
    let mut lfs: Vec<&Upload> = vec![];
    for f in &files {
        let mode = modes
            .get("files")
            .and_then(Value::as_array)
            .and_then(|a| a.iter().find(|m| m["path"] == f.path.as_str()))
            .and_then(|m| m["uploadMode"].as_str());
        match mode {
            Some("lfs") => lfs.push(f),
            Some("regular") => {}
            _ => return Err(c.reply(what, &format!("no upload mode 'lfs' or 'regular' for {}", f.path), &text)),
        }
    }

    let mut lfs_uploaded = 0;
    if !lfs.is_empty() {
        let what = "requesting LFS uploads";
        let batch = json!({
            "operation": "upload", "transfers": ["basic"], "hash_algo": "sha256", "ref": {"name": "main"},
            "objects": lfs.iter().map(|f| json!({"oid": f.sha256, "size": f.bytes.len()})).collect::<Vec<_>>(),
        });
        let (_, text) = c.send(
            what,
            true,
            &|h| {
                h.post(format!("{ep}/datasets/{repo}.git/info/lfs/objects/batch"))
                    .header("Accept", "application/vnd.git-lfs+json")
                    .header("Content-Type", "application/vnd.git-lfs+json")
                    .body(batch.to_string())
            },
            &[],
        )?;
        let answer = c.object(what, &text)?;
        let objects = answer.get("objects").and_then(Value::as_array).cloned().unwrap_or_default();
        for f in &lfs {
            let Some(obj) = objects.iter().find(|o| o["oid"] == f.sha256.as_str()) else {
                return Err(c.reply(what, &format!("no entry for {} ({})", f.path, f.sha256), &text));
            };
            if let Some(e) = obj.get("error") {
                return Err(HubError::Http {
                    status: e["code"].as_u64().map_or(0, |c| c.min(999) as u16),
                    what: format!("uploading {}", f.path),
                    message: redact(e["message"].as_str().unwrap_or(""), &cfg.token),
                });
            }
            let Some(upload) = obj["actions"].get("upload") else {
                continue; // the Hub has these bytes already
            };
            let what = format!("uploading {}", f.path);
            if upload["header"].get("chunk_size").is_some() {
                return Err(HubError::Io(format!(
                    "{} needs a multipart upload, which hgym does not do; split it with --shard-rows",
                    f.path
                )));
            }
            let Some(href) = upload["href"].as_str() else {
                return Err(c.reply(&what, "the upload action has no href", &text));
            };
            let mut headers = vec![];
            for (k, v) in upload["header"].as_object().into_iter().flatten() {
                let Some(v) = v.as_str() else {
                    return Err(c.reply(&what, &format!("the upload header {k} is not a string"), &text));
                };
                headers.push((k.clone(), v.to_string()));
            }
            progress(&format!("uploading {} ({} bytes)", f.path, f.bytes.len()));
            let seconds = cfg.timeout + Duration::from_secs(f.bytes.len() as u64 >> 20);
            c.send(
                &what,
                false,
                &|h| {
                    let mut r = h.put(href).timeout(seconds).body(f.bytes.clone());
                    for (k, v) in &headers {
                        r = r.header(k.as_str(), v.as_str());
                    }
                    r
                },
                &[],
            )?;
            if let Some(verify) = obj["actions"].get("verify") {
                let what = format!("verifying {}", f.path);
                let Some(href) = verify["href"].as_str() else {
                    return Err(c.reply(&what, "the verify action has no href", &text));
                };
                let body = json!({"oid": f.sha256, "size": f.bytes.len()});
                c.send(&what, true, &|h| h.post(href).json(&body), &[])?;
            }
            lfs_uploaded += 1;
        }
    }

    let what = "committing";
    progress(what);
    let mut ndjson = json!({"key": "header", "value": {"summary": message, "description": ""}}).to_string();
    for f in &files {
        let line = if lfs.iter().any(|l| l.path == f.path) {
            json!({"key": "lfsFile", "value": {"path": f.path, "algo": "sha256", "oid": f.sha256, "size": f.bytes.len()}})
        } else {
            json!({"key": "file", "value": {"path": f.path, "encoding": "base64", "content": b64.encode(&f.bytes)}})
        };
        ndjson.push('\n');
        ndjson.push_str(&line.to_string());
    }
    let (_, text) = c.send(
        what,
        true,
        &|h| {
            h.post(format!("{ep}/api/datasets/{repo}/commit/main"))
                .header("Content-Type", "application/x-ndjson")
                .body(ndjson.clone())
        },
        &[],
    )?;
    let commit = c.object(what, &text)?;
    // A commit id is a hex digest (40 digits on the Hub); anything else confirms nothing.
    let Some(commit) = commit
        .get("commitOid")
        .and_then(Value::as_str)
        .filter(|c| !c.is_empty() && c.bytes().all(|b| b.is_ascii_hexdigit()))
    else {
        return Err(c.reply(what, "no commitOid (a hex commit id): the commit cannot be confirmed", &text));
    };
    Ok(PushReport {
        repo: repo.to_string(),
        url: format!("{ep}/datasets/{repo}"),
        created,
        files: files.len(),
        lfs_files: lfs.len(),
        lfs_uploaded,
        bytes: files.iter().map(|f| f.bytes.len() as u64).sum(),
        commit: commit.to_string(),
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
    fn endpoints_are_https_or_loopback_http() {
        let t = || Token("hf_x".into());
        let d = Duration::from_secs(1);
        for ok in [
            "https://huggingface.co",
            "https://hub.example:8443/",
            "http://127.0.0.1:9",
            "http://localhost:80",
            "http://[::1]:5",
        ] {
            assert!(HubConfig::new(ok, t(), 0, d).is_ok(), "{ok}");
        }
        for bad in [
            "http://huggingface.co",
            "http://10.0.0.1",
            "ftp://x",
            "huggingface.co",
            "https://u:p@h.co",
            "file:///tmp",
        ] {
            let e = HubConfig::new(bad, t(), 0, d).err().unwrap_or_else(|| panic!("{bad} accepted"));
            assert!(e.is_bad_input(), "{bad}");
        }
        let e = HubConfig::new("http://hub.example", t(), 0, d)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("plain http") && e.contains("https://"), "{e}");
    }

    #[test]
    fn server_text_is_redacted() {
        let t = Token("s3cr3t-token".into());
        assert_eq!(redact("bad s3cr3t-token here", &t), "bad hf_*** here");
        assert_eq!(redact("key hf_AbCdEf123456 and hf_ok", &t), "key hf_*** and hf_ok");
        assert_eq!(redact(&"x".repeat(1000), &t).len(), 300);
        // Pieces of the token (an echo that dropped a character, a cut) are masked too, and the
        // cut at 300 characters comes after the masking, so it cannot expose a prefix.
        assert_eq!(redact("echo 3cr3t-tok and s3cr3t-t", &t), "echo hf_*** and hf_***");
        assert_eq!(redact("short s3cr3t is kept", &t), "short s3cr3t is kept");
        let cut = format!("{}s3cr3t-token", "y".repeat(292));
        assert!(!redact(&cut, &t).contains("s3cr3t-t"), "{}", redact(&cut, &t));
    }

    #[test]
    fn retry_after_is_seconds_or_nothing() {
        assert_eq!(retry_after(" 3 "), Some(Duration::from_secs(3)));
        assert_eq!(retry_after("99999999999999999999999"), Some(Duration::from_secs(60)));
        for bad in ["NaN", "-1", "1.5", "inf", "", "Wed, 21 Oct 2015 07:28:00 GMT"] {
            assert_eq!(retry_after(bad), None, "{bad}");
        }
    }

    #[test]
    fn token_debug_is_hidden() {
        let t = Token("hf_secret_value".into());
        assert!(!format!("{t:?}").contains("secret"));
    }
}
