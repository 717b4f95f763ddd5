//! Comparison protocols (`benchmarks/protocols/*.toml`, `hgym compare FILE`): several algorithms
//! trained on one environment over the same seeds, and the number of environment samples each
//! needs to reach a fixed fraction of the reference algorithm's final evaluation return.
//!
//! "Reaching 90 % of PPO's final return" is measured on the improvement over the uncontrolled
//! flow: the threshold is `R_0 + 0.9 (R_ref - R_0)`, with `R_0` the zero-action return on the same
//! evaluation episodes and `R_ref` the reference algorithm's final evaluation return (mean over
//! seeds). (A fraction of the raw return is meaningless when returns carry an offset: for the
//! mixing objective the uncontrolled flow alone already earns ~100.) A run's samples-to-threshold
//! is the first evaluation at which its return reaches the threshold (`None` if it never does).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::config::TrainConfig;
use super::curve::{from_csv, CurveRow};
use super::eval::{evaluate, Stat};
use crate::flow::Level;
use crate::report::plots;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    pub name: String,
    pub description: String,
    pub env: String,
    pub level: Level,
    pub seeds: Vec<u64>,
    /// Registered algorithm names.
    pub algos: Vec<String>,
    /// The algorithm whose final return sets the threshold.
    pub reference: String,
    /// Fraction of the reference's improvement over the uncontrolled return.
    pub fraction: f64,
    /// Training configuration shared by every run (a `hgym train --config` file's content).
    #[serde(default)]
    pub config: TrainConfig,
}

/// Why a comparison could not be set up or analysed.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A protocol file or a run's curve that does not have the expected content (bad input).
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    #[error(transparent)]
    Plot(#[from] plots::PlotError),
}

impl CompareError {
    pub fn is_bad_input(&self) -> bool {
        matches!(self, CompareError::Invalid { .. })
    }
}

impl Protocol {
    pub fn load(path: &Path) -> Result<Protocol, CompareError> {
        let invalid = |message: String| CompareError::Invalid {
            path: path.to_path_buf(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|source| CompareError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let mut p: Protocol = toml::from_str(&text).map_err(|e| invalid(e.to_string()))?;
        for name in p.algos.iter().chain([&p.reference]) {
            hgym_agents::learn::algorithm(name).map_err(|e| invalid(e.to_string()))?;
        }
        if !p.algos.contains(&p.reference) {
            return Err(invalid(format!("the reference '{}' is not among algos", p.reference)));
        }
        p.config.algos = p.config.algos.complete().map_err(|e| invalid(e.to_string()))?;
        Ok(p)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunResult {
    pub algo: String,
    pub seed: u64,
    pub dir: PathBuf,
    pub final_return: f64,
    pub samples_to_threshold: Option<u64>,
    pub wall_s: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AlgoSummary {
    pub algo: String,
    pub final_return: Stat,
    /// Mean over the seeds that reached the threshold.
    pub samples_to_threshold: Stat,
    pub seeds_reaching: usize,
    pub wall_s: Stat,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Comparison {
    pub schema: String,
    pub protocol: Protocol,
    pub uncontrolled_return: f64,
    pub reference_final_return: f64,
    pub threshold: f64,
    pub runs: Vec<RunResult>,
    pub summary: Vec<AlgoSummary>,
    /// `1 - samples(algo) / samples(reference)` per non-reference algorithm (mean samples over
    /// seeds that reached the threshold).
    pub sample_reduction_vs_reference: Vec<(String, f64)>,
}

/// Return of the zero policy on the periodic evaluation episodes of `config` on `env_id`.
pub fn uncontrolled_return(env_id: &str, level: Level, config: &TrainConfig) -> Result<f64, super::TrainError> {
    let spec = super::resolve_spec(env_id, config)?;
    let mut env = spec.make(level, crate::env::default_cache_dir())?;
    let n = config.train.eval_episodes.max(1);
    let seeds: Vec<u64> = (0..n as u64).map(|k| config.train.eval_seed + k).collect();
    let mut zero = hgym_agents::baselines::BaselinePolicy::new(hgym_agents::baselines::Baseline::Zero, 0);
    let refs = vec![super::eval::Uncontrolled::drag(f64::NAN); n];
    let hash = spec.hash();
    let r = evaluate(
        &mut env,
        &mut zero,
        "zero",
        spec.id(),
        &hash,
        level.name(),
        &seeds,
        &refs,
        None,
        &mut |_| {},
    )?;
    Ok(r.ret.mean)
}

/// The last evaluation return of a learning curve (NaN if none).
pub fn final_eval(rows: &[CurveRow]) -> f64 {
    rows.iter()
        .rev()
        .find(|r| r.eval_return.is_finite())
        .map(|r| r.eval_return)
        .unwrap_or(f64::NAN)
}

/// Reads the finished runs under `root/<algo>/seed<S>` and computes the comparison.
pub fn analyse(p: &Protocol, root: &Path, r0: f64) -> Result<Comparison, CompareError> {
    let mut curves: Vec<(String, u64, PathBuf, Vec<CurveRow>, f64)> = vec![];
    for algo in &p.algos {
        for seed in &p.seeds {
            let dir = root.join(algo).join(format!("seed{seed}"));
            let path = dir.join("curve.csv");
            let text = std::fs::read_to_string(&path).map_err(|source| CompareError::Read {
                path: path.clone(),
                source,
            })?;
            let rows = from_csv(&text).map_err(|e| CompareError::Invalid { path, message: e.0 })?;
            let wall = rows.last().map(|r| r.wall_s).unwrap_or(f64::NAN);
            curves.push((algo.clone(), *seed, dir, rows, wall));
        }
    }
    let reference: Vec<f64> = curves.iter().filter(|c| c.0 == p.reference).map(|c| final_eval(&c.3)).collect();
    let r_ref = Stat::of(&reference).mean;
    let threshold = r0 + p.fraction * (r_ref - r0);
    let runs: Vec<RunResult> = curves
        .iter()
        .map(|(algo, seed, dir, rows, wall)| RunResult {
            algo: algo.clone(),
            seed: *seed,
            dir: dir.clone(),
            final_return: final_eval(rows),
            samples_to_threshold: rows
                .iter()
                .find(|r| r.eval_return.is_finite() && r.eval_return >= threshold)
                .map(|r| r.samples),
            wall_s: *wall,
        })
        .collect();
    let summary: Vec<AlgoSummary> = p
        .algos
        .iter()
        .map(|a| {
            let mine: Vec<&RunResult> = runs.iter().filter(|r| r.algo == *a).collect();
            let reached: Vec<f64> = mine.iter().filter_map(|r| r.samples_to_threshold.map(|s| s as f64)).collect();
            AlgoSummary {
                algo: a.clone(),
                final_return: Stat::of(&mine.iter().map(|r| r.final_return).collect::<Vec<_>>()),
                samples_to_threshold: Stat::of(&reached),
                seeds_reaching: reached.len(),
                wall_s: Stat::of(&mine.iter().map(|r| r.wall_s).collect::<Vec<_>>()),
            }
        })
        .collect();
    let ref_samples = summary.iter().find(|s| s.algo == p.reference).map(|s| s.samples_to_threshold.mean);
    let sample_reduction_vs_reference = summary
        .iter()
        .filter(|s| s.algo != p.reference)
        .map(|s| (s.algo.clone(), 1.0 - s.samples_to_threshold.mean / ref_samples.unwrap_or(f64::NAN)))
        .collect();
    let cmp = Comparison {
        schema: "hgym/comparison/v1".into(),
        protocol: p.clone(),
        uncontrolled_return: r0,
        reference_final_return: r_ref,
        threshold,
        runs,
        summary,
        sample_reduction_vs_reference,
    };
    plot(p, &curves, threshold, r0, &root.join("learning_curves.png"))?;
    Ok(cmp)
}

/// Mean +- std over seeds of each algorithm's evaluation return against samples.
fn plot(
    p: &Protocol,
    curves: &[(String, u64, PathBuf, Vec<CurveRow>, f64)],
    threshold: f64,
    r0: f64,
    path: &Path,
) -> Result<(), crate::report::plots::PlotError> {
    let groups: Vec<(String, Vec<&[CurveRow]>)> = p
        .algos
        .iter()
        .map(|a| (a.clone(), curves.iter().filter(|c| c.0 == *a).map(|c| &c.3[..]).collect()))
        .collect();
    let hlines = [
        (
            format!("threshold ({:.0} % of the reference's gain)", 100.0 * p.fraction),
            threshold,
        ),
        ("uncontrolled".to_string(), r0),
    ];
    curve_plot(path, &format!("{}: {} ({})", p.name, p.env, p.level.name()), &groups, &hlines)
}

/// Learning curves of several groups of runs, each as the mean +- std over its runs of the
/// evaluation return against samples (a group's runs evaluate at the same sample counts), and
/// horizontal lines across the whole span.
pub fn curve_plot(
    path: &Path,
    title: &str,
    groups: &[(String, Vec<&[CurveRow]>)],
    hlines: &[(String, f64)],
) -> Result<(), crate::report::plots::PlotError> {
    let mut xs: Vec<Vec<f64>> = vec![];
    let mut ys: Vec<Vec<f64>> = vec![];
    let mut bands: Vec<Vec<f64>> = vec![];
    let mut labels: Vec<String> = vec![];
    for (name, runs) in groups {
        let Some(first) = runs.first() else { continue };
        let points: Vec<u64> = first.iter().filter(|r| r.eval_return.is_finite()).map(|r| r.samples).collect();
        let (mut x, mut y, mut b) = (vec![], vec![], vec![]);
        for s in points {
            let vals: Vec<f64> = runs
                .iter()
                .filter_map(|rows| rows.iter().find(|r| r.samples == s).map(|r| r.eval_return))
                .filter(|v| v.is_finite())
                .collect();
            let st = Stat::of(&vals);
            x.push(s as f64);
            y.push(st.mean);
            b.push(st.std);
        }
        xs.push(x);
        ys.push(y);
        bands.push(b);
        labels.push(format!("{} (mean +- std, {} seeds)", name, runs.len()));
    }
    let span = xs.iter().flat_map(|x| x.iter().copied()).fold(0.0, f64::max);
    let hx = [0.0, span];
    let hy: Vec<[f64; 2]> = hlines.iter().map(|(_, v)| [*v, *v]).collect();
    let mut lines: Vec<plots::Line> = (0..xs.len())
        .map(|k| plots::Line {
            label: &labels[k],
            x: &xs[k],
            y: &ys[k],
            band: Some(&bands[k]),
        })
        .collect();
    for ((label, _), y) in hlines.iter().zip(&hy) {
        lines.push(plots::Line {
            label,
            x: &hx,
            y,
            band: None,
        });
    }
    plots::lines(path, title, "environment samples", "evaluation return", &lines)
}
