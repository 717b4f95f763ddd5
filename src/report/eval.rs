//! The evaluation report (`eval.json`, written by `hgym eval` and at the end of training): the
//! statistics over episodes that the leaderboard aggregates.

use serde::{Deserialize, Serialize};

/// JSON has no NaN: serde_json writes it as `null`; read `null` back as NaN.
pub fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// Mean and sample standard deviation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    #[serde(deserialize_with = "nan_if_null")]
    pub mean: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub std: f64,
}

impl Stat {
    pub fn of(v: &[f64]) -> Stat {
        let n = v.len();
        if n == 0 {
            return Stat {
                mean: f64::NAN,
                std: f64::NAN,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Stat { mean, std }
    }
}

/// One evaluation episode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalEpisode {
    pub seed: u64,
    #[serde(deserialize_with = "nan_if_null")]
    pub ret: f64,
    pub length: usize,
    pub terminated: bool,
    #[serde(deserialize_with = "nan_if_null")]
    pub mean_c_d: f64,
    /// Mean C_D of the uncontrolled flow from the same initial state.
    #[serde(deserialize_with = "nan_if_null")]
    pub uncontrolled_c_d: f64,
    /// `100 (1 - C_D / C_D,uncontrolled)`.
    #[serde(deserialize_with = "nan_if_null")]
    pub drag_reduction_pct: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub mean_abs_c_l: f64,
    /// Mean over steps of the sum of squared normalised actions.
    #[serde(deserialize_with = "nan_if_null")]
    pub actuation_cost: f64,
    /// The gust flows' load figure (flows whose reward has a reference lift).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lift_deviation: Option<LiftDeviation>,
}

/// How far the lift strays from the undisturbed flow's mean over one episode, controlled and
/// uncontrolled from the same state: the mean of |C_L - C_L,ref| (info `dC_L`), the lift term of
/// the gust reward.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LiftDeviation {
    #[serde(deserialize_with = "nan_if_null")]
    pub mean_abs_dc_l: f64,
    #[serde(deserialize_with = "nan_if_null")]
    pub uncontrolled_abs_dc_l: f64,
    /// `100 (1 - mean_abs_dc_l / uncontrolled_abs_dc_l)`.
    #[serde(deserialize_with = "nan_if_null")]
    pub reduction_pct: f64,
}

/// [`LiftDeviation`] over the evaluation's episodes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LiftDeviationStat {
    pub mean_abs_dc_l: Stat,
    pub uncontrolled_abs_dc_l: Stat,
    pub reduction_pct: Stat,
}

impl LiftDeviationStat {
    /// Mean and std over `episodes` when every one has the figure.
    pub fn of(episodes: &[EvalEpisode]) -> Option<Self> {
        let figures: Option<Vec<LiftDeviation>> = episodes.iter().map(|e| e.lift_deviation).collect();
        let figures = figures.filter(|f| !f.is_empty())?;
        let col = |g: fn(&LiftDeviation) -> f64| Stat::of(&figures.iter().map(g).collect::<Vec<_>>());
        Some(LiftDeviationStat {
            mean_abs_dc_l: col(|f| f.mean_abs_dc_l),
            uncontrolled_abs_dc_l: col(|f| f.uncontrolled_abs_dc_l),
            reduction_pct: col(|f| f.reduction_pct),
        })
    }

    /// The reduction's mean and std over several evaluations (seeds) of the per-evaluation means,
    /// when every one has the figure.
    pub fn reduction_over<'a>(reports: impl IntoIterator<Item = &'a EvalReport>) -> Option<Stat> {
        let means: Option<Vec<f64>> = reports
            .into_iter()
            .map(|r| r.lift_deviation.map(|l| l.reduction_pct.mean))
            .collect();
        means.map(|v| Stat::of(&v))
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    pub schema: String,
    pub env_id: String,
    pub spec_hash: String,
    pub level: String,
    pub policy: String,
    pub episodes: Vec<EvalEpisode>,
    pub ret: Stat,
    pub mean_c_d: Stat,
    pub uncontrolled_c_d: Stat,
    pub drag_reduction_pct: Stat,
    pub mean_abs_c_l: Stat,
    pub actuation_cost: Stat,
    /// The gust flows' load figure over the episodes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lift_deviation: Option<LiftDeviationStat>,
}

impl EvalReport {
    /// The statistics over `episodes` of one policy on one environment.
    pub fn of(episodes: Vec<EvalEpisode>, policy: &str, env_id: &str, spec_hash: &str, level: &str) -> EvalReport {
        let col = |f: fn(&EvalEpisode) -> f64| Stat::of(&episodes.iter().map(f).collect::<Vec<_>>());
        EvalReport {
            schema: "hgym/eval/v1".into(),
            env_id: env_id.into(),
            spec_hash: spec_hash.into(),
            level: level.into(),
            policy: policy.into(),
            ret: col(|e| e.ret),
            mean_c_d: col(|e| e.mean_c_d),
            uncontrolled_c_d: col(|e| e.uncontrolled_c_d),
            drag_reduction_pct: col(|e| e.drag_reduction_pct),
            mean_abs_c_l: col(|e| e.mean_abs_c_l),
            actuation_cost: col(|e| e.actuation_cost),
            lift_deviation: LiftDeviationStat::of(&episodes),
            episodes,
        }
    }
}
