//! The flow set-up layer: what a 2D lattice-Boltzmann flow is (bodies, domain, edges, inlet,
//! Reynolds number, collision operator, resolution levels, absorbing layers, refinement) as plain
//! data, its checks, its lattice numbers at a level ([`FlowSetup::plan`]), and the one function
//! that makes the solver from it ([`FlowSetup::build`]).
//!
//! Validation cases (`validate::case`) and environment specs (`env::spec`) each describe a flow
//! in their own file format and turn it into a [`FlowSetup`]; both then build their solver
//! through [`FlowSetup::build`], so what validation vouches for is the path the environments
//! run. This module knows nothing of either.
//!
//! Units: lengths in the reference body's length L (body 0's diameter, side, chord, depth or
//! width), velocities in U, times in L/U. Nodes are cell-centred: node `(i, j)` sits at
//! `(x0 + (i + 1/2) dx, y0 + (j + 1/2) dx)`, so walls of the domain fall on its edges.

pub mod build;
pub mod domain;
pub mod field;
pub mod geometry;
pub mod inlet;
pub mod level;
pub mod plan;
pub mod ranks;
pub mod span;

use serde::{Deserialize, Deserializer, Serialize};
use thiserror::Error;

use hgym_solvers::lbm::{Collision, LbmError};

pub use build::LbmFlow;
pub use domain::{BoundaryKind, BoundarySpec, DomainSpec, EdgeName, SpongeSpec};
pub use field::{plane_vorticity, vorticity_field, Field};
pub use geometry::GeometrySpec;
pub use inlet::{InletSpec, Profile, VelocityReference};
pub use level::{Level, ResolutionSpec, UnknownLevel};
pub use plan::{FlowPlan, RefinementPlan, RefinementSpec, MAX_LATTICE_SPEED, MAX_NODES};
pub use span::{Lattice3Name, LbmFlow3, SpanSpec};

/// `[a, b]` and nothing else: TOML readers fill a fixed-size array from the front and drop what
/// follows, so `x = [0, 60, 90]` would silently lose its third number.
pub fn pair<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 2], D::Error> {
    exactly_two(&Vec::<f64>::deserialize(d)?)
}

fn exactly_two<E: serde::de::Error>(v: &[f64]) -> Result<[f64; 2], E> {
    <[f64; 2]>::try_from(v).map_err(|_| E::invalid_length(v.len(), &"two numbers [a, b]"))
}

/// `[a, b, c]` and nothing else (see [`pair`]).
pub fn triple<'de, D: Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    <[f64; 3]>::try_from(v.as_slice()).map_err(|_| serde::de::Error::invalid_length(v.len(), &"three numbers [x, y, z]"))
}

/// A list of `[a, b]` pairs, each checked as [`pair`] checks one.
pub fn pairs<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<[f64; 2]>, D::Error> {
    Vec::<Vec<f64>>::deserialize(d)?.iter().map(|p| exactly_two(p)).collect()
}

/// A flow that cannot be set up. `field` names the set-up's field (as [`FlowSetup`] calls it);
/// the message says what is wrong and how to fix it.
#[derive(Debug, Error)]
pub enum FlowError {
    #[error("`{field}`: {message}")]
    Invalid { field: &'static str, message: String },
    #[error("the solver cannot be built")]
    Solver(#[source] LbmError),
}

impl FlowError {
    fn invalid(field: &'static str, message: impl Into<String>) -> Self {
        FlowError::Invalid {
            field,
            message: message.into(),
        }
    }
}

/// A 2D lattice-Boltzmann flow set-up. Body 0 is the reference body: its length is L, the unit
/// of every length here and of the resolution levels.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FlowSetup {
    pub bodies: Vec<GeometrySpec>,
    pub domain: DomainSpec,
    pub boundaries: BoundarySpec,
    pub inlet: InletSpec,
    pub reynolds: f64,
    /// Lattice value of U.
    pub lattice_velocity: f64,
    pub collision: Collision,
    /// Smagorinsky constant of the subgrid viscosity (0: none).
    pub smagorinsky: f64,
    pub resolution: ResolutionSpec,
    pub sponges: Vec<SpongeSpec>,
    pub refinement: Option<RefinementSpec>,
    /// The span of a 3D flow; `None` for a 2D one (left out of the JSON form, so 2D set-ups
    /// hash as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub span: Option<SpanSpec>,
}

impl FlowSetup {
    /// SHA-256 of the set-up's JSON form: two flows with the same hash are the same flow.
    pub fn hash(&self) -> String {
        use sha2::{Digest, Sha256};
        // Plain fields with string keys: serialising to JSON cannot fail.
        let json = serde_json::to_string(self).expect("a flow set-up serialises to JSON");
        format!("{:x}", Sha256::digest(json.as_bytes()))
    }

    /// The area the force coefficients divide by, in L^2: in 3D the span times L for a body along
    /// the whole span, the frontal area for a sphere (pi/4) or a cube (1); 1 in 2D, where forces
    /// are per unit span (L times one lattice spacing in the solver's units).
    pub fn reference_area(&self) -> f64 {
        match (&self.span, self.bodies.first()) {
            (None, _) => 1.0,
            (Some(_), Some(GeometrySpec::Sphere { .. })) => std::f64::consts::FRAC_PI_4,
            (Some(_), Some(GeometrySpec::Cube { .. })) => 1.0,
            (Some(span), _) => span.length() / self.reference_length(),
        }
    }

    /// The reference length L (body 0's), or 1 for a flow without bodies.
    pub fn reference_length(&self) -> f64 {
        self.bodies.first().map_or(1.0, GeometrySpec::reference_length)
    }

    /// Checks that do not depend on the resolution level: positive finite numbers, Mach below
    /// 0.3 at the inlet's peak, edges that pair up, absorbing layers and refinement regions
    /// that fit, immersed bodies inside the domain with two coarsest cells to spare.
    pub fn check(&self) -> Result<(), FlowError> {
        fn bad(field: &'static str, message: impl Into<String>) -> FlowError {
            FlowError::invalid(field, message)
        }
        if !(self.reynolds.is_finite() && self.reynolds > 0.0) {
            return Err(bad("reynolds", format!("must be a positive number, got {}", self.reynolds)));
        }
        let u = self.lattice_velocity;
        if !(u.is_finite() && u > 0.0) {
            return Err(bad("lattice_velocity", format!("must be positive, got {u}")));
        }
        let k = self.inlet.peak_factor();
        if u * k > MAX_LATTICE_SPEED {
            return Err(bad(
                "lattice_velocity",
                format!(
                    "the inlet reaches lattice speed {:.3} (Mach {:.2}); the limit is {MAX_LATTICE_SPEED} (Mach 0.3): \
                     lower lattice_velocity to at most {:.3}",
                    u * k,
                    u * k * 3f64.sqrt(),
                    MAX_LATTICE_SPEED / k
                ),
            ));
        }
        if !(self.smagorinsky.is_finite() && self.smagorinsky >= 0.0) {
            return Err(bad("smagorinsky", format!("must be zero or positive, got {}", self.smagorinsky)));
        }
        let d = &self.domain;
        if !(d.x[1] > d.x[0] && d.y[1] > d.y[0]) || d.x.iter().chain(&d.y).any(|v| !v.is_finite()) {
            return Err(bad("domain", "x and y must be finite [min, max] pairs with min < max"));
        }
        let Some(first) = self.bodies.first() else {
            return Err(bad(
                "bodies",
                "give at least one body: the first one's length is the reference length",
            ));
        };
        for (i, g) in self.bodies.iter().enumerate() {
            g.check().map_err(|m| bad("bodies", format!("body {}: {m}", i + 1)))?;
        }
        let l = first.reference_length();
        let r = &self.resolution;
        for (lvl, n) in [("coarse", r.coarse), ("default", r.default), ("fine", r.fine)] {
            if n < 4 {
                return Err(bad("resolution", format!("{lvl} = {n} cells per length is too few (at least 4)")));
            }
        }
        let b = &self.boundaries;
        if (b.west == BoundaryKind::Periodic) != (b.east == BoundaryKind::Periodic) {
            return Err(bad("boundaries", "west and east must both be periodic or neither"));
        }
        if (b.south == BoundaryKind::Periodic) != (b.north == BoundaryKind::Periodic) {
            return Err(bad("boundaries", "south and north must both be periodic or neither"));
        }
        for (side, kind) in [("east", b.east), ("south", b.south), ("north", b.north)] {
            if kind == BoundaryKind::Inlet {
                return Err(bad(
                    "boundaries",
                    format!("{side} = \"inlet\": only the west side can be an inlet (flow in +x)"),
                ));
            }
        }
        if self.inlet.ramp < 0.0 || !self.inlet.ramp.is_finite() {
            return Err(bad("inlet.ramp", "must be zero or a positive time"));
        }
        if self.inlet.characteristic_time < 0.0 || !self.inlet.characteristic_time.is_finite() {
            return Err(bad(
                "inlet.characteristic_time",
                "must be zero (a rigid inlet) or a positive time in L/U, e.g. 20",
            ));
        }
        for (i, sp) in self.sponges.iter().enumerate() {
            if self.sponges[..i].iter().any(|o| o.edge == sp.edge) {
                return Err(bad("sponge", format!("two layers on the {:?} edge; give one per edge", sp.edge)));
            }
            if !(sp.thickness.is_finite() && sp.thickness > 0.0) {
                return Err(bad("sponge.thickness", format!("must be a positive length, got {}", sp.thickness)));
            }
            if !(sp.strength.is_finite() && sp.strength > 0.0 && sp.strength <= 1.0) {
                return Err(bad(
                    "sponge.strength",
                    format!("the relaxation per step at the edge must be in (0, 1], got {}", sp.strength),
                ));
            }
            if self.inlet.ramp > 0.0 {
                return Err(bad(
                    "sponge",
                    "a layer relaxes to the full free stream, which a ramped inlet only reaches at the end of its ramp: \
                     use one or the other",
                ));
            }
        }
        if let Some(rf) = &self.refinement {
            rf.check(d, self.span.as_ref())?;
        }
        match &self.span {
            None => {
                if let Some(g) = self.bodies.iter().find(|g| g.is_3d_only()) {
                    return Err(bad(
                        "bodies",
                        format!("a {} needs a 3D flow: give the set-up a span ([span] z = [z0, z1])", g.name()),
                    ));
                }
            }
            Some(span) => {
                span.check()?;
                let duct = self.bodies.iter().any(GeometrySpec::is_duct);
                let shaped = self.inlet.profile == Profile::Parabolic && duct && self.inlet.reference_velocity == VelocityReference::Mean;
                if (self.inlet.profile != Profile::Uniform && !shaped) || self.inlet.characteristic_time > 0.0 {
                    return Err(bad(
                        "inlet",
                        "a 3D inlet is rigid and uniform, or parabolic (Poiseuille of the mean velocity) into a pipe body: \
                         use profile = \"uniform\" (or \"parabolic\" with a pipe and reference_velocity = \"mean\") and \
                         characteristic_time = 0",
                    ));
                }
                let dz = l / r.coarse.min(r.default).min(r.fine) as f64;
                for (i, g) in self.bodies.iter().enumerate() {
                    if let Some([z0, z1]) = g.z_extent() {
                        if z0 < span.z[0] + 2.0 * dz || z1 > span.z[1] - 2.0 * dz {
                            return Err(bad(
                                "bodies",
                                format!(
                                    "body {} spans z [{z0:.3}, {z1:.3}], which does not fit inside the span [{}, {}] with two cells \
                                     to spare (a body may not cross a periodic face): enlarge the span or move the body",
                                    i + 1,
                                    span.z[0],
                                    span.z[1]
                                ),
                            ));
                        }
                    }
                }
            }
        }
        // Immersed bodies inside the domain, two cells from every edge even at the coarsest level.
        let dx = l / r.coarse.min(r.default).min(r.fine) as f64;
        for g in self.bodies.iter().filter(|g| g.is_immersed()) {
            let bb = g.shape().bounding_box();
            if bb[0] < d.x[0] + 2.0 * dx || bb[2] > d.x[1] - 2.0 * dx || bb[1] < d.y[0] + 2.0 * dx || bb[3] > d.y[1] - 2.0 * dx {
                return Err(bad(
                    "bodies",
                    format!(
                        "the body spans [{:.3}, {:.3}] x [{:.3}, {:.3}], which does not fit inside the domain [{}, {}] x [{}, {}] \
                         with two cells to spare: enlarge the domain or move/shrink the body",
                        bb[0], bb[2], bb[1], bb[3], d.x[0], d.x[1], d.y[0], d.y[1]
                    ),
                ));
            }
            for sp in &self.sponges {
                let inside = match sp.edge {
                    EdgeName::West => bb[0] < d.x[0] + sp.thickness,
                    EdgeName::East => bb[2] > d.x[1] - sp.thickness,
                    EdgeName::South => bb[1] < d.y[0] + sp.thickness,
                    EdgeName::North => bb[3] > d.y[1] - sp.thickness,
                };
                if inside {
                    return Err(bad(
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
}
