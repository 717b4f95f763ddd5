//! The Blasius boundary layer: the similarity solution of the laminar boundary layer on a flat
//! plate at zero pressure gradient (Blasius 1908; Schlichting & Gersten, "Boundary-Layer Theory",
//! 9th ed., 2017, sec. 6.5).
//!
//! `f''' + f f'' / 2 = 0`, `f(0) = f'(0) = 0`, `f'(inf) = 1`, with `eta = y sqrt(U / (nu x))`,
//! `u = U f'(eta)` and `v = (1/2) sqrt(nu U / x) (eta f' - f)`. The wall curvature `f''(0)` is
//! found by shooting (secant on `f'(eta_max) - 1`) with classical fourth-order Runge-Kutta; the
//! table then answers `u`, `v` and the integral thicknesses at any `x`.

/// Edge of the integration in `eta`; `1 - f'` is below 1e-15 there.
const ETA_MAX: f64 = 14.0;
/// RK4 steps per unit `eta`.
const STEPS_PER_ETA: usize = 400;

/// The solved similarity profile on a uniform `eta` grid.
#[derive(Clone, Debug)]
pub struct Blasius {
    /// `(f, f', f'')` at `eta = n h`.
    table: Vec<[f64; 3]>,
    h: f64,
    /// `f''(0)`: the wall shear is `mu U f''(0) sqrt(U / (nu x))`, so `C_f = 2 f''(0) / sqrt(Re_x)`.
    pub wall_curvature: f64,
    /// `delta* sqrt(U / (nu x)) = lim (eta - f)`.
    pub displacement: f64,
    /// `theta sqrt(U / (nu x)) = int f' (1 - f') deta`.
    pub momentum: f64,
}

fn rhs(s: [f64; 3]) -> [f64; 3] {
    [s[1], s[2], -0.5 * s[0] * s[2]]
}

fn integrate(curvature: f64, h: f64, n: usize, mut visit: impl FnMut([f64; 3])) -> [f64; 3] {
    let mut s = [0.0, 0.0, curvature];
    visit(s);
    let add = |s: [f64; 3], k: [f64; 3], a: f64| [s[0] + a * k[0], s[1] + a * k[1], s[2] + a * k[2]];
    for _ in 0..n {
        let k1 = rhs(s);
        let k2 = rhs(add(s, k1, 0.5 * h));
        let k3 = rhs(add(s, k2, 0.5 * h));
        let k4 = rhs(add(s, k3, h));
        s = std::array::from_fn(|c| s[c] + h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]));
        visit(s);
    }
    s
}

impl Blasius {
    /// Solves the Blasius equation (a few milliseconds).
    pub fn solve() -> Self {
        let n = (ETA_MAX as usize) * STEPS_PER_ETA;
        let h = ETA_MAX / n as f64;
        let miss = |c: f64| integrate(c, h, n, |_| {})[1] - 1.0;
        let (mut c0, mut c1) = (0.3, 0.35);
        let (mut m0, mut m1) = (miss(c0), miss(c1));
        for _ in 0..50 {
            if m1 == m0 || m1.abs() < 1e-15 {
                break;
            }
            let c2 = c1 - m1 * (c1 - c0) / (m1 - m0);
            (c0, m0) = (c1, m1);
            c1 = c2;
            m1 = miss(c1);
        }
        let mut table = Vec::with_capacity(n + 1);
        integrate(c1, h, n, |s| table.push(s));
        // Trapezoidal rule for theta with the Euler-Maclaurin end correction (fourth order).
        let g = |s: &[f64; 3]| s[1] * (1.0 - s[1]);
        let dg = |s: &[f64; 3]| s[2] * (1.0 - 2.0 * s[1]);
        let momentum =
            h * (table.iter().map(g).sum::<f64>() - 0.5 * (g(&table[0]) + g(&table[n]))) - h * h / 12.0 * (dg(&table[n]) - dg(&table[0]));
        let displacement = ETA_MAX - table[n][0];
        Blasius {
            table,
            h,
            wall_curvature: c1,
            displacement,
            momentum,
        }
    }

    /// `(f, f', f'')` at `eta >= 0`: cubic Hermite between table points (using `f'` and `f''`
    /// as the derivatives of `f` and `f'`), the free-stream asymptote beyond the table.
    pub fn at(&self, eta: f64) -> [f64; 3] {
        let n = self.table.len() - 1;
        let x = (eta.max(0.0) / self.h).min(n as f64);
        let i = (x.floor() as usize).min(n - 1);
        let t = x - i as f64;
        if eta >= ETA_MAX {
            return [eta - self.displacement, 1.0, 0.0];
        }
        let (a, b) = (self.table[i], self.table[i + 1]);
        let third = -0.5 * a[0] * a[2];
        let third_b = -0.5 * b[0] * b[2];
        let hermite = |p0: f64, d0: f64, p1: f64, d1: f64| {
            let (t2, t3) = (t * t, t * t * t);
            (2.0 * t3 - 3.0 * t2 + 1.0) * p0 + (t3 - 2.0 * t2 + t) * self.h * d0 + (-2.0 * t3 + 3.0 * t2) * p1 + (t3 - t2) * self.h * d1
        };
        [
            hermite(a[0], a[1], b[0], b[1]),
            hermite(a[1], a[2], b[1], b[2]),
            hermite(a[2], third, b[2], third_b),
        ]
    }

    /// `(u, v)` at height `y` and distance `x > 0` from the leading edge, free stream `u_inf`.
    pub fn velocity(&self, x: f64, y: f64, u_inf: f64, nu: f64) -> (f64, f64) {
        let scale = (nu * x / u_inf).sqrt();
        let [f, fp, _] = self.at(y / scale);
        let eta = y / scale;
        (u_inf * fp, 0.5 * (nu * u_inf / x).sqrt() * (eta * fp - f))
    }

    /// The distance from the leading edge where the displacement thickness is `delta_star`.
    pub fn x_of_displacement(&self, delta_star: f64, u_inf: f64, nu: f64) -> f64 {
        let r = delta_star / self.displacement;
        r * r * u_inf / nu
    }

    /// Skin-friction coefficient `C_f = 2 tau_w / (rho U^2)` at `Re_x = U x / nu`.
    pub fn c_f(&self, re_x: f64) -> f64 {
        2.0 * self.wall_curvature / re_x.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_classical_constants() {
        // f''(0) = 0.332057336, delta* = 1.7207876573, theta = 0.6641146 (Boyd 2008, SIAM Rev.).
        let b = Blasius::solve();
        assert!((b.wall_curvature - 0.332_057_336).abs() < 1e-8, "{}", b.wall_curvature);
        assert!((b.displacement - 1.720_787_657).abs() < 1e-8, "{}", b.displacement);
        // theta = 2 f''(0) by the momentum integral: an independent check of the quadrature.
        assert!((b.momentum - 2.0 * b.wall_curvature).abs() < 1e-7, "{}", b.momentum);
    }

    #[test]
    fn interpolation_matches_the_table_and_the_free_stream_limit() {
        let b = Blasius::solve();
        let [f, fp, fpp] = b.at(0.0);
        assert_eq!((f, fp), (0.0, 0.0));
        assert!((fpp - b.wall_curvature).abs() < 1e-15);
        // Between table points: the ODE residual of the interpolant stays small.
        let eta = 2.345_678;
        let e = 1e-4;
        let (lo, mid, hi) = (b.at(eta - e), b.at(eta), b.at(eta + e));
        let fppp = (hi[2] - lo[2]) / (2.0 * e);
        assert!((fppp + 0.5 * mid[0] * mid[2]).abs() < 1e-6);
        assert!((b.at(20.0)[1] - 1.0).abs() < 1e-15);
        // v tends to 0.8604 sqrt(nu U / x) above the layer.
        let (_, v) = b.velocity(1.0, 30.0, 1.0, 1.0);
        assert!((v - 0.5 * b.displacement).abs() < 1e-12);
    }
}
