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
];

/// Largest lattice speed anywhere on the inlet (Mach 0.3 = 0.173 lattice units): above it the
/// compressibility error of the LBM exceeds a few percent.
pub const MAX_LATTICE_SPEED: f64 = 0.173;
/// Largest grid accepted (nodes), about 3.6 GB of populations.
pub const MAX_NODES: usize = 50_000_000;

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
    #[serde(default)]
    pub reference: Vec<ReferenceSpec>,
}

/// Nested refined rectangles `[x0, x1, y0, y1]` (case length units), coarsest first: inside the
/// first the grid is twice as fine as the level's (`cells_per_length` applies outside), inside
/// the second four times, and so on. Each lies inside the one before; the last contains every
/// body with some room; the first stays clear of the domain's edges and absorbing layers.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RefinementSpec {
    pub regions: Vec<[f64; 4]>,
}

/// An edge of the rectangular domain, by compass direction.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum EdgeName {
    West,
    East,
    South,
    North,
}

impl EdgeName {
    pub fn lattice(self) -> hgym_solvers::lbm::Edge {
        use hgym_solvers::lbm::Edge;
        match self {
            EdgeName::West => Edge::West,
            EdgeName::East => Edge::East,
            EdgeName::South => Edge::South,
            EdgeName::North => Edge::North,
        }
    }
}

/// An absorbing layer (see `hgym_solvers::lbm::sponge`): `thickness` in reference lengths,
/// `strength` the relaxation per lattice step at the edge (the ramp is quadratic), target the
/// free stream `(rho, u) = (1, U)`. Used by environment specs (`sponge`) and validation cases
/// (`[[sponge]]`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpongeSpec {
    pub edge: EdgeName,
    pub thickness: f64,
    pub strength: f64,
}

impl SpongeSpec {
    /// The solver's layer at `cells_per_length` cells per reference length, free stream at lattice
    /// speed `u`: at least one node thick.
    pub fn lattice(&self, cells_per_length: f64, u: f64) -> hgym_solvers::lbm::Sponge {
        hgym_solvers::lbm::Sponge {
            edge: self.edge.lattice(),
            width: ((self.thickness * cells_per_length).round() as usize).max(1),
            strength: self.strength,
            rho: 1.0,
            u: [u, 0.0],
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    pub name: String,
    pub family: String,
    #[serde(default)]
    pub description: String,
}

/// The body. Its reference length (for Re, coefficients and resolution) is the diameter, the
/// side, or the chord.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum GeometrySpec {
    Circle {
        center: [f64; 2],
        diameter: f64,
    },
    Square {
        center: [f64; 2],
        side: f64,
    },
    Naca {
        digits: String,
        chord: f64,
        leading_edge: [f64; 2],
        aoa_deg: f64,
    },
    /// An open cavity cut into a flat wall `y = leading_edge[1]` (the plate upstream and
    /// downstream of it is solid down to the domain's bottom); reference length: the depth.
    Cavity {
        leading_edge: [f64; 2],
        length: f64,
        depth: f64,
    },
    /// A cosine constriction of a straight channel (the domain's walls) with its throat at
    /// `center`; reference length: the channel width.
    Stenosis {
        center: [f64; 2],
        width: f64,
        length: f64,
        severity: f64,
    },
}

impl GeometrySpec {
    pub fn reference_length(&self) -> f64 {
        match self {
            GeometrySpec::Circle { diameter, .. } => *diameter,
            GeometrySpec::Square { side, .. } => *side,
            GeometrySpec::Naca { chord, .. } => *chord,
            GeometrySpec::Cavity { depth, .. } => *depth,
            GeometrySpec::Stenosis { width, .. } => *width,
        }
    }

    /// Whether fluid at `p` starts at rest when a flow is spun up from the uniform stream: below
    /// a cavity's lips (an impulsive start with U inside the cavity sheds vortices that the thin
    /// layer above it keeps for tens of time units); everywhere in a stenosed channel (its
    /// oscillatory inflow starts from zero); nowhere for the other shapes.
    pub fn starts_at_rest(&self, p: [f64; 2]) -> bool {
        match self {
            GeometrySpec::Cavity { leading_edge, .. } => p[1] < leading_edge[1],
            GeometrySpec::Stenosis { .. } => true,
            _ => false,
        }
    }

    /// A point at the body's centre (for the initial perturbation).
    pub fn center(&self) -> [f64; 2] {
        match self {
            GeometrySpec::Circle { center, .. } | GeometrySpec::Square { center, .. } | GeometrySpec::Stenosis { center, .. } => *center,
            GeometrySpec::Naca { chord, leading_edge, .. } => [leading_edge[0] + 0.5 * chord, leading_edge[1]],
            GeometrySpec::Cavity {
                leading_edge,
                length,
                depth,
            } => [leading_edge[0] + 0.5 * length, leading_edge[1] - 0.5 * depth],
        }
    }
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    pub x: [f64; 2],
    pub y: [f64; 2],
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryKind {
    Inlet,
    Outlet,
    Periodic,
    Wall,
    FreeSlip,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    pub west: BoundaryKind,
    pub east: BoundaryKind,
    pub south: BoundaryKind,
    pub north: BoundaryKind,
}

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    #[default]
    Uniform,
    /// `u(y) = u_max 4 (y - y0)(y1 - y) / (y1 - y0)^2` across the whole domain height.
    Parabolic,
}

/// Which inlet velocity U is (for Re and the coefficients) when the profile is parabolic.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum VelocityReference {
    #[default]
    Mean,
    Max,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct InletSpec {
    #[serde(default)]
    pub profile: Profile,
    #[serde(default)]
    pub reference_velocity: VelocityReference,
    /// Smooth ramp of the inlet from 0 to full speed over this time (0: impulsive start).
    #[serde(default)]
    pub ramp: f64,
    /// Non-reflecting (characteristic) inlet: the inflow's normal velocity follows outgoing
    /// pressure waves, `u_n = U - c_s (rho - rho_ref)`, with `rho_ref` the inlet's mean density
    /// averaged over this time (L/U); 0 (the default) keeps the rigid velocity inlet, which
    /// reflects them. See `hgym_solvers::lbm::boundary::InletReference`.
    #[serde(default)]
    pub characteristic_time: f64,
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
pub struct ResolutionSpec {
    pub coarse: u32,
    pub default: u32,
    pub fine: u32,
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
}

/// Resolution level: a number of cells per reference length, never a different case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    Coarse,
    Default,
    Fine,
}

impl Level {
    pub fn name(self) -> &'static str {
        match self {
            Level::Coarse => "coarse",
            Level::Default => "default",
            Level::Fine => "fine",
        }
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
    ValidateError::Unrunnable {
        case: case.to_string(),
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
    fn check_static(&self) -> Result<(), ValidateError> {
        let c = &self.case;
        let name = c.case.name.as_str();
        if name.is_empty() || !name.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-') {
            return Err(bad(
                name,
                "case.name",
                "use letters, digits, '_' and '-' only (it names the output files)",
            ));
        }
        let f = &c.flow;
        if !(f.reynolds.is_finite() && f.reynolds > 0.0) {
            return Err(bad(name, "flow.reynolds", format!("must be a positive number, got {}", f.reynolds)));
        }
        if !(f.lattice_velocity.is_finite() && f.lattice_velocity > 0.0) {
            return Err(bad(
                name,
                "flow.lattice_velocity",
                format!("must be positive, got {}", f.lattice_velocity),
            ));
        }
        let peak = f.lattice_velocity * self.inlet_peak_factor();
        if peak > MAX_LATTICE_SPEED {
            return Err(bad(
                name,
                "flow.lattice_velocity",
                format!(
                    "the inlet reaches lattice speed {peak:.3} (Mach {:.2}); the limit is {MAX_LATTICE_SPEED} (Mach 0.3): \
                     lower lattice_velocity to at most {:.3}",
                    peak * 3f64.sqrt(),
                    MAX_LATTICE_SPEED / self.inlet_peak_factor()
                ),
            ));
        }
        if !(f.perturbation.is_finite() && f.perturbation.abs() <= 1.0) {
            return Err(bad(name, "flow.perturbation", "must be between -1 and 1 (a fraction of U)"));
        }
        let d = &c.domain;
        if !(d.x[1] > d.x[0] && d.y[1] > d.y[0]) || d.x.iter().chain(&d.y).any(|v| !v.is_finite()) {
            return Err(bad(name, "domain", "x and y must be finite [min, max] pairs with min < max"));
        }
        let l = c.geometry.reference_length();
        if !(l.is_finite() && l > 0.0) {
            return Err(bad(
                name,
                "geometry",
                format!("the reference length (diameter, side or chord) must be positive, got {l}"),
            ));
        }
        if let GeometrySpec::Naca { digits, .. } = &c.geometry {
            if hgym_solvers::geometry::Naca4::from_digits(digits, 1.0, [0.0, 0.0], 0.0).is_none() {
                return Err(bad(
                    name,
                    "geometry.digits",
                    format!("'{digits}' is not a NACA 4-digit code (e.g. \"0012\")"),
                ));
            }
        }
        let r = &c.resolution;
        for (lvl, n) in [("coarse", r.coarse), ("default", r.default), ("fine", r.fine)] {
            if n < 4 {
                return Err(bad(
                    name,
                    "resolution",
                    format!("{lvl} = {n} cells per length is too few (at least 4)"),
                ));
            }
        }
        let b = &c.boundaries;
        if (b.west == BoundaryKind::Periodic) != (b.east == BoundaryKind::Periodic) {
            return Err(bad(name, "boundaries", "west and east must both be periodic or neither"));
        }
        if (b.south == BoundaryKind::Periodic) != (b.north == BoundaryKind::Periodic) {
            return Err(bad(name, "boundaries", "south and north must both be periodic or neither"));
        }
        for (side, kind) in [("east", b.east), ("south", b.south), ("north", b.north)] {
            if kind == BoundaryKind::Inlet {
                return Err(bad(
                    name,
                    "boundaries",
                    format!("{side} = \"inlet\": only the west side can be an inlet (flow in +x)"),
                ));
            }
        }
        if c.inlet.ramp < 0.0 || !c.inlet.ramp.is_finite() {
            return Err(bad(name, "inlet.ramp", "must be zero or a positive time"));
        }
        if c.inlet.characteristic_time < 0.0 || !c.inlet.characteristic_time.is_finite() {
            return Err(bad(
                name,
                "inlet.characteristic_time",
                "must be zero (a rigid inlet) or a positive time in L/U, e.g. 20",
            ));
        }
        for (i, sp) in c.sponge.iter().enumerate() {
            if c.sponge[..i].iter().any(|o| o.edge == sp.edge) {
                return Err(bad(
                    name,
                    "sponge",
                    format!("two layers on the {:?} edge; give one per edge", sp.edge),
                ));
            }
            if !(sp.thickness.is_finite() && sp.thickness > 0.0) {
                return Err(bad(
                    name,
                    "sponge.thickness",
                    format!("must be a positive length, got {}", sp.thickness),
                ));
            }
            if !(sp.strength.is_finite() && sp.strength > 0.0 && sp.strength <= 1.0) {
                return Err(bad(
                    name,
                    "sponge.strength",
                    format!("the relaxation per step at the edge must be in (0, 1], got {}", sp.strength),
                ));
            }
            if c.inlet.ramp > 0.0 {
                return Err(bad(
                    name,
                    "sponge",
                    "a layer relaxes to the full free stream, which a ramped inlet only reaches at the end of its ramp: \
                     use one or the other",
                ));
            }
        }
        let t = &c.time;
        if !(t.spin_up.is_finite() && t.spin_up >= 0.0 && t.average.is_finite() && t.average > 0.0) {
            return Err(bad(name, "time", "spin_up must be >= 0 and average > 0"));
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
        }
        for q in &c.measure.quantities {
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
        if let Some(rf) = &c.refinement {
            if rf.regions.is_empty() {
                return Err(bad(name, "refinement.regions", "list at least one region [x0, x1, y0, y1]"));
            }
            let mut outer = [d.x[0], d.x[1], d.y[0], d.y[1]];
            for (k, region) in rf.regions.iter().enumerate() {
                let [x0, x1, y0, y1] = *region;
                if !(region.iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1) {
                    return Err(bad(
                        name,
                        "refinement.regions",
                        format!("region {} must be [x0, x1, y0, y1] with x0 < x1 and y0 < y1, got {region:?}", k + 1),
                    ));
                }
                if x0 <= outer[0] || x1 >= outer[1] || y0 <= outer[2] || y1 >= outer[3] {
                    return Err(bad(
                        name,
                        "refinement.regions",
                        format!(
                            "region {} {region:?} must lie inside {} {outer:?} with room to spare",
                            k + 1,
                            if k == 0 { "the domain".to_string() } else { format!("region {k}") }
                        ),
                    ));
                }
                outer = *region;
            }
        }
        // Bodies inside the domain, at least two cells from every edge even at the coarse level.
        let dx = l / r.coarse.min(r.default).min(r.fine) as f64;
        for g in std::iter::once(&c.geometry).chain(&c.more_bodies) {
            let body = super::run::build_shape(g);
            let bb = body.bounding_box();
            if bb[0] < d.x[0] + 2.0 * dx || bb[2] > d.x[1] - 2.0 * dx || bb[1] < d.y[0] + 2.0 * dx || bb[3] > d.y[1] - 2.0 * dx {
                return Err(bad(
                    name,
                    "geometry",
                    format!(
                        "the body spans [{:.3}, {:.3}] x [{:.3}, {:.3}], which does not fit inside the domain [{}, {}] x [{}, {}] \
                     with two cells to spare: enlarge the domain or move/shrink the body",
                        bb[0], bb[2], bb[1], bb[3], d.x[0], d.x[1], d.y[0], d.y[1]
                    ),
                ));
            }
            for sp in &c.sponge {
                let inside = match sp.edge {
                    EdgeName::West => bb[0] < d.x[0] + sp.thickness,
                    EdgeName::East => bb[2] > d.x[1] - sp.thickness,
                    EdgeName::South => bb[1] < d.y[0] + sp.thickness,
                    EdgeName::North => bb[3] > d.y[1] - sp.thickness,
                };
                if inside {
                    return Err(bad(
                        name,
                        "sponge.thickness",
                        format!(
                            "the {:?} layer ({} thick) reaches a body; make it thinner or the domain larger",
                            sp.edge, sp.thickness
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Peak inlet speed over U.
    pub fn inlet_peak_factor(&self) -> f64 {
        match (self.case.inlet.profile, self.case.inlet.reference_velocity) {
            (Profile::Parabolic, VelocityReference::Mean) => 1.5,
            _ => 1.0,
        }
    }

    pub fn cells_per_length(&self, level: Level) -> u32 {
        let r = &self.case.resolution;
        match level {
            Level::Coarse => r.coarse,
            Level::Default => r.default,
            Level::Fine => r.fine,
        }
    }
}

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
