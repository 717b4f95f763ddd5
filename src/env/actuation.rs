//! Actuators and the temporal smoothing of control actions, as the HydroGym paper defines them
//! (Methods, "Temporal smoothing of control actions", "Synthetic jet actuation", "Surface rotation
//! actuation").
//!
//! - Smoothing: `A(t) = A_old + (A_new - A_old) R(tau)`, `tau = (t - t_update) / (N_r dt)` in
//!   `[0, 1]`, with `R_tanh(tau) = (tanh(b (tau - 1/2)) + 1) / 2` or
//!   `R_exp(tau) = (e^{k tau} - 1) / (e^k - 1)`. The paper's tanh ramp is not exactly 0 and 1 at
//!   the ends (`R(0) = (1 - tanh(b/2)) / 2`), which would make `A(t)` jump by
//!   `(A_new - A_old)(1 - R(1))` at every update; we rescale it to `(R - R(0)) / (R(1) - R(0))` so
//!   the actuation is continuous. Default: tanh with `b = 10`.
//! - Jet `j` (centre `x_j`, direction `t_j = (cos a_j, sin a_j)`, width `W_j`):
//!   `u_w(x) = A_j (1 - (2 d_perp / W_j)^2) t_j` where `d_perp` is the distance from `x` to the jet's
//!   centre line, for `d_perp <= W_j / 2` and `|x - x_j| <= W_j` (the second condition keeps a jet
//!   on its own side of the body).
//! - Rotation about `x_c` with angular velocity `w`: `u_w = w (-(y - y_c), x - x_c)`.
//!
//! Velocities here are non-dimensional (units of U); [`apply`] converts to lattice units.

use serde::{Deserialize, Serialize};

use hgym_solvers::lbm::{D2q9, Units};

use super::spec::ActuationSpec;
use crate::flow::GeometrySpec;

/// Normalised ramp `R(tau)`, `R(0) = 0`, `R(1) = 1`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Ramp {
    /// S-shaped: `(tanh(b (tau - 1/2)) + 1) / 2`, rescaled to end exactly at 0 and 1.
    Tanh { b: f64 },
    /// Slow start, fast end: `(e^{k tau} - 1) / (e^k - 1)`.
    Exponential { k: f64 },
}

impl Default for Ramp {
    fn default() -> Self {
        Ramp::Tanh { b: 10.0 }
    }
}

impl Ramp {
    /// `R(tau)` for `tau` clamped to `[0, 1]`.
    pub fn weight(&self, tau: f64) -> f64 {
        let tau = tau.clamp(0.0, 1.0);
        match *self {
            Ramp::Tanh { b } => {
                let r = |s: f64| 0.5 * ((b * (s - 0.5)).tanh() + 1.0);
                let (r0, r1) = (r(0.0), r(1.0));
                if r1 - r0 > 0.0 {
                    (r(tau) - r0) / (r1 - r0)
                } else {
                    tau
                }
            }
            Ramp::Exponential { k } => {
                if k.abs() < 1e-12 {
                    tau
                } else {
                    (k * tau).exp_m1() / k.exp_m1()
                }
            }
        }
    }

    /// `A(tau) = A_old + (A_new - A_old) R(tau)`.
    pub fn blend(&self, a_old: f64, a_new: f64, tau: f64) -> f64 {
        a_old + (a_new - a_old) * self.weight(tau)
    }
}

/// A synthetic jet on a body's wall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Jet {
    /// Centre of the jet's exit on the wall.
    pub center: [f64; 2],
    /// Blowing direction, degrees from +x.
    pub angle_deg: f64,
    /// Exit width (chord across the slot).
    pub width: f64,
}

impl Jet {
    /// A jet on a circle of `radius` around `center`, centred at polar angle `theta_deg`, blowing
    /// radially outward, spanning `span_deg` of the circumference.
    pub fn on_circle(center: [f64; 2], radius: f64, theta_deg: f64, span_deg: f64) -> Self {
        let t = theta_deg.to_radians();
        Jet {
            center: [center[0] + radius * t.cos(), center[1] + radius * t.sin()],
            angle_deg: theta_deg,
            width: 2.0 * radius * (0.5 * span_deg.to_radians()).sin(),
        }
    }

    /// The spatial profile `S_j(x)` (zero outside the jet).
    pub fn profile(&self, p: [f64; 2]) -> [f64; 2] {
        let r = [p[0] - self.center[0], p[1] - self.center[1]];
        // Most wall points are far from the jet: reject them before the trigonometry (the
        // actuation is set on every link at every lattice step). `hypot` is within an ulp of
        // the root, so the margin never rejects a point the exact test below keeps.
        if r[0] * r[0] + r[1] * r[1] > (1.0 + 1e-9) * self.width * self.width {
            return [0.0, 0.0];
        }
        let a = self.angle_deg.to_radians();
        let t = [a.cos(), a.sin()];
        let along = r[0] * t[0] + r[1] * t[1];
        let d_perp = (r[0] - along * t[0]).hypot(r[1] - along * t[1]);
        let half = 0.5 * self.width;
        if d_perp > half || r[0].hypot(r[1]) > self.width {
            return [0.0, 0.0];
        }
        let s = 1.0 - (d_perp / half).powi(2);
        [s * t[0], s * t[1]]
    }
}

/// Surface rotation velocity `w (-(y - y_c), x - x_c)`.
pub fn rotation(omega: f64, center: [f64; 2], p: [f64; 2]) -> [f64; 2] {
    [-omega * (p[1] - center[1]), omega * (p[0] - center[0])]
}

/// The jets and rotation centres of a section actuator, resolved against the bodies: for
/// `ZnmfJets` the pair on its circle, for `ZnmfJetsPerBody` a pair per listed circle (jets
/// `2k`, `2k + 1` on the `k`-th), for `Jets` the listed jets, for `Rotation` the centre of each
/// listed circle. An actuated body that is not a circle (where one must be), or that does not
/// exist, is an error naming it.
pub fn resolve(spec: &ActuationSpec, bodies: &[GeometrySpec]) -> Result<(Vec<Jet>, Vec<[f64; 2]>), String> {
    let circle = |i: usize| match bodies.get(i) {
        Some(GeometrySpec::Circle { center, diameter }) => Ok((*center, 0.5 * diameter)),
        _ => Err(format!("actuated body {i} must be a circle")),
    };
    Ok(match spec {
        ActuationSpec::ZnmfJets {
            body,
            angles_deg,
            span_deg,
            ..
        } => {
            let (c, r) = circle(*body)?;
            (angles_deg.iter().map(|a| Jet::on_circle(c, r, *a, *span_deg)).collect(), vec![])
        }
        ActuationSpec::ZnmfJetsPerBody {
            bodies: listed,
            angles_deg,
            span_deg,
            ..
        } => {
            let mut jets = vec![];
            for &b in listed {
                let (c, r) = circle(b)?;
                jets.extend(angles_deg.iter().map(|a| Jet::on_circle(c, r, *a, *span_deg)));
            }
            (jets, vec![])
        }
        ActuationSpec::Jets { body, jets, .. } => {
            if *body >= bodies.len() {
                return Err(format!("jets on body {body}, which does not exist"));
            }
            (jets.clone(), vec![])
        }
        ActuationSpec::Rotation { bodies: listed, .. } => {
            (vec![], listed.iter().map(|&i| circle(i).map(|c| c.0)).collect::<Result<_, _>>()?)
        }
        ActuationSpec::InletTemperature { .. } => (vec![], vec![]),
    })
}

/// Non-dimensional wall velocity (units of U) at the wall point `p` of body `b` under a section
/// actuator with physical actions `a` (units of U or U/D; the temperature actuator moves no
/// wall), `jets` and `centers` as [`resolve`] gives them:
/// - `ZnmfJets`: the first jet blows `a_0`, the second sucks the same;
/// - `ZnmfJetsPerBody`: on the `k`-th listed body, its pair blows and sucks `a_k`;
/// - `Jets`: jet `k` blows `a_k`;
/// - `Rotation`: the `k`-th listed body turns at `a_k`.
pub fn section_velocity(spec: &ActuationSpec, jets: &[Jet], centers: &[[f64; 2]], b: usize, a: &[f64], p: [f64; 2]) -> [f64; 2] {
    let mut u = [0.0, 0.0];
    let mut blow = |jets: &[Jet], amplitudes: &mut dyn Iterator<Item = f64>| {
        for (jet, a) in jets.iter().zip(amplitudes) {
            let s = jet.profile(p);
            u[0] += a * s[0];
            u[1] += a * s[1];
        }
    };
    match spec {
        ActuationSpec::ZnmfJets { body, .. } if *body == b => blow(jets, &mut [a[0], -a[0]].into_iter()),
        ActuationSpec::ZnmfJetsPerBody { bodies, .. } => {
            if let Some(k) = bodies.iter().position(|&i| i == b) {
                blow(&jets[2 * k..2 * k + 2], &mut [a[k], -a[k]].into_iter());
            }
        }
        ActuationSpec::Jets { body, .. } if *body == b => blow(jets, &mut a.iter().copied()),
        ActuationSpec::Rotation { bodies, .. } => {
            if let Some(k) = bodies.iter().position(|&i| i == b) {
                let r = rotation(a[k], centers[k], p);
                u[0] += r[0];
                u[1] += r[1];
            }
        }
        _ => {}
    }
    u
}

/// The wall links (indices into the solver's wall points) that a section actuator can move:
/// those where some unit action gives a non-zero velocity. Every actuator is linear in the
/// action, so the other links stay at rest whatever the action, and [`apply`] sets only these
/// (the actuation is set at every lattice step; most links are far from any jet).
pub fn moving_links(solver: &D2q9, spec: &ActuationSpec, jets: &[Jet], centers: &[[f64; 2]], act_dim: usize) -> Vec<usize> {
    let mut unit = vec![0.0; act_dim];
    let mut moving = Vec::new();
    for (l, wp) in solver.wall_points().iter().enumerate() {
        let moves = (0..act_dim).any(|k| {
            unit.fill(0.0);
            unit[k] = 1.0;
            section_velocity(spec, jets, centers, wp.body, &unit, wp.position) != [0.0, 0.0]
        });
        if moves {
            moving.push(l);
        }
    }
    moving
}

/// Sets the wall velocity of the `moving` links (see [`moving_links`]) from a section actuator
/// (see [`section_velocity`]), converted to lattice units.
pub fn apply(solver: &mut D2q9, moving: &[usize], spec: &ActuationSpec, jets: &[Jet], centers: &[[f64; 2]], a: &[f64], units: &Units) {
    solver.set_link_velocities(moving, |wp| {
        let u = section_velocity(spec, jets, centers, wp.body, a, wp.position);
        [units.lattice_velocity(u[0]), units.lattice_velocity(u[1])]
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use hgym_solvers::geometry::{Circle, Shape};
    use hgym_solvers::lbm::{D2q9Config, Grid, Side, Sides};
    use std::sync::Arc;

    #[test]
    fn ramps_start_at_zero_end_at_one_and_are_monotone() {
        for ramp in [
            Ramp::Tanh { b: 10.0 },
            Ramp::Tanh { b: 2.0 },
            Ramp::Exponential { k: 3.0 },
            Ramp::Exponential { k: -2.0 },
        ] {
            assert!(ramp.weight(0.0).abs() < 1e-15, "{ramp:?}");
            assert!((ramp.weight(1.0) - 1.0).abs() < 1e-15, "{ramp:?}");
            let mut prev = 0.0;
            for j in 1..=1000 {
                let w = ramp.weight(j as f64 / 1000.0);
                assert!(w >= prev - 1e-15, "{ramp:?} not monotone");
                prev = w;
            }
        }
    }

    /// A sequence of control updates gives a continuous actuation: at each update the new ramp
    /// starts exactly where the old one ended.
    #[test]
    fn smoothed_actuation_is_continuous_across_updates() {
        let ramp = Ramp::default();
        let actions = [0.0, 1.0, -0.5, 0.25, 0.25, -1.0];
        let n = 50;
        let mut series = Vec::new();
        for w in actions.windows(2) {
            for s in 0..=n {
                series.push(ramp.blend(w[0], w[1], s as f64 / n as f64));
            }
        }
        // Between the last sample of one interval and the first of the next there is no jump.
        for k in 1..actions.len() - 1 {
            let end = series[k * (n + 1) - 1];
            let start = series[k * (n + 1)];
            assert_eq!(end, start, "jump at update {k}");
            assert_eq!(end, actions[k]);
        }
        // And within an interval the largest step is bounded by the ramp's steepest slope.
        let max_step = series.windows(2).map(|w| (w[1] - w[0]).abs()).fold(0.0, f64::max);
        assert!(max_step < 1.5 * 0.4, "max step {max_step}");
    }

    #[test]
    fn jet_profile_is_parabolic_and_local() {
        let jet = Jet::on_circle([0.0, 0.0], 0.5, 90.0, 10.0);
        let top = jet.profile([0.0, 0.5]);
        assert!((top[1] - 1.0).abs() < 1e-12 && top[0].abs() < 1e-12);
        // Edge of the slot: zero; the opposite side of the cylinder: zero.
        let edge = [0.5 * (95f64).to_radians().cos(), 0.5 * (95f64).to_radians().sin()];
        assert!(jet.profile(edge)[1].abs() < 1e-9);
        assert_eq!(jet.profile([0.0, -0.5]), [0.0, 0.0]);
    }

    #[test]
    fn rotation_is_tangential() {
        let u = rotation(2.0, [1.0, 1.0], [1.5, 1.0]);
        assert!((u[0]).abs() < 1e-15 && (u[1] - 1.0).abs() < 1e-15);
    }

    /// A closed box of 160 x 96 nodes at 16 per D with a circle of diameter 1 at each centre.
    fn boxed_circles(centers: &[[f64; 2]]) -> (D2q9, Units) {
        let units = Units {
            cells_per_length: 16.0,
            u_lattice: 0.05,
            reynolds: 100.0,
        };
        let (nx, ny) = (160, 96);
        let dx = 1.0 / 16.0;
        let grid = Grid {
            origin: [0.5 * dx, -0.5 * (ny as f64 - 1.0) * dx],
            dx,
        };
        let sides = Sides {
            west: Side::Wall,
            east: Side::Wall,
            south: Side::Wall,
            north: Side::Wall,
        };
        let mut cfg = D2q9Config::new(nx, ny, units.tau(), sides);
        cfg.grid = grid;
        let bodies = centers
            .iter()
            .map(|&center| Arc::new(Circle { center, radius: 0.5 }) as Arc<dyn Shape>)
            .collect();
        (D2q9::new(cfg, bodies).unwrap(), units)
    }

    /// Zero-net-mass-flux jet pair at 90 and 270 degrees on a cylinder placed symmetrically on the
    /// grid: the mass the moving-wall terms inject sums to zero to round-off, while one jet alone
    /// injects a finite amount.
    #[test]
    fn znmf_jet_pair_injects_no_net_mass() {
        let center = [3.0, 0.0];
        let (mut s, units) = boxed_circles(&[center]);
        let spec = ActuationSpec::ZnmfJets {
            body: 0,
            angles_deg: [90.0, 270.0],
            span_deg: 10.0,
            max_velocity: 1.0,
        };
        let (jets, _) = resolve(&spec, &[GeometrySpec::Circle { center, diameter: 1.0 }]).unwrap();
        let a = 0.8;
        let links = moving_links(&s, &spec, &jets, &[], 1);
        apply(&mut s, &links, &spec, &jets, &[], &[a], &units);
        let pair = s.wall_mass_source(0);
        let one_jet = ActuationSpec::Jets {
            body: 0,
            jets: jets[..1].to_vec(),
            max_velocity: 1.0,
        };
        let (mut s, _) = boxed_circles(&[center]);
        let links = moving_links(&s, &one_jet, &jets[..1], &[], 1);
        apply(&mut s, &links, &one_jet, &jets[..1], &[], &[a], &units);
        let one = s.wall_mass_source(0);
        println!("ZNMF pair: net injected mass per step {pair:.3e}; one jet alone {one:.3e}");
        assert!(one.abs() > 1e-4, "a single jet must inject mass ({one})");
        assert!(pair.abs() < 1e-12 * one.abs().max(1.0), "ZNMF pair injects {pair:e}");
    }

    /// Setting only the links an actuator can move gives the flow that setting every link of
    /// every body gives, bitwise: jet pairs on two of three cylinders (a few links move) and
    /// the rotation of two (all their links move, the third's none).
    #[test]
    fn setting_only_the_moving_links_changes_nothing() {
        let centers = [[3.0, 0.0], [4.5, 1.0], [4.5, -1.0]];
        let bodies: Vec<_> = centers
            .iter()
            .map(|&center| GeometrySpec::Circle { center, diameter: 1.0 })
            .collect();
        let specs = [
            ActuationSpec::ZnmfJetsPerBody {
                bodies: vec![1, 2],
                angles_deg: [90.0, 270.0],
                span_deg: 20.0,
                max_velocity: 1.0,
            },
            ActuationSpec::Rotation {
                bodies: vec![1, 2],
                max_omega: 1.0,
            },
        ];
        for spec in specs {
            let (jets, centers_of) = resolve(&spec, &bodies).unwrap();
            let (mut every, units) = boxed_circles(&centers);
            let (mut moving, _) = boxed_circles(&centers);
            let links = moving_links(&moving, &spec, &jets, &centers_of, 2);
            let total = moving.wall_points().len();
            let on_rotors = moving.wall_points().iter().filter(|w| w.body != 0).count();
            match spec {
                ActuationSpec::Rotation { .. } => assert_eq!(links.len(), on_rotors, "{spec:?}"),
                _ => assert!(
                    !links.is_empty() && links.len() < total / 4,
                    "{} of {total} links move",
                    links.len()
                ),
            }
            for k in 0..20 {
                let a = [0.05 * (k as f64 * 0.7).sin(), -0.03];
                for b in 0..3 {
                    every.set_wall_velocity(b, |wp| {
                        let u = section_velocity(&spec, &jets, &centers_of, b, &a, wp.position);
                        [units.lattice_velocity(u[0]), units.lattice_velocity(u[1])]
                    });
                }
                apply(&mut moving, &links, &spec, &jets, &centers_of, &a, &units);
                every.step().unwrap();
                moving.step().unwrap();
            }
            assert!(every.populations() == moving.populations(), "{spec:?}");
            assert!(every.body_forces()[1][1] != 0.0, "the actuation acts");
        }
    }

    /// The profile's early rejection keeps every point the full test keeps: bitwise the textbook
    /// profile on a fine grid around a jet, its rim included.
    #[test]
    fn jet_profile_rejection_changes_no_value() {
        let jet = Jet::on_circle([0.3, -0.2], 0.5, 63.0, 25.0);
        let textbook = |p: [f64; 2]| {
            let a = jet.angle_deg.to_radians();
            let t = [a.cos(), a.sin()];
            let r = [p[0] - jet.center[0], p[1] - jet.center[1]];
            let along = r[0] * t[0] + r[1] * t[1];
            let d_perp = (r[0] - along * t[0]).hypot(r[1] - along * t[1]);
            let half = 0.5 * jet.width;
            if d_perp > half || r[0].hypot(r[1]) > jet.width {
                return [0.0, 0.0];
            }
            let s = 1.0 - (d_perp / half).powi(2);
            [s * t[0], s * t[1]]
        };
        let mut inside = 0;
        for i in -300..=300 {
            for j in -300..=300 {
                let p = [
                    jet.center[0] + i as f64 * jet.width / 250.0,
                    jet.center[1] + j as f64 * jet.width / 250.0,
                ];
                let (new, old) = (jet.profile(p), textbook(p));
                assert_eq!(new.map(f64::to_bits), old.map(f64::to_bits), "at {p:?}");
                inside += (old != [0.0, 0.0]) as usize;
            }
        }
        assert!(inside > 1000, "{inside} points inside the jet");
    }
}
