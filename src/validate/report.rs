//! The validation report: what was measured against what, and whether it passed. Serialised to
//! JSON (shape: `schemas/validation.schema.json`) and printed as a table.

use std::path::Path;

use plotters::style::RGBColor;
use serde::{Deserialize, Serialize};

use super::analysis::{analyse, spectrum, standard_error, Analysis};
use super::case::{Component, LoadedCase, Quantity};
use super::run::{RunOutput, RunStatus};
use super::wake::recirculation_length;
use crate::report::manifest::{manifest, Manifest};
use crate::report::plots;

pub const SCHEMA_ID: &str = "hgym/validation/v1";

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Pass,
    Fail,
    Diverged,
    /// Completed with no judged reference: measured, not validated.
    Unjudged,
}

impl Status {
    /// Whether the run met everything it was judged on (exit 0): passed, or only measured.
    pub fn is_ok(self) -> bool {
        matches!(self, Status::Pass | Status::Unjudged)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Parameters {
    pub reynolds: f64,
    pub cells_per_length: f64,
    pub lattice_velocity: f64,
    pub tau: f64,
    pub mach: f64,
    pub nx: usize,
    pub ny: usize,
    /// Nodes along the span (3D cases).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nz: Option<usize>,
    pub collision: String,
    pub spin_up: f64,
    pub average: f64,
    pub steps_planned: u64,
    pub steps_run: u64,
    pub mlups: f64,
    /// The nested 2:1 patches, when the case refines.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refinement: Option<RefinementParams>,
}

/// Each patch as `[x0, x1, y0, y1]` in the node indices of the grid it refines; cells per length
/// and relaxation time of the finest grid.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RefinementParams {
    /// Each patch's node ranges in its parent's nodes: `[x0, x1, y0, y1]`, with `z0, z1` in 3D.
    pub patches: Vec<Vec<usize>>,
    pub cells_per_length: f64,
    pub tau: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct QuantityResult {
    pub name: String,
    /// `None` when it could not be measured (e.g. no shedding, or the run diverged).
    pub measured: Option<f64>,
    pub reference: Option<f64>,
    pub tolerance: Option<f64>,
    /// "relative" or "absolute".
    pub tolerance_kind: Option<String>,
    /// Relative `(measured - reference) / |reference|` or absolute `measured - reference`.
    pub deviation: Option<f64>,
    /// Within tolerance; `None` for quantities measured without a reference.
    pub pass: Option<bool>,
    pub source: Option<String>,
    /// `false` for an unconfirmed reference: `pass` is shown but the status ignores it.
    #[serde(default = "judged_by_default", skip_serializing_if = "is_judged")]
    pub judged: bool,
    /// Why the reference is unconfirmed (with `judged = false`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The quantity over each batch of consecutive whole periods of the window (batch means,
    /// [`crate::validate::analysis::BATCHES`]); absent for short windows and in reports written
    /// before it was added.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub batches: Vec<f64>,
    /// Standard error of `measured` from the batches' scatter: how far this window's length pins
    /// the value down (sampling, not discretisation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub standard_error: Option<f64>,
}

fn judged_by_default() -> bool {
    true
}

fn is_judged(judged: &bool) -> bool {
    *judged
}

impl QuantityResult {
    /// A quantity whose tolerance the case's status hangs on and which is outside it.
    pub fn fails(&self) -> bool {
        self.judged && self.pass == Some(false)
    }

    /// The standard error as the table prints it: relative to the measured value (`±4.1%`) for
    /// relative tolerances and quantities without a reference, absolute (`±0.0040`) otherwise.
    pub fn standard_error_text(&self) -> Option<String> {
        let se = self.standard_error?;
        match (self.tolerance_kind.as_deref(), self.measured) {
            (Some("absolute"), _) => Some(format!("±{se:.4}")),
            (_, Some(m)) if m != 0.0 => Some(format!("±{:.1}%", 100.0 * se / m.abs())),
            _ => Some(format!("±{se:.4}")),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AnalysisOut {
    pub strouhal_zero_crossings: Option<f64>,
    pub strouhal_spectral: Option<f64>,
    pub periods: usize,
    pub window: [f64; 2],
    /// The lift spectrum's substantial peaks `[St, height / tallest]`, tallest first (absent in
    /// reports written before it was added).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lift_peaks: Vec<[f64; 2]>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ValidationReport {
    pub schema: String,
    pub case: String,
    pub family: String,
    pub description: String,
    pub origin: String,
    pub case_hash: String,
    pub level: String,
    pub status: Status,
    pub message: Option<String>,
    pub parameters: Parameters,
    pub quantities: Vec<QuantityResult>,
    pub analysis: AnalysisOut,
    /// Plot files, relative to the report's folder.
    pub plots: Vec<String>,
    pub manifest: Manifest,
}

/// Mean of `v` over the samples with `t` in `[w0, w1)`.
fn window_mean(t: &[f64], v: &[f64], w: [f64; 2]) -> Option<f64> {
    let (s, n) = t
        .iter()
        .zip(v)
        .filter(|(t, _)| **t >= w[0] && **t < w[1])
        .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
    (n > 0).then(|| s / n as f64)
}

fn measured(a: &Analysis, q: Quantity, out: &RunOutput) -> Option<f64> {
    if let Some((b, component)) = q.body() {
        let per_body = match component {
            Component::Drag => &out.cd_bodies,
            Component::Lift => &out.cl_bodies,
        };
        return per_body
            .get(b)
            .and_then(|v| window_mean(&out.t, v, a.window))
            .filter(|v| v.is_finite());
    }
    match q {
        Quantity::Strouhal => a.strouhal,
        Quantity::MeanCd => Some(a.mean_cd),
        Quantity::MeanCl => Some(a.mean_cl),
        Quantity::ClAmplitude => Some(a.cl_amplitude),
        Quantity::ClRms => Some(a.cl_rms),
        Quantity::CdAmplitude => Some(a.cd_amplitude),
        Quantity::RecirculationLength => out.wake.as_ref().and_then(recirculation_length),
        Quantity::MeanCl1 | Quantity::MeanCl2 | Quantity::MeanCl3 | Quantity::MeanCd1 | Quantity::MeanCd2 | Quantity::MeanCd3 => None,
    }
    .filter(|v| v.is_finite())
}

impl ValidationReport {
    pub fn from_run(c: &LoadedCase, out: &RunOutput, threads: usize) -> Self {
        let case = &c.case;
        let diverged = matches!(out.status, RunStatus::Diverged { .. });
        let a = analyse(&out.t, &out.cd, &out.cl, case.time.spin_up);
        let mut quantities = Vec::new();
        for &q in &case.measure.quantities {
            let m = if diverged { None } else { measured(&a, q, out) };
            // The wake is averaged over the whole window only, not per batch.
            let batches: Vec<f64> = if m.is_some() && q != Quantity::RecirculationLength {
                a.batches.iter().map_while(|b| measured(b, q, out)).collect()
            } else {
                vec![]
            };
            let batches = if batches.len() == a.batches.len() { batches } else { vec![] };
            let r = case.reference.iter().find(|r| r.quantity == q);
            let (reference, tolerance, kind, deviation, pass, source) = match r {
                None => (None, None, None, None, None, None),
                Some(r) => {
                    let (tol, kind) = match (r.tolerance, r.abs_tolerance) {
                        (Some(t), _) => (t, "relative"),
                        (None, Some(t)) => (t, "absolute"),
                        (None, None) => (0.0, "relative"),
                    };
                    let dev = m.map(|m| {
                        if kind == "relative" {
                            (m - r.value) / r.value.abs()
                        } else {
                            m - r.value
                        }
                    });
                    let pass = dev.is_some_and(|d| d.abs() <= tol);
                    (
                        Some(r.value),
                        Some(tol),
                        Some(kind.to_string()),
                        dev,
                        Some(pass),
                        Some(r.source.clone()),
                    )
                }
            };
            quantities.push(QuantityResult {
                name: q.name().into(),
                measured: m,
                reference,
                tolerance,
                tolerance_kind: kind,
                deviation,
                pass,
                source,
                standard_error: standard_error(&batches),
                batches,
                judged: r.is_none_or(|r| r.is_judged()),
                reason: r.and_then(|r| r.reason.clone()),
            });
        }
        let (status, message) = match &out.status {
            RunStatus::Diverged { message, .. } => (Status::Diverged, Some(message.clone())),
            RunStatus::Completed => {
                if !quantities.iter().any(|q| q.judged && q.reference.is_some()) {
                    (
                        Status::Unjudged,
                        Some("no judged reference: these are measurements, not a validation".to_string()),
                    )
                } else if !quantities.iter().any(QuantityResult::fails) {
                    (Status::Pass, None)
                } else {
                    let failed: Vec<String> = quantities.iter().filter(|q| q.fails()).map(|q| q.name.clone()).collect();
                    (Status::Fail, Some(format!("out of tolerance: {}", failed.join(", "))))
                }
            }
        };
        let p = &out.plan;
        ValidationReport {
            schema: SCHEMA_ID.into(),
            case: case.case.name.clone(),
            family: case.case.family.clone(),
            description: case.case.description.clone(),
            origin: c.origin.clone(),
            case_hash: c.hash.clone(),
            level: p.flow.level.name().into(),
            status,
            message,
            parameters: Parameters {
                reynolds: case.flow.reynolds,
                cells_per_length: p.flow.units.cells_per_length,
                lattice_velocity: p.flow.units.u_lattice,
                tau: p.flow.tau,
                mach: p.flow.mach,
                nx: p.flow.nx,
                ny: p.flow.ny,
                nz: p.flow.nz,
                collision: p.flow.collision.name().into(),
                spin_up: case.time.spin_up,
                average: case.time.average,
                steps_planned: p.total_steps,
                steps_run: out.steps,
                mlups: out.mlups,
                refinement: p.flow.refinement.as_ref().map(|r| RefinementParams {
                    patches: r
                        .patches
                        .iter()
                        .map(|p| vec![p.x[0], p.x[1], p.y[0], p.y[1]])
                        .chain(r.boxes.iter().map(|b| vec![b.lo[0], b.hi[0], b.lo[1], b.hi[1], b.lo[2], b.hi[2]]))
                        .collect(),
                    cells_per_length: r.cells_per_length,
                    tau: r.tau,
                }),
            },
            quantities,
            analysis: AnalysisOut {
                strouhal_zero_crossings: a.strouhal,
                strouhal_spectral: a.strouhal_spectral,
                periods: a.periods,
                window: a.window,
                lift_peaks: a.lift_peaks.clone(),
            },
            plots: ["forces.png", "spectrum.png", "vorticity.png"]
                .into_iter()
                .chain(out.wake.as_ref().map(|_| "wake.png"))
                .map(String::from)
                .collect(),
            manifest: manifest(threads, out.wall_time_s),
        }
    }

    /// A line for each quantity whose standard error from the batches is more than half its
    /// tolerance: twice the standard error is about the 95 % half-width (with four batches
    /// Student's t gives 3.2 times it, so the note is, if anything, too rarely shown), so this
    /// window's length cannot tell a pass from a fail, whatever the solver does.
    pub fn sampling_notes(&self) -> Vec<String> {
        self.quantities
            .iter()
            .filter_map(|q| {
                let (se, tol) = (q.standard_error?, q.tolerance?);
                let se_in_tol_units = if q.tolerance_kind.as_deref() == Some("absolute") {
                    se
                } else {
                    se / q.reference?.abs()
                };
                (2.0 * se_in_tol_units > tol).then(|| {
                    let values: Vec<String> = q.batches.iter().map(|v| format!("{v:.4}")).collect();
                    format!(
                        "sampling: {} over {} batches of the window is {} (standard error {}), more than half the tolerance: a longer window is needed to decide it",
                        q.name,
                        q.batches.len(),
                        values.join(", "),
                        q.standard_error_text().unwrap_or_default()
                    )
                })
            })
            .collect()
    }

    /// A line for a lift that is no limit cycle: its spectrum's substantial peaks are not all
    /// harmonics of the frequency measured, so a Strouhal number summarises a broadband wake.
    pub fn broadband_note(&self) -> Option<String> {
        let f = self.analysis.strouhal_spectral?;
        let peaks = &self.analysis.lift_peaks;
        if peaks.is_empty() || crate::validate::analysis::is_harmonic_series(peaks, f) {
            return None;
        }
        let list: Vec<String> = peaks.iter().map(|p| format!("{:.3} ({:.2})", p[0], p[1])).collect();
        Some(format!(
            "broadband lift, not a limit cycle: spectral peaks at St {} (height / tallest); the Strouhal number counts the cycles of the tallest",
            list.join(", ")
        ))
    }

    /// Plain-text table: quantity, measured, its standard error, reference, deviation, tolerance,
    /// pass/fail; then notes (failures, a broadband lift, a window too short to decide).
    pub fn table(&self) -> String {
        let p = &self.parameters;
        let grid = match p.nz {
            Some(nz) => format!("{} x {} x {nz}", p.nx, p.ny),
            None => format!("{} x {}", p.nx, p.ny),
        };
        let mut s = format!(
            "{} [{}] level {} ({grid} cells, {} cells/L, tau {:.5}, Ma {:.3}): {}\n",
            self.case,
            self.family,
            self.level,
            self.parameters.cells_per_length,
            self.parameters.tau,
            self.parameters.mach,
            match self.status {
                Status::Pass => "PASS",
                Status::Fail => "FAIL",
                Status::Diverged => "DIVERGED",
                Status::Unjudged => "UNJUDGED",
            }
        );
        if let Some(r) = &self.parameters.refinement {
            let patches: Vec<String> = r
                .patches
                .iter()
                .map(|p| {
                    let axes = ["x", "y", "z"].iter().zip(p.chunks(2));
                    axes.map(|(a, r)| format!("{a} {}..={}", r[0], r[1])).collect::<Vec<_>>().join(", ")
                })
                .collect();
            s += &format!(
                "  refined 2:1 x {} around the bodies (each patch in its parent's nodes: {}): {} cells/L, tau {:.5} there\n",
                r.patches.len(),
                patches.join("; "),
                r.cells_per_length,
                r.tau
            );
        }
        s += &format!(
            "  {:<20} {:>10} {:>9} {:>10} {:>10} {:>10}  {}\n",
            "quantity", "measured", "s.e.", "reference", "deviation", "tolerance", "result"
        );
        for q in &self.quantities {
            let num = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4}"));
            let (dev, tol) = match q.tolerance_kind.as_deref() {
                Some("absolute") => (
                    q.deviation.map_or("-".into(), |d| format!("{d:+.4}")),
                    q.tolerance.map_or("-".into(), |t| format!("{t:.4}")),
                ),
                _ => (
                    q.deviation.map_or("-".into(), |d| format!("{:+.2}%", 100.0 * d)),
                    q.tolerance.map_or("-".into(), |t| format!("{:.1}%", 100.0 * t)),
                ),
            };
            let res = match (q.pass, q.judged) {
                (Some(true), true) => "pass",
                (Some(false), true) => "FAIL",
                (Some(true), false) => "within (unconfirmed ref.)",
                (Some(false), false) => "outside (unconfirmed ref.)",
                (None, _) => "(info)",
            };
            s += &format!(
                "  {:<20} {:>10} {:>9} {:>10} {:>10} {:>10}  {}\n",
                q.name,
                num(q.measured),
                q.standard_error_text().unwrap_or_else(|| "-".into()),
                num(q.reference),
                dev,
                tol,
                res
            );
        }
        if let Some(m) = &self.message {
            s += &format!("  note: {m}\n");
        }
        // Unjudged quantities, grouped by their reason (one reason usually covers several).
        let mut reasons: Vec<(&str, Vec<&str>)> = vec![];
        for q in self.quantities.iter().filter(|q| !q.judged) {
            let reason = q.reason.as_deref().unwrap_or("no reason recorded");
            match reasons.iter_mut().find(|(r, _)| *r == reason) {
                Some((_, names)) => names.push(&q.name),
                None => reasons.push((reason, vec![&q.name])),
            }
        }
        for (reason, names) in reasons {
            s += &format!("  note: not judged (unconfirmed references): {}: {reason}\n", names.join(", "));
        }
        if let Some(line) = self.broadband_note() {
            s += &format!("  note: {line}\n");
        }
        for line in self.sampling_notes() {
            s += &format!("  note: {line}\n");
        }
        let averaged = match self.analysis.periods {
            0 => "no shedding (steady lift), means".to_string(),
            p => format!("{p} whole periods averaged"),
        };
        s += &format!(
            "  {} of {} steps in {:.1} s ({:.0} MLUPS), {averaged} over t = [{:.1}, {:.1}]\n",
            self.parameters.steps_run,
            self.parameters.steps_planned,
            self.manifest.wall_time_s,
            self.parameters.mlups,
            self.analysis.window[0],
            self.analysis.window[1]
        );
        s
    }
}

/// Force history (window marked), lift spectrum (measured and reference St marked), vorticity.
pub fn write_plots(r: &ValidationReport, out: &RunOutput, dir: &Path) -> Result<(), plots::PlotError> {
    let title = format!("{} ({} level): drag and lift", r.case, r.level);
    let window = (r.analysis.window[1] > r.analysis.window[0]).then_some(r.analysis.window);
    plots::time_series(
        &dir.join("forces.png"),
        &title,
        &out.t,
        &[
            plots::Series {
                label: "C_D",
                values: &out.cd,
            },
            plots::Series {
                label: "C_L",
                values: &out.cl,
            },
        ],
        window,
    )?;
    let first = out.t.iter().position(|&t| t >= r.parameters.spin_up).unwrap_or(out.t.len());
    let (freqs, amps) = spectrum(&out.t[first..], &out.cl[first..]);
    let mut marks = Vec::new();
    if let Some(st) = r.analysis.strouhal_zero_crossings {
        marks.push((st, format!("measured St = {st:.4}"), RGBColor(200, 30, 30)));
    }
    if let Some(q) = r.quantities.iter().find(|q| q.name == "strouhal") {
        if let Some(v) = q.reference {
            marks.push((v, format!("reference St = {v:.4}"), RGBColor(30, 150, 30)));
        }
    }
    let f_max = marks.iter().map(|m| m.0).fold(0.5f64, f64::max) * 2.0;
    plots::spectrum(
        &dir.join("spectrum.png"),
        &format!("{}: lift spectrum after spin-up", r.case),
        &freqs,
        &amps,
        f_max.min(2.0),
        &marks,
    )?;
    let t_end = out.t.last().copied().unwrap_or(0.0);
    plots::field_png(
        &out.vorticity,
        &dir.join("vorticity.png"),
        &format!("{}: vorticity w L/U at t = {t_end:.1}", r.case),
    )?;
    if let Some(w) = &out.wake {
        let zero = vec![0.0; w.x.len()];
        plots::lines(
            &dir.join("wake.png"),
            &format!(
                "{}: mean streamwise velocity on the wake's centreline ({} samples)",
                r.case, w.samples
            ),
            "x / L behind the base",
            "mean u / U",
            &[
                plots::Line {
                    label: "mean u / U",
                    x: &w.x,
                    y: &w.u,
                    band: None,
                },
                plots::Line {
                    label: "0",
                    x: &w.x,
                    y: &zero,
                    band: None,
                },
            ],
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled square Re 200 case's report (spin-up 60 L/U) for a synthetic force history
    /// sampled every 0.01 L/U up to 220 L/U: drag 1.46, lift `sin(2 pi phase(t))`.
    fn synthetic_report(phase: &dyn Fn(f64) -> f64) -> ValidationReport {
        let c = crate::validate::bundled()
            .unwrap()
            .into_iter()
            .find(|c| c.case.case.name == "square_re200")
            .unwrap();
        ValidationReport::from_run(&c, &synthetic_output(phase), 1)
    }

    /// A coarse square_re200 run's output with drag 1.46 and a lift of amplitude 0.4 at `phase(t)`.
    fn synthetic_output(phase: &dyn Fn(f64) -> f64) -> RunOutput {
        use crate::flow::Field;
        use crate::validate::run::RunStatus;
        let c = crate::validate::bundled()
            .unwrap()
            .into_iter()
            .find(|c| c.case.case.name == "square_re200")
            .unwrap();
        let plan = crate::validate::plan(&c, crate::validate::Level::Coarse).unwrap();
        let t: Vec<f64> = (0..22_000).map(|j| j as f64 * 0.01).collect();
        RunOutput {
            plan,
            cd: vec![1.46; t.len()],
            cl: t.iter().map(|&t| 0.4 * (2.0 * std::f64::consts::PI * phase(t)).sin()).collect(),
            t,
            cd_bodies: vec![],
            cl_bodies: vec![],
            vorticity: Field {
                nx: 0,
                ny: 0,
                extent: [0.0; 4],
                values: vec![],
            },
            wake: None,
            status: RunStatus::Completed,
            wall_time_s: 0.0,
            steps: 0,
            mlups: 0.0,
        }
    }

    /// Each quantity carries its batch values and their standard error. A limit cycle's are at
    /// round-off and the table says nothing more; a lift whose frequency alternates between 0.14
    /// and 0.16 every 40 L/U (six periods, about a batch) has a standard error of about 4 %, more
    /// than half the 3 % tolerance of St, and the table says the window cannot decide it.
    #[test]
    fn the_table_says_when_the_window_is_too_short_to_decide() {
        let steady = synthetic_report(&|t| 0.15 * t);
        let st = &steady.quantities[0];
        assert_eq!(st.name, "strouhal");
        assert_eq!(st.batches.len(), crate::validate::analysis::BATCHES);
        assert!(st.standard_error.unwrap() < 1e-5, "{st:?}");
        assert!(steady.sampling_notes().is_empty());
        assert!(steady.table().contains("±0.0%"), "{}", steady.table());
        // 0.14 on [60, 100), 0.16 on [100, 140), ...: the phase, integrated piecewise.
        let f = |k: i64| if k % 2 == 0 { 0.14 } else { 0.16 };
        let phase = |t: f64| {
            let k = ((t + 20.0) / 40.0).floor() as i64;
            (0..k).map(|j| 40.0 * f(j)).sum::<f64>() - 20.0 * f(0) + f(k) * (t + 20.0 - 40.0 * k as f64)
        };
        let wandering = synthetic_report(&phase);
        println!("{}", wandering.table());
        let st = &wandering.quantities[0];
        let se = st.standard_error.unwrap() / st.measured.unwrap();
        assert!((0.02..0.045).contains(&se), "{st:?}");
        let notes = wandering.sampling_notes();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("sampling: strouhal over 4 batches of the window is 0.1"),
            "{notes:?}"
        );
        assert!(wandering.table().contains(&format!("note: {}", notes[0])));
        // Serialised with the report, and read back.
        let json = serde_json::to_string(&wandering).unwrap();
        let back: ValidationReport = serde_json::from_str(&json).unwrap();
        assert_eq!(back.quantities[0].batches, st.batches);
    }

    /// A report written before `lift_peaks` existed still reads (the committed square-cylinder
    /// Re 1000 report with the field taken out) and has no note; the committed report itself, a
    /// broadband wake, names its peaks in its table, tallest first; a harmonic series does not.
    #[test]
    fn a_broadband_lift_is_named_in_the_table() {
        // Read at run time: a build reused from another clone of the tree would carry its path.
        let repo = std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_else(|| env!("CARGO_MANIFEST_DIR").into());
        let path = Path::new(&repo).join("results/validation/square_re1000.json");
        let text = std::fs::read_to_string(path).unwrap();
        let mut old: serde_json::Value = serde_json::from_str(&text).unwrap();
        old["analysis"].as_object_mut().unwrap().remove("lift_peaks");
        let old: ValidationReport = serde_json::from_value(old).unwrap();
        assert!(old.analysis.lift_peaks.is_empty());
        assert!(old.broadband_note().is_none());
        let mut r: ValidationReport = serde_json::from_str(&text).unwrap();
        let peaks = r.analysis.lift_peaks.clone();
        assert!(peaks.len() >= 3, "{peaks:?}");
        assert_eq!(peaks[0][1], 1.0);
        let table = r.table();
        let first = format!(
            "note: broadband lift, not a limit cycle: spectral peaks at St {:.3} (1.00), {:.3} ({:.2})",
            peaks[0][0], peaks[1][0], peaks[1][1]
        );
        assert!(table.contains(&first), "{table}");
        r.analysis.strouhal_spectral = Some(0.0917);
        r.analysis.lift_peaks = vec![[0.0917, 1.0], [0.1834, 0.6], [0.2751, 0.3]];
        assert!(r.broadband_note().is_none());
        assert!(!r.table().contains("broadband"));
    }

    /// An unconfirmed reference (judged = false) is reported with its deviation and reason but
    /// does not fail the case; the same reference judged fails it; and a case file cannot mark a
    /// reference unjudged without saying why.
    #[test]
    fn an_unjudged_reference_is_reported_but_does_not_fail_the_case() {
        let shedding = |t: f64| 0.15 * t;
        let mut c = crate::validate::bundled()
            .unwrap()
            .into_iter()
            .find(|c| c.case.case.name == "square_re200")
            .unwrap();
        // St and mean C_D only (the synthetic lift's RMS is not the square's).
        c.case.reference.retain(|x| x.quantity != crate::validate::case::Quantity::ClRms);
        let out = synthetic_output(&shedding);
        assert_eq!(ValidationReport::from_run(&c, &out, 1).status, Status::Pass);
        // The mean C_D reference of the case: judged (None) or not (Some(false)), with a reason or not.
        let set_cd = |c: &mut LoadedCase, judged: Option<bool>, reason: Option<&str>| {
            let cd = c
                .case
                .reference
                .iter_mut()
                .find(|x| x.quantity == crate::validate::case::Quantity::MeanCd)
                .unwrap();
            cd.value = 2.0; // the synthetic run's mean C_D is 1.46: 27 % off
            cd.judged = judged;
            cd.reason = reason.map(String::from);
        };
        set_cd(&mut c, Some(false), Some("no independent value"));
        c.check_static().unwrap();
        let r = ValidationReport::from_run(&c, &out, 1);
        assert_eq!(r.status, Status::Pass, "{}", r.table());
        let table = r.table();
        assert!(
            table.contains("outside (unconfirmed ref.)") && table.contains("no independent value"),
            "{table}"
        );
        set_cd(&mut c, None, None);
        assert_eq!(ValidationReport::from_run(&c, &out, 1).status, Status::Fail);
        set_cd(&mut c, Some(false), None);
        let e = c.check_static().unwrap_err();
        assert!(e.to_string().contains("reason"), "{e}");
    }
}
