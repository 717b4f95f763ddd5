//! Point probes: density and velocity at any physical point by bilinear interpolation of the four
//! surrounding nodes (solid nodes count as resting fluid at rho = 1, which is the wall value).

use super::error::LbmError;
use super::solver::D2q9;

impl D2q9 {
    /// `(rho, ux, uy)` in lattice units at physical point `p`. A collective on a split grid, as
    /// [`Self::probes`].
    pub fn probe(&self, p: [f64; 2]) -> Result<[f64; 3], LbmError> {
        Ok(self.probes(&[p])?[0])
    }

    /// [`Self::probe`] at every point of `ps`. On a split grid the rank owning a stencil's first
    /// row interpolates (its ghost row holds the second) and the others add zeros, all points in
    /// one sum over the ranks: exact, so every rank gets one process's bits.
    pub fn probes(&self, ps: &[[f64; 2]]) -> Result<Vec<[f64; 3]>, LbmError> {
        let g = self.config().grid;
        let (nx, ny) = (self.nx(), self.ny());
        let mut out = vec![[0.0f64; 3]; ps.len()];
        for (p, o) in ps.iter().zip(out.iter_mut()) {
            let xi = (p[0] - g.origin[0]) / g.dx;
            let eta = (p[1] - g.origin[1]) / g.dx;
            if !(xi >= 0.0 && eta >= 0.0 && xi <= (nx - 1) as f64 && eta <= (ny - 1) as f64) {
                let hi = g.position((nx - 1) as f64, (ny - 1) as f64);
                return Err(LbmError::ProbeOutside {
                    x: p[0],
                    y: p[1],
                    xmin: g.origin[0],
                    xmax: hi[0],
                    ymin: g.origin[1],
                    ymax: hi[1],
                });
            }
            let stencil = bilinear(xi, eta, nx, ny);
            if !self.owns_row(stencil[0].1) {
                continue;
            }
            for (x, y, w) in stencil {
                let (rho, ux, uy) = if self.is_solid(x, y) { (1.0, 0.0, 0.0) } else { self.node(x, y) };
                o[0] += w * rho as f64;
                o[1] += w * ux as f64;
                o[2] += w * uy as f64;
            }
        }
        Ok(self.sum_over_ranks(out))
    }
}

/// The bilinear stencil at lattice coordinates `(xi, eta)` (node `(i, j)` at `(i, j)`, inside the
/// grid): the four surrounding nodes and their weights, in a fixed order.
pub(crate) fn bilinear(xi: f64, eta: f64, nx: usize, ny: usize) -> [(usize, usize, f64); 4] {
    let x0 = (xi.floor() as usize).min(nx - 2);
    let y0 = (eta.floor() as usize).min(ny - 2);
    let (tx, ty) = (xi - x0 as f64, eta - y0 as f64);
    [
        (x0, y0, (1.0 - tx) * (1.0 - ty)),
        (x0 + 1, y0, tx * (1.0 - ty)),
        (x0, y0 + 1, (1.0 - tx) * ty),
        (x0 + 1, y0 + 1, tx * ty),
    ]
}
