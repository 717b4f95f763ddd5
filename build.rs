//! Embeds the git commit the binary is built from (`HGYM_GIT_COMMIT`, with `-dirty` when
//! tracked files had uncommitted changes) for the manifests of results; empty outside a git
//! checkout. Re-run when the checkout's HEAD or branch heads move (a commit, a checkout) or
//! the sources change (the dirty flag); not on index updates, which `git status` makes.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    // A path that does not exist would re-run the script (and rebuild the crate) every time.
    for path in [
        ".git/HEAD",
        ".git/refs/heads",
        ".git/packed-refs",
        "src",
        "solvers/src",
        "agents/src",
        "benchmarks",
    ] {
        if std::path::Path::new(path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    let commit = match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(c) if !c.is_empty() => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
            format!("{c}{}", if dirty { "-dirty" } else { "" })
        }
        _ => String::new(),
    };
    println!("cargo:rustc-env=HGYM_GIT_COMMIT={commit}");
}
