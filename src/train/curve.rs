//! The learning curve: one row per round, written as CSV and drawn as PNG.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::report::plots;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    pub round: u64,
    pub samples: u64,
    pub updates: u64,
    pub wall_s: f64,
    /// Mean over the round's training episodes (with exploration).
    pub train_return: f64,
    pub train_c_d: f64,
    /// Deterministic evaluation (NaN on rounds without one).
    pub eval_return: f64,
    pub eval_c_d: f64,
    pub eval_drag_reduction_pct: f64,
}

impl CurveRow {
    /// Fills the evaluation columns from a periodic evaluation.
    pub fn set_eval(&mut self, r: &super::eval::EvalReport) {
        self.eval_return = r.ret.mean;
        self.eval_c_d = r.mean_c_d.mean;
        self.eval_drag_reduction_pct = r.drag_reduction_pct.mean;
    }
}

pub const CSV_HEADER: &str = "round,samples,updates,wall_s,train_return,train_c_d,eval_return,eval_c_d,eval_drag_reduction_pct";

pub fn to_csv(rows: &[CurveRow]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for r in rows {
        s += &format!(
            "{},{},{},{:.3},{},{},{},{},{}\n",
            r.round, r.samples, r.updates, r.wall_s, r.train_return, r.train_c_d, r.eval_return, r.eval_c_d, r.eval_drag_reduction_pct
        );
    }
    s
}

/// Reads a curve back (for `hgym plot` and leaderboards); empty cells and "NaN" are NaN.
/// A `curve.csv` that is not an hgym learning curve (the user's input).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct CurveFormatError(pub String);

pub fn from_csv(text: &str) -> Result<Vec<CurveRow>, CurveFormatError> {
    let mut lines = text.lines();
    if lines.next().map(|h| h.trim()) != Some(CSV_HEADER) {
        return Err(CurveFormatError("not an hgym learning curve (unexpected header)".into()));
    }
    let f = |s: &str| s.trim().parse::<f64>().unwrap_or(f64::NAN);
    let u = |s: &str| {
        s.trim()
            .parse::<u64>()
            .map_err(|_| CurveFormatError(format!("'{s}' is not a count")))
    };
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            if c.len() != 9 {
                return Err(CurveFormatError(format!("curve row '{l}' has {} columns, expected 9", c.len())));
            }
            Ok(CurveRow {
                round: u(c[0])?,
                samples: u(c[1])?,
                updates: u(c[2])?,
                wall_s: f(c[3]),
                train_return: f(c[4]),
                train_c_d: f(c[5]),
                eval_return: f(c[6]),
                eval_c_d: f(c[7]),
                eval_drag_reduction_pct: f(c[8]),
            })
        })
        .collect()
}

/// `curve.png`: training and evaluation return against samples; `drag_reduction.png`: the
/// evaluation drag reduction.
pub fn plot(dir: &Path, title: &str, rows: &[CurveRow]) -> Result<(), crate::report::plots::PlotError> {
    let x: Vec<f64> = rows.iter().map(|r| r.samples as f64).collect();
    let tr: Vec<f64> = rows.iter().map(|r| r.train_return).collect();
    let ev: Vec<f64> = rows.iter().map(|r| r.eval_return).collect();
    let (xe, ye): (Vec<f64>, Vec<f64>) = x.iter().zip(&ev).filter(|(_, y)| y.is_finite()).map(|(a, b)| (*a, *b)).unzip();
    plots::lines(
        &dir.join("curve.png"),
        title,
        "environment samples",
        "episode return",
        &[
            plots::Line {
                label: "training (with exploration)",
                x: &x,
                y: &tr,
                band: None,
            },
            plots::Line {
                label: "evaluation (deterministic)",
                x: &xe,
                y: &ye,
                band: None,
            },
        ],
    )?;
    let (xd, yd): (Vec<f64>, Vec<f64>) = rows
        .iter()
        .filter(|r| r.eval_drag_reduction_pct.is_finite())
        .map(|r| (r.samples as f64, r.eval_drag_reduction_pct))
        .unzip();
    plots::lines(
        &dir.join("drag_reduction.png"),
        title,
        "environment samples",
        "drag reduction (%)",
        &[plots::Line {
            label: "evaluation (deterministic)",
            x: &xd,
            y: &yd,
            band: None,
        }],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_keeps_nan() {
        let rows = vec![CurveRow {
            round: 1,
            samples: 400,
            updates: 3,
            wall_s: 1.5,
            train_return: -3.25,
            train_c_d: 1.5,
            eval_return: f64::NAN,
            eval_c_d: f64::NAN,
            eval_drag_reduction_pct: f64::NAN,
        }];
        let back = from_csv(&to_csv(&rows)).unwrap();
        assert_eq!(back[0].samples, 400);
        assert_eq!(back[0].train_return, -3.25);
        assert!(back[0].eval_return.is_nan());
    }
}
