//! Validation of the Kolmogorov flow at Re 40, k_f = 4 (`hgym validate kolmogorov`): the
//! uncontrolled flow must show the intermittent dissipation bursts of Farazmand & Sapsis (2017,
//! Sci. Adv. 3, e1701533): long quiet stretches with `D / D_lam` around 0.1 and rare short
//! excursions far above it. Reports the mean and spread of `D / D_lam`, the bursts (up-crossings
//! of mean + 3 std, separated by more than 5 time units below it), the fraction of time spent in them, and plots the time series.
//!
//! The case (record length, burst definition, checks) is data:
//! `benchmarks/validation/kolmogorov_re40.toml` — at least one burst in the record; bursts occupy
//! less than 5 % of the time (intermittency); the mean `D / D_lam` lies in [0.05, 0.2]
//! (Farazmand & Sapsis' quiet level ~0.1; our calibration run: 0.094).

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::env::kolmogorov::{spec, KolmogorovEnv};
use crate::flow::Level;
use crate::report::plots;
use hgym_agents::{Env, EnvError};

/// The committed case file.
pub const CASE: &str = include_str!("../../benchmarks/validation/kolmogorov_re40.toml");

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Checks {
    pub min_bursts: usize,
    pub max_burst_time_fraction: f64,
    pub mean_d_over_dlam: [f64; 2],
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub case: String,
    pub description: String,
    pub reference: String,
    pub reynolds: u32,
    pub time: f64,
    pub sample_interval: f64,
    pub threshold_sigma: f64,
    pub burst_gap: f64,
    pub checks: Checks,
}

pub fn case() -> Result<Case, toml::de::Error> {
    toml::from_str(CASE)
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct KolmogorovValidation {
    pub schema: String,
    pub case: String,
    pub level: String,
    pub n: usize,
    pub dt: f64,
    pub time: f64,
    pub mean_d_over_dlam: f64,
    pub std_d_over_dlam: f64,
    pub max_d_over_dlam: f64,
    pub threshold_d_over_dlam: f64,
    pub bursts: usize,
    pub burst_time_fraction: f64,
    pub mean_burst_duration: f64,
    pub checks: Vec<(String, bool)>,
    pub pass: bool,
    pub manifest: crate::report::manifest::Manifest,
}

/// Runs the case's record uncontrolled and writes `<out>/<case>.json` and
/// `<out>/<case>/dissipation.png`.
pub fn validate(level: Level, out: &Path, progress: &mut dyn FnMut(usize, usize)) -> Result<KolmogorovValidation, EnvError> {
    let started = std::time::Instant::now();
    let c = case().map_err(|e| EnvError::Backend(format!("the bundled case kolmogorov_re40.toml: {e}")))?;
    let time = c.time;
    let mut s = spec(c.reynolds);
    s.control_interval = c.sample_interval;
    s.episode_actions = (time / s.control_interval).round().max(1.0) as usize;
    let d_lam = s.dissipation_laminar();
    let (n, dt) = (s.n(level), s.dt(level));
    let mut env = KolmogorovEnv::new(s.clone(), level)?;
    env.reset(0)?;
    let zero = [0.0; 4];
    let (mut t, mut d) = (vec![], vec![]);
    for k in 0..s.episode_actions {
        let r = env.step(&zero)?;
        if r.terminated {
            return Err(EnvError::Backend(format!(
                "Kolmogorov Re 40 diverged: {}",
                r.info.text("reason").unwrap_or("?")
            )));
        }
        t.push(crate::env::info_value(&r.info, "t")?);
        d.push(crate::env::info_value(&r.info, "dissipation")? / d_lam);
        progress(k + 1, s.episode_actions);
    }
    let m = d.len() as f64;
    let mean = d.iter().sum::<f64>() / m;
    let std = (d.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (m - 1.0)).sqrt();
    let threshold = mean + c.threshold_sigma * std;
    let above: Vec<bool> = d.iter().map(|v| *v > threshold).collect();
    // A burst: an up-crossing more than 5 time units after the previous sample above threshold
    // (the noisy crossings of one event count once).
    let gap = (c.burst_gap / s.control_interval) as usize;
    let mut bursts = 0;
    let mut last_above: Option<usize> = None;
    for (k, a) in above.iter().enumerate() {
        if *a {
            if last_above.is_none_or(|j| k - j > gap) {
                bursts += 1;
            }
            last_above = Some(k);
        }
    }
    let frac = above.iter().filter(|a| **a).count() as f64 / m;
    let max = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let k = &c.checks;
    let checks = vec![
        (
            format!("at least {} burst(s) above mean + {} std", k.min_bursts, c.threshold_sigma),
            bursts >= k.min_bursts,
        ),
        (
            format!("bursts occupy < {} % of the time", 100.0 * k.max_burst_time_fraction),
            frac < k.max_burst_time_fraction,
        ),
        (
            format!("mean D/D_lam in [{}, {}]", k.mean_d_over_dlam[0], k.mean_d_over_dlam[1]),
            (k.mean_d_over_dlam[0]..=k.mean_d_over_dlam[1]).contains(&mean),
        ),
    ];
    let pass = checks.iter().all(|c| c.1);
    let report = KolmogorovValidation {
        schema: "hgym/kolmogorov-validation/v1".into(),
        case: c.case.clone(),
        level: level.name().into(),
        n,
        dt,
        time,
        mean_d_over_dlam: mean,
        std_d_over_dlam: std,
        max_d_over_dlam: max,
        threshold_d_over_dlam: threshold,
        bursts,
        burst_time_fraction: frac,
        mean_burst_duration: if bursts > 0 { frac * time / bursts as f64 } else { 0.0 },
        checks,
        pass,
        manifest: crate::report::manifest::manifest(rayon::current_num_threads(), started.elapsed().as_secs_f64()),
    };
    let dir = out.join(&c.case);
    std::fs::create_dir_all(&dir).map_err(|e| EnvError::Backend(format!("cannot create {}: {e}", dir.display())))?;
    std::fs::write(
        out.join(format!("{}.json", c.case)),
        serde_json::to_string_pretty(&report).unwrap_or_default() + "\n",
    )
    .map_err(|e| EnvError::Backend(e.to_string()))?;
    let th = vec![threshold; t.len()];
    plots::lines(
        &dir.join("dissipation.png"),
        &format!("Kolmogorov flow Re {}, k_f 4 ({}^2): dissipation, {} bursts", c.reynolds, n, bursts),
        "t",
        "D / D_lam",
        &[
            plots::Line {
                label: "D / D_lam",
                x: &t,
                y: &d,
                band: None,
            },
            plots::Line {
                label: "mean + 3 std",
                x: &t,
                y: &th,
                band: None,
            },
        ],
    )
    .map_err(|e| EnvError::Backend(crate::report::chain(&e)))?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    #[test]
    fn committed_case_parses() {
        let c = super::case().unwrap();
        assert_eq!(c.reynolds, 40);
        assert!(c.time > 0.0 && c.sample_interval > 0.0);
    }
}
