//! What an environment's observations and actions mean, so that a policy trained on one flow can
//! be moved to another (the `transfer` module): each observation is a quantity, at a position
//! relative to the body in body lengths where it is a probe; each action drives a named actuator.
//!
//! Lattice-Boltzmann environments observe `(u, v, p[, T])` at each probe, positioned relative to
//! the centre of their first body in its reference length (D); actuators are named from their
//! kind and, for independent jets, from where they sit on the body (`jet_front_top`, ...). Other
//! families are known by index (`obs0`, `a0`, ...).

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
        let mut quantities = vec!["u", "v", "p"];
        if spec.thermal.is_some() {
            quantities.push("T");
        }
        let observations = spec
            .probes
            .iter()
            .flat_map(|p| {
                let at = [(p[0] - center[0]) / d, (p[1] - center[1]) / d];
                quantities.iter().map(move |q| Channel {
                    quantity: q.to_string(),
                    at: Some(at),
                })
            })
            .collect();
        Layout {
            observations,
            actuators: actuator_names(&spec.actuation, center),
        }
    }
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
        assert_eq!(
            s.to_string(),
            "20 probes of (u, v, p) at x/D 1..5, y/D -1..1 from the body; actuators jet_front_top, jet_front_bottom, jet_rear_top, jet_rear_bottom"
        );
    }
}
