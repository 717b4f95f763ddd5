//! `hgym export --to hf`: trajectories written by `hgym eval` become a dataset folder that
//! Python `datasets` and pandas load (tests/read_hf.py, in the venv `make setup` builds), with
//! the same numbers as the MCAP files, flow-field snapshots included.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::python;

fn hgym(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hgym")).args(args).output().expect("run hgym")
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}\nstdout: {}\nstderr: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn load_with_python(ds: &Path, runs: &Path, hf_home: &Path) -> serde_json::Value {
    let script = common::repo().join("tests/read_hf.py");
    let o = Command::new(python())
        .arg(script)
        .arg(ds)
        .arg(runs)
        .env("HF_HOME", hf_home)
        .output()
        .expect("run python");
    serde_json::from_str(&ok(&o)).unwrap()
}

#[test]
fn export_loads_with_datasets_and_pandas_and_matches_the_mcap_files() {
    let tmp = tempfile::tempdir().unwrap();
    let runs = tmp.path().join("runs");
    let r = runs.to_str().unwrap();
    ok(&hgym(&[
        "eval",
        "--policy",
        "random",
        "--env",
        "Kolmogorov_2D_Re40",
        "--episodes",
        "2",
        "--out",
        r,
        "--fields-every",
        "40",
    ]));
    ok(&hgym(&[
        "eval",
        "--policy",
        "zero",
        "--env",
        "Cylinder_2D_Re100",
        "--episodes",
        "1",
        "--out",
        r,
        "--fields-every",
        "100",
    ]));
    let ds = tmp.path().join("ds");
    let text = ok(&hgym(&[
        "export",
        "--to",
        "hf",
        r,
        ds.to_str().unwrap(),
        "--shard-rows",
        "150",
        "--json",
    ]));
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(report["schema"], "hgym/hf-export/v1");
    let schema: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(common::repo().join("schemas/hf-export.schema.json")).unwrap()).unwrap();
    let on_disk: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(ds.join("hgym_export.json")).unwrap()).unwrap();
    assert_eq!(on_disk, report);
    let errors: Vec<String> = jsonschema::validator_for(&schema)
        .unwrap()
        .iter_errors(&report)
        .map(|e| e.to_string())
        .collect();
    assert!(
        errors.is_empty(),
        "hgym_export.json matches schemas/hf-export.schema.json: {errors:?}"
    );
    // Kolmogorov: 2 episodes x (100 actions + reset); cylinder: 200 actions + reset.
    assert_eq!(report["rows"], 2 * 101 + 201, "{report}");
    // Snapshots at each reset, every K actions and at each episode's end: Kolmogorov 0, 40, 80,
    // 100 twice; cylinder 0, 100, 200.
    assert_eq!(report["snapshots"], 8 + 3, "{report}");
    assert_eq!(
        report["configs"],
        serde_json::json!([
            "Cylinder_2D_Re100",
            "Cylinder_2D_Re100-fields",
            "Kolmogorov_2D_Re40",
            "Kolmogorov_2D_Re40-fields"
        ])
    );

    let s = load_with_python(&ds, &runs, &tmp.path().join("hf_home"));
    assert_eq!(s["card"]["license"], "cc-by-4.0");
    assert_eq!(s["card"]["task_categories"], serde_json::json!(["reinforcement-learning"]));
    assert_eq!(s["grid_schemas"], serde_json::json!(["foxglove.Grid"]));
    let k = &s["configs"]["Kolmogorov_2D_Re40"];
    assert_eq!(k["rows"], 202, "{s}");
    assert_eq!(k["pandas_rows"], 202);
    assert_eq!(k["shards"], 2, "150 rows per shard: {k}");
    assert_eq!(k["mismatches"], 0, "every obs and reward equals the MCAP file's: {k}");
    assert_eq!(k["null_actions"], 2, "one reset row per episode: {k}");
    assert_eq!(k["episodes"], 2);
    let cols = k["columns"].as_array().unwrap();
    for c in [
        "run",
        "env_id",
        "policy",
        "seed",
        "episode",
        "step",
        "t",
        "obs",
        "action",
        "reward",
        "dissipation",
    ] {
        assert!(cols.iter().any(|v| v == c), "column {c} in {cols:?}");
    }
    let c = &s["configs"]["Cylinder_2D_Re100"];
    assert_eq!(c["rows"], 201);
    assert_eq!(c["mismatches"], 0, "{c}");
    for col in ["c_d", "c_l"] {
        assert_eq!(c["dtypes"][col], "float64", "{c}");
    }
    let f = &s["configs"]["Kolmogorov_2D_Re40-fields"];
    assert_eq!(f["rows"], 8);
    assert_eq!(f["field_mismatches"], 0.0, "vorticity in Parquet equals the MCAP grid: {f}");
    assert!(f["nx"].as_i64().unwrap() >= 32);
    assert_eq!(f["nan_cells"], 0, "a periodic box has no bodies: {f}");
    let f = &s["configs"]["Cylinder_2D_Re100-fields"];
    assert_eq!(f["rows"], 3);
    assert_eq!(f["field_mismatches"], 0.0, "{f}");
    assert!(f["nan_cells"].as_i64().unwrap() > 0, "the cylinder's cells are NaN: {f}");

    // Re-export into the same folder replaces the data; a foreign folder is refused.
    ok(&hgym(&["export", "--to", "hf", r, ds.to_str().unwrap()]));
    let foreign = tmp.path().join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let o = hgym(&["export", "--to", "hf", r, foreign.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not an hgym export"));
    let o = hgym(&["export", "--to", "hf", tmp.path().join("nothing").to_str().unwrap(), "x"]);
    assert_eq!(o.status.code(), Some(2));
}

/// A trajectory whose manifest's env_id would name a folder outside the output (`../../x`, an
/// absolute path) or none at all: export refuses it with exit 2, naming the file, and writes
/// nothing anywhere.
#[test]
fn export_refuses_env_ids_that_are_not_ids() {
    use hgym_agents::Info;
    let tmp = tempfile::tempdir().unwrap();
    let escape = tmp.path().join("escape");
    let hostile = [
        Some("../../escape/x".to_string()),
        Some(escape.join("abs").display().to_string()),
        Some("Cylinder_2D_Re100/../../../escape".to_string()),
        None,
    ];
    for (k, env_id) in hostile.iter().enumerate() {
        let runs = tmp.path().join(format!("runs{k}"));
        std::fs::create_dir_all(runs.join("r")).unwrap();
        let mut manifest = std::collections::BTreeMap::new();
        if let Some(id) = env_id {
            manifest.insert("env_id".to_string(), id.clone());
        }
        let mut w = hgym::data::trajectory::TrajectoryWriter::create(&runs.join("r/trajectory.mcap"), 1.0, manifest).unwrap();
        w.reset(&[0.0], &Info::default()).unwrap();
        w.finish().unwrap();
        let out = tmp.path().join(format!("deep/a/b/out{k}"));
        let o = hgym(&["export", "--to", "hf", runs.to_str().unwrap(), out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{env_id:?}: {err}");
        assert!(err.contains("trajectory.mcap") && err.contains("env_id"), "{env_id:?}: {err}");
        assert!(
            !tmp.path().join("deep").exists(),
            "{env_id:?}: nothing written, in or beside the output"
        );
        assert!(!escape.exists(), "{env_id:?}: nothing at the absolute path");
    }
}
