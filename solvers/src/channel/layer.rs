//! Statistics of a spatially developing boundary layer on the bottom wall: spanwise- and
//! time-averaged `u` and `u^2` at every `(x, y)` and the wall shear stress at every `x`, and the
//! integral quantities they give per station.
//!
//! The edge of the layer at a station is the height of the largest mean `u` (below the top
//! cell): the free stream above a layer under a pressure gradient is not uniform in `y`, and its
//! maximum is where the layer ends. `Ue` is the mean `u` there; `delta*` and `theta` integrate up
//! to it (midpoint rule on the cells).

use super::grid::Grid;
use super::solver::Channel;

/// Running sums over samples and the span.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LayerSums {
    pub nx: usize,
    pub ny: usize,
    /// Samples added (each one a whole field: `nz` values per entry).
    pub samples: usize,
    pub u: Vec<f64>,
    pub uu: Vec<f64>,
    pub tau: Vec<f64>,
    /// Scratch for the wall shear of one sample (not a statistic).
    #[serde(skip)]
    shear: [Vec<f64>; 2],
}

/// The mean layer at one station.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Station {
    pub x: f64,
    pub ue: f64,
    pub delta_star: f64,
    pub theta: f64,
    /// Height of the edge.
    pub edge: f64,
    /// Mean wall shear stress (`u_tau^2`).
    pub tau_w: f64,
}

impl Station {
    pub fn shape_factor(&self) -> f64 {
        self.delta_star / self.theta
    }
    pub fn u_tau(&self) -> f64 {
        self.tau_w.max(0.0).sqrt()
    }
    /// `C_f = 2 tau_w / Ue^2`.
    pub fn c_f(&self) -> f64 {
        2.0 * self.tau_w / (self.ue * self.ue)
    }
}

impl LayerSums {
    pub fn new(g: &Grid) -> Self {
        let (nx, ny) = (g.nx, g.ny);
        LayerSums {
            nx,
            ny,
            samples: 0,
            u: vec![0.0; nx * ny],
            uu: vec![0.0; nx * ny],
            tau: vec![0.0; nx],
            shear: [vec![0.0; nx * g.nz], vec![0.0; nx * g.nz]],
        }
    }

    /// Adds the current field of `c`.
    pub fn add(&mut self, c: &Channel) {
        let g = c.grid();
        let (nx, nz) = (g.nx, g.nz);
        if self.shear[0].len() != nx * nz {
            self.shear = [vec![0.0; nx * nz], vec![0.0; nx * nz]];
        }
        let [bottom, top] = &mut self.shear;
        c.wall_shear(bottom, top);
        for k in 0..nz {
            for i in 0..nx {
                self.tau[i] += bottom[k * nx + i];
            }
        }
        let u = c.u();
        for k in 0..nz {
            for j in 0..g.ny {
                let row = &u[g.at(0, j, k)..][..nx];
                let (su, suu) = (&mut self.u[j * nx..][..nx], &mut self.uu[j * nx..][..nx]);
                for i in 0..nx {
                    su[i] += row[i];
                    suu[i] += row[i] * row[i];
                }
            }
        }
        self.samples += 1;
    }

    fn count(&self, g: &Grid) -> f64 {
        (self.samples * g.nz) as f64
    }

    /// Mean `u` at `(i, j)` (the `u` position `x = i dx`).
    pub fn mean_u(&self, g: &Grid, i: usize, j: usize) -> f64 {
        self.u[j * self.nx + i] / self.count(g)
    }

    /// Root-mean-square fluctuation of `u` at `(i, j)`.
    pub fn rms_u(&self, g: &Grid, i: usize, j: usize) -> f64 {
        let m = self.mean_u(g, i, j);
        (self.uu[j * self.nx + i] / self.count(g) - m * m).max(0.0).sqrt()
    }

    /// The mean layer at `u` position `i`.
    pub fn station(&self, g: &Grid, i: usize) -> Station {
        let prof = |j| self.mean_u(g, i, j);
        let top = (0..g.ny - 1).max_by(|&a, &b| prof(a).total_cmp(&prof(b))).unwrap_or(g.ny - 1);
        let ue = prof(top);
        let (mut delta_star, mut theta) = (0.0, 0.0);
        for j in 0..=top {
            let r = prof(j) / ue;
            delta_star += g.dyf[j] * (1.0 - r);
            theta += g.dyf[j] * r * (1.0 - r);
        }
        Station {
            x: i as f64 * g.dx,
            ue,
            delta_star,
            theta,
            edge: g.yf[top + 1],
            tau_w: self.tau[i] / self.count(g),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channel::{ChannelConfig, Drive, Top};

    #[test]
    fn the_stations_of_a_laminar_open_channel_are_the_parabolas() {
        // u = U_c (2 eta - eta^2), eta = y / h: delta* = h / 3, theta = 2 h / 15, tau_w = 2 nu U_c / h.
        let (nu, grad) = (0.01, 0.02);
        let cfg = ChannelConfig {
            n: [4, 64, 2],
            length: [1.0, 1.0, 1.0],
            stretch: 0.0,
            top: Top::FreeSlip,
            nu,
            dt: 1e-3,
            drive: Drive::PressureGradient(grad),
            check_interval: 0,
        };
        let mut c = Channel::new(cfg).unwrap();
        c.set_laminar();
        let mut sums = LayerSums::new(c.grid());
        sums.add(&c);
        sums.add(&c);
        let uc = grad / (2.0 * nu);
        let s = sums.station(c.grid(), 1);
        assert!((s.ue - uc).abs() < 1e-3 * uc, "{}", s.ue);
        assert!((s.delta_star - 1.0 / 3.0).abs() < 0.02, "{}", s.delta_star);
        assert!((s.theta - 2.0 / 15.0).abs() < 0.01, "{}", s.theta);
        assert!((s.tau_w - 2.0 * nu * uc).abs() < 1e-9, "{}", s.tau_w);
        assert!(sums.rms_u(c.grid(), 1, 10) < 1e-6);
    }
}
