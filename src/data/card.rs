//! The dataset card (`README.md`) of an exported dataset: YAML front matter in the form the
//! Hugging Face Hub reads (`license`, `pretty_name`, `tags`, `task_categories`,
//! `size_categories`, and `configs` with their `data_files`), then what the data is: per
//! environment the runs (policy, seeds, level, code version), the env spec and its hash, the
//! columns, and how to load it.

use std::collections::BTreeMap;
use std::fmt::Write;

use super::hf::{ExportOptions, ExportReport};
use super::read::Trajectory;

/// The Hub's `size_categories` bucket of a row count.
pub fn size_category(rows: usize) -> &'static str {
    match rows {
        0..1_000 => "n<1K",
        1_000..10_000 => "1K<n<10K",
        10_000..100_000 => "10K<n<100K",
        100_000..1_000_000 => "100K<n<1M",
        1_000_000..10_000_000 => "1M<n<10M",
        _ => "10M<n<100M",
    }
}

/// YAML double-quoted string.
fn q(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

pub fn card(report: &ExportReport, trajectories: &[&Trajectory], opts: &ExportOptions) -> String {
    let envs: Vec<&String> = report.configs.iter().filter(|c| !c.ends_with("-fields")).collect();
    let title = opts.pretty_name.clone().unwrap_or_else(|| {
        format!(
            "hgym flow-control trajectories: {}",
            envs.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        )
    });
    let mut s = String::new();
    let _ = writeln!(s, "---");
    let _ = writeln!(s, "license: {}", opts.license);
    let _ = writeln!(s, "pretty_name: {}", q(&title));
    let _ = writeln!(s, "tags:");
    for t in ["reinforcement-learning", "flow-control", "fluid-dynamics", "cfd", "hgym"] {
        let _ = writeln!(s, "- {t}");
    }
    let _ = writeln!(s, "task_categories:\n- reinforcement-learning");
    let _ = writeln!(s, "size_categories:\n- {}", size_category(report.rows));
    let _ = writeln!(s, "configs:");
    for (k, c) in report.configs.iter().enumerate() {
        let (folder, env) = match c.strip_suffix("-fields") {
            Some(env) => ("fields", env),
            None => ("data", c.as_str()),
        };
        let _ = writeln!(s, "- config_name: {}", q(c));
        let _ = writeln!(
            s,
            "  data_files:\n  - split: train\n    path: {}",
            q(&format!("{folder}/{env}/*.parquet"))
        );
        if k == 0 {
            let _ = writeln!(s, "  default: true");
        }
    }
    let _ = writeln!(s, "---\n");
    let _ = writeln!(s, "# {title}\n");
    let _ = writeln!(
        s,
        "Trajectories of flow-control environments simulated with {}: \
         {} control steps in {} trajectory files{}. Exported from MCAP trajectory files by \
         `hgym export --to hf`; every run below names the code version and the hash of the \
         environment spec it used, so the numbers can be regenerated.\n",
        report.code_version,
        report.rows,
        report.runs.len(),
        if report.snapshots > 0 {
            format!(", with {} flow-field snapshots", report.snapshots)
        } else {
            String::new()
        }
    );
    let _ = writeln!(s, "## Loading\n\n```python\nfrom datasets import load_dataset\n");
    for c in &report.configs {
        let _ = writeln!(s, "ds = load_dataset(\"<user>/<name>\", {}, split=\"train\")", q(c));
    }
    let _ = writeln!(
        s,
        "```\n\nLocally: `load_dataset(\"parquet\", data_files=\"data/{}/*.parquet\")` or \
         `pandas.read_parquet(\"data/{}\")`.\n",
        envs.first().map(|s| s.as_str()).unwrap_or("ENV"),
        envs.first().map(|s| s.as_str()).unwrap_or("ENV")
    );
    let _ = writeln!(s, "## Columns (configs named after the environment)\n");
    let _ = writeln!(s, "| column | type | meaning |\n|---|---|---|");
    for (c, t, m) in [
        ("run", "string", "the trajectory's folder (one hgym run/eval/train result)"),
        ("env_id", "string", "environment ID"),
        ("policy", "string", "policy or algorithm that acted"),
        ("seed", "int64", "reset seed of the episode (null if unknown)"),
        ("episode", "int64", "episode index within the run"),
        ("step", "int64", "control step; 0 is the reset (no action, no reward)"),
        ("t", "float64", "simulated time (units of the env: D/U for bluff bodies)"),
        ("obs", "list<float64>", "observation after the step"),
        ("action", "list<float64>", "normalised action in [-1, 1] (null at step 0)"),
        ("action_physical", "list<float64>", "the action in physical units (null at step 0)"),
        ("reward", "float64", "reward of the step (null at step 0)"),
        ("terminated / truncated", "bool", "Gymnasium episode ends"),
        ("c_d, c_l, ...", "float64", "every numeric info value of the env, snake case"),
    ] {
        let _ = writeln!(s, "| `{c}` | {t} | {m} |");
    }
    if report.snapshots > 0 {
        let _ = writeln!(
            s,
            "\nConfigs `<ENV>-fields`: one row per snapshot: `episode`, `step`, `t`, `nx`, `ny`, \
             `extent` (x0, x1, y0, y1), and `u`, `v`, `vorticity` as float32 lists, row-major \
             `f[y * nx + x]`, NaN inside bodies."
        );
    }
    let mut specs: BTreeMap<&str, (&str, &str)> = BTreeMap::new();
    for t in trajectories {
        let g = |k: &str| t.manifest.get(k).map(|s| s.as_str()).unwrap_or("");
        specs.entry(t.env_id()).or_insert((g("spec_hash"), g("spec")));
    }
    for env in &envs {
        let _ = writeln!(s, "\n## {env}\n");
        let _ = writeln!(
            s,
            "| run | policy | level | seeds | episodes | steps | code | commit |\n|---|---|---|---|---|---|---|---|"
        );
        for r in report.runs.iter().filter(|r| &&r.env_id == env) {
            let _ = writeln!(
                s,
                "| `{}` | {} | {} | {} | {} | {} | {} | {} |",
                r.run,
                r.policy,
                r.level,
                r.seeds,
                r.episodes,
                r.rows,
                r.code_version,
                r.git_commit.get(..10).unwrap_or(&r.git_commit)
            );
        }
        if let Some((hash, spec)) = specs.get(env.as_str()) {
            let pretty = serde_json::from_str::<serde_json::Value>(spec)
                .and_then(|v| serde_json::to_string_pretty(&v))
                .unwrap_or_else(|_| spec.to_string());
            let _ = writeln!(s, "\nEnvironment spec (hash `{hash}`):\n\n```json\n{pretty}\n```");
        }
    }
    let _ = writeln!(
        s,
        "\n## Citation\n\nThe environments follow HydroGym (Lagemann et al., 2025) where the spec says so."
    );
    s
}
