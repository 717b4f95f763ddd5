//! What an environment's observations and actions mean, so that a policy trained on one flow can
//! be moved to another (the `transfer` module): each observation is a quantity, at a position
//! relative to the body in body lengths where it is a probe; each action drives a named actuator.
//!
//! Lattice-Boltzmann environments observe `(u, v, p[, T])` at each probe, positioned relative to
//! the centre of their first body in its reference length (D); actuators are named from their
//! kind and, for independent jets, from where they sit on the body (`jet_front_top`, ...). The 3D
//! ones with a section actuator on each spanwise segment add `w` and, with several segments, the
//! segment ([`Layout::of3`]). Other families are known by index (`obs0`, `a0`, ...).

use std::fmt;

use super::spec::ActuationSpec;
use super::EnvSpec;

/// One observation: a quantity, and where it is measured when it is a probe.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub quantity: String,
    /// Position relative to the body, in its reference length.
    pub at: Option<[f64; 2]>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub observations: Vec<Channel>,
    pub actuators: Vec<String>,
}

impl Layout {
    /// Observations and actuators known only by index.
    pub fn indexed(obs_dim: usize, act_dim: usize) -> Self {
        Layout {
            observations: (0..obs_dim)
                .map(|i| Channel {
                    quantity: format!("obs{i}"),
                    at: None,
                })
                .collect(),
            actuators: (0..act_dim).map(|k| format!("a{k}")).collect(),
        }
    }

    /// The layout of a lattice-Boltzmann environment.
    pub fn of(spec: &EnvSpec) -> Self {
        let (center, d) = spec
            .bodies
            .first()
            .map_or(([0.0, 0.0], 1.0), |b| (b.center(), b.reference_length()));
        let quantities = with_temperature(&["u", "v", "p"], spec.thermal.is_some());
        Layout {
            observations: probe_channels(&spec.probes, center, d, &quantities, str::to_string),
            actuators: actuator_names(&spec.actuation, center),
        }
    }

    /// The layout of a 3D lattice-Boltzmann environment whose section actuator repeats on each
    /// spanwise segment: `(u, v, w, p[, T])` at each probe of each segment's mid-plane, relative
    /// to the first body's centre in its reference length, and the section's actuators. With one
    /// segment the names are the 2D ones (a 2D policy reads the same probes and drives the same
    /// actuator); with several, each quantity and actuator carries its segment (`u@s2`,
    /// `jet_pair@s2`), so a whole-flow map never silently reads one segment for another. Surface
    /// jets (sphere, cube) are known by index.
    pub fn of3(spec: &super::spec3::Env3Spec) -> Self {
        let super::spec3::Actuation3Spec::Segments { actuator } = &spec.actuation else {
            return Layout::indexed(spec.obs_dim(), spec.act_dim());
        };
        let (center, d) = spec
            .bodies
            .first()
            .map_or(([0.0, 0.0], 1.0), |b| (b.center(), b.reference_length()));
        let quantities = with_temperature(&["u", "v", "w", "p"], spec.thermal.is_some());
        let segments = spec.segments();
        let name = |base: &str, s: usize| match segments {
            1 => base.to_string(),
            _ => format!("{base}@s{s}"),
        };
        let observations = (0..segments)
            .flat_map(|s| probe_channels(&spec.probes, center, d, &quantities, |q| name(q, s)))
            .collect();
        let section = actuator_names(actuator, center);
        let actuators = (0..segments).flat_map(|s| section.iter().map(move |a| name(a, s))).collect();
        Layout { observations, actuators }
    }
}

/// The probed quantities, the temperature last when the flow carries one.
fn with_temperature(velocity_and_pressure: &[&'static str], thermal: bool) -> Vec<&'static str> {
    let mut q = velocity_and_pressure.to_vec();
    if thermal {
        q.push("T");
    }
    q
}

/// Each quantity at each probe (probe-major), placed relative to `center` in units of `d`.
fn probe_channels(probes: &[[f64; 2]], center: [f64; 2], d: f64, quantities: &[&str], name: impl Fn(&str) -> String) -> Vec<Channel> {
    probes
        .iter()
        .flat_map(|p| {
            let at = [(p[0] - center[0]) / d, (p[1] - center[1]) / d];
            quantities.iter().map(move |q| (at, *q))
        })
        .map(|(at, q)| Channel {
            quantity: name(q),
            at: Some(at),
        })
        .collect()
}

/// Names of the actuators, one per action.
fn actuator_names(a: &ActuationSpec, center: [f64; 2]) -> Vec<String> {
    let numbered = |stem: &str, bodies: &[usize]| -> Vec<String> {
        match bodies {
            [_] => vec![stem.to_string()],
            _ => bodies.iter().map(|b| format!("{stem}{b}")).collect(),
        }
    };
    match a {
        ActuationSpec::ZnmfJets { .. } => vec!["jet_pair".into()],
        ActuationSpec::ZnmfJetsPerBody { bodies, .. } => numbered("jet_pair", bodies),
        ActuationSpec::Rotation { bodies, .. } => numbered("rotation", bodies),
        ActuationSpec::InletTemperature { .. } => vec!["inlet_temperature".into()],
        ActuationSpec::Jets { jets, .. } => {
            let side = |v: f64, neg: &str, pos: &str| match v {
                v if v < -1e-9 => neg.to_string(),
                v if v > 1e-9 => pos.to_string(),
                _ => "mid".to_string(),
            };
            let names: Vec<String> = jets
                .iter()
                .map(|j| {
                    let (dx, dy) = (j.center[0] - center[0], j.center[1] - center[1]);
                    format!("jet_{}_{}", side(dx, "front", "rear"), side(dy, "bottom", "top"))
                })
                .collect();
            let unique = names.iter().enumerate().all(|(k, n)| !names[..k].contains(n));
            if unique {
                names
            } else {
                (0..jets.len()).map(|k| format!("jet{k}")).collect()
            }
        }
    }
}

impl fmt::Display for Layout {
    /// One line: the quantities, the probes' extent, the actuators.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let probes: Vec<[f64; 2]> = self.observations.iter().filter_map(|c| c.at).collect();
        let mut quantities: Vec<&str> = vec![];
        for c in &self.observations {
            if c.at.is_some() && !quantities.contains(&c.quantity.as_str()) {
                quantities.push(&c.quantity);
            }
        }
        if probes.is_empty() {
            write!(f, "{} observations by index", self.observations.len())?;
        } else {
            let (lo, hi) = probes.iter().fold(([f64::MAX; 2], [f64::MIN; 2]), |(lo, hi), p| {
                ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
            });
            let r = |v: f64| (v * 1e3).round() / 1e3;
            write!(
                f,
                "{} probes of ({}) at x/D {}..{}, y/D {}..{} from the body",
                probes.len() / quantities.len().max(1),
                quantities.join(", "),
                r(lo[0]),
                r(hi[0]),
                r(lo[1]),
                r(hi[1])
            )?;
        }
        write!(f, "; actuators {}", self.actuators.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::lookup;

    fn layout(id: &str) -> Layout {
        lookup(id).unwrap().layout()
    }

    #[test]
    fn bluff_bodies_share_their_wake_rake_and_name_their_actuators() {
        let c = layout("Cylinder_2D_Re200");
        assert_eq!(c.observations.len(), 60);
        assert_eq!(
            c.observations[0],
            Channel {
                quantity: "u".into(),
                at: Some([1.0, -1.0])
            }
        );
        assert_eq!(c.actuators, ["jet_pair"]);
        let s = layout("SquareCylinder_2D_Re200");
        assert_eq!(s.observations, c.observations);
        assert_eq!(
            s.actuators,
            ["jet_front_top", "jet_front_bottom", "jet_rear_top", "jet_rear_bottom"]
        );
        assert_eq!(layout("RotaryCylinder_2D_Re100").actuators, ["rotation"]);
        assert_eq!(layout("Pinball_2D_Re100").actuators, ["rotation0", "rotation1", "rotation2"]);
        assert_eq!(layout("Kolmogorov_2D_Re40").actuators, ["a0", "a1", "a2", "a3"]);
        // The 3D cylinder of one segment reads the 2D rake (plus w) and drives the same pair.
        let c3 = layout("Cylinder_3D_Re200");
        assert_eq!(c3.observations.len(), 80);
        assert_eq!(
            c3.observations[3],
            Channel {
                quantity: "p".into(),
                at: Some([1.0, -1.0])
            }
        );
        assert_eq!(c3.actuators, ["jet_pair"]);
        let c4 = layout("Cylinder_3D_Re1000");
        assert_eq!(c4.actuators, ["jet_pair@s0", "jet_pair@s1", "jet_pair@s2", "jet_pair@s3"]);
        assert_eq!(c4.observations[80].quantity, "u@s1");
        assert_eq!(
            s.to_string(),
            "20 probes of (u, v, p) at x/D 1..5, y/D -1..1 from the body; actuators jet_front_top, jet_front_bottom, jet_rear_top, jet_rear_bottom"
        );
    }
}
