//! An aerofoil's suction side laid flat: the plate of [`super::plate`] whose free stream follows
//! the edge velocity `Ue(s)` of [`SuctionSide`] along the arc length `s`, starting at chordwise
//! position `x_in` (plate `x = s - s(x_in)`), with the integral estimate's layer as the base flow
//! (Blasius' profile before the trip, the power law of [`layer_shape`] after it) and a trip sized
//! by that layer. Curvature is left out: the wing's layer is thin against its radius of curvature
//! over the control region, and the pressure gradient it feels enters through `Ue`.

use super::plate::layer_shape;
use super::trip::TripSpec;
use crate::bl_integral::Station;
use crate::blasius::Blasius;
use crate::suction_side::SuctionSide;

#[derive(Clone, Debug)]
pub struct WingPlate {
    pub side: SuctionSide,
    /// Arc length of the plate's start from the stagnation point.
    pub s_in: f64,
    blasius: Blasius,
}

impl WingPlate {
    pub fn new(side: SuctionSide, x_in: f64) -> Self {
        let s_in = side.at(x_in).s;
        WingPlate {
            side,
            s_in,
            blasius: Blasius::solve(),
        }
    }

    /// Plate `x` of chordwise position `xc`.
    pub fn x_of(&self, xc: f64) -> f64 {
        self.side.at(xc).s - self.s_in
    }

    /// Chordwise position of plate `x` (clamped to the surface).
    pub fn xc_of(&self, x: f64) -> f64 {
        let s = self.s_in + x;
        let st = &self.side.stations;
        let k = st.partition_point(|p| p.s < s).clamp(1, st.len() - 1);
        let t = ((s - st[k - 1].s) / (st[k].s - st[k - 1].s)).clamp(0.0, 1.0);
        self.side.x[k - 1] + t * (self.side.x[k] - self.side.x[k - 1])
    }

    /// The integral estimate of the layer at plate `x`.
    pub fn station(&self, x: f64) -> Station {
        self.side.at_s(self.s_in + x)
    }

    pub fn ue(&self, x: f64) -> f64 {
        self.station(x).ue
    }

    /// `u / Ue` of the estimated layer at plate `(x, y)`.
    pub fn shape(&self, x: f64, y: f64) -> f64 {
        let p = self.station(x);
        layer_shape(&self.blasius, p.theta, p.h, p.turbulent, y)
    }

    /// The trip of Schlatter & Orlu at chordwise `xc`, in units of the laminar layer's
    /// displacement thickness there (`delta* = H theta`, Blasius' `H` where the estimate has
    /// already turned turbulent): Gaussian widths `4 delta*` by `delta*`,
    /// shortest spanwise wavelength `4 delta*`, patterns renewed every `4 delta* / Ue`, and the
    /// time-dependent amplitude `amplitude Ue^2 / delta*`. Widths are kept to at least two cells in
    /// x and wavelengths to three in z, so a coarse grid still resolves the force.
    pub fn trip(&self, xc: f64, amplitude: f64, dx: f64, dz: f64, seed: u64) -> TripSpec {
        let x0 = self.x_of(xc);
        let p = self.station(x0);
        let h = if p.turbulent {
            self.blasius.displacement / self.blasius.momentum
        } else {
            p.h
        };
        let delta_star = h * p.theta;
        TripSpec {
            x0,
            lx: (4.0 * delta_star).max(2.0 * dx),
            ly: delta_star,
            z_s: (4.0 * delta_star).max(3.0 * dz),
            t_s: 4.0 * delta_star / p.ue,
            a_steady: 0.0,
            a_time: amplitude * p.ue * p.ue / delta_star,
            seed,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Naca4;

    fn naca0012() -> WingPlate {
        let wing = Naca4::from_digits("0012", 1.0, [0.0, 0.0], 0.0).unwrap();
        WingPlate::new(SuctionSide::of(&wing, 0.0, 2e5, 0.1).unwrap(), 0.06)
    }

    #[test]
    fn chordwise_positions_and_plate_positions_invert() {
        let p = naca0012();
        assert!(p.x_of(0.06).abs() < 1e-12);
        for xc in [0.1, 0.25, 0.5, 0.86] {
            assert!((p.xc_of(p.x_of(xc)) - xc).abs() < 1e-9, "{xc}");
        }
        // The arc is longer than the chord it spans, by little on a thin section.
        let arc = p.x_of(0.86) - p.x_of(0.25);
        assert!(arc > 0.61 && arc < 0.62, "{arc}");
    }

    #[test]
    fn the_base_layer_follows_the_estimate_through_the_trip() {
        let p = naca0012();
        let x = p.x_of(0.5);
        let st = p.station(x);
        assert!(st.turbulent && (p.ue(x) - st.ue).abs() < 1e-15);
        // u/Ue reaches 1 at the edge and its momentum thickness is the estimate's.
        let dy = st.theta * 1e-3;
        let theta: f64 = (0..40_000)
            .map(|k| {
                let r = p.shape(x, (k as f64 + 0.5) * dy);
                dy * r * (1.0 - r)
            })
            .sum();
        assert!((theta / st.theta - 1.0).abs() < 2e-3, "{theta} {}", st.theta);
        let trip = p.trip(0.1, 0.12, 1e-3, 1e-3, 1);
        assert!(trip.x0 > 0.0 && trip.ly > 0.0 && trip.a_time > 0.0);
    }
}
