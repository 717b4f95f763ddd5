//! The staggered channel grid: uniform and periodic in x and z, stretched towards the walls in y.
//!
//! Cell `(i, j, k)` has its centre at `((i + 1/2) dx, yc[j], (k + 1/2) dz)`. Pressure lives at
//! centres; `u` on the x-faces (`u[i]` at `x = i dx`), `w` on the z-faces, `v` on the y-faces
//! `yf[j]`, `j = 0..=ny`, of which `yf[0] = 0` and `yf[ny] = ly` are the walls.
//!
//! The centres come from the stretching map and the interior faces sit half-way between
//! neighbouring centres (not the other way round): a centred difference of two centre values is
//! then the exact derivative of a quadratic at the face between them, which is what makes laminar
//! Poiseuille flow an exact discrete steady state on any stretched grid.

use super::error::ChannelError;

/// What bounds the channel at `y = ly`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Top {
    /// A no-slip wall (full channel, walls at `y = 0` and `y = ly`).
    Wall,
    /// A free-slip (symmetry) plane: `v = 0`, `du/dy = dw/dy = 0` (the open channel).
    FreeSlip,
}

/// The grid in y and the spacings in x and z.
#[derive(Clone, Debug)]
pub struct Grid {
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub lx: f64,
    pub ly: f64,
    pub lz: f64,
    pub dx: f64,
    pub dz: f64,
    /// Cell centres, `ny` values in `(0, ly)`.
    pub yc: Vec<f64>,
    /// Faces, `ny + 1` values from 0 to `ly`.
    pub yf: Vec<f64>,
    /// Cell widths `yf[j + 1] - yf[j]`.
    pub dyf: Vec<f64>,
    /// Centre-to-centre distances below face `j`: `yc[j] - yc[j - 1]` for `j = 1..ny`;
    /// entries 0 and `ny` (the walls) hold the distance from the wall to the nearest centre.
    pub dyc: Vec<f64>,
    pub top: Top,
    /// Wall-normal stencils of `u` and `w` per cell row (see [`FaceStencil`]).
    pub stencil: Vec<FaceStencil>,
}

/// Value and y-derivative of a centre field (`u`, `w`) on the lower and upper face of cell row
/// `j`, as weights of the rows `j - 1` (`m`), `j` (`0`) and `j + 1` (`p`):
/// `lo = lo[0] s0 + lo[1] sm`, `dlo = dlo[0] s0 + dlo[1] sm + dlo[2] sp`, and likewise `hi`,
/// `dhi` (`hi = hi[0] s0 + hi[1] sp`, `dhi = dhi[0] s0 + dhi[1] sp + dhi[2] sm`). Interior faces
/// average and difference the two centres; a wall face takes the wall value 0 and the quadratic
/// closure; a free-slip top takes the centre value and a zero derivative. A missing row
/// (`m` at the bottom, `p` at the top) has zero weight; `jm`, `jp` name rows that exist.
#[derive(Clone, Copy, Debug, Default)]
pub struct FaceStencil {
    pub jm: usize,
    pub jp: usize,
    pub lo: [f64; 2],
    pub dlo: [f64; 3],
    pub hi: [f64; 2],
    pub dhi: [f64; 3],
}

impl Grid {
    /// A grid with `ny` cells in y clustered towards the walls by `y = tanh` stretching of strength
    /// `stretch` (0 is uniform; 1.5 to 2.5 is usual for DNS). With a free-slip top only the bottom
    /// wall is clustered.
    pub fn new(n: [usize; 3], length: [f64; 3], stretch: f64, top: Top) -> Result<Self, ChannelError> {
        let [nx, ny, nz] = n;
        let [lx, ly, lz] = length;
        if nx == 0 || nz == 0 {
            return Err(ChannelError::config("n", "nx and nz must be at least 1"));
        }
        if ny < 4 {
            return Err(ChannelError::config("n", format!("ny = {ny}: at least 4 cells across the channel")));
        }
        for (name, l) in [("lx", lx), ("ly", ly), ("lz", lz)] {
            if !(l > 0.0 && l.is_finite()) {
                return Err(ChannelError::config("length", format!("{name} = {l} must be positive")));
            }
        }
        if !(0.0..=5.0).contains(&stretch) {
            return Err(ChannelError::config(
                "stretch",
                format!("{stretch}: use 0 (uniform) to 5 (tanh stretching strength)"),
            ));
        }
        let map = |eta: f64| -> f64 {
            if stretch == 0.0 {
                return eta;
            }
            match top {
                Top::Wall => 0.5 * (1.0 + (stretch * (2.0 * eta - 1.0)).tanh() / stretch.tanh()),
                Top::FreeSlip => 1.0 + (stretch * (eta - 1.0)).tanh() / stretch.tanh(),
            }
        };
        let yc: Vec<f64> = (0..ny).map(|j| ly * map((j as f64 + 0.5) / ny as f64)).collect();
        let mut yf = vec![0.0; ny + 1];
        for j in 1..ny {
            yf[j] = 0.5 * (yc[j - 1] + yc[j]);
        }
        yf[ny] = ly;
        let dyf: Vec<f64> = (0..ny).map(|j| yf[j + 1] - yf[j]).collect();
        let mut dyc = vec![0.0; ny + 1];
        dyc[0] = yc[0];
        for j in 1..ny {
            dyc[j] = yc[j] - yc[j - 1];
        }
        dyc[ny] = ly - yc[ny - 1];
        if dyf.iter().any(|&d| !(d > 0.0)) {
            return Err(ChannelError::config("stretch", format!("{stretch} folds the grid over; use less")));
        }
        let mut grid = Grid {
            nx,
            ny,
            nz,
            lx,
            ly,
            lz,
            dx: lx / nx as f64,
            dz: lz / nz as f64,
            yc,
            yf,
            dyf,
            dyc,
            top,
            stencil: vec![],
        };
        grid.stencil = (0..ny).map(|j| grid.face_stencil(j)).collect();
        Ok(grid)
    }

    fn face_stencil(&self, j: usize) -> FaceStencil {
        let ny = self.ny;
        let mut s = FaceStencil {
            jm: j.saturating_sub(1),
            jp: (j + 1).min(ny - 1),
            ..Default::default()
        };
        if j == 0 {
            let [_, b, c] = self.bottom_gradient();
            s.dlo = [b, 0.0, c];
        } else {
            let r = 1.0 / self.dyc[j];
            s.lo = [0.5, 0.5];
            s.dlo = [r, -r, 0.0];
        }
        if j + 1 < ny {
            let r = 1.0 / self.dyc[j + 1];
            s.hi = [0.5, 0.5];
            s.dhi = [-r, r, 0.0];
        } else if self.top == Top::Wall {
            let [_, b, c] = self.top_gradient();
            s.dhi = [-b, 0.0, -c];
        } else {
            s.hi = [1.0, 0.0];
        }
        s
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Index of cell `(i, j, k)` in a centre-row array (`u`, `w`, `p`): x fastest, then y, then z.
    #[inline(always)]
    pub fn at(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.ny + j) * self.nx + i
    }

    /// Index of face `(i, j, k)` in the `v` array, which has `ny + 1` rows per plane.
    #[inline(always)]
    pub fn at_v(&self, i: usize, j: usize, k: usize) -> usize {
        (k * (self.ny + 1) + j) * self.nx + i
    }

    /// Derivative at the wall `y = 0` of the quadratic through the wall value `s_wall` and the
    /// values at the first two centres; `(a, b, c)` with `ds/dy(0) = a s_wall + b s0 + c s1`.
    pub fn bottom_gradient(&self) -> [f64; 3] {
        quadratic_gradient(self.yc[0], self.yc[1])
    }

    /// The same at the top wall, as a derivative in `-y` (into the fluid).
    pub fn top_gradient(&self) -> [f64; 3] {
        let n = self.ny;
        quadratic_gradient(self.ly - self.yc[n - 1], self.ly - self.yc[n - 2])
    }
}

/// One-sided derivative at `0` of the quadratic through `(0, s_w)`, `(d0, s0)`, `(d1, s1)`:
/// `s'(0) = -(d0 + d1)/(d0 d1) s_w + d1/(d0 (d1 - d0)) s0 - d0/(d1 (d1 - d0)) s1`.
fn quadratic_gradient(d0: f64, d1: f64) -> [f64; 3] {
    [-(d0 + d1) / (d0 * d1), d1 / (d0 * (d1 - d0)), -d0 / (d1 * (d1 - d0))]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_are_midway_between_centres_and_tile_the_channel() {
        for top in [Top::Wall, Top::FreeSlip] {
            let g = Grid::new([4, 24, 4], [1.0, 2.0, 1.0], 2.0, top).unwrap();
            let sum: f64 = g.dyf.iter().sum();
            assert!((sum - 2.0).abs() < 1e-14);
            for j in 1..g.ny {
                assert!((g.yf[j] - 0.5 * (g.yc[j - 1] + g.yc[j])).abs() < 1e-15);
            }
            assert!(g.yc[0] > 0.0 && g.yc[g.ny - 1] < 2.0);
        }
        let g = Grid::new([4, 24, 4], [1.0, 2.0, 1.0], 2.0, Top::Wall).unwrap();
        assert!(g.dyf[0] < 0.5 * g.dyf[g.ny / 2], "clustered at the walls");
    }

    #[test]
    fn the_wall_gradient_is_exact_for_quadratics() {
        let g = Grid::new([1, 16, 1], [1.0, 2.0, 1.0], 1.7, Top::Wall).unwrap();
        let s = |y: f64| 3.0 + 2.0 * y - 5.0 * y * y;
        let [a, b, c] = g.bottom_gradient();
        let d = a * s(0.0) + b * s(g.yc[0]) + c * s(g.yc[1]);
        assert!((d - 2.0).abs() < 1e-10, "{d}");
        // Into the fluid from the top wall: -s'(ly).
        let [a, b, c] = g.top_gradient();
        let n = g.ny;
        let d = a * s(2.0) + b * s(g.yc[n - 1]) + c * s(g.yc[n - 2]);
        assert!((d - -(2.0 - 20.0)).abs() < 1e-9, "{d}");
    }
}
