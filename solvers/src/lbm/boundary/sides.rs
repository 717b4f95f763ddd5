//! Domain edges. Each rule gives the population `g_k(x)` entering node `x` from outside the
//! domain (see [`Side`] for the equations).

use super::super::collision::moments;
use super::super::domain::{Edge, Side};
use super::super::kernel::KernelCtx;
use super::super::lattice::{CX, CY, OPP, Q, W};
use super::super::post::Post;

/// Value entering node `(x, y)` in direction `k` from outside the domain.
#[inline]
pub(crate) fn side_value(c: &KernelCtx, src: &Post, x: usize, y: usize, k: usize) -> f32 {
    let xs = x as isize - CX[k] as isize;
    let ys = y as isize - CY[k] as isize;
    let out_x = if c.periodic_x {
        None
    } else if xs < 0 {
        Some(Edge::West)
    } else if xs >= c.nx as isize {
        Some(Edge::East)
    } else {
        None
    };
    let out_y = if c.periodic_y {
        None
    } else if ys < 0 {
        Some(Edge::South)
    } else if ys >= c.ny as isize {
        Some(Edge::North)
    } else {
        None
    };
    // At a corner a wall wins over an outlet; between two walls the y edge is taken.
    let edge = match (out_x, out_y) {
        (Some(ex), Some(ey)) => {
            if c.sides.get(ey).is_wall_like() || !c.sides.get(ex).is_wall_like() {
                ey
            } else {
                ex
            }
        }
        (Some(e), None) | (None, Some(e)) => e,
        // Not outside the domain: a solid source without a link cannot happen (every solid
        // source of a fluid node gets a link); bounce back to stay safe.
        (None, None) => return src.at(x, y, OPP[k]),
    };
    match c.sides.get(edge) {
        Side::Periodic => src.at(x, y, OPP[k]),
        Side::Wall => src.at(x, y, OPP[k]),
        Side::Velocity { profile } => {
            let along = match edge {
                Edge::West | Edge::East => y,
                Edge::South | Edge::North => x,
            };
            let u = profile[along];
            let (ux, uy) = (u[0] * c.velocity_scale, u[1] * c.velocity_scale);
            let mut g = [0.0f32; Q];
            for (i, gi) in g.iter_mut().enumerate() {
                *gi = src.at(x, y, i);
            }
            let rho = 1.0 + moments(&g).0;
            let (ux, uy) = match &c.inlet_reference {
                Some(r) => r.velocity(edge, rho, ux, uy),
                None => (ux, uy),
            };
            src.at(x, y, OPP[k]) + 6.0 * W[k] * rho * (CX[k] as f32 * ux + CY[k] as f32 * uy)
        }
        Side::FreeSlip => {
            // Specular reflection: the population arriving with (cx, cy) left the neighbour
            // along the wall with the normal component reversed.
            let (m, nxb, nyb) = match edge {
                Edge::South | Edge::North => {
                    let m = dir(CX[k], -CY[k]);
                    let xb = c.neighbour(x, y, -CX[k], 0).map_or(x, |p| p.0);
                    (m, xb, y)
                }
                Edge::West | Edge::East => {
                    let m = dir(-CX[k], CY[k]);
                    let yb = c.neighbour(x, y, 0, -CY[k]).map_or(y, |p| p.1);
                    (m, x, yb)
                }
            };
            src.at(nxb, nyb, m)
        }
        Side::Outlet => {
            // Zero gradient across the edge, shifted to the equilibrium at rho = 1.
            let xc = xs.clamp(0, c.nx as isize - 1) as usize;
            let yc = ys.clamp(0, c.ny as isize - 1) as usize;
            let xc = if c.periodic_x { xs.rem_euclid(c.nx as isize) as usize } else { xc };
            let yc = if c.periodic_y { ys.rem_euclid(c.ny as isize) as usize } else { yc };
            let (xc, yc) = if c.solid[yc * c.nx + xc] { (x, y) } else { (xc, yc) };
            let mut g = [0.0f32; Q];
            for (i, gi) in g.iter_mut().enumerate() {
                *gi = src.at(xc, yc, i);
            }
            let (drho, jx, jy) = moments(&g);
            let rho = 1.0 + drho;
            let (ux, uy) = (jx / rho, jy / rho);
            let cu = 3.0 * (CX[k] as f32 * ux + CY[k] as f32 * uy);
            let shape = 1.0 + cu + 0.5 * cu * cu - 1.5 * (ux * ux + uy * uy);
            g[k] - drho * W[k] * shape
        }
    }
}

/// Direction index of the lattice velocity `(cx, cy)`.
fn dir(cx: i32, cy: i32) -> usize {
    (0..Q).find(|&i| CX[i] == cx && CY[i] == cy).unwrap_or(0)
}
