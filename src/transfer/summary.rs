//! The comparison of a zero-shot deployment protocol's arms (`comparison.json`, schema
//! `transfer-deployment.schema.json`; `friction.png`, `reductions.png`): per arm the local
//! skin-friction and the plate's drag reductions (the zero-shot arm's as mean +- std over the
//! source seeds), and the cost of training in the source flow against training on the target.
//! The latter is extrapolated from the deployments: the source runs' episodes times the CPU time
//! of one target episode. It leaves out the learner's updates, which grow with the target's
//! agents, so it is a lower bound.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::compare::{cost, json};
use super::deploy::ArmRecord;
use super::protocol::Protocol;
use super::SourceRun;
use crate::env::wing_tbl::TargetCheck;
use crate::report::eval::Stat;
use crate::report::plots::{self, Line};
use crate::train::compare::CompareError;

pub const SCHEMA: &str = "hgym/transfer-deployment/v1";

/// The folder of each deployment arm under the protocol's root, in order: the uncontrolled
/// flow, each baseline (neither needs the source runs), the zero-shot arm of each seed.
pub fn arm_dirs(p: &Protocol, root: &Path) -> Vec<(String, Option<u64>, std::path::PathBuf)> {
    let mut dirs = vec![("uncontrolled".to_string(), None, root.join("uncontrolled"))];
    if let Some(d) = &p.deployment {
        dirs.extend(d.baselines.iter().map(|b| (b.name.clone(), None, root.join(&b.name))));
    }
    let zeroshot = |&s: &u64| ("zeroshot".to_string(), Some(s), p.arm_dir(root, "zeroshot", s));
    dirs.extend(p.seeds.iter().map(zeroshot));
    dirs
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ArmSummary {
    pub arm: String,
    pub policy: String,
    /// Deployments (source seeds for the zero-shot arm, else 1).
    pub deployments: usize,
    pub local_friction_reduction_pct: Stat,
    pub plate_drag_reduction_pct: Stat,
    pub actuation_rms_plus: Stat,
    pub cpu_s_per_episode: Stat,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Cost {
    /// One source training run (mean +- std over the seeds).
    pub source_core_hours: Stat,
    /// Whether those are measured CPU time (else wall time times threads).
    pub source_core_hours_measured: bool,
    /// Episodes of one source training run.
    pub source_episodes: f64,
    pub source_core_hours_per_episode: f64,
    /// One target episode under the zero-shot policy.
    pub target_core_hours_per_episode: f64,
    /// `source_episodes x target_core_hours_per_episode`.
    pub target_training_core_hours: f64,
    /// `target_training_core_hours / source_core_hours`.
    pub ratio: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct DeploymentComparison {
    pub schema: String,
    pub protocol: Protocol,
    /// The uncontrolled target against what it is built to match (the wing's layer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<TargetCheck>,
    pub arms: Vec<ArmSummary>,
    pub cost: Cost,
}

/// An arm's wall-shear profile: mean and spread over its deployments at each `x`.
struct Profile {
    arm: String,
    x: Vec<f64>,
    mean: Vec<f64>,
    std: Vec<f64>,
}

/// Episodes of a training run: its samples over the transitions of one episode (one per agent
/// and action).
fn episodes(src: &SourceRun) -> Result<f64, CompareError> {
    let m: serde_json::Value = json(&src.dir.join("manifest.json"))?;
    let invalid = |message: &str| CompareError::Invalid {
        path: src.dir.join("manifest.json"),
        message: message.into(),
    };
    let samples = m["samples"].as_f64().ok_or_else(|| invalid("no samples"))?;
    let spec = src.spec.to_json().map_err(|e| invalid(&e.to_string()))?;
    let actions = spec["episode_actions"]
        .as_f64()
        .ok_or_else(|| invalid("the spec has no episode_actions"))?;
    let agents = src.spec.decomposition().map_or(1, |a| a.len()) as f64;
    Ok(samples / (agents * actions))
}

/// Reads every arm under `root`, compares them and draws the figures.
pub fn analyse(
    p: &Protocol,
    root: &Path,
    sources: &[SourceRun],
    target: Option<TargetCheck>,
) -> Result<DeploymentComparison, CompareError> {
    let mut records: Vec<ArmRecord> = vec![];
    for (_, _, dir) in arm_dirs(p, root) {
        let file = dir.join("deployment.json");
        let r: ArmRecord = json(&file)?;
        // Every arm's friction profile is sampled at the same stations (the same target grid).
        let stations = records.first().map_or(r.x.len(), |f| f.x.len());
        if r.profile.len() != r.x.len() || records.first().is_some_and(|f| f.x != r.x) {
            return Err(CompareError::Invalid {
                path: file,
                message: format!(
                    "its friction profile has {} values at {} stations, the first arm's {stations}: the arms ran on \
                     different set-ups, or the file was cut; delete this arm's folder and run the protocol again",
                    r.profile.len(),
                    r.x.len(),
                ),
            });
        }
        records.push(r);
    }
    let mut arms: Vec<ArmSummary> = vec![];
    let mut lines: Vec<Profile> = vec![];
    for r in &records {
        let group: Vec<&ArmRecord> = records.iter().filter(|o| o.arm == r.arm).collect();
        if arms.iter().any(|a| a.arm == r.arm) {
            continue;
        }
        let across = |f: fn(&ArmRecord) -> f64| Stat::of(&group.iter().map(|g| f(g)).collect::<Vec<_>>());
        // One deployment: its spread over episodes; several (seeds): the spread of their means.
        let stat = |f: fn(&ArmRecord) -> Stat| match group.len() {
            1 => f(group[0]),
            _ => Stat::of(&group.iter().map(|g| f(g).mean).collect::<Vec<_>>()),
        };
        arms.push(ArmSummary {
            arm: r.arm.clone(),
            policy: r.policy.clone(),
            deployments: group.len(),
            local_friction_reduction_pct: stat(|g| g.local_friction_reduction_pct),
            plate_drag_reduction_pct: stat(|g| g.plate_drag_reduction_pct),
            actuation_rms_plus: stat(|g| g.actuation_rms_plus),
            cpu_s_per_episode: across(|g| g.cpu_s_per_episode),
        });
        let n = r.profile.len();
        let at = |i: usize| group.iter().map(|g| 1.0 + g.profile[i]).collect::<Vec<_>>();
        let (mean, std): (Vec<f64>, Vec<f64>) = (0..n).map(|i| Stat::of(&at(i))).map(|s| (s.mean, s.std)).unzip();
        lines.push(Profile {
            arm: r.arm.clone(),
            x: r.x.clone(),
            mean,
            std,
        });
    }
    let zeroshot = arms.iter().find(|a| a.arm == "zeroshot").ok_or_else(|| CompareError::Invalid {
        path: root.to_path_buf(),
        message: "no zero-shot arm".into(),
    })?;
    let mut source_hours = vec![];
    let mut measured = true;
    let mut source_episodes = vec![];
    for src in sources {
        let (_, hours, m) = cost(&src.dir)?;
        source_hours.push(hours);
        measured &= m;
        source_episodes.push(episodes(src)?);
    }
    let source_core_hours = Stat::of(&source_hours);
    let source_episodes = Stat::of(&source_episodes).mean;
    let per_episode = zeroshot.cpu_s_per_episode.mean / 3600.0;
    let cost = Cost {
        source_core_hours,
        source_core_hours_measured: measured,
        source_episodes,
        source_core_hours_per_episode: source_core_hours.mean / source_episodes,
        target_core_hours_per_episode: per_episode,
        target_training_core_hours: source_episodes * per_episode,
        ratio: source_episodes * per_episode / source_core_hours.mean,
    };
    let drawn: Vec<Line> = lines
        .iter()
        .map(|p| Line {
            label: &p.arm,
            x: &p.x,
            y: &p.mean,
            band: Some(&p.std),
        })
        .collect();
    plots::lines(
        &root.join("friction.png"),
        &format!("{}: wall shear stress over the uncontrolled flow's, span- and time-mean", p.target),
        "x (chords along the wall from the box's inflow)",
        "tau_w / tau_w,0(x)",
        &drawn,
    )?;
    let bars: Vec<(String, f64, f64)> = arms
        .iter()
        .filter(|a| a.arm != "uncontrolled")
        .flat_map(|a| {
            [
                (format!("{} local", a.arm), a.local_friction_reduction_pct),
                (format!("{} plate", a.arm), a.plate_drag_reduction_pct),
            ]
        })
        .map(|(l, s)| (l, s.mean, s.std))
        .collect();
    plots::bars(
        &root.join("reductions.png"),
        &format!("{}: skin-friction reduction, control region (local) and plate", p.target),
        "reduction (%)",
        &bars,
    )?;
    if let Some(t) = &target {
        target_plots(root, &p.target, t)?;
    }
    Ok(DeploymentComparison {
        schema: SCHEMA.into(),
        protocol: p.clone(),
        target,
        arms,
        cost,
    })
}

/// `target_u_tau.png` and `target_re_theta.png`: the measured uncontrolled layer against the
/// integral estimate over the control region.
fn target_plots(root: &Path, id: &str, t: &TargetCheck) -> Result<(), CompareError> {
    let pair = |measured: &'static str, estimate: &'static str| [measured, estimate];
    for (file, quantity, [a, b], measured, estimate) in [
        (
            "target_u_tau.png",
            "u_tau / U",
            pair("measured", "integral estimate"),
            &t.u_tau,
            &t.u_tau_estimate,
        ),
        (
            "target_re_theta.png",
            "Re_theta",
            pair("measured", "integral estimate"),
            &t.re_theta,
            &t.re_theta_estimate,
        ),
    ] {
        let lines = [
            Line {
                label: a,
                x: &t.xc,
                y: measured,
                band: None,
            },
            Line {
                label: b,
                x: &t.xc,
                y: estimate,
                band: None,
            },
        ];
        let title = format!("{id} uncontrolled ({}): {quantity} over the control region", t.level);
        plots::lines(&root.join(file), &title, "x / c", quantity, &lines)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An arm whose friction profile is not sampled where the others' are is refused by name,
    /// not indexed past its end.
    #[test]
    fn arms_of_another_grid_are_refused() {
        let p = Protocol::find("channel", "naca0012").unwrap();
        let tmp = tempfile::tempdir().unwrap();
        let committed = Path::new("results/transfer/channel_wing/uncontrolled/deployment.json");
        let mut r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(committed).unwrap()).unwrap();
        for (arm, cut) in [("uncontrolled", false), ("opposition", true)] {
            let dir = tmp.path().join(arm);
            std::fs::create_dir_all(&dir).unwrap();
            if cut {
                r["arm"] = arm.into();
                r["profile"].as_array_mut().unwrap().pop();
            }
            std::fs::write(dir.join("deployment.json"), r.to_string()).unwrap();
        }
        match analyse(&p, tmp.path(), &[], None) {
            Err(CompareError::Invalid { path, message }) => {
                assert!(path.ends_with("opposition/deployment.json"), "{}", path.display());
                assert!(message.contains("different set-ups"), "{message}");
            }
            other => panic!("expected the opposition arm refused, got {other:?}"),
        }
    }
}
