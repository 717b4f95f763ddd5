//! Validation against the literature: one generic runner for every case file in
//! `benchmarks/validation/` (or any file a user writes).
//!
//! [`validate_case`] plans the case at a resolution level (refusing what cannot run), runs the
//! solver, analyses the force history over whole shedding periods, compares each quantity with
//! its reference and tolerance, and writes `<out>/<case>.json` (shape:
//! `schemas/validation.schema.json`), plots and the force history (`forces.csv`, see [`series`])
//! in `<out>/<case>/`. A diverged run still writes its report, the plots and the history up to
//! the failure.

pub mod analysis;
pub mod case;
pub mod channel;
pub mod plate;
pub mod report;
pub mod run;
pub mod series;
pub mod wake;

use std::path::{Path, PathBuf};

use thiserror::Error;

pub use case::{bundled, families, load_file, Level, LoadedCase};
pub use report::{Status, ValidationReport};

#[derive(Debug, Error)]
pub enum ValidateError {
    #[error("unknown validation family or case '{family}'; the bundled families are: {} (`hgym validate --list` shows their cases). Or run a case file with --case FILE", known.join(", "))]
    UnknownFamily { family: String, known: Vec<String> },
    #[error("cannot read case file {path}: {message}")]
    CaseRead { path: String, message: String },
    #[error("malformed case file {path}: {message}")]
    CaseParse { path: String, message: String },
    #[error("case '{case}' cannot run, `{field}`: {message}")]
    Unrunnable { case: String, field: String, message: String },
    #[error("solver error: {0}")]
    Solver(String),
    #[error("cannot write results to {path}: {message}")]
    Output { path: String, message: String },
}

impl ValidateError {
    /// Whether the error is the user's input (exit code 2) rather than a failed run.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            ValidateError::UnknownFamily { .. }
                | ValidateError::CaseRead { .. }
                | ValidateError::CaseParse { .. }
                | ValidateError::Unrunnable { .. }
        )
    }
}

/// The bundled cases of one family (e.g. "cylinder"), or the bundled case of that name (e.g.
/// "cylinder_re100").
pub fn family_cases(family: &str) -> Result<Vec<LoadedCase>, ValidateError> {
    let cases: Vec<LoadedCase> = bundled()?
        .into_iter()
        .filter(|c| c.case.case.family == family || c.case.case.name == family)
        .collect();
    if cases.is_empty() {
        return Err(ValidateError::UnknownFamily {
            family: family.to_string(),
            known: families()?,
        });
    }
    Ok(cases)
}

/// Options of a validation run.
#[derive(Clone, Debug)]
pub struct Options {
    pub level: Level,
    /// Output folder; the report goes to `<out>/<case>.json`, plots to `<out>/<case>/`.
    pub out: PathBuf,
    pub threads: usize,
}

/// Plans, runs, analyses, compares, and writes one case. `progress(done, total)` reports steps.
pub fn validate_case(c: &LoadedCase, opts: &Options, progress: &mut dyn FnMut(u64, u64)) -> Result<ValidationReport, ValidateError> {
    let plan = run::Plan::new(c, opts.level)?;
    let output = run::run(c, &plan, progress)?;
    let report = ValidationReport::from_run(c, &output, opts.threads);
    write_outputs(&report, &output, &opts.out)?;
    Ok(report)
}

/// Plans a case without running it (the refusals of bad parameters happen here).
pub fn plan(c: &LoadedCase, level: Level) -> Result<run::Plan, ValidateError> {
    run::Plan::new(c, level)
}

fn out_err(path: &Path) -> impl Fn(String) -> ValidateError + '_ {
    move |message| ValidateError::Output {
        path: path.display().to_string(),
        message,
    }
}

fn write_outputs(report: &ValidationReport, output: &run::RunOutput, out: &Path) -> Result<(), ValidateError> {
    if !crate::flow::ranks::leader() {
        return Ok(()); // under MPI rank 0 writes for every rank
    }
    let dir = out.join(&report.case);
    std::fs::create_dir_all(&dir).map_err(|e| out_err(&dir)(e.to_string()))?;
    report::write_plots(report, output, &dir).map_err(|e| out_err(&dir)(crate::report::chain(&e)))?;
    let csv = dir.join("forces.csv");
    series::write_forces_csv(output, &csv).map_err(|e| out_err(&csv)(e.to_string()))?;
    let json_path = out.join(format!("{}.json", report.case));
    let text = serde_json::to_string_pretty(report).map_err(|e| out_err(&json_path)(e.to_string()))?;
    std::fs::write(&json_path, text + "\n").map_err(|e| out_err(&json_path)(e.to_string()))?;
    Ok(())
}
