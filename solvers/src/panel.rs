//! Two-dimensional inviscid, incompressible flow about a closed aerofoil by the linear-strength
//! vortex panel method (Katz & Plotkin, "Low-Speed Aerodynamics", 2nd ed., 2001, sec. 11.4.2).
//!
//! The outline is `N` straight panels between `N + 1` nodes, ordered clockwise from the trailing
//! edge: along the lower surface to the leading edge and back along the upper surface, the last
//! node equal to the first. The vortex density varies linearly along each panel and is
//! continuous at the nodes (`N + 1` unknowns `gamma_j`). No flow through the panels at their
//! midpoints gives `N` equations and the Kutta condition `gamma_0 + gamma_N = 0` (equal speeds
//! leaving the trailing edge on both sides) the last one. The velocity inside the body is zero,
//! so the speed just outside the surface at node `j` is `|gamma_j|`.
//!
//! Units: free stream of speed 1 at angle of attack `alpha` (radians, nose up, flow along +x at
//! `alpha = 0`); lengths as given.

use faer::linalg::solvers::Solve;
use faer::Mat;

/// An outline the method cannot use.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PanelError {
    #[error("an outline needs at least 3 panels and a last node equal to the first (got {nodes} nodes)")]
    NotClosed { nodes: usize },
    #[error("panel {panel} has zero length")]
    ZeroLength { panel: usize },
    #[error("the panel equations are singular (coincident or crossing panels)")]
    Singular,
}

/// The solution: vortex density at the nodes and the lift coefficient.
#[derive(Clone, Debug)]
pub struct PanelFlow {
    pub nodes: Vec<[f64; 2]>,
    /// Vortex density at each node (counter-clockwise positive); the surface speed is its size.
    pub gamma: Vec<f64>,
    /// `C_L = 2 Gamma / c` with `Gamma` the clockwise circulation and `c` the distance from the
    /// trailing edge to the farthest node.
    pub c_l: f64,
}

/// Velocity at `p` induced by a panel from `a` to `b` of unit vortex density at `a` (first) and at
/// `b` (second), each linear along the panel and zero at the other end (Katz & Plotkin eq. 10.72
/// and 10.73). On the panel itself the limit from its left (the fluid side of a clockwise
/// outline) is taken.
fn influence(a: [f64; 2], b: [f64; 2], p: [f64; 2], on_panel: bool) -> [[f64; 2]; 2] {
    let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
    let l = (tx * tx + ty * ty).sqrt();
    let (tx, ty) = (tx / l, ty / l);
    // Panel frame: x along the panel from `a`, y to its left.
    let (dx, dy) = (p[0] - a[0], p[1] - a[1]);
    let x = dx * tx + dy * ty;
    let y = -dx * ty + dy * tx;
    let log = ((x * x + y * y) / ((x - l) * (x - l) + y * y)).sqrt().ln();
    let dtheta = if on_panel {
        std::f64::consts::PI
    } else {
        y.atan2(x - l) - y.atan2(x)
    };
    let two_pi = 2.0 * std::f64::consts::PI;
    // Density gamma_a (1 - s/l) + gamma_b s/l: the parts multiplying gamma_a and gamma_b.
    let u_lin = (x * dtheta - y * log) / l;
    let v_lin = (x * log - l + y * dtheta) / l;
    let ua = -(dtheta - u_lin) / two_pi;
    let ub = -u_lin / two_pi;
    let va = (log - v_lin) / two_pi;
    let vb = v_lin / two_pi;
    let global = |u: f64, v: f64| [u * tx - v * ty, u * ty + v * tx];
    [global(ua, va), global(ub, vb)]
}

impl PanelFlow {
    /// Solves the flow about the closed clockwise outline `nodes` at angle of attack `alpha`.
    pub fn solve(nodes: &[[f64; 2]], alpha: f64) -> Result<PanelFlow, PanelError> {
        let n = nodes.len().saturating_sub(1);
        if n < 3 || nodes[0] != nodes[n] {
            return Err(PanelError::NotClosed { nodes: nodes.len() });
        }
        for k in 0..n {
            if nodes[k] == nodes[k + 1] {
                return Err(PanelError::ZeroLength { panel: k });
            }
        }
        let free = [alpha.cos(), alpha.sin()];
        let mut a = Mat::<f64>::zeros(n + 1, n + 1);
        let mut rhs = Mat::<f64>::zeros(n + 1, 1);
        for i in 0..n {
            let (p, q) = (nodes[i], nodes[i + 1]);
            let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
            let l = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
            // Outward normal: to the left of the clockwise direction of travel.
            let normal = [-(q[1] - p[1]) / l, (q[0] - p[0]) / l];
            for j in 0..n {
                let [va, vb] = influence(nodes[j], nodes[j + 1], mid, i == j);
                a[(i, j)] += va[0] * normal[0] + va[1] * normal[1];
                a[(i, j + 1)] += vb[0] * normal[0] + vb[1] * normal[1];
            }
            rhs[(i, 0)] = -(free[0] * normal[0] + free[1] * normal[1]);
        }
        a[(n, 0)] = 1.0;
        a[(n, n)] = 1.0;
        let x = a.partial_piv_lu().solve(&rhs);
        let gamma: Vec<f64> = (0..=n).map(|j| x[(j, 0)]).collect();
        if gamma.iter().any(|g| !g.is_finite()) {
            return Err(PanelError::Singular);
        }
        // Clockwise circulation: minus the counter-clockwise integral of the density.
        let circulation: f64 = (0..n)
            .map(|k| {
                let l = ((nodes[k + 1][0] - nodes[k][0]).powi(2) + (nodes[k + 1][1] - nodes[k][1]).powi(2)).sqrt();
                -0.5 * (gamma[k] + gamma[k + 1]) * l
            })
            .sum();
        let te = nodes[0];
        let chord = nodes
            .iter()
            .map(|p| ((p[0] - te[0]).powi(2) + (p[1] - te[1]).powi(2)).sqrt())
            .fold(0.0, f64::max);
        Ok(PanelFlow {
            nodes: nodes.to_vec(),
            gamma,
            c_l: 2.0 * circulation / chord,
        })
    }

    /// Surface speed (units of the free stream) at each node.
    pub fn speed(&self) -> Vec<f64> {
        self.gamma.iter().map(|g| g.abs()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A circle of radius 1 through (1, 0), clockwise from there, `n` panels.
    fn circle(n: usize) -> Vec<[f64; 2]> {
        let mut nodes: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let th = -2.0 * PI * k as f64 / n as f64;
                [th.cos(), th.sin()]
            })
            .collect();
        nodes.push(nodes[0]);
        nodes
    }

    /// The symmetric Joukowski aerofoil `z = zeta + 1/zeta` of the circle of radius `1 + eps`
    /// centred at `-eps`, `n` panels clockwise from the trailing edge (z = 2), and the exact
    /// surface speed at each node at angle of attack `alpha` (Kutta condition at the edge).
    fn joukowski(eps: f64, n: usize, alpha: f64) -> (Vec<[f64; 2]>, Vec<f64>) {
        let r = 1.0 + eps;
        let mut nodes = vec![];
        let mut speed = vec![];
        for k in 0..=n {
            // Clustered at the edges, where the curvature is largest.
            let th = -PI * (1.0 - (PI * k as f64 / n as f64).cos());
            let (zr, zi) = (-eps + r * th.cos(), r * th.sin());
            let m2 = zr * zr + zi * zi;
            nodes.push([zr + zr / m2, zi - zi / m2]);
            // Circle flow: |W| = 2 |sin(th - alpha) + sin(alpha)| on the circle; divide by |dz/dzeta|.
            let w = 2.0 * ((th - alpha).sin() + alpha.sin()).abs();
            let (ar, ai) = (zr * zr - zi * zi, 2.0 * zr * zi);
            let (dr, di) = (1.0 - ar / (m2 * m2), ai / (m2 * m2));
            speed.push(w / (dr * dr + di * di).sqrt());
        }
        nodes[n] = nodes[0];
        (nodes, speed)
    }

    #[test]
    fn circle_speed_converges_at_second_order() {
        let error = |n: usize| {
            let f = PanelFlow::solve(&circle(n), 0.0).unwrap();
            (0..n)
                .map(|k| {
                    let th = 2.0 * PI * k as f64 / n as f64;
                    (f.speed()[k] - 2.0 * th.sin().abs()).abs()
                })
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (error(64), error(128));
        let order = (e1 / e2).log2();
        assert!(e2 < 2e-3 && order > 1.8, "errors {e1:.2e} {e2:.2e}, order {order:.2}");
    }

    #[test]
    fn joukowski_aerofoil_speed_and_lift_match_the_conformal_map() {
        let alpha = 5f64.to_radians();
        let eps = 0.1;
        let check = |n: usize| {
            let (nodes, exact) = joukowski(eps, n, alpha);
            let f = PanelFlow::solve(&nodes, alpha).unwrap();
            // Away from the edge, where the exact speed is finite but the map is singular.
            let err = (n / 20..n - n / 20).map(|k| (f.speed()[k] - exact[k]).abs()).fold(0.0, f64::max);
            (err, f.c_l)
        };
        let (e1, _) = check(100);
        let (e2, c_l) = check(200);
        // C_L = 8 pi (1 + eps) sin(alpha) / c, with the chord from the edge (z = 2) to the nose.
        let nose = 1.0 + 2.0 * eps;
        let exact_c_l = 8.0 * PI * (1.0 + eps) * alpha.sin() / (2.0 + nose + 1.0 / nose);
        assert!((c_l - exact_c_l).abs() < 5e-3 * exact_c_l, "C_L {c_l} against {exact_c_l}");
        assert!(e2 < 1e-2 && e1 / e2 > 3.0, "speed errors {e1:.2e} {e2:.2e}");
    }

    #[test]
    fn an_open_outline_is_refused() {
        let mut c = circle(8);
        c[8] = [0.99, 0.0];
        assert!(matches!(PanelFlow::solve(&c, 0.0), Err(PanelError::NotClosed { .. })));
    }
}
