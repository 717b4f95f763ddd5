//! The boundary layer on an aerofoil's upper surface at a chord Reynolds number: the inviscid edge
//! velocity from the panel method ([`crate::panel`]), then the layer from the stagnation point by
//! Thwaites' method, tripped to Head's turbulent method ([`crate::bl_integral`]). An estimate of
//! `Re_theta(x)` and `u_tau(x)` without the layer's displacement acting back on `Ue` (no
//! viscous-inviscid interaction), used to design flows that stand in for the wing's layer.
//!
//! Units: chord 1, free stream 1, `nu = 1 / Re_c`.

use crate::bl_integral::{develop, Station};
use crate::geometry::Naca4;
use crate::panel::{PanelError, PanelFlow};

#[derive(Clone, Debug)]
pub struct SuctionSide {
    /// Chordwise position of each station (body coordinates, from the leading edge).
    pub x: Vec<f64>,
    pub stations: Vec<Station>,
    pub nu: f64,
}

impl SuctionSide {
    /// The upper surface of `aerofoil` (its outline in body coordinates, at angle of attack
    /// `alpha` radians) at `Re_c = re_c`, tripped at chordwise position `trip`.
    pub fn of(aerofoil: &Naca4, alpha: f64, re_c: f64, trip: f64) -> Result<Self, PanelError> {
        // Clockwise from the trailing edge: the lower surface first.
        let mut nodes: Vec<[f64; 2]> = aerofoil.outline().iter().rev().copied().collect();
        // The closed trailing edge meets itself up to round-off in the thickness polynomial.
        let n = nodes.len() - 1;
        if (nodes[n][0] - nodes[0][0]).abs() + (nodes[n][1] - nodes[0][1]).abs() < 1e-12 * aerofoil.chord {
            nodes[n] = nodes[0];
        }
        let flow = PanelFlow::solve(&nodes, alpha)?;
        let speed = flow.speed();
        // The stagnation point: the slowest node; the upper surface runs from it to the trailing edge.
        let stag = (1..n).min_by(|&a, &b| speed[a].total_cmp(&speed[b])).unwrap_or(n / 2);
        let (mut x, mut s, mut ue) = (vec![nodes[stag][0]], vec![0.0], vec![0.0]);
        for k in stag + 1..n {
            let d = ((nodes[k][0] - nodes[k - 1][0]).powi(2) + (nodes[k][1] - nodes[k - 1][1]).powi(2)).sqrt();
            s.push(s[s.len() - 1] + d);
            x.push(nodes[k][0]);
            ue.push(speed[k]);
        }
        let nu = 1.0 / re_c;
        let s_trip = x.iter().zip(&s).find(|(&x, _)| x >= trip).map_or(f64::INFINITY, |(_, &s)| s);
        Ok(SuctionSide {
            stations: develop(&s, &ue, nu, s_trip, 0.0),
            x,
            nu,
        })
    }

    /// The station data linearly interpolated at chordwise position `x` (clamped to the surface).
    pub fn at(&self, x: f64) -> Station {
        let k = self.x.partition_point(|&v| v < x).clamp(1, self.x.len() - 1);
        let (a, b) = (&self.stations[k - 1], &self.stations[k]);
        let t = ((x - self.x[k - 1]) / (self.x[k] - self.x[k - 1])).clamp(0.0, 1.0);
        let mix = |p: f64, q: f64| p + t * (q - p);
        Station {
            s: mix(a.s, b.s),
            ue: mix(a.ue, b.ue),
            theta: mix(a.theta, b.theta),
            h: mix(a.h, b.h),
            c_f: mix(a.c_f, b.c_f),
            turbulent: b.turbulent,
        }
    }

    /// The station data linearly interpolated at arc length `s` from the stagnation point.
    pub fn at_s(&self, s: f64) -> Station {
        let k = self.stations.partition_point(|p| p.s < s).clamp(1, self.x.len() - 1);
        self.at(self.x[k - 1] + (s - self.stations[k - 1].s) / (self.stations[k].s - self.stations[k - 1].s) * (self.x[k] - self.x[k - 1]))
    }

    /// Mean of `Re_theta` over the arc length between chordwise positions `x0` and `x1`.
    pub fn mean_re_theta(&self, x0: f64, x1: f64) -> f64 {
        let (mut sum, mut length) = (0.0, 0.0);
        for k in 1..self.x.len() {
            if self.x[k - 1] >= x0 && self.x[k] <= x1 {
                let ds = self.stations[k].s - self.stations[k - 1].s;
                sum += 0.5 * (self.stations[k].re_theta(self.nu) + self.stations[k - 1].re_theta(self.nu)) * ds;
                length += ds;
            }
        }
        sum / length
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_naca0012_layer_at_re_c_2e5() {
        let wing = Naca4::from_digits("0012", 1.0, [0.0, 0.0], 0.0).unwrap();
        let side = SuctionSide::of(&wing, 0.0, 2e5, 0.1).unwrap();
        // Laminar before the trip, turbulent after; the trip keeps theta.
        assert!(!side.at(0.09).turbulent && side.at(0.2).turbulent);
        // Ue: the panel method's peak just behind the nose, falling to about 1 at x/c 0.85.
        let peak = side.stations.iter().map(|p| p.ue).fold(0.0, f64::max);
        assert!((1.18..1.2).contains(&peak), "{peak}");
        // The adverse gradient thickens the layer: H grows and C_f falls over the control region.
        let (a, b) = (side.at(0.25), side.at(0.86));
        assert!(b.h > a.h && b.c_f < a.c_f && b.theta > 2.0 * a.theta);
        // Arc length and chordwise position name the same stations.
        let p = side.at(0.3);
        assert!((side.at_s(p.s).ue - p.ue).abs() < 1e-9 && (side.at_s(p.s).theta - p.theta).abs() < 1e-12);
        let mean = side.mean_re_theta(0.25, 0.86);
        println!("mean Re_theta over x/c 0.25-0.86: {mean:.1}");
        assert!(mean > 200.0 && mean < 800.0, "{mean}");
    }
}
