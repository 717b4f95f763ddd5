//! Plane-averaged turbulence statistics of the channel at the cell centres: means of `u`, `v`,
//! `w` and the second moments `uu`, `vv`, `ww`, `uv`, each averaged over x and z. `u` and `w`
//! are averaged from their two faces to the centre, `v` interpolated linearly in y.

use rayon::prelude::*;

use super::grid::Grid;

/// Sums of plane averages over samples; [`Profiles`] turns them into means and fluctuations.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlaneSums {
    pub samples: u64,
    /// Per row j: `[u, v, w, uu, vv, ww, uv]`.
    pub rows: Vec<[f64; 7]>,
}

/// Means and fluctuation moments per row: `u`, `v`, `w` means; `uu`, `vv`, `ww` variances; `uv`
/// covariance.
#[derive(Clone, Debug, PartialEq)]
pub struct Profiles {
    pub mean: Vec<[f64; 3]>,
    pub var: Vec<[f64; 3]>,
    pub uv: Vec<f64>,
}

impl PlaneSums {
    pub fn new(ny: usize) -> Self {
        PlaneSums {
            samples: 0,
            rows: vec![[0.0; 7]; ny],
        }
    }

    /// Adds one sample of the fields (`at` / `at_v` order, see [`Grid`]).
    pub fn add(&mut self, g: &Grid, u: &[f64], v: &[f64], w: &[f64]) {
        let (nx, nz) = (g.nx, g.nz);
        let inv = 1.0 / (nx * nz) as f64;
        self.rows.par_iter_mut().enumerate().for_each(|(j, acc)| {
            let t = (g.yc[j] - g.yf[j]) / g.dyf[j];
            let mut s = [0.0; 7];
            for k in 0..nz {
                let kp = if k + 1 == nz { 0 } else { k + 1 };
                for i in 0..nx {
                    let ip = if i + 1 == nx { 0 } else { i + 1 };
                    let uc = 0.5 * (u[g.at(i, j, k)] + u[g.at(ip, j, k)]);
                    let wc = 0.5 * (w[g.at(i, j, k)] + w[g.at(i, j, kp)]);
                    let (vl, vh) = (v[g.at_v(i, j, k)], v[g.at_v(i, j + 1, k)]);
                    let vc = vl + t * (vh - vl);
                    for (a, b) in s.iter_mut().zip([uc, vc, wc, uc * uc, vc * vc, wc * wc, uc * vc]) {
                        *a += b;
                    }
                }
            }
            for (a, b) in acc.iter_mut().zip(s) {
                *a += b * inv;
            }
        });
        self.samples += 1;
    }

    pub fn profiles(&self) -> Profiles {
        let n = self.samples.max(1) as f64;
        let mut p = Profiles {
            mean: vec![],
            var: vec![],
            uv: vec![],
        };
        for r in &self.rows {
            let m = [r[0] / n, r[1] / n, r[2] / n];
            p.var.push([r[3] / n - m[0] * m[0], r[4] / n - m[1] * m[1], r[5] / n - m[2] * m[2]]);
            p.uv.push(r[6] / n - m[0] * m[1]);
            p.mean.push(m);
        }
        p
    }
}
