//! Environments validated as they run (`hgym validate --env ID --level L`): an environment's own
//! uncontrolled flow (its domain, its grid at that level, built by the same
//! `FlowSetup::build` its `reset` uses) measured with its family's validation case: the case's
//! quantities, references, tolerances, spin-up and averaging window. The deviations are kept in
//! a committed table (`benchmarks/envs/fidelity.toml`, refreshed by `--record`) that `hgym envs`
//! shows, so a user sees how far each ID and level is from the literature.
//!
//! The Kolmogorov flow, which has no force references, is checked for the intermittent bursts of
//! its uncontrolled dynamics instead ([`kolmogorov`], `hgym validate kolmogorov`).
//!
//! This module joins `env` and `validate`, which know nothing of each other.

pub mod kolmogorov;
mod sentence;

pub use sentence::sentence;

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::env::registry::LbmFlowSpec;
use crate::flow::Level;
use crate::validate::{self, LoadedCase, Status, ValidateError, ValidationReport};

/// The committed table, as text (embedded at build time).
pub const TABLE: &str = include_str!("../../benchmarks/envs/fidelity.toml");

#[derive(Debug, Error)]
pub enum FidelityError {
    #[error("{id} has no literature references here: {reason}; `hgym validate --env all` runs every ID that has them")]
    NoReference { id: String, reason: String },
    #[error(transparent)]
    Validate(#[from] ValidateError),
    #[error("{path}: {message}")]
    Table { path: String, message: String },
    #[error(transparent)]
    Record(#[from] crate::report::table::TableError),
}

impl FidelityError {
    /// Whether the error is the user's input (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        match self {
            FidelityError::NoReference { .. } | FidelityError::Table { .. } => true,
            FidelityError::Validate(v) => v.is_bad_input(),
            FidelityError::Record(e) => matches!(e, crate::report::table::TableError::Malformed { .. }),
        }
    }
}

/// One row of the table: the measured St and mean C_D of an ID's uncontrolled flow at a level,
/// and their relative deviations from the references (`(measured - reference) / reference`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    /// Hash of the flow set-up measured (`FlowSetup::hash`): a row whose hash differs from the
    /// registered flow's is stale and not shown.
    pub flow_hash: String,
    /// The validation case whose references were used.
    pub case: String,
    pub status: Status,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strouhal: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strouhal_deviation: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_cd: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_cd_deviation: Option<f64>,
}

impl Entry {
    /// The row of a report of `spec`'s flow.
    pub fn from_report(spec: &dyn LbmFlowSpec, report: &ValidationReport, case: &str) -> Entry {
        let q = |name: &str| report.quantities.iter().find(|q| q.name == name);
        let measured = |name: &str| q(name).and_then(|q| q.measured);
        let deviation = |name: &str| q(name).and_then(|q| q.deviation);
        Entry {
            flow_hash: spec.flow_setup().hash(),
            case: case.to_string(),
            status: report.status,
            strouhal: measured("strouhal"),
            strouhal_deviation: deviation("strouhal"),
            mean_cd: measured("mean_cd"),
            mean_cd_deviation: deviation("mean_cd"),
        }
    }

    /// `St 0.1605 (-2.7 %), mean C_D 1.5116 (+13.7 %) against the references of cylinder_re100:
    /// outside its tolerances`, a sentence for reports.
    pub fn describe(&self) -> String {
        if self.status == Status::Diverged {
            return format!("diverged (case {})", self.case);
        }
        let part = |name: &str, value: Option<f64>, deviation: Option<f64>| match (value, deviation) {
            (Some(v), Some(d)) => format!("{name} {v:.4} ({:+.1} %)", 100.0 * d),
            (Some(v), None) => format!("{name} {v:.4}"),
            _ => format!("{name} n/a"),
        };
        let verdict = match self.status {
            Status::Pass => "within its tolerances",
            Status::Fail => "outside its tolerances",
            _ => "measured, not judged",
        };
        format!(
            "{}, {} against the references of {}: {verdict}",
            part("St", self.strouhal, self.strouhal_deviation),
            part("mean C_D", self.mean_cd, self.mean_cd_deviation),
            self.case,
        )
    }

    /// `St +2.1% C_D +14.3%` (or `diverged`).
    pub fn summary(&self) -> String {
        if self.status == Status::Diverged {
            return "diverged".into();
        }
        // n/a: the run gave no value (e.g. no whole shedding period for St).
        let pct = |d: Option<f64>| d.map_or("n/a".to_string(), |d| format!("{:+.1}%", 100.0 * d));
        format!("St {} C_D {}", pct(self.strouhal_deviation), pct(self.mean_cd_deviation))
    }
}

/// What is known of an environment's uncontrolled flow against the literature at a level.
#[derive(Clone, Copy, Debug)]
pub enum Known {
    /// The committed row, measured on the flow registered now.
    Measured(&'static Entry),
    /// The flow has references but no current row at this level.
    NotMeasured,
    /// No references here: not a lattice-Boltzmann flow (the Kolmogorov flows' check is `hgym
    /// validate kolmogorov`), or no validation case for its family and Reynolds number.
    NoReference,
}

impl Known {
    /// `St -2.7% C_D +13.7%`, `not measured` or `-` (the `hgym envs` column).
    pub fn summary(&self) -> String {
        match self {
            Known::Measured(e) => e.summary(),
            Known::NotMeasured => "not measured".into(),
            Known::NoReference => "-".into(),
        }
    }

    pub fn entry(&self) -> Option<&'static Entry> {
        match self {
            Known::Measured(e) => Some(e),
            _ => None,
        }
    }
}

/// What the committed table says of environment `spec`'s uncontrolled flow at `level`.
pub fn known(spec: &crate::env::Spec, level: Level) -> Known {
    match crate::env::registry::lbm_flow(spec) {
        Some(flow) => match committed(flow, level) {
            Some(e) => Known::Measured(e),
            None if has_reference(flow) => Known::NotMeasured,
            None => Known::NoReference,
        },
        None => Known::NoReference,
    }
}

/// The table key of `id` at `level`.
pub fn key(id: &str, level: Level) -> String {
    format!("{id}@{}", level.name())
}

/// Parses a table; a malformed one is an error naming the problem.
pub fn parse_table(text: &str, path: &str) -> Result<BTreeMap<String, Entry>, FidelityError> {
    toml::from_str(text).map_err(|e| FidelityError::Table {
        path: path.to_string(),
        message: e.to_string(),
    })
}

/// The committed table, parsed once (a test checks that it parses; a broken one reads empty).
pub fn table() -> &'static BTreeMap<String, Entry> {
    static PARSED: std::sync::OnceLock<BTreeMap<String, Entry>> = std::sync::OnceLock::new();
    PARSED.get_or_init(|| parse_table(TABLE, "benchmarks/envs/fidelity.toml").unwrap_or_default())
}

/// The committed row of `spec` at `level`, if it was measured on the flow registered now.
pub fn committed(spec: &dyn LbmFlowSpec, level: Level) -> Option<&'static Entry> {
    table()
        .get(&key(spec.id(), level))
        .filter(|e| e.flow_hash == spec.flow_setup().hash())
}

/// The validation case of `spec`'s own flow at its level: the family's bundled case (its
/// quantities, references, times and kick) on the environment's flow, named `<ID>-<level>`.
pub fn env_case(spec: &dyn LbmFlowSpec, level: Level) -> Result<(LoadedCase, String), FidelityError> {
    let no_reference = |reason: String| FidelityError::NoReference {
        id: spec.id().to_string(),
        reason,
    };
    let case = spec
        .validation_case()
        .ok_or_else(|| no_reference("no validation case for its family and Reynolds number".into()))?;
    let base = validate::bundled()?
        .into_iter()
        .find(|c| c.case.case.name == case)
        .ok_or_else(|| no_reference(format!("no bundled validation case '{case}'")))?;
    let name = format!("{}-{}", spec.id(), level.name());
    let description = format!(
        "{}: the environment's uncontrolled flow at the {} level, against the references of {case}",
        spec.id(),
        level.name()
    );
    let loaded = base.on_flow(&spec.flow_setup(), &name, &description, &format!("env:{}", spec.id()))?;
    Ok((loaded, case))
}

/// Whether `spec`'s flow has a bundled case to compare with.
pub fn has_reference(spec: &dyn LbmFlowSpec) -> bool {
    let Some(case) = spec.validation_case() else {
        return false;
    };
    validate::case::BUNDLED
        .iter()
        .any(|(file, _)| file.strip_suffix(".toml") == Some(case.as_str()))
}

/// Writes `rows` into the table at `path` (re-read first, so rows recorded meanwhile by other
/// runs are kept), atomically.
pub fn record(path: &Path, rows: &[(String, Entry)]) -> Result<(), FidelityError> {
    crate::report::table::record(path, rows).map_err(FidelityError::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn committed_table_parses_and_names_registered_ids() {
        let entries = parse_table(TABLE, "fidelity.toml").unwrap();
        let ids: Vec<String> = crate::env::registry::all().iter().map(|s| s.id().to_string()).collect();
        for k in entries.keys() {
            let (id, level) = k.split_once('@').unwrap();
            assert!(ids.iter().any(|i| i == id), "{k}: unknown ID");
            assert!(["coarse", "default", "fine"].contains(&level), "{k}: unknown level");
        }
    }

    /// The environment's case runs the environment's flow: same set-up, the case's references.
    #[test]
    fn env_case_runs_the_environment_flow() {
        let spec = crate::env::lbm_spec("Cylinder_2D_Re100").unwrap();
        let (c, case) = env_case(&spec, Level::Coarse).unwrap();
        assert_eq!(case, "cylinder_re100");
        assert_eq!(c.case.flow_setup(), spec.flow_setup());
        assert!(!c.case.reference.is_empty());
        let err = env_case(&crate::env::lbm_spec("Cavity_2D_Re7500").unwrap(), Level::Coarse).unwrap_err();
        assert!(err.is_bad_input(), "{err}");
    }
}
