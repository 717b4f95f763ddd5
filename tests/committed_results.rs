//! Committed results stay reproducible: every result folder under `results/` was run on the spec
//! its ID has now, with the run's own `[env]` overrides if it has any (same SHA-256), so a refactor that changes a spec's hash, or its physics,
//! fails here rather than silently orphaning the results. The folders run on specs that changed
//! since are listed below with the reason; they are to be regenerated (issue: leaderboard on
//! current specs), never silently dropped.

mod common;
use common::{files_under, repo};

/// Result folders run on an earlier spec of their ID: (folder prefix under results/, why).
const STALE: &[(&str, &str)] = &[
    ("stale/", "runs on retired specs, kept for the leaderboard's stale section"),
    (
        "runs/Pinball_2D_Re",
        "the pinball's domain and reward changed after these showcase runs",
    ),
    (
        "runs/SquareCylinder_2D_Re",
        "the square cylinder's set-up changed after these showcase runs",
    ),
];

#[test]
fn committed_results_were_run_on_the_registered_specs() {
    let results = repo().join("results");
    let files = files_under(&results, &|p| p.file_name().is_some_and(|n| n == "manifest.json"));
    let mut current = 0;
    let mut problems = vec![];
    for f in &files {
        let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
        let (Some(id), Some(hash)) = (m["env_id"].as_str(), m["spec_hash"].as_str()) else {
            continue;
        };
        let rel = f.strip_prefix(&results).unwrap().to_string_lossy().replace('\\', "/");
        let stale = STALE.iter().any(|(prefix, _)| rel.starts_with(prefix));
        // A run with [env] overrides was made on the registered spec with them (the leaderboard's
        // notion of current, too).
        let registered = match m["config_toml"].as_str() {
            Some(text) => {
                let config = hgym::train::config::TrainConfig::parse(text, &rel).unwrap_or_else(|e| panic!("{rel}: {e}"));
                hgym::train::resolve_spec(id, &config)
                    .unwrap_or_else(|e| panic!("{rel}: {e}"))
                    .hash()
            }
            None => hgym::env::lookup(id).unwrap_or_else(|e| panic!("{rel}: {e}")).hash(),
        };
        match (registered == hash, stale) {
            (true, false) => current += 1,
            (false, true) => {}
            (true, true) => problems.push(format!("{rel}: listed as stale but its spec is current; remove it from STALE")),
            (false, false) => problems.push(format!("{rel}: {id} was run on spec {hash}, registered now as {registered}")),
        }
    }
    assert!(problems.is_empty(), "{problems:#?}");
    assert!(current >= 20, "expected the committed runs on current specs, found {current}");
}
