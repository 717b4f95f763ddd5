//! A flat-plate boundary layer in the channel box: free-slip top carrying the outflow of a
//! potential-flow base flow ([`BaseFlow::potential`]), a fringe at the end of the box that turns
//! the outflow back into the inflow, and an optional trip. The caller gives the edge velocity
//! `Ue(x)` along the plate (`x` from the inflow) and the layer's shape `u / Ue (x, y)` the base
//! flow starts from and the fringe restores.

use super::error::ChannelError;
use super::fringe::{BaseFlow, FringeSpec};
use super::grid::Top;
use super::solver::{Channel, ChannelConfig, Drive};
use super::trip::TripSpec;
use crate::blasius::Blasius;

/// The box and the forcing of a plate.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlateSpec {
    /// Cells `[nx, ny, nz]`.
    pub n: [usize; 3],
    /// Box `[lx, ly, lz]`, the fringe included in `lx`.
    pub length: [f64; 3],
    pub stretch: f64,
    pub nu: f64,
    pub dt: f64,
    pub fringe: FringeSpec,
    /// Modes of the potential flow's fit to `Ue(x)`.
    pub modes: usize,
    pub trip: Option<TripSpec>,
}

/// The layer's `u / Ue` at height `y` for momentum thickness `theta` and shape factor `h`:
/// Blasius' profile for a laminar layer, the power law `(y / delta)^(1/n)` with `n = 2 / (H - 1)`
/// and `delta = theta (n + 1)(n + 2) / n` (the thicknesses of that law) for a turbulent one.
pub fn layer_shape(blasius: &Blasius, theta: f64, h: f64, turbulent: bool, y: f64) -> f64 {
    if turbulent {
        let n = 2.0 / (h - 1.0);
        let delta = theta * (n + 1.0) * (n + 2.0) / n;
        (y / delta).clamp(0.0, 1.0).powf(1.0 / n)
    } else {
        blasius.at(y * blasius.momentum / theta)[1]
    }
}

/// The plate of `spec` under `ue(x)` with the layer `shape(x, y)`, started from its base flow
/// (spanwise uniform) and with its fringe and trip set; and the largest misfit of the base flow's
/// wall velocity to `ue` upstream of the fringe.
pub fn plate(spec: &PlateSpec, ue: impl Fn(f64) -> f64, shape: impl Fn(f64, f64) -> f64) -> Result<(Channel, f64), ChannelError> {
    let cfg = ChannelConfig {
        n: spec.n,
        length: spec.length,
        stretch: spec.stretch,
        top: Top::FreeSlip,
        nu: spec.nu,
        dt: spec.dt,
        drive: Drive::PressureGradient(0.0),
        check_interval: 50,
    };
    let mut c = Channel::new(cfg)?;
    let g = c.grid().clone();
    let (base, misfit) = BaseFlow::potential(&g, &spec.fringe, ue, spec.modes, shape);
    c.set_transpiration(&vec![0.0; g.nx * g.nz], &base.top().repeat(g.nz))?;
    let (u, v) = (base.u.repeat(g.nz), base.v.repeat(g.nz));
    c.set_velocity(&u, &v, &vec![0.0; u.len()])?;
    c.set_fringe(spec.fringe, base)?;
    if let Some(trip) = spec.trip {
        c.set_trip(trip)?;
    }
    Ok((c, misfit))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shapes_have_the_thicknesses_they_are_given() {
        let b = Blasius::solve();
        for (theta, h, turbulent) in [(0.3, b.displacement / b.momentum, false), (0.2, 1.4, true), (0.5, 1.6, true)] {
            let dy = 1e-4;
            let (mut ds, mut th) = (0.0, 0.0);
            for k in 0..200_000 {
                let r = layer_shape(&b, theta, h, turbulent, (k as f64 + 0.5) * dy);
                ds += dy * (1.0 - r);
                th += dy * r * (1.0 - r);
            }
            assert!((th - theta).abs() < 1e-3 * theta, "theta {th} for {theta}");
            assert!((ds / th - h).abs() < 1e-3 * h, "H {} for {h}", ds / th);
        }
    }
}
