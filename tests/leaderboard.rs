//! `hgym leaderboard` rebuilds the committed leaderboard from the committed results: the same
//! entries as `results/leaderboard.json`, the markdown table and one bar chart per group.

mod common;

use std::path::Path;
use std::process::Command;

/// Copies every `metrics.json` and `manifest.json` below `from` to the same place below `to`
/// (what the leaderboard reads; trajectories and plots are left behind).
fn copy_results(from: &Path, to: &Path) {
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let p = e.path();
        let q = to.join(e.file_name());
        if p.is_dir() {
            copy_results(&p, &q);
        } else if matches!(p.file_name().and_then(|n| n.to_str()), Some("metrics.json" | "manifest.json")) {
            std::fs::create_dir_all(to).unwrap();
            std::fs::copy(&p, &q).unwrap();
        }
    }
}

#[test]
fn leaderboard_rebuilds_the_committed_one_from_the_committed_results() {
    let root = &common::repo();
    let tmp = tempfile::tempdir().unwrap();
    let results = tmp.path().join("results");
    copy_results(&root.join("results"), &results);
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["leaderboard", "--results", results.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |p: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
    };
    let built = read(&results.join("leaderboard.json"));
    let committed = read(&root.join("results/leaderboard.json"));
    let entries = built["entries"].as_array().unwrap();
    assert!(!entries.is_empty());
    assert_eq!(
        built, committed,
        "results/leaderboard.json is not what the committed results give: run `hgym leaderboard`"
    );
    let md = std::fs::read_to_string(results.join("LEADERBOARD.md")).unwrap();
    let pngs = std::fs::read_dir(results.join("leaderboard")).unwrap().count();
    println!(
        "{} entries, {} markdown lines, {pngs} bar charts",
        entries.len(),
        md.lines().count()
    );
    for e in entries {
        assert!(
            md.contains(e["env_id"].as_str().unwrap()),
            "{} missing from LEADERBOARD.md",
            e["env_id"]
        );
    }
    assert!(pngs >= 1);
    // A single run has no spread to show: its row gives the mean alone.
    for row in md
        .lines()
        .filter(|l| l.starts_with("| ") && l.split('|').nth(4).map(str::trim) == Some("1"))
    {
        assert!(!row.contains('±'), "a one-run entry shows a spread: {row}");
    }
    // Stale entries: the pinball TD3 runs were trained on spec 2560ad80, which the registry no
    // longer gives Pinball_2D_Re100; the Kolmogorov comparison runs use an [env] override of the
    // objective (spec 777475c1), which it still gives. Stale entries come after every current one.
    let stale = |hash: &str| {
        entries
            .iter()
            .find(|e| e["spec_hash"].as_str().unwrap().starts_with(hash))
            .map(|e| e["stale"] == true)
            .unwrap()
    };
    assert!(stale("2560ad80") && !stale("777475c1") && !stale("a42c4a1a"));
    let heading = md.find("# Stale").expect("a stale section");
    assert!(md.find("spec 2560ad80").unwrap() > heading && md.find("spec 777475c1").unwrap() < heading);
    // Each current entry of a flow with references says how far its uncontrolled flow is from
    // the literature at its level: the committed row of `hgym validate --env`, in the JSON and
    // under the section's heading; a stale entry says nothing of a flow that no longer exists.
    let table: toml::Table = std::fs::read_to_string(root.join("benchmarks/envs/fidelity.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let st = table["Cylinder_2D_Re100@coarse"]["strouhal"].as_float().unwrap();
    let cylinder = entries
        .iter()
        .find(|e| e["spec_hash"].as_str().unwrap().starts_with("a42c4a1a") && e["policy"] == "td3")
        .unwrap();
    let text = cylinder["literature"]
        .as_str()
        .expect("a literature line for Cylinder_2D_Re100 at coarse");
    assert!(
        text.starts_with(&format!("St {st:.4} (")) && text.contains("cylinder_re100"),
        "{text}"
    );
    assert!(md.contains(&format!("The uncontrolled flow at this level: {text}.")));
    assert!(entries.iter().filter(|e| e["stale"] == true).all(|e| e.get("literature").is_none()));
    // Every current entry says something, if only that hgym bundles no reference for its flow.
    for e in entries.iter().filter(|e| e["stale"] == false) {
        assert!(e["literature"].as_str().is_some_and(|t| !t.is_empty()), "{}", e["env_id"]);
    }
    // Every entry says how to make it again; a training run's command takes the run's own
    // configuration from its folder (`--config RUN_DIR`), and each entry links its folders.
    let td3 = "hgym train --env Cylinder_2D_Re100 --algo td3 --res coarse --seeds 0..=4 \
               --config results/train/Cylinder_2D_Re100-td3-coarse/seed0";
    assert!(entries
        .iter()
        .all(|e| e["reproduce"].as_str().is_some_and(|c| c.starts_with("hgym "))));
    assert!(entries.iter().any(|e| e["reproduce"] == td3), "no entry reproduced by {td3}");
    assert!(md.contains(&format!("`{td3}`")) && md.contains("[seed4](train/Cylinder_2D_Re100-td3-coarse/seed4)"));
    // A transfer protocol's three arms are three entries, not one: from scratch, fine-tuned
    // (named by its source flow) and zero-shot (its five evaluations one entry, not five
    // baselines named by a path), each reproduced by the protocol.
    let arms: Vec<(&str, &str, u64)> = entries
        .iter()
        .filter(|e| e["env_id"] == "Cylinder_2D_Re1000")
        .map(|e| {
            (
                e["policy"].as_str().unwrap(),
                e["kind"].as_str().unwrap(),
                e["seeds"].as_u64().unwrap(),
            )
        })
        .collect();
    for arm in [
        ("td3", "learned", 5),
        ("td3 fine-tuned from Cylinder_2D_Re200", "learned", 5),
        ("td3 zero-shot from Cylinder_2D_Re200", "zero-shot", 5),
    ] {
        assert!(arms.contains(&arm), "{arm:?} not among {arms:?}");
    }
    assert!(entries
        .iter()
        .filter(|e| e["env_id"] == "Cylinder_2D_Re1000" && e["kind"] != "baseline")
        .all(|e| e["reproduce"] == "hgym transfer --protocol benchmarks/protocols/transfer/cylinder_re200_re1000.toml"));
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .current_dir(root)
        .args([
            "train",
            "--print-config",
            "--config",
            "results/train/Cylinder_2D_Re100-td3-coarse/seed0",
        ])
        .output()
        .unwrap();
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && printed.contains("steps = 30000"), "{printed}");
    // The gust flow ranks by the lift deviation reduction, which its section shows, and the
    // P controller on dC_L (+9.9 %) is above TD3 (+0.6 %) there.
    let gust: Vec<&serde_json::Value> = entries
        .iter()
        .filter(|e| e["env_id"] == "NACA0012Gust_2D_Re1000_AoA20" && e["level"] == "coarse")
        .collect();
    let lift = |e: &serde_json::Value| e["lift_deviation_reduction_pct"]["mean"].as_f64().unwrap();
    let rank = |policy: &str| gust.iter().position(|e| e["policy"] == policy).unwrap();
    assert!(gust.iter().all(|e| lift(e).is_finite()), "{gust:?}");
    assert_eq!(gust[rank("td3")]["seeds"], 5);
    assert!(rank("pd=dC_L,-0.6,0") < rank("td3") && lift(gust[0]) >= lift(gust[gust.len() - 1]));
    assert!(md.contains("| rank | policy | kind | seeds | lift deviation reduction | drag reduction |"));
    // The coarse-trained cylinder policies evaluated at default: one entry per algorithm, its
    // five seeds together, reproduced by one command per run folder.
    let moved = entries
        .iter()
        .find(|e| e["env_id"] == "Cylinder_2D_Re100" && e["level"] == "default" && e["policy"] == "td3 trained at coarse")
        .expect("the coarse TD3 policies at default");
    assert_eq!((moved["kind"].as_str(), moved["seeds"].as_u64()), (Some("zero-shot"), Some(5)));
    let command = moved["reproduce"].as_str().unwrap();
    let eval =
        |s: u64| format!("hgym eval --env Cylinder_2D_Re100 --policy results/train/Cylinder_2D_Re100-td3-coarse/seed{s} --res default");
    assert!(
        command.starts_with(&eval(0)) && (1..5).all(|s| command.contains(&format!(" && {}", eval(s)))),
        "{command}"
    );
}

/// A folder whose metrics.json is damaged is listed as a problem row (JSON, markdown, a warning
/// on stderr), not silently left out; the readable runs are still ranked.
#[test]
fn malformed_result_folders_become_problem_rows() {
    let root = &common::repo();
    let tmp = tempfile::tempdir().unwrap();
    let results = tmp.path().join("results");
    copy_results(&root.join("results/eval"), &results.join("eval"));
    let broken = results.join("eval/Cylinder_2D_Re100-zero-coarse");
    std::fs::write(broken.join("metrics.json"), "{\"schema\": \"hgym/eval/v1\", \"env_id\": ").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_hgym"))
        .args(["leaderboard", "--json", "--results", results.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let lb: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let problems = lb["problems"].as_array().expect("a problems list");
    assert_eq!(problems.len(), 1, "{lb:#}");
    assert!(problems[0]["dir"].as_str().unwrap().ends_with("Cylinder_2D_Re100-zero-coarse"));
    assert!(problems[0]["message"].as_str().unwrap().contains("not JSON"));
    assert!(!lb["entries"].as_array().unwrap().is_empty());
    assert!(String::from_utf8_lossy(&o.stderr).contains("could not be read"));
    let md = std::fs::read_to_string(results.join("LEADERBOARD.md")).unwrap();
    assert!(md.contains("Folders that could not be read") && md.contains("Cylinder_2D_Re100-zero-coarse"));
}
