//! The comparison of a transfer protocol's arms (`comparison.json`, `transfer.png`).
//!
//! Performance is measured as in `hgym compare` ([`crate::train::compare`]): the threshold is
//! `R_0 + fraction (R_scratch - R_0)` with `R_0` the uncontrolled return on the periodic
//! evaluation episodes and `R_scratch` the from-scratch arm's final periodic evaluation (mean over
//! seeds). A run reaches it at the first evaluation from which it stays at or above it (every
//! later evaluation too): a fine-tuning run evaluates its starting policy at 0 samples, and a
//! source that is good enough there but is unlearned in the first updates must not count as
//! having reached it at 0. A run whose final evaluation is below never reaches it. When the
//! from-scratch arm ends at or below the uncontrolled return there is no gain to reach a fraction
//! of: the threshold is undefined (`null`), no arm reaches it, and no saving is reported.
//! Final drag reductions and returns are each run's final evaluation (`metrics.json`). Cost is
//! core-hours: the run's measured CPU time (manifest `cpu_time_s`, which a shared machine does not
//! inflate), or wall time times threads for runs that predate that clock; the cost to threshold
//! scales a run's core-hours by the fraction of its samples spent before reaching the threshold.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::protocol::Protocol;
use crate::train::compare::{curve_plot, final_eval, CompareError};
use crate::train::curve::{from_csv, CurveRow};
use crate::train::eval::{EvalReport, Stat};

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ArmRun {
    pub arm: String,
    pub seed: u64,
    pub dir: PathBuf,
    pub final_drag_reduction_pct: f64,
    pub final_return: f64,
    /// Environment samples collected (0 for the zero-shot arm).
    pub samples: u64,
    pub samples_to_threshold: Option<u64>,
    pub wall_s: f64,
    pub core_hours: f64,
    /// Whether `core_hours` is measured CPU time (else wall time times threads).
    pub core_hours_measured: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ArmSummary {
    pub arm: String,
    pub final_drag_reduction_pct: Stat,
    pub final_return: Stat,
    /// Over the seeds that reach the threshold.
    pub samples_to_threshold: Stat,
    pub episodes_to_threshold: Stat,
    pub seeds_reaching: usize,
    pub wall_s: Stat,
    /// Summed over seeds.
    pub core_hours: f64,
    /// Mean over the seeds that reach the threshold.
    pub core_hours_to_threshold: Stat,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TransferComparison {
    pub schema: String,
    pub protocol: Protocol,
    pub uncontrolled_return: f64,
    pub scratch_final_return: f64,
    pub threshold: f64,
    pub episode_actions: usize,
    pub runs: Vec<ArmRun>,
    pub arms: Vec<ArmSummary>,
    /// `100 (1 - episodes(finetune) / episodes(scratch))` to the threshold (the paper: ~50 %).
    pub episode_saving_pct: f64,
    /// `100 (1 - core-hours(finetune) / core-hours(scratch))` to the threshold.
    pub cost_saving_pct: f64,
}

/// Samples at the first evaluation from which every evaluation is at or above `threshold`.
fn stays_above(rows: &[CurveRow], threshold: f64) -> Option<u64> {
    if !threshold.is_finite() {
        return None;
    }
    let evals: Vec<&CurveRow> = rows.iter().filter(|r| r.eval_return.is_finite()).collect();
    let from = evals.iter().rposition(|r| r.eval_return < threshold).map_or(0, |k| k + 1);
    evals.get(from).map(|r| r.samples)
}

fn read(path: &Path) -> Result<String, CompareError> {
    std::fs::read_to_string(path).map_err(|source| CompareError::Read {
        path: path.to_path_buf(),
        source,
    })
}

pub(crate) fn json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CompareError> {
    serde_json::from_str(&read(path)?).map_err(|e| CompareError::Invalid {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Wall time, core-hours and whether those were measured as CPU time, from a result folder's
/// `manifest.json` (train or eval).
pub(crate) fn cost(dir: &Path) -> Result<(f64, f64, bool), CompareError> {
    let m: serde_json::Value = json(&dir.join("manifest.json"))?;
    let wall = m["manifest"]["wall_time_s"].as_f64().unwrap_or(f64::NAN);
    let threads = m["manifest"]["threads"].as_f64().unwrap_or(f64::NAN);
    Ok(match m["manifest"]["cpu_time_s"].as_f64() {
        Some(cpu) => (wall, cpu / 3600.0, true),
        None => (wall, wall * threads / 3600.0, false),
    })
}

/// Reads every arm of every seed under `root` and compares them; writes `transfer.png`.
pub fn analyse(p: &Protocol, root: &Path, r0: f64, episode_actions: usize) -> Result<TransferComparison, CompareError> {
    let mut curves: Vec<(String, Vec<CurveRow>)> = vec![];
    let mut runs = vec![];
    for arm in super::protocol::ARMS {
        for &seed in &p.seeds {
            let dir = p.arm_dir(root, arm, seed);
            let report: EvalReport = json(&dir.join("metrics.json"))?;
            let (wall_s, core_hours, core_hours_measured) = cost(&dir)?;
            let rows = if arm == "zeroshot" {
                vec![]
            } else {
                let path = dir.join("curve.csv");
                from_csv(&read(&path)?).map_err(|e| CompareError::Invalid { path, message: e.0 })?
            };
            runs.push(ArmRun {
                arm: arm.into(),
                seed,
                dir: dir.clone(),
                final_drag_reduction_pct: report.drag_reduction_pct.mean,
                final_return: report.ret.mean,
                samples: rows.last().map_or(0, |r| r.samples),
                samples_to_threshold: None,
                wall_s,
                core_hours,
                core_hours_measured,
            });
            curves.push((arm.into(), rows));
        }
    }
    let scratch: Vec<f64> = curves.iter().filter(|c| c.0 == "scratch").map(|c| final_eval(&c.1)).collect();
    let r_scratch = Stat::of(&scratch).mean;
    let threshold = match r_scratch > r0 {
        true => r0 + p.fraction * (r_scratch - r0),
        false => f64::NAN,
    };
    for (run, (_, rows)) in runs.iter_mut().zip(&curves) {
        run.samples_to_threshold = if run.arm == "zeroshot" {
            (run.final_return >= threshold).then_some(0)
        } else {
            stays_above(rows, threshold)
        };
    }
    let arms: Vec<ArmSummary> = super::protocol::ARMS
        .iter()
        .map(|arm| {
            let mine: Vec<&ArmRun> = runs.iter().filter(|r| r.arm == *arm).collect();
            let col = |f: fn(&ArmRun) -> f64| Stat::of(&mine.iter().map(|r| f(r)).collect::<Vec<_>>());
            let reached: Vec<&&ArmRun> = mine.iter().filter(|r| r.samples_to_threshold.is_some()).collect();
            let to = |r: &ArmRun| r.samples_to_threshold.unwrap_or(0) as f64;
            ArmSummary {
                arm: arm.to_string(),
                final_drag_reduction_pct: col(|r| r.final_drag_reduction_pct),
                final_return: col(|r| r.final_return),
                samples_to_threshold: Stat::of(&reached.iter().map(|r| to(r)).collect::<Vec<_>>()),
                episodes_to_threshold: Stat::of(&reached.iter().map(|r| to(r) / episode_actions as f64).collect::<Vec<_>>()),
                seeds_reaching: reached.len(),
                wall_s: col(|r| r.wall_s),
                core_hours: mine.iter().map(|r| r.core_hours).sum(),
                core_hours_to_threshold: Stat::of(
                    &reached
                        .iter()
                        .map(|r| {
                            if r.samples == 0 {
                                r.core_hours
                            } else {
                                r.core_hours * to(r) / r.samples as f64
                            }
                        })
                        .collect::<Vec<_>>(),
                ),
            }
        })
        .collect();
    let get = |a: &str| arms.iter().find(|s| s.arm == a);
    let saving = |f: fn(&ArmSummary) -> f64| match (get("finetune"), get("scratch")) {
        (Some(ft), Some(sc)) => 100.0 * (1.0 - f(ft) / f(sc)),
        _ => f64::NAN,
    };
    let cmp = TransferComparison {
        schema: "hgym/transfer/v1".into(),
        protocol: p.clone(),
        uncontrolled_return: r0,
        scratch_final_return: r_scratch,
        threshold,
        episode_actions,
        episode_saving_pct: saving(|s| s.episodes_to_threshold.mean),
        cost_saving_pct: saving(|s| s.core_hours_to_threshold.mean),
        runs,
        arms,
    };
    plot(p, &cmp, &curves, &root.join("transfer.png"))?;
    Ok(cmp)
}

/// The fine-tuning and from-scratch learning curves (mean +- std), the zero-shot return, the
/// threshold and the uncontrolled return; the episodes saved in the title.
fn plot(p: &Protocol, cmp: &TransferComparison, curves: &[(String, Vec<CurveRow>)], path: &Path) -> Result<(), CompareError> {
    let groups: Vec<(String, Vec<&[CurveRow]>)> = ["finetune", "scratch"]
        .iter()
        .map(|a| (a.to_string(), curves.iter().filter(|c| c.0 == *a).map(|c| &c.1[..]).collect()))
        .collect();
    let zs = cmp
        .arms
        .iter()
        .find(|a| a.arm == "zeroshot")
        .map_or(f64::NAN, |a| a.final_return.mean);
    let hlines: Vec<(String, f64)> = [
        ("zero-shot (source policy, mean)".to_string(), zs),
        (format!("threshold ({:.0} % of scratch's gain)", 100.0 * p.fraction), cmp.threshold),
        ("uncontrolled".to_string(), cmp.uncontrolled_return),
    ]
    .into_iter()
    .filter(|(_, y)| y.is_finite())
    .collect();
    let saving = if !cmp.threshold.is_finite() {
        "no threshold: training from scratch does not beat the uncontrolled flow".to_string()
    } else if cmp.episode_saving_pct.is_finite() {
        format!("fine-tuning saves {:.0} % of episodes", cmp.episode_saving_pct)
    } else {
        "no saving: an arm never stays above the threshold".to_string()
    };
    let title = format!("{} -> {} ({}): {saving}", p.source, p.target, p.level.name());
    Ok(curve_plot(path, &title, &groups, &hlines)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(evals: &[f64]) -> Vec<CurveRow> {
        let text = std::iter::once(crate::train::curve::CSV_HEADER.to_string())
            .chain(
                evals
                    .iter()
                    .enumerate()
                    .map(|(k, e)| format!("{k},{},0,0,NaN,NaN,{e},1,0", 1000 * k)),
            )
            .collect::<Vec<_>>()
            .join("\n");
        from_csv(&text).unwrap()
    }

    #[test]
    fn a_run_reaches_the_threshold_where_it_stays_above_it() {
        // Above at the start, below after: reached only from the third evaluation on.
        assert_eq!(stays_above(&rows(&[-400.0, -480.0, -430.0, -420.0]), -440.0), Some(2000));
        assert_eq!(stays_above(&rows(&[-400.0, -410.0]), -440.0), Some(0));
        // Ends below: never.
        assert_eq!(stays_above(&rows(&[-400.0, -430.0, -450.0]), -440.0), None);
        // No threshold (scratch never beat the uncontrolled flow): never.
        assert_eq!(stays_above(&rows(&[-400.0, -410.0]), f64::NAN), None);
    }
}
