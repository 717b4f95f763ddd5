//! Validation cases as data: the TOML format, its checks, and the bundled cases.
//!
//! A case file says what it checks (`[case]`), the set-up (`[geometry]`, `[domain]`,
//! `[boundaries]`, `[inlet]`, `[flow]`, `[resolution]`, `[time]`, optional absorbing layers
//! `[[sponge]]`), which quantities to measure (`[measure]`) and the reference values with their
//! sources and tolerances (`[[reference]]`).
//! Lengths are in units of the body's reference length (diameter, side or chord), velocities in
//! units of the reference velocity U, times in L/U. Every key is checked: an unknown key is an
//! error that names it. See `benchmarks/validation/*.toml` for complete examples.

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use hgym_solvers::lbm::Collision;

pub use crate::flow::{
    BoundaryKind, BoundarySpec, DomainSpec, EdgeName, GeometrySpec, InletSpec, Level, Profile, RefinementSpec, ResolutionSpec, SpanSpec,
    SpongeSpec, VelocityReference, MAX_LATTICE_SPEED, MAX_NODES,
};
use crate::flow::{FlowError, FlowSetup};

use super::ValidateError;

/// The cases shipped inside the binary: `(file name, text)`.
pub const BUNDLED: &[(&str, &str)] = &[
    (
        "cylinder_re100.toml",
        include_str!("../../benchmarks/validation/cylinder_re100.toml"),
    ),
    (
        "cylinder_re200.toml",
        include_str!("../../benchmarks/validation/cylinder_re200.toml"),
    ),
    (
        "cylinder_re1000.toml",
        include_str!("../../benchmarks/validation/cylinder_re1000.toml"),
    ),
    ("pinball_re30.toml", include_str!("../../benchmarks/validation/pinball_re30.toml")),
    ("pinball_re100.toml", include_str!("../../benchmarks/validation/pinball_re100.toml")),
    ("pinball_re150.toml", include_str!("../../benchmarks/validation/pinball_re150.toml")),
    (
        "pinball_re30_steady.toml",
        include_str!("../../benchmarks/validation/pinball_re30_steady.toml"),
    ),
    ("square_re200.toml", include_str!("../../benchmarks/validation/square_re200.toml")),
    ("square_re1000.toml", include_str!("../../benchmarks/validation/square_re1000.toml")),
    ("sphere_re100.toml", include_str!("../../benchmarks/validation/sphere_re100.toml")),
    ("sphere_re300.toml", include_str!("../../benchmarks/validation/sphere_re300.toml")),
    (
        "sphere_re100_refined.toml",
        include_str!("../../benchmarks/validation/sphere_re100_refined.toml"),
    ),
    (
        "sphere_re300_refined.toml",
        include_str!("../../benchmarks/validation/sphere_re300_refined.toml"),
    ),
    (
        "square3d_re300.toml",
        include_str!("../../benchmarks/validation/square3d_re300.toml"),
    ),
    ("cube_re300.toml", include_str!("../../benchmarks/validation/cube_re300.toml")),
    (
        "cylinder3d_re200.toml",
        include_str!("../../benchmarks/validation/cylinder3d_re200.toml"),
    ),
    (
        "cylinder3d_re3900.toml",
        include_str!("../../benchmarks/validation/cylinder3d_re3900.toml"),
    ),
    (
        "pinball3d_re30.toml",
        include_str!("../../benchmarks/validation/pinball3d_re30.toml"),
    ),
    (
        "pinball3d_re100.toml",
        include_str!("../../benchmarks/validation/pinball3d_re100.toml"),
    ),
    (
        "pinball3d_re150.toml",
        include_str!("../../benchmarks/validation/pinball3d_re150.toml"),
    ),
];

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub case: CaseInfo,
    /// The reference body (its length is L; it is body 1 in per-body quantities).
    pub geometry: GeometrySpec,
    /// Further bodies (`[[more_bodies]]`, same keys as `[geometry]`): bodies 2, 3, ... Drag and
    /// lift quantities are totals over all bodies; `mean_cl_2`, `mean_cl_3` are per body.
    #[serde(default)]
    pub more_bodies: Vec<GeometrySpec>,
    pub domain: DomainSpec,
    pub boundaries: BoundarySpec,
    #[serde(default)]
    pub inlet: InletSpec,
    pub flow: FlowSpec,
    pub resolution: ResolutionSpec,
    pub time: TimeSpec,
    pub measure: MeasureSpec,
    /// Absorbing layers (`[[sponge]]`) that let pressure waves leave the domain: without them the
    /// waves of the impulsive start stay trapped between a velocity inlet, an outlet and periodic
    /// sides, where the weak viscosity at Re >= 30 takes hundreds of L/U to damp them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sponge: Vec<SpongeSpec>,
    /// Local grid refinement (`[refinement]`): a rectangle around the bodies solved on a grid
    /// twice as fine, coupled to the grid of the level (see `hgym_solvers::lbm::Refined`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refinement: Option<RefinementSpec>,
    /// The span of a 3D case (`[span]`): z range, spanwise faces, segments, velocity set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub span: Option<SpanSpec>,
    #[serde(default)]
    pub reference: Vec<ReferenceSpec>,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    pub name: String,
    pub family: String,
    #[serde(default)]
    pub description: String,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FlowSpec {
    pub reynolds: f64,
    /// Lattice value of U.
    pub lattice_velocity: f64,
    /// `"bgk"`, `"regularized"` (default) or `"recursive"` (recursive regularised: stable much
    /// closer to tau = 1/2, see `hgym_solvers::lbm::collision`).
    #[serde(default)]
    pub collision: Collision,
    /// Smagorinsky constant of the subgrid viscosity (regularised operators; 0 = none). Laminar
    /// validation cases leave it at 0; under-resolved runs at Re >= 1000 need about 0.1.
    #[serde(default)]
    pub smagorinsky: f64,
    /// Amplitude (fraction of U) of a transverse velocity kick near the body at t = 0; a negative
    /// value is the mirror image of the positive one (it selects the other of two mirror states).
    #[serde(default)]
    pub perturbation: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Time discarded before averaging (L/U).
    pub spin_up: f64,
    /// Length of the averaging window (L/U); statistics use the whole shedding periods in it.
    pub average: f64,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Shedding frequency `f L / U` from the lift signal.
    Strouhal,
    MeanCd,
    MeanCl,
    /// Half the peak-to-peak lift per shedding period, averaged.
    ClAmplitude,
    ClRms,
    CdAmplitude,
    /// Mean lift of body 1, 2, 3 (1 = `[geometry]`, then `[[more_bodies]]` in order).
    #[serde(rename = "mean_cl_1")]
    MeanCl1,
    #[serde(rename = "mean_cl_2")]
    MeanCl2,
    #[serde(rename = "mean_cl_3")]
    MeanCl3,
    /// Mean drag of body 1, 2, 3.
    #[serde(rename = "mean_cd_1")]
    MeanCd1,
    #[serde(rename = "mean_cd_2")]
    MeanCd2,
    #[serde(rename = "mean_cd_3")]
    MeanCd3,
    /// Mean recirculation length `L_r / L`: from the body's base to where the time-averaged
    /// streamwise velocity on the wake's centreline (averaged along an extruded body's span)
    /// turns from negative to positive.
    RecirculationLength,
}

/// Which force component a per-body quantity averages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Component {
    Drag,
    Lift,
}

impl Quantity {
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Strouhal => "strouhal",
            Quantity::MeanCd => "mean_cd",
            Quantity::MeanCl => "mean_cl",
            Quantity::ClAmplitude => "cl_amplitude",
            Quantity::ClRms => "cl_rms",
            Quantity::CdAmplitude => "cd_amplitude",
            Quantity::MeanCl1 => "mean_cl_1",
            Quantity::MeanCl2 => "mean_cl_2",
            Quantity::MeanCl3 => "mean_cl_3",
            Quantity::MeanCd1 => "mean_cd_1",
            Quantity::MeanCd2 => "mean_cd_2",
            Quantity::MeanCd3 => "mean_cd_3",
            Quantity::RecirculationLength => "recirculation_length",
        }
    }

    /// The body (0-based) and force component of a per-body quantity.
    pub fn body(self) -> Option<(usize, Component)> {
        match self {
            Quantity::MeanCl1 => Some((0, Component::Lift)),
            Quantity::MeanCl2 => Some((1, Component::Lift)),
            Quantity::MeanCl3 => Some((2, Component::Lift)),
            Quantity::MeanCd1 => Some((0, Component::Drag)),
            Quantity::MeanCd2 => Some((1, Component::Drag)),
            Quantity::MeanCd3 => Some((2, Component::Drag)),
            _ => None,
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeasureSpec {
    pub quantities: Vec<Quantity>,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    pub quantity: Quantity,
    pub value: f64,
    /// Allowed relative deviation `|measured - value| / |value|`.
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Allowed absolute deviation (for references near zero).
    #[serde(default)]
    pub abs_tolerance: Option<f64>,
    pub source: String,
    /// `false` marks an unconfirmed reference: the report prints its deviation and `reason`,
    /// but the case's pass or fail does not hang on it. Absent means judged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub judged: Option<bool>,
    /// Why a reference is not judged (required with `judged = false`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl ReferenceSpec {
    /// Whether the case's pass or fail hangs on this reference.
    pub fn is_judged(&self) -> bool {
        self.judged != Some(false)
    }
}

impl Case {
    /// The flow this case runs: `[geometry]` and `[[more_bodies]]` in order, then the set-up's
    /// tables, with `[flow]`'s Reynolds number, lattice velocity, collision and subgrid model.
    pub fn flow_setup(&self) -> FlowSetup {
        FlowSetup {
            bodies: std::iter::once(&self.geometry).chain(&self.more_bodies).cloned().collect(),
            domain: self.domain.clone(),
            boundaries: self.boundaries.clone(),
            inlet: self.inlet.clone(),
            reynolds: self.flow.reynolds,
            lattice_velocity: self.flow.lattice_velocity,
            collision: self.flow.collision,
            smagorinsky: self.flow.smagorinsky,
            resolution: self.resolution.clone(),
            sponges: self.sponge.clone(),
            refinement: self.refinement.clone(),
            span: self.span.clone(),
        }
    }
}

impl LoadedCase {
    /// This case's quantities, references, times and initial kick on another flow (an
    /// environment's own domain and grid), named `name`; `origin` says where the flow came from.
    /// The hash is that of the new case's JSON form.
    pub fn on_flow(&self, setup: &FlowSetup, name: &str, description: &str, origin: &str) -> Result<LoadedCase, ValidateError> {
        let mut bodies = setup.bodies.iter().cloned();
        let geometry = bodies.next().ok_or_else(|| bad(name, "geometry", "the flow has no body"))?;
        let mut case = self.case.clone();
        case.case.name = name.to_string();
        case.case.description = description.to_string();
        case.geometry = geometry;
        case.more_bodies = bodies.collect();
        case.domain = setup.domain.clone();
        case.boundaries = setup.boundaries.clone();
        case.inlet = setup.inlet.clone();
        case.flow.reynolds = setup.reynolds;
        case.flow.lattice_velocity = setup.lattice_velocity;
        case.flow.collision = setup.collision;
        case.flow.smagorinsky = setup.smagorinsky;
        case.resolution = setup.resolution.clone();
        case.sponge = setup.sponges.clone();
        case.refinement = setup.refinement.clone();
        case.span = setup.span.clone();
        let json = serde_json::to_string(&case).map_err(|e| bad(name, "case", e.to_string()))?;
        let loaded = LoadedCase {
            case,
            origin: origin.to_string(),
            hash: format!("{:x}", Sha256::digest(json.as_bytes())),
        };
        loaded.check_static()?;
        Ok(loaded)
    }
}

/// A set-up error as a case error, naming the field as the case file spells it.
pub(crate) fn flow_error(case: &str, e: FlowError) -> ValidateError {
    match e {
        FlowError::Invalid { field, message } => {
            let field = match field {
                "reynolds" | "lattice_velocity" | "smagorinsky" => format!("flow.{field}"),
                "bodies" => "geometry".to_string(),
                other => other.to_string(),
            };
            ValidateError::Unrunnable {
                case: case.to_string(),
                field,
                message,
            }
        }
        FlowError::Solver(source) => ValidateError::Solver(source.to_string()),
    }
}

/// A parsed case with where it came from.
#[derive(Clone, Debug)]
pub struct LoadedCase {
    pub case: Case,
    /// File path, or `bundled:<name>`.
    pub origin: String,
    /// SHA-256 of the file's text.
    pub hash: String,
}

fn bad(case: &str, field: &str, message: impl Into<String>) -> ValidateError {
    let shown: String = case.chars().take(MAX_NAME).collect();
    ValidateError::Unrunnable {
        case: if shown.len() < case.len() { shown + "..." } else { shown },
        field: field.to_string(),
        message: message.into(),
    }
}

impl LoadedCase {
    /// Parses and checks a case; `origin` names the file in error messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, ValidateError> {
        let case: Case = toml::from_str(text).map_err(|e| ValidateError::CaseParse {
            path: origin.to_string(),
            message: e.to_string(),
        })?;
        let hash = format!("{:x}", Sha256::digest(text.as_bytes()));
        let loaded = LoadedCase {
            case,
            origin: origin.to_string(),
            hash,
        };
        loaded.check_static()?;
        Ok(loaded)
    }

    /// Checks that do not depend on the resolution level.
    pub(crate) fn check_static(&self) -> Result<(), ValidateError> {
        let c = &self.case;
        let name = c.case.name.as_str();
        if name.is_empty() || name.len() > MAX_NAME || !name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-') {
            return Err(bad(
                name,
                "case.name",
                format!("use 1 to {MAX_NAME} letters, digits, '_' and '-' (it names the output files)"),
            ));
        }
        c.flow_setup().check().map_err(|e| flow_error(name, e))?;
        if !(c.flow.perturbation.is_finite() && c.flow.perturbation.abs() <= 1.0) {
            return Err(bad(name, "flow.perturbation", "must be between -1 and 1 (a fraction of U)"));
        }
        let t = &c.time;
        if !(t.spin_up.is_finite() && t.spin_up >= 0.0 && t.average.is_finite() && t.average > 0.0) || t.spin_up.max(t.average) > MAX_TIME {
            return Err(bad(
                name,
                "time",
                format!(
                    "spin_up must be in [0, {MAX_TIME:e}] and average in (0, {MAX_TIME:e}] (times in L/U), got {:e} and {:e}",
                    t.spin_up, t.average
                ),
            ));
        }
        if c.measure.quantities.is_empty() {
            return Err(bad(name, "measure.quantities", "list at least one quantity"));
        }
        for r in &c.reference {
            if !c.measure.quantities.contains(&r.quantity) {
                return Err(bad(
                    name,
                    "reference.quantity",
                    format!(
                        "'{}' has a reference but is not in measure.quantities; add it there",
                        r.quantity.name()
                    ),
                ));
            }
            if !r.value.is_finite() || (r.value == 0.0 && r.tolerance.is_some()) {
                return Err(bad(
                    name,
                    "reference.value",
                    format!(
                        "'{}': the value must be a finite number, and not 0 with a relative tolerance (use abs_tolerance), got {}",
                        r.quantity.name(),
                        r.value
                    ),
                ));
            }
            match (r.tolerance, r.abs_tolerance) {
                (Some(t), None) | (None, Some(t)) if t.is_finite() && t > 0.0 => {}
                _ => {
                    return Err(bad(
                        name,
                        "reference.tolerance",
                        format!(
                            "'{}': give exactly one positive tolerance (relative) or abs_tolerance",
                            r.quantity.name()
                        ),
                    ))
                }
            }
            let has_reason = r.reason.as_deref().is_some_and(|s| !s.trim().is_empty());
            match (r.is_judged(), has_reason) {
                (false, false) => {
                    return Err(bad(
                        name,
                        "reference.reason",
                        format!("'{}' has judged = false: say why in reason = \"...\"", r.quantity.name()),
                    ))
                }
                (true, true) => {
                    return Err(bad(
                        name,
                        "reference.reason",
                        format!(
                            "'{}': reason is only for judged = false; drop it or add judged = false",
                            r.quantity.name()
                        ),
                    ))
                }
                _ => {}
            }
        }
        for q in &c.measure.quantities {
            if *q == Quantity::RecirculationLength && c.geometry.wake_axis().is_none() {
                return Err(bad(
                    name,
                    "measure.quantities",
                    format!(
                        "'recirculation_length' needs a bluff body with a wake axis (circle, square, sphere, cube), not a {}",
                        c.geometry.name()
                    ),
                ));
            }
            if let Some((b, _)) = q.body() {
                if b > c.more_bodies.len() {
                    return Err(bad(
                        name,
                        "measure.quantities",
                        format!(
                            "'{}' needs body {}, but the case has {} bodies",
                            q.name(),
                            b + 1,
                            1 + c.more_bodies.len()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    pub fn cells_per_length(&self, level: Level) -> u32 {
        self.case.resolution.at(level)
    }
}

/// Longest case name (it names the output files).
pub const MAX_NAME: usize = 64;
/// Longest spin-up or averaging time, in L/U.
pub const MAX_TIME: f64 = 1e5;

/// Reads and parses a case file.
pub fn load_file(path: &std::path::Path) -> Result<LoadedCase, ValidateError> {
    let text = std::fs::read_to_string(path).map_err(|e| ValidateError::CaseRead {
        path: path.display().to_string(),
        message: e.to_string(),
    })?;
    LoadedCase::parse(&text, &path.display().to_string())
}

/// All bundled cases.
pub fn bundled() -> Result<Vec<LoadedCase>, ValidateError> {
    BUNDLED
        .iter()
        .map(|(file, text)| LoadedCase::parse(text, &format!("bundled:{file}")))
        .collect()
}

/// Names of the bundled families, sorted and unique.
pub fn families() -> Result<Vec<String>, ValidateError> {
    let mut f: Vec<String> = bundled()?.into_iter().map(|c| c.case.case.family).collect();
    f.sort();
    f.dedup();
    Ok(f)
}
