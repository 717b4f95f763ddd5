//! Every JSON file under `results/` validates against its schema in `schemas/` (chosen by the
//! file's `schema` field, or by its name for the files that have none: `policy.json`, rollout
//! `metrics.json`). A JSON file without a schema fails the test.

use std::path::Path;

mod common;
use common::{files_under, repo};

fn schema_file(path: &Path, v: &serde_json::Value) -> Option<&'static str> {
    let by_field = match v.get("schema").and_then(|s| s.as_str()) {
        Some("hgym/validation/v1") => Some("validation.schema.json"),
        Some("hgym/kolmogorov-validation/v1") => Some("kolmogorov-validation.schema.json"),
        Some("hgym/channel-validation/v1") => Some("channel-validation.schema.json"),
        Some("hgym/tbl-validation/v1") => Some("tbl-validation.schema.json"),
        Some("hgym/train/v1") => Some("train.schema.json"),
        Some("hgym/eval/v1") => Some("eval.schema.json"),
        Some("hgym/eval-manifest/v1") => Some("eval-manifest.schema.json"),
        Some("hgym/seeds/v1") => Some("seeds.schema.json"),
        Some("hgym/comparison/v1") => Some("comparison.schema.json"),
        Some("hgym/transfer/v1") => Some("transfer.schema.json"),
        Some("hgym/transfer-deployment/v1") => Some("transfer-deployment.schema.json"),
        Some("hgym/deployment-arm/v1") => Some("deployment-arm.schema.json"),
        Some("hgym/rollout/v1") => Some("rollout.schema.json"),
        Some("hgym/leaderboard/v1") => Some("leaderboard.schema.json"),
        Some("hgym/hf-export/v1") => Some("hf-export.schema.json"),
        Some(_) => None,
        None => match path.file_name().and_then(|n| n.to_str()) {
            Some("policy.json") => Some("policy.schema.json"),
            Some("init_from.json") => Some("init-from.schema.json"),
            Some("metrics.json") if v.get("c_d").is_some() => Some("rollout-metrics.schema.json"),
            _ => None,
        },
    };
    by_field
}

#[test]
fn every_result_json_matches_its_schema() {
    let schemas = repo().join("schemas");
    let mut opts = jsonschema::options();
    let mut loaded = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(&schemas).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(e.path()).unwrap()).unwrap_or_else(|err| panic!("{name}: {err}"));
        opts = opts.with_resource(
            format!("https://hgym.dev/schemas/{name}"),
            jsonschema::Resource::from_contents(v.clone()).unwrap(),
        );
        loaded.insert(name, v);
    }
    let files = files_under(&repo().join("results"), &|p| p.extension().is_some_and(|x| x == "json"));
    assert!(files.len() > 20, "expected the committed results");
    let mut counts = std::collections::BTreeMap::new();
    for f in &files {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let name = schema_file(f, &v).unwrap_or_else(|| panic!("{} has no schema in schemas/", f.display()));
        let validator = opts.build(&loaded[name]).unwrap_or_else(|e| panic!("{name} does not compile: {e}"));
        let errors: Vec<String> = validator
            .iter_errors(&v)
            .take(5)
            .map(|e| format!("{e} at {}", e.instance_path))
            .collect();
        assert!(errors.is_empty(), "{} does not match schemas/{name}: {errors:?}", f.display());
        *counts.entry(name).or_insert(0) += 1;
    }
    println!("validated {} files: {counts:?}", files.len());
}

/// Every bundled validation case has a committed report in `results/validation/`, produced from
/// the case file as it is now (same SHA-256) at the default level: editing a case without
/// re-running it, or committing a coarse run, fails here.
#[test]
fn committed_validation_reports_come_from_the_current_case_files() {
    let cases = hgym::validate::bundled().expect("bundled cases parse");
    assert!(cases.len() >= 9, "expected the bundled cases, found {}", cases.len());
    let mut stale = vec![];
    for c in &cases {
        let name = &c.case.case.name;
        let path = repo().join("results/validation").join(format!("{name}.json"));
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let report: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        if report["case_hash"].as_str() != Some(c.hash.as_str()) {
            stale.push(format!("{name}: report from case {}, file is {}", report["case_hash"], c.hash));
        }
        if report["level"].as_str() != Some("default") {
            stale.push(format!("{name}: report at level {}, not default", report["level"]));
        }
    }
    assert!(
        stale.is_empty(),
        "re-run `hgym validate --case benchmarks/validation/<name>.toml`: {stale:#?}"
    );
}
