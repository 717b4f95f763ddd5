//! `hgym plot` (learning curves of several runs in one figure) and `hgym leaderboard`.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::{Outcome, UsageError};

/// Learning curves of several training runs in one figure.
#[derive(Args)]
pub struct PlotArgs {
    /// Training result folders (each with curve.csv).
    #[arg(required = true)]
    runs: Vec<PathBuf>,
    /// Output PNG.
    #[arg(short, long, default_value = "learning_curves.png")]
    out: PathBuf,
    /// Plot the evaluation drag reduction instead of the return.
    #[arg(long)]
    drag: bool,
    /// Plot the training return (with exploration) instead of the evaluation return.
    #[arg(long)]
    train: bool,
}

/// The leaderboard's sources and output.
#[derive(Args)]
pub struct LeaderboardArgs {
    /// Only this environment.
    #[arg(long)]
    env: Option<String>,
    /// The results folder.
    #[arg(long, default_value = "results")]
    results: PathBuf,
    /// Print the leaderboard's entries as JSON.
    #[arg(long)]
    json: bool,
}

/// The spec today's registry gives `id` with a run's training configuration (its `[env]`
/// overrides); without one, the registered spec.
fn run_spec(id: &str, config_toml: Option<&str>) -> Option<hgym::env::Spec> {
    match config_toml {
        Some(text) => {
            let config = hgym::train::config::TrainConfig::parse(text, "a run's manifest").ok()?;
            hgym::train::resolve_spec(id, &config).ok()
        }
        None => hgym::env::lookup(id).ok(),
    }
}

fn current_hash(id: &str, config_toml: Option<&str>) -> Option<String> {
    run_spec(id, config_toml).map(|s| s.hash())
}

/// How far the uncontrolled flow of `id` at `level`, with a run's training configuration, is
/// from the literature (`hgym::fidelity::sentence`).
fn literature(id: &str, level: &str, config_toml: Option<&str>) -> Option<String> {
    let spec = run_spec(id, config_toml)?;
    let level: hgym::flow::Level = level.parse().ok()?;
    Some(hgym::fidelity::sentence(&spec, level))
}

/// `hgym leaderboard`: writes results/leaderboard.json, LEADERBOARD.md and the bar charts.
pub fn leaderboard(args: LeaderboardArgs) -> Result<Outcome> {
    let lb = hgym::report::leaderboard::build(&args.results, args.env.as_deref(), &current_hash, &literature);
    hgym::report::leaderboard::write(&args.results, &lb)?;
    if !lb.problems.is_empty() {
        eprintln!(
            "warning: {} result folder(s) could not be read (listed in LEADERBOARD.md):",
            lb.problems.len()
        );
        for p in &lb.problems {
            eprintln!("  {}: {}", p.dir.display(), p.message);
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&lb)?);
    } else {
        print!("{}", hgym::report::leaderboard::markdown(&lb));
    }
    Ok(Outcome::Ok)
}

/// `hgym plot`.
pub fn plot(args: PlotArgs) -> Result<Outcome> {
    run_plot(&args.runs, &args.out, args.drag, args.train)
}

fn run_plot(runs: &[PathBuf], out: &std::path::Path, drag: bool, train: bool) -> Result<Outcome> {
    use hgym::report::plots::{lines, Line};
    let mut series: Vec<(String, Vec<f64>, Vec<f64>)> = vec![];
    for dir in runs {
        let file = dir.join("curve.csv");
        let text = std::fs::read_to_string(&file).map_err(|e| {
            UsageError(format!(
                "{}: {e} (give training result folders, each with curve.csv)",
                file.display()
            ))
        })?;
        let rows = hgym::train::curve::from_csv(&text).map_err(|e| UsageError(format!("{}: {e}", file.display())))?;
        let (x, y): (Vec<f64>, Vec<f64>) = rows
            .iter()
            .map(|r| {
                let y = if drag {
                    r.eval_drag_reduction_pct
                } else if train {
                    r.train_return
                } else {
                    r.eval_return
                };
                (r.samples as f64, y)
            })
            .filter(|(_, y)| y.is_finite())
            .unzip();
        let label = dir
            .components()
            .rev()
            .take(2)
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<Vec<_>>()
            .join("/");
        series.push((label, x, y));
    }
    let lines_: Vec<Line> = series
        .iter()
        .map(|(l, x, y)| Line {
            label: l,
            x,
            y,
            band: None,
        })
        .collect();
    let what = if drag {
        "evaluation drag reduction (%)"
    } else if train {
        "training return"
    } else {
        "evaluation return"
    };
    lines(out, "learning curves", "environment samples", what, &lines_).map_err(anyhow::Error::from)?;
    println!("wrote {} ({} runs)", out.display(), series.len());
    Ok(Outcome::Ok)
}
