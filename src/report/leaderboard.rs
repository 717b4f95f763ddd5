//! `hgym leaderboard`: aggregates result folders into `results/leaderboard.json`,
//! `results/LEADERBOARD.md` and one bar chart per environment (`results/leaderboard/<ID>.png`).
//!
//! Sources: training runs (`results/train/<ID>-<algo>-<level>/seed<S>/` and the runs of
//! comparison and transfer protocols under `results/compare/` and `results/transfer/`), each with
//! `metrics.json` (final deterministic evaluation) and `manifest.json`; classical baselines
//! evaluated with `hgym eval --out results/eval` (`results/eval/<ID>-<policy>-<level>/`), and
//! policies of another flow evaluated zero-shot. Entries are grouped by (environment, level,
//! algorithm or baseline; a fine-tuned or zero-shot policy by its source flow too); per entry:
//! seeds, mean +- std over seeds of the drag reduction (for flows with a drag coefficient) and
//! of the return (and on the gust flows of the lift deviation reduction), samples, wall time,
//! code versions. Ranking: by the lift deviation reduction on the gust flows, by drag reduction
//! where there is one, else by return ([`Figure`]).
//!
//! An entry whose spec hash is not the one today's registry gives its runs (the registered spec
//! with the run's `[env]` overrides) is *stale*: the environment it was trained on no longer
//! exists. Stale entries are kept, in a section of their own, never ranked with current ones.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::report::eval::{EvalReport, LiftDeviationStat, Stat};
use crate::report::plots;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Entry {
    pub env_id: String,
    pub level: String,
    /// The environment spec the runs share (overrides such as another objective change it).
    pub spec_hash: String,
    /// Algorithm (`td3`, `ppo`, ...) or baseline (`zero`, `opposition=1`, ...).
    pub policy: String,
    pub kind: String,
    pub seeds: usize,
    pub drag_reduction_pct: Stat,
    /// Gust flows: the reduction of the lift's deviation from the undisturbed mean
    /// (`LiftDeviation` of the evaluations), the figure they rank by.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lift_deviation_reduction_pct: Option<Stat>,
    pub ret: Stat,
    pub samples: Option<u64>,
    pub wall_time_s: Option<f64>,
    pub code_versions: Vec<String>,
    pub runs: Vec<PathBuf>,
    /// The command that makes these runs again (from the repository's root).
    pub reproduce: String,
    /// The spec hash is not the current one for these runs (see the module's doc).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stale: bool,
    /// How far the uncontrolled flow of this environment and level is from the literature
    /// (`hgym validate --env ID --level L`), so a reader sees the physics behind the numbers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub literature: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Leaderboard {
    pub schema: String,
    pub entries: Vec<Entry>,
    /// Result folders that hold a `metrics.json` that could not be read as an evaluation: listed,
    /// not silently left out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub problems: Vec<Problem>,
}

/// A result folder left out of the ranking, and why.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Problem {
    pub dir: PathBuf,
    pub message: String,
}

struct Run {
    env_id: String,
    level: String,
    policy: String,
    kind: &'static str,
    report: EvalReport,
    samples: Option<u64>,
    wall: Option<f64>,
    version: Option<String>,
    /// The run's training configuration (its `[env]` overrides change the spec).
    config_toml: Option<String>,
    /// A training run's seed and the run it was fine-tuned from; an evaluation's first seed
    /// and episodes.
    seed: Option<u64>,
    init_from: Option<String>,
    episodes: Option<u64>,
    dir: PathBuf,
    /// What the command that made the run was given: a training run's `--algo`, an
    /// evaluation's `--policy` (a baseline or a run folder).
    made_with: String,
}

/// The spec hash today's registry gives an environment ID with a run's training configuration
/// (`None`: the ID or the configuration is unknown today).
pub type CurrentHash<'a> = &'a dyn Fn(&str, Option<&str>) -> Option<String>;

/// What is known of the uncontrolled flow of an environment ID at a level (name) with a run's
/// training configuration against the literature (`None`: nothing to say).
pub type Literature<'a> = &'a dyn Fn(&str, &str, Option<&str>) -> Option<String>;

fn read_json(p: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{} is not JSON: {e}", p.display()))
}

/// The evaluation in folder `p`'s `metrics.json`: `Ok(None)` for `hgym run`'s time series (no
/// schema, a `t` column), which are not evaluations; an error for anything else unreadable.
fn read_eval(p: &Path) -> Result<Option<(EvalReport, serde_json::Value)>, String> {
    let v = read_json(&p.join("metrics.json"))?;
    if v.get("schema").is_none() && v.get("t").is_some() {
        return Ok(None);
    }
    if v["schema"] != "hgym/eval/v1" {
        return Err(format!("metrics.json has schema {}, not hgym/eval/v1", v["schema"]));
    }
    let report = serde_json::from_value::<EvalReport>(v).map_err(|e| format!("metrics.json: {e}"))?;
    let manifest = match p.join("manifest.json") {
        m if m.exists() => read_json(&m)?,
        _ => serde_json::Value::Null,
    };
    Ok(Some((report, manifest)))
}

/// How an evaluation whose `--policy` is a training run folder (relative to `root`) is labelled:
/// `td3 zero-shot from Cylinder_2D_Re200` for a run of another environment than `env_id`,
/// `td3 trained at coarse` for a run of the same environment at another level than `level`.
fn zero_shot_source(root: &Path, policy: &str, env_id: &str, level: &str) -> Option<String> {
    let source = read_json(&root.join(policy).join("manifest.json")).ok()?;
    let (algo, from, at) = (source["algo"].as_str()?, source["env_id"].as_str()?, source["level"].as_str()?);
    if source["schema"] != "hgym/train/v1" {
        return None;
    }
    if from != env_id {
        Some(format!("{algo} zero-shot from {from}"))
    } else {
        (at != level).then(|| format!("{algo} trained at {at}"))
    }
}

/// Every folder below `dir` holding a `metrics.json` of the evaluation schema; folders whose
/// `metrics.json` cannot be read go to `problems`.
fn collect(dir: &Path, root: &Path, out: &mut Vec<Run>, problems: &mut Vec<Problem>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if !p.is_dir() {
            continue;
        }
        let shown = p.strip_prefix(root).unwrap_or(&p).to_path_buf();
        if !p.join("metrics.json").exists() {
            collect(&p, root, out, problems);
            continue;
        }
        let (report, manifest) = match read_eval(&p) {
            Ok(Some(r)) => r,
            Ok(None) => continue,
            Err(message) => {
                problems.push(Problem { dir: shown, message });
                continue;
            }
        };
        let trained = manifest["schema"] == "hgym/train/v1";
        let (made_with, policy, kind) = if trained {
            let Some(algo) = manifest["algo"].as_str() else {
                problems.push(Problem {
                    dir: shown,
                    message: "manifest.json of a training run names no algo".into(),
                });
                continue;
            };
            let label = match manifest["init_from"]["env_id"].as_str() {
                Some(source) => format!("{algo} fine-tuned from {source}"),
                None => algo.to_string(),
            };
            (algo.to_string(), label, "learned")
        } else {
            let evaluated = manifest["policy"].as_str().unwrap_or(&report.policy).to_string();
            match zero_shot_source(root, &evaluated, &report.env_id, &report.level) {
                Some(label) => (evaluated, label, "zero-shot"),
                None => (evaluated.clone(), evaluated, "baseline"),
            }
        };
        out.push(Run {
            env_id: report.env_id.clone(),
            level: report.level.clone(),
            policy,
            kind,
            samples: manifest["samples"].as_u64(),
            wall: manifest["manifest"]["wall_time_s"].as_f64(),
            version: manifest["manifest"]["git_commit"]
                .as_str()
                .map(|c| format!("{} ({c})", manifest["manifest"]["code_version"].as_str().unwrap_or("hgym")))
                .or_else(|| manifest["manifest"]["code_version"].as_str().map(|s| s.to_string())),
            config_toml: manifest["config_toml"].as_str().map(str::to_string),
            seed: manifest["seed"].as_u64().or(manifest["eval_seed"].as_u64()),
            init_from: manifest["init_from"]["dir"].as_str().map(str::to_string),
            episodes: manifest["episodes"].as_u64(),
            dir: shown,
            made_with,
            report,
        });
    }
}

/// Builds the leaderboard from everything under `results` (optionally one environment);
/// `current` tells which spec hashes are today's, `literature` how far each current entry's
/// uncontrolled flow is from the literature.
pub fn build(results: &Path, env: Option<&str>, current: CurrentHash, literature: Literature) -> Leaderboard {
    let (mut runs, mut problems) = (vec![], vec![]);
    let root = results.parent().unwrap_or(Path::new("."));
    collect(results, root, &mut runs, &mut problems);
    let mut groups: BTreeMap<(String, String, String, String), Vec<Run>> = BTreeMap::new();
    for r in runs.into_iter().filter(|r| env.is_none_or(|e| r.env_id == e)) {
        let key = (r.env_id.clone(), r.level.clone(), r.report.spec_hash.clone(), r.policy.clone());
        groups.entry(key).or_default().push(r);
    }
    let mut entries: Vec<Entry> = groups
        .into_iter()
        .map(|((env_id, level, spec_hash, policy), runs)| {
            let col = |f: &dyn Fn(&Run) -> f64| Stat::of(&runs.iter().map(f).collect::<Vec<_>>());
            let mut versions: Vec<String> = runs.iter().filter_map(|r| r.version.clone()).collect();
            versions.sort();
            versions.dedup();
            let samples: Vec<u64> = runs.iter().filter_map(|r| r.samples).collect();
            let walls: Vec<f64> = runs.iter().filter_map(|r| r.wall).collect();
            let stale = runs
                .iter()
                .any(|r| current(&env_id, r.config_toml.as_deref()).as_deref() != Some(spec_hash.as_str()));
            Entry {
                reproduce: reproduce(&env_id, &level, &runs),
                literature: (!stale)
                    .then(|| literature(&env_id, &level, runs[0].config_toml.as_deref()))
                    .flatten(),
                stale,
                kind: runs[0].kind.to_string(),
                seeds: runs.len(),
                drag_reduction_pct: col(&|r| r.report.drag_reduction_pct.mean),
                lift_deviation_reduction_pct: LiftDeviationStat::reduction_over(runs.iter().map(|r| &r.report)),
                ret: col(&|r| r.report.ret.mean),
                samples: (!samples.is_empty()).then(|| samples.iter().sum::<u64>() / samples.len() as u64),
                wall_time_s: (!walls.is_empty()).then(|| walls.iter().sum::<f64>() / walls.len() as f64),
                code_versions: versions,
                runs: runs.iter().map(|r| r.dir.clone()).collect(),
                env_id,
                level,
                spec_hash,
                policy,
            }
        })
        .collect();
    let key = |e: &Entry| e.figure().of(e).mean;
    entries.sort_by(|a, b| {
        (a.stale, &a.env_id, &a.level, &a.spec_hash)
            .cmp(&(b.stale, &b.env_id, &b.level, &b.spec_hash))
            .then(key(b).total_cmp(&key(a)))
    });
    Leaderboard {
        schema: "hgym/leaderboard/v1".into(),
        entries,
        problems,
    }
}

/// What an entry ranks by: the lift deviation reduction on the gust flows, else the drag
/// reduction where there is a drag coefficient, else the return.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Figure {
    LiftDeviationReduction,
    DragReduction,
    Return,
}

impl Figure {
    /// The chart's axis label.
    pub fn label(self) -> &'static str {
        match self {
            Figure::LiftDeviationReduction => "lift deviation reduction (%)",
            Figure::DragReduction => "drag reduction (%)",
            Figure::Return => "evaluation return",
        }
    }

    /// The entry's value of this figure (NaN where it has none).
    pub fn of(self, e: &Entry) -> Stat {
        match self {
            Figure::LiftDeviationReduction => e.lift_deviation_reduction_pct.unwrap_or(Stat::of(&[])),
            Figure::DragReduction => e.drag_reduction_pct,
            Figure::Return => e.ret,
        }
    }
}

impl Entry {
    /// The figure this entry ranks by.
    pub fn figure(&self) -> Figure {
        match self.lift_deviation_reduction_pct {
            Some(l) if l.mean.is_finite() => Figure::LiftDeviationReduction,
            _ if self.drag_reduction_pct.mean.is_finite() => Figure::DragReduction,
            _ => Figure::Return,
        }
    }
}

/// The protocol that made a run of `results/transfer/<name>/` or `results/compare/<name>/` (the
/// protocols' files are named by their `name`).
fn protocol_command(dir: &Path) -> Option<String> {
    let mut parts = dir.components().map(|c| c.as_os_str().to_str());
    let (Some(Some("results")), Some(Some(command)), Some(Some(name))) = (parts.next(), parts.next(), parts.next()) else {
        return None;
    };
    match command {
        "transfer" => Some(format!("hgym transfer --protocol benchmarks/protocols/transfer/{name}.toml")),
        "compare" => Some(format!("hgym compare --protocol benchmarks/protocols/{name}.toml")),
        _ => None,
    }
}

/// The protocol that made the runs (`hgym transfer` / `hgym compare`); else `hgym train` with
/// the first run's configuration (`--config RUN_DIR`) over the entry's seeds, or `hgym eval` of
/// the baseline with its seeds.
fn reproduce(env: &str, level: &str, runs: &[Run]) -> String {
    let first = &runs[0];
    if let Some(command) = protocol_command(&first.dir) {
        return command;
    }
    if first.kind != "learned" {
        let config = first
            .config_toml
            .as_ref()
            .map(|_| format!(" --config {}", first.dir.display()))
            .unwrap_or_default();
        let out = first.dir.parent().unwrap_or(Path::new("results/eval")).display();
        // Several evaluated run folders (one per seed of a training): one command each.
        return runs
            .iter()
            .map(|r| {
                format!(
                    "hgym eval --env {env} --policy {} --res {level} --episodes {} --eval-seed {}{config} --out {out}",
                    r.made_with,
                    first.episodes.unwrap_or(first.report.episodes.len() as u64),
                    first.seed.unwrap_or(first.report.episodes.first().map_or(0, |e| e.seed)),
                )
            })
            .collect::<Vec<_>>()
            .join(" && ");
    }
    let mut seeds: Vec<u64> = runs.iter().filter_map(|r| r.seed).collect();
    seeds.sort();
    let contiguous = seeds.windows(2).all(|w| w[1] == w[0] + 1);
    let seeds = match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if contiguous && b > a => format!("{a}..={b}"),
        _ => seeds.iter().map(u64::to_string).collect::<Vec<_>>().join(","),
    };
    let init = first.init_from.as_ref().map(|d| format!(" --init-from {d}")).unwrap_or_default();
    format!(
        "hgym train --env {env} --algo {} --res {level} --seeds {seeds} --config {}{init}",
        first.made_with,
        first.dir.display()
    )
}

/// `results/train/X/seed0` as a link from `results/LEADERBOARD.md`.
fn link(dir: &Path) -> String {
    let rel = dir.strip_prefix("results").unwrap_or(dir);
    let name = dir
        .file_name()
        .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned());
    format!("[{name}]({})", rel.display())
}

/// `mean ± std` over an entry's `runs`; the mean alone for a single run, whose spread is unknown.
fn fmt_stat(s: &Stat, unit: &str, runs: usize) -> String {
    match (s.mean.is_finite(), runs) {
        (false, _) => "–".into(),
        (true, 0 | 1) => format!("{:+.2}{unit}", s.mean),
        (true, _) => format!("{:+.2}{unit} ± {:.2}", s.mean, s.std),
    }
}

/// The markdown table, one section per (environment, level).
pub fn markdown(lb: &Leaderboard) -> String {
    let mut s = String::from(
        "# hgym leaderboard\n\nGenerated by `hgym leaderboard` from the result folders under `results/`. \
         Drag reduction is against the uncontrolled flow of the same spec from the same initial states \
         (deterministic evaluation); mean ± std over seeds; an entry of one run (every baseline) shows its mean alone. \
         The gust flows rank by the lift deviation reduction, `100 (1 - mean |C_L - C_L,ref| / the uncontrolled flow's)` \
         with C_L,ref the undisturbed flow's mean lift at that level.\n",
    );
    let mut last = (String::new(), String::new(), String::new());
    let mut rank = 0;
    // Gust sections show the lift deviation reduction they rank by.
    let mut lift = false;
    let mut stale_heading = false;
    let mut commands = String::new();
    for e in &lb.entries {
        if e.stale && !stale_heading {
            stale_heading = true;
            s += "\n# Stale: trained on specs that are no longer registered\n\nThe environments below have changed since these runs (another spec hash for the same ID); \
                  their numbers are not comparable with the sections above and are kept for the record.\n";
        }
        let group = (e.env_id.clone(), e.level.clone(), e.spec_hash.clone());
        if group != last {
            s += &std::mem::take(&mut commands);
            last = group;
            rank = 0;
            let short = &e.spec_hash[..e.spec_hash.len().min(8)];
            s += &format!(
                "\n## {} ({}, spec {short})\n\n![{}](leaderboard/{}-{}-{short}.png)\n\n",
                e.env_id, e.level, e.env_id, e.env_id, e.level
            );
            if let Some(text) = &e.literature {
                s += &format!("The uncontrolled flow at this level: {text}.\n\n");
            }
            lift = e.lift_deviation_reduction_pct.is_some();
            let (head, rule) = if lift { ("lift deviation reduction | ", "---|") } else { ("", "") };
            s += &format!("| rank | policy | kind | seeds | {head}drag reduction | return | samples | wall time | code |\n|---|---|---|---|{rule}---|---|---|---|---|\n");
        }
        rank += 1;
        let lift_cell = match (lift, &e.lift_deviation_reduction_pct) {
            (false, _) => String::new(),
            (true, Some(l)) => format!("{} | ", fmt_stat(l, " %", e.seeds)),
            (true, None) => "– | ".into(),
        };
        s += &format!(
            "| {rank} | {} | {} | {} | {lift_cell}{} | {} | {} | {} | {} |\n",
            e.policy,
            e.kind,
            e.seeds,
            fmt_stat(&e.drag_reduction_pct, " %", e.seeds),
            fmt_stat(&e.ret, "", e.seeds),
            e.samples.map(|v| v.to_string()).unwrap_or_else(|| "–".into()),
            e.wall_time_s.map(|v| format!("{v:.0} s")).unwrap_or_else(|| "–".into()),
            e.code_versions.join(", ")
        );
        if commands.is_empty() {
            commands += "\nReproduce (from the repository's root), and the result folders:\n\n";
        }
        let links: Vec<String> = e.runs.iter().map(|d| link(d)).collect();
        commands += &format!("- {}: `{}` ({})\n", e.policy, e.reproduce, links.join(", "));
    }
    s += &commands;
    if !lb.problems.is_empty() {
        s += "\n## Folders that could not be read\n\n| folder | problem |\n|---|---|\n";
        for p in &lb.problems {
            s += &format!("| {} | {} |\n", p.dir.display(), p.message.replace('|', "\\|"));
        }
    }
    s
}

/// Writes `leaderboard.json`, `LEADERBOARD.md` and `leaderboard/<ID>-<level>.png` under `results`.
pub fn write(results: &Path, lb: &Leaderboard) -> Result<(), super::ReportError> {
    use super::ReportError;
    let json = serde_json::to_string_pretty(lb).map_err(|source| ReportError::Json {
        what: "the leaderboard".into(),
        source,
    })?;
    let path = results.join("leaderboard.json");
    std::fs::write(&path, json + "\n").map_err(ReportError::io(&path))?;
    let path = results.join("LEADERBOARD.md");
    std::fs::write(&path, markdown(lb)).map_err(ReportError::io(&path))?;
    let dir = results.join("leaderboard");
    std::fs::create_dir_all(&dir).map_err(ReportError::io(&dir))?;
    let mut by_env: BTreeMap<(String, String, String), Vec<&Entry>> = BTreeMap::new();
    for e in &lb.entries {
        let short = e.spec_hash[..e.spec_hash.len().min(8)].to_string();
        by_env.entry((e.env_id.clone(), e.level.clone(), short)).or_default().push(e);
    }
    for ((env, level, short), es) in by_env {
        // The section's figure: the one its best entry ranks by (entries are sorted by it).
        let figure = es[0].figure();
        let bars: Vec<(String, f64, f64)> = es
            .iter()
            .map(|e| {
                let s = figure.of(e);
                (
                    e.policy.clone(),
                    if s.mean.is_finite() { s.mean } else { 0.0 },
                    if s.std.is_finite() { s.std } else { 0.0 },
                )
            })
            .collect();
        plots::bars(
            &dir.join(format!("{env}-{level}-{short}.png")),
            &format!("{env} ({level}, spec {short})"),
            figure.label(),
            &bars,
        )?;
    }
    Ok(())
}
