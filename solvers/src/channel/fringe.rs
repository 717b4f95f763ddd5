//! The fringe region (Nordstrom, Nordin & Henningson, SIAM J. Sci. Comput. 20, 1999): a volume
//! force `lambda(x) (u_target - u)` added to the momentum equations near the end of the periodic
//! box pulls the outflow back to a prescribed inflow, so the periodic solver computes a spatially
//! developing flow (a boundary layer growing in x) upstream of the fringe.
//!
//! `lambda(x) = lambda_max [S((x - x_start) / rise) - S((x - x_end) / fall + 1)]` with the smooth
//! step `S(a) = 0` for `a <= 0`, `1 / (1 + exp(1/(a - 1) + 1/a))` for `0 < a < 1` and `1` for
//! `a >= 1`. The target is a [`BaseFlow`] `(u(x, y), v(x, y), 0)`: an edge velocity `Ue(x)` times
//! a boundary-layer shape, blended inside the fringe back to the inflow, with the `v` of discrete
//! continuity, so the target is itself divergence-free and its `v` at the top is what the top
//! boundary must carry.

use super::error::ChannelError;
use super::grid::Grid;

/// Where the fringe lies and how hard it pulls.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FringeSpec {
    /// Start and end of the region in x (`0 <= x_start < x_end <= lx`).
    pub x_start: f64,
    pub x_end: f64,
    /// Widths over which `lambda` rises from 0 and falls back (their sum at most `x_end - x_start`).
    pub rise: f64,
    pub fall: f64,
    /// Peak strength (an inverse time).
    pub lambda_max: f64,
}

/// The forcing ready to apply: `lambda` at the `u` and at the centre x-positions, and the target.
#[derive(Clone, Debug)]
pub struct Fringe {
    spec: FringeSpec,
    lambda_u: Vec<f64>,
    lambda_c: Vec<f64>,
    base: BaseFlow,
}

/// A spanwise-uniform, discretely divergence-free field on the grid: `u` at the x-faces (`ny` rows
/// of `nx`) and `v` at the y-faces (`ny + 1` rows of `nx`, the walls included).
#[derive(Clone, Debug, PartialEq)]
pub struct BaseFlow {
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    nx: usize,
    ny: usize,
}

impl BaseFlow {
    /// `u = ue(x) shape(x, y)` with `shape` the layer's `u / Ue` (1 above it). Upstream of the
    /// fringe both are taken at `x`; inside it each is `(1 - b) f(x_start) +
    /// b f(0)` with `b = S((x - x_start) / (x_end - x_start))`, which returns to the inflow at
    /// `x_end` (and `x_end` must then be `lx`, the inflow's periodic image). `v` follows from
    /// continuity, cell by cell up from a solid bottom wall.
    pub fn blended(grid: &Grid, spec: &FringeSpec, ue: impl Fn(f64) -> f64, shape: impl Fn(f64, f64) -> f64) -> Self {
        let (nx, ny) = (grid.nx, grid.ny);
        let blend = |x: f64, f: &dyn Fn(f64) -> f64| {
            if x < spec.x_start {
                f(x)
            } else {
                let b = smooth_step((x - spec.x_start) / (spec.x_end - spec.x_start));
                (1.0 - b) * f(spec.x_start) + b * f(0.0)
            }
        };
        let mut u = vec![0.0; nx * ny];
        for i in 0..nx {
            let x = i as f64 * grid.dx;
            let edge = blend(x, &ue);
            for j in 0..ny {
                let y = grid.yc[j];
                u[j * nx + i] = edge * blend(x, &|x| shape(x, y));
            }
        }
        Self::with_continuity(grid, u)
    }

    /// `u` with the `v` of discrete continuity, up from a solid bottom wall.
    fn with_continuity(grid: &Grid, u: Vec<f64>) -> Self {
        let (nx, ny) = (grid.nx, grid.ny);
        let mut v = vec![0.0; nx * (ny + 1)];
        for j in 0..ny {
            for i in 0..nx {
                let dudx = (u[j * nx + (i + 1) % nx] - u[j * nx + i]) / grid.dx;
                v[(j + 1) * nx + i] = v[j * nx + i] - grid.dyf[j] * dudx;
            }
        }
        BaseFlow { u, v, nx, ny }
    }

    /// `u` at `(i, j)`.
    pub fn u_at(&self, i: usize, j: usize) -> f64 {
        self.u[j * self.nx + i]
    }

    /// `u = U(x, y) shape(x, y)`: `U` is the potential flow in the periodic strip
    /// `U = U0 + sum_m cosh(k_m y) (a_m cos k_m x + b_m sin k_m x)`, `k_m = 2 pi m / lx`, whose wall
    /// velocity is the least-squares fit of `ue(x)` over the region upstream of the fringe with
    /// `modes` modes (inside the fringe it is free: the smoothest return the fit gives), and
    /// `shape` is the layer's `u / Ue` (1 above it), blended in the fringe as in [`Self::blended`].
    /// Irrotational outside the layer, so the outer flow leaves the fringe uniform in `y`; the
    /// largest misfit of the wall velocity upstream of the fringe comes with it.
    pub fn potential(
        grid: &Grid,
        spec: &FringeSpec,
        ue: impl Fn(f64) -> f64,
        modes: usize,
        shape: impl Fn(f64, f64) -> f64,
    ) -> (Self, f64) {
        let (nx, ny) = (grid.nx, grid.ny);
        let k = |m: usize| 2.0 * std::f64::consts::PI * m as f64 / grid.lx;
        let basis = |c: usize, x: f64| match c {
            0 => 1.0,
            c if c % 2 == 1 => (k(c.div_ceil(2)) * x).cos(),
            c => (k(c / 2) * x).sin(),
        };
        let n = 2 * modes + 1;
        let fit: Vec<f64> = (0..nx).map(|i| i as f64 * grid.dx).filter(|&x| x < spec.x_start).collect();
        let mut a = faer::Mat::<f64>::zeros(n, n);
        let mut rhs = faer::Mat::<f64>::zeros(n, 1);
        for &x in &fit {
            let target = ue(x);
            for p in 0..n {
                rhs[(p, 0)] += basis(p, x) * target;
                for q in 0..n {
                    a[(p, q)] += basis(p, x) * basis(q, x);
                }
            }
        }
        // A little Tikhonov weight against oscillating fringe returns, heavier for the modes
        // whose cosh(k ly) amplifies them most at the top.
        let scale = fit.len() as f64 * 1e-6;
        for p in 1..n {
            a[(p, p)] += scale * (k(p.div_ceil(2)) * grid.ly).cosh().powi(2);
        }
        let c = faer::linalg::solvers::Solve::solve(&a.partial_piv_lu(), &rhs);
        let coef: Vec<f64> = (0..n).map(|p| c[(p, 0)]).collect();
        let wall = |x: f64| (0..n).map(|p| coef[p] * basis(p, x)).sum::<f64>();
        let misfit = fit.iter().map(|&x| (wall(x) - ue(x)).abs()).fold(0.0, f64::max);
        let blend_shape = |x: f64, y: f64| {
            if x < spec.x_start {
                shape(x, y)
            } else {
                let b = smooth_step((x - spec.x_start) / (spec.x_end - spec.x_start));
                (1.0 - b) * shape(spec.x_start, y) + b * shape(0.0, y)
            }
        };
        let mut u = vec![0.0; nx * ny];
        for j in 0..ny {
            let y = grid.yc[j];
            for i in 0..nx {
                let x = i as f64 * grid.dx;
                let outer: f64 = (0..n).map(|p| coef[p] * basis(p, x) * (k(p.div_ceil(2)) * y).cosh()).sum();
                u[j * nx + i] = outer * blend_shape(x, y);
            }
        }
        (Self::with_continuity(grid, u), misfit)
    }

    /// `v` through the top, `nx` values: the outflow (positive) a boundary layer's displacement
    /// pushes out and the inflow that returns it in the fringe; they sum to zero.
    pub fn top(&self) -> &[f64] {
        &self.v[self.ny * self.nx..]
    }
}

/// The smooth step `S` of Nordstrom et al.
pub fn smooth_step(a: f64) -> f64 {
    if a <= 0.0 {
        0.0
    } else if a >= 1.0 {
        1.0
    } else {
        1.0 / (1.0 + (1.0 / (a - 1.0) + 1.0 / a).exp())
    }
}

impl FringeSpec {
    /// `lambda(x)`.
    pub fn lambda(&self, x: f64) -> f64 {
        self.lambda_max * (smooth_step((x - self.x_start) / self.rise) - smooth_step((x - self.x_end) / self.fall + 1.0))
    }
}

impl Fringe {
    /// The fringe of `spec` on `grid`, pulling towards `base`.
    pub fn new(grid: &Grid, spec: FringeSpec, base: BaseFlow) -> Result<Self, ChannelError> {
        let fits = 0.0 <= spec.x_start && spec.x_start < spec.x_end && spec.x_end <= grid.lx;
        if !fits {
            return Err(ChannelError::config(
                "fringe",
                format!("[{}, {}] must be an interval inside [0, {}]", spec.x_start, spec.x_end, grid.lx),
            ));
        }
        let ramps = spec.rise > 0.0 && spec.fall > 0.0 && spec.rise + spec.fall <= spec.x_end - spec.x_start;
        if !ramps {
            return Err(ChannelError::config(
                "fringe",
                format!(
                    "rise {} and fall {} must be positive and fit in the fringe's {}",
                    spec.rise,
                    spec.fall,
                    spec.x_end - spec.x_start
                ),
            ));
        }
        if !(spec.lambda_max > 0.0 && spec.lambda_max.is_finite()) {
            return Err(ChannelError::config(
                "fringe",
                format!("lambda_max = {} must be positive", spec.lambda_max),
            ));
        }
        if (base.nx, base.ny) != (grid.nx, grid.ny) {
            let (got, want) = (base.u.len(), grid.nx * grid.ny);
            return Err(ChannelError::Size {
                what: "fringe base flow",
                got,
                want,
            });
        }
        Ok(Fringe {
            lambda_u: (0..grid.nx).map(|i| spec.lambda(i as f64 * grid.dx)).collect(),
            lambda_c: (0..grid.nx).map(|i| spec.lambda((i as f64 + 0.5) * grid.dx)).collect(),
            spec,
            base,
        })
    }

    pub fn spec(&self) -> &FringeSpec {
        &self.spec
    }

    /// `lambda` at the `u` positions `x = i dx`.
    pub fn lambda_u(&self) -> &[f64] {
        &self.lambda_u
    }

    pub fn base(&self) -> &BaseFlow {
        &self.base
    }

    /// Adds the forcing of `u` and `w` on cell row `j` to their right-hand sides.
    pub fn force_uw_row(&self, j: usize, u: &[f64], w: &[f64], ru: &mut [f64], rw: &mut [f64]) {
        let n = ru.len();
        let target = &self.base.u[j * n..][..n];
        for i in 0..n {
            ru[i] += self.lambda_u[i] * (target[i] - u[i]);
            rw[i] -= self.lambda_c[i] * w[i];
        }
    }

    /// Adds the forcing of `v` on face row `j` to its right-hand side.
    pub fn force_v_row(&self, j: usize, v: &[f64], rv: &mut [f64]) {
        let n = rv.len();
        let target = &self.base.v[j * n..][..n];
        for i in 0..n {
            rv[i] += self.lambda_c[i] * (target[i] - v[i]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::channel::Top;

    #[test]
    fn lambda_rises_holds_and_falls_smoothly() {
        let s = FringeSpec {
            x_start: 6.0,
            x_end: 10.0,
            rise: 1.5,
            fall: 1.0,
            lambda_max: 2.0,
        };
        assert_eq!(s.lambda(5.9), 0.0);
        assert!((s.lambda(6.75) - 1.0).abs() < 1e-12, "half-way up the rise");
        assert_eq!(s.lambda(8.0), 2.0);
        assert!((s.lambda(9.5) - 1.0).abs() < 1e-12, "half-way down the fall");
        assert_eq!(s.lambda(10.0), 0.0);
        let g = Grid::new([20, 8, 1], [10.0, 1.0, 1.0], 0.0, Top::FreeSlip).unwrap();
        let base = BaseFlow::blended(&g, &s, |_| 1.0, |_, _| 1.0);
        let bad = Fringe::new(&g, FringeSpec { rise: 3.0, fall: 2.0, ..s }, base.clone());
        assert!(matches!(bad, Err(ChannelError::Config { field: "fringe", .. })));
        let other = Grid::new([20, 9, 1], [10.0, 1.0, 1.0], 0.0, Top::FreeSlip).unwrap();
        let short = Fringe::new(&other, s, base);
        assert!(matches!(short, Err(ChannelError::Size { .. })));
    }

    #[test]
    fn the_base_flow_is_divergence_free_and_its_top_flux_sums_to_zero() {
        let g = Grid::new([40, 16, 1], [20.0, 6.0, 1.0], 1.5, Top::FreeSlip).unwrap();
        let s = FringeSpec {
            x_start: 14.0,
            x_end: 20.0,
            rise: 2.0,
            fall: 1.0,
            lambda_max: 1.0,
        };
        // A layer thickening like sqrt(x) under a free stream that speeds up.
        let ue = |x: f64| 1.0 + 0.01 * x;
        let shape = |x: f64, y: f64| (y / (1.0 + 0.1 * x).sqrt()).tanh();
        let b = BaseFlow::blended(&g, &s, ue, shape);
        let div = max_divergence(&b, &g);
        assert!(div < 1e-11, "{div}");
        let net: f64 = b.top().iter().sum();
        let out: f64 = b.top().iter().filter(|&&v| v > 0.0).sum();
        assert!(out > 0.0 && net.abs() < 1e-13 * out, "{net} of {out}");
    }

    /// The largest discrete divergence over the cells.
    fn max_divergence(b: &BaseFlow, g: &Grid) -> f64 {
        let mut m = 0.0f64;
        for j in 0..g.ny {
            for i in 0..g.nx {
                let dudx = (b.u[j * g.nx + (i + 1) % g.nx] - b.u[j * g.nx + i]) / g.dx;
                let dvdy = (b.v[(j + 1) * g.nx + i] - b.v[j * g.nx + i]) / g.dyf[j];
                m = m.max((dudx + dvdy).abs());
            }
        }
        m
    }

    /// The largest spanwise vorticity `dv/dx - du/dy` at the interior cell corners of rows
    /// `j0..ny` (the staggered centred differences).
    fn max_vorticity(b: &BaseFlow, g: &Grid, j0: usize) -> f64 {
        let mut m = 0.0f64;
        for j in j0.max(1)..g.ny {
            for i in 0..g.nx {
                let im = (i + g.nx - 1) % g.nx;
                let dvdx = (b.v[j * g.nx + i] - b.v[j * g.nx + im]) / g.dx;
                let dudy = (b.u[j * g.nx + i] - b.u[(j - 1) * g.nx + i]) / g.dyc[j];
                m = m.max((dvdx - dudy).abs());
            }
        }
        m
    }

    #[test]
    fn the_potential_base_flow_fits_the_wall_velocity_and_carries_no_vorticity() {
        let g = Grid::new([128, 32, 1], [20.0, 2.0, 1.0], 0.0, Top::FreeSlip).unwrap();
        let s = FringeSpec {
            x_start: 14.0,
            x_end: 20.0,
            rise: 2.0,
            fall: 2.0,
            lambda_max: 1.0,
        };
        // A free stream that slows down over the plate and must come back in the fringe.
        let ue = |x: f64| 1.1 - 0.01 * x;
        let (b, misfit) = BaseFlow::potential(&g, &s, ue, 8, |_, _| 1.0);
        assert!(misfit < 1e-3, "{misfit}");
        let div = max_divergence(&b, &g);
        assert!(div < 1e-11, "{div}");
        let net: f64 = b.top().iter().sum();
        assert!(net.abs() < 1e-11, "{net}");
        // The same wall velocity as an edge velocity uniform in y carries vorticity wherever
        // it changes along x; the potential flow carries almost none.
        let rotational = BaseFlow::blended(&g, &s, ue, |_, _| 1.0);
        let (w_pot, w_rot) = (max_vorticity(&b, &g, 0), max_vorticity(&rotational, &g, 0));
        assert!(w_pot < 0.01 * w_rot, "{w_pot} against {w_rot}");
    }
}
