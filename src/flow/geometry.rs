//! Bodies as data (`GeometrySpec`) and as the solver's signed-distance shapes (`build_shape`).
//! Lengths are in units of the reference length; a body's own reference length (diameter, side,
//! chord, depth or width) is the one coefficients and resolution refer to.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use hgym_solvers::geometry::{Circle, Naca4, OpenCavity, Rectangle, Shape, Stenosis};

/// The body. Its reference length (for Re, coefficients and resolution) is the diameter, the
/// side, or the chord.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum GeometrySpec {
    Circle {
        #[serde(deserialize_with = "super::pair")]
        center: [f64; 2],
        diameter: f64,
    },
    Square {
        #[serde(deserialize_with = "super::pair")]
        center: [f64; 2],
        side: f64,
    },
    Naca {
        digits: String,
        chord: f64,
        #[serde(deserialize_with = "super::pair")]
        leading_edge: [f64; 2],
        aoa_deg: f64,
    },
    /// An open cavity cut into a flat wall `y = leading_edge[1]` (the plate upstream and
    /// downstream of it is solid down to the domain's bottom); reference length: the depth.
    Cavity {
        #[serde(deserialize_with = "super::pair")]
        leading_edge: [f64; 2],
        length: f64,
        depth: f64,
    },
    /// A sphere (3D flows only); reference length: the diameter.
    Sphere {
        #[serde(deserialize_with = "super::triple")]
        center: [f64; 3],
        diameter: f64,
    },
    /// An axis-aligned cube (3D flows only); reference length: the side.
    Cube {
        #[serde(deserialize_with = "super::triple")]
        center: [f64; 3],
        side: f64,
    },
    /// A cosine constriction of a straight channel (the domain's walls) with its throat at
    /// `center`; reference length: the channel width.
    Stenosis {
        #[serde(deserialize_with = "super::pair")]
        center: [f64; 2],
        width: f64,
        length: f64,
        severity: f64,
    },
    /// A round pipe along x (3D flows only) whose radius narrows by the same cosine law to a
    /// throat at `center` (on the pipe's axis); solid outside it. Reference length: the diameter.
    Pipe {
        #[serde(deserialize_with = "super::triple")]
        center: [f64; 3],
        diameter: f64,
        length: f64,
        severity: f64,
    },
}

impl GeometrySpec {
    /// Finite coordinates, positive lengths, an angle of attack within +-90 degrees, a NACA code
    /// with a thickness, a stenosis that leaves the channel open (severity in [0, 0.5)); the
    /// message names the key.
    pub(crate) fn check(&self) -> Result<(), String> {
        let finite = |key: &str, p: &[f64; 2]| {
            if p.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(format!("{key} must be two finite numbers, got {p:?}"))
            }
        };
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{key} must be a positive length, got {v}"))
            }
        };
        match self {
            GeometrySpec::Circle { center, diameter } => {
                finite("center", center)?;
                positive("diameter", *diameter)
            }
            GeometrySpec::Square { center, side } => {
                finite("center", center)?;
                positive("side", *side)
            }
            GeometrySpec::Naca {
                digits,
                chord,
                leading_edge,
                aoa_deg,
            } => {
                finite("leading_edge", leading_edge)?;
                positive("chord", *chord)?;
                if !(aoa_deg.is_finite() && aoa_deg.abs() <= 90.0) {
                    return Err(format!("aoa_deg must be an angle within -90 to 90 degrees, got {aoa_deg}"));
                }
                if Naca4::from_digits(digits, 1.0, [0.0, 0.0], 0.0).is_none() || digits.ends_with("00") {
                    return Err(format!(
                        "digits '{digits}' is not a NACA 4-digit code with a thickness (e.g. \"0012\": the last two digits are the thickness in % of the chord)"
                    ));
                }
                Ok(())
            }
            GeometrySpec::Cavity {
                leading_edge,
                length,
                depth,
            } => {
                finite("leading_edge", leading_edge)?;
                positive("length", *length)?;
                positive("depth", *depth)
            }
            GeometrySpec::Sphere { center, diameter } => {
                finite("center", &[center[0], center[1]])?;
                finite("center", &[center[2], 0.0])?;
                positive("diameter", *diameter)
            }
            GeometrySpec::Cube { center, side } => {
                finite("center", &[center[0], center[1]])?;
                finite("center", &[center[2], 0.0])?;
                positive("side", *side)
            }
            GeometrySpec::Stenosis {
                center,
                width,
                length,
                severity,
            } => {
                finite("center", center)?;
                positive("width", *width)?;
                positive("length", *length)?;
                check_severity(*severity)
            }
            GeometrySpec::Pipe {
                center,
                diameter,
                length,
                severity,
            } => {
                finite("center", &[center[0], center[1]])?;
                finite("center", &[center[2], 0.0])?;
                positive("diameter", *diameter)?;
                positive("length", *length)?;
                check_severity(*severity)
            }
        }
    }

    /// The shape's name as set-ups spell it.
    pub fn name(&self) -> &'static str {
        match self {
            GeometrySpec::Circle { .. } => "circle",
            GeometrySpec::Square { .. } => "square",
            GeometrySpec::Naca { .. } => "naca",
            GeometrySpec::Cavity { .. } => "cavity",
            GeometrySpec::Stenosis { .. } => "stenosis",
            GeometrySpec::Pipe { .. } => "pipe",
            GeometrySpec::Sphere { .. } => "sphere",
            GeometrySpec::Cube { .. } => "cube",
        }
    }

    pub fn reference_length(&self) -> f64 {
        match self {
            GeometrySpec::Circle { diameter, .. } => *diameter,
            GeometrySpec::Square { side, .. } => *side,
            GeometrySpec::Naca { chord, .. } => *chord,
            GeometrySpec::Cavity { depth, .. } => *depth,
            GeometrySpec::Stenosis { width, .. } => *width,
            GeometrySpec::Pipe { diameter, .. } => *diameter,
            GeometrySpec::Sphere { diameter, .. } => *diameter,
            GeometrySpec::Cube { side, .. } => *side,
        }
    }

    /// Whether fluid at `p` starts at rest when a flow is spun up from the uniform stream: below
    /// a cavity's lips (an impulsive start with U inside the cavity sheds vortices that the thin
    /// layer above it keeps for tens of time units); everywhere in a stenosed channel (its
    /// oscillatory inflow starts from zero); nowhere for the other shapes.
    pub fn starts_at_rest(&self, p: [f64; 2]) -> bool {
        match self {
            GeometrySpec::Cavity { leading_edge, .. } => p[1] < leading_edge[1],
            GeometrySpec::Stenosis { .. } | GeometrySpec::Pipe { .. } => true,
            _ => false,
        }
    }

    /// A point at the body's centre (for the initial perturbation).
    pub fn center(&self) -> [f64; 2] {
        match self {
            GeometrySpec::Circle { center, .. } | GeometrySpec::Square { center, .. } | GeometrySpec::Stenosis { center, .. } => *center,
            GeometrySpec::Sphere { center, .. } | GeometrySpec::Cube { center, .. } | GeometrySpec::Pipe { center, .. } => {
                [center[0], center[1]]
            }
            GeometrySpec::Naca { chord, leading_edge, .. } => [leading_edge[0] + 0.5 * chord, leading_edge[1]],
            GeometrySpec::Cavity {
                leading_edge,
                length,
                depth,
            } => [leading_edge[0] + 0.5 * length, leading_edge[1] - 0.5 * depth],
        }
    }

    /// The wake's centreline behind a bluff body: the body's base (its downstream end on the
    /// centreline, `x = centre + L/2`) and the line's `(y, z)`, with `z = None` for a section
    /// extruded along a span (the line is averaged over the span). `None` for bodies without a
    /// wake on an axis of symmetry (an aerofoil, a cavity, a channel).
    pub fn wake_axis(&self) -> Option<(f64, f64, Option<f64>)> {
        match self {
            GeometrySpec::Circle { center, diameter: l } | GeometrySpec::Square { center, side: l } => {
                Some((center[0] + 0.5 * l, center[1], None))
            }
            GeometrySpec::Sphere { center, diameter: l } | GeometrySpec::Cube { center, side: l } => {
                Some((center[0] + 0.5 * l, center[1], Some(center[2])))
            }
            _ => None,
        }
    }

    /// Whether the body stands free in the flow (circle, square, aerofoil), as opposed to a wall
    /// feature that reaches the domain's edges (a cavity's plate, a stenosed channel's walls).
    pub fn is_immersed(&self) -> bool {
        matches!(
            self,
            GeometrySpec::Circle { .. }
                | GeometrySpec::Square { .. }
                | GeometrySpec::Naca { .. }
                | GeometrySpec::Sphere { .. }
                | GeometrySpec::Cube { .. }
        )
    }

    /// Whether the body only exists in 3D (a sphere, a cube, a pipe): the others are 2D sections,
    /// extruded along the span in a 3D flow.
    pub fn is_3d_only(&self) -> bool {
        matches!(
            self,
            GeometrySpec::Sphere { .. } | GeometrySpec::Cube { .. } | GeometrySpec::Pipe { .. }
        )
    }

    /// Whether the body is a duct the flow runs inside (a pipe), whose inlet can carry its
    /// laminar profile ([`Self::duct_inflow`]).
    pub fn is_duct(&self) -> bool {
        matches!(self, GeometrySpec::Pipe { .. })
    }

    /// The laminar inflow of a duct body over its mean velocity at `p` (3D): Poiseuille's
    /// `2 (1 - (r / R)^2)` inside a pipe of radius `R` at the inlet, 0 outside it; `None` for the
    /// other shapes.
    pub fn duct_inflow(&self, p: [f64; 3]) -> Option<f64> {
        match self {
            GeometrySpec::Pipe { center, diameter, .. } => {
                let r = (p[1] - center[1]).hypot(p[2] - center[2]) / (0.5 * diameter);
                Some((2.0 * (1.0 - r * r)).max(0.0))
            }
            _ => None,
        }
    }

    /// The body's extent along z `[z0, z1]` (3D-only bodies), `None` for a section extruded
    /// along the whole span.
    pub fn z_extent(&self) -> Option<[f64; 2]> {
        match self {
            GeometrySpec::Sphere { center, diameter } => Some([center[2] - 0.5 * diameter, center[2] + 0.5 * diameter]),
            GeometrySpec::Cube { center, side } => Some([center[2] - 0.5 * side, center[2] + 0.5 * side]),
            _ => None,
        }
    }

    /// The body as the solver's signed-distance shape (for a sphere or a cube, its section
    /// through the centre, which gives its x-y extent).
    pub fn shape(&self) -> Arc<dyn Shape> {
        match self {
            GeometrySpec::Sphere { center, diameter } => Arc::new(Circle {
                center: [center[0], center[1]],
                radius: 0.5 * diameter,
            }),
            GeometrySpec::Cube { center, side } => Arc::new(Rectangle {
                center: [center[0], center[1]],
                size: [*side, *side],
            }),
            GeometrySpec::Circle { center, diameter } => Arc::new(Circle {
                center: *center,
                radius: 0.5 * diameter,
            }),
            GeometrySpec::Square { center, side } => Arc::new(Rectangle {
                center: *center,
                size: [*side, *side],
            }),
            GeometrySpec::Naca {
                digits,
                chord,
                leading_edge,
                aoa_deg,
            } => {
                // Digits are checked by `FlowSetup::check`; fall back to a symmetric 12 % section.
                Arc::new(
                    Naca4::from_digits(digits, *chord, *leading_edge, *aoa_deg)
                        .unwrap_or_else(|| Naca4::new(0.0, 0.0, 0.12, *chord, *leading_edge, *aoa_deg)),
                )
            }
            GeometrySpec::Cavity {
                leading_edge,
                length,
                depth,
            } => Arc::new(OpenCavity {
                leading_edge: *leading_edge,
                length: *length,
                depth: *depth,
            }),
            GeometrySpec::Stenosis {
                center,
                width,
                length,
                severity,
            } => Arc::new(Stenosis {
                center: *center,
                width: *width,
                length: *length,
                severity: *severity,
            }),
            // The axial section (the pipe's profile in the plane z = center z).
            GeometrySpec::Pipe {
                center,
                diameter,
                length,
                severity,
            } => Arc::new(Stenosis {
                center: [center[0], center[1]],
                width: *diameter,
                length: *length,
                severity: *severity,
            }),
        }
    }
}

fn check_severity(severity: f64) -> Result<(), String> {
    if severity.is_finite() && (0.0..0.5).contains(&severity) {
        Ok(())
    } else {
        Err(format!(
            "severity must be in [0, 0.5) (0.25 halves the width at the throat; 0.5 closes it), got {severity}"
        ))
    }
}
