//! Interpolated bounce-back on a curved wall, linear variant of Bouzidi, Firdaouss & Lallemand,
//! Phys. Fluids 13, 3452 (2001), with the moving-wall term of Lallemand & Luo, J. Comput. Phys.
//! 184 (2003).
//!
//! Fluid node `x`, direction `i = opp(k)` pointing at the wall, wall at `x + q c_i`:
//!
//! - `q <  1/2`: `f_k(x, t+1) = 2q f*_i(x) + (1 - 2q) f*_i(x - c_i) + 6 w_k rho_w c_k.u_w`
//! - `q >= 1/2`: `f_k(x, t+1) = f*_i(x) / (2q) + (2q - 1)/(2q) f*_k(x) + 6 w_k rho_w c_k.u_w / (2q)`
//!
//! with `rho_w = 1`. The weights of each formula sum to one, so it holds unchanged for the
//! shifted populations `g = f - w`. Where `x - c_i` is not a fluid node (a gap of one cell), the
//! `q < 1/2` branch falls back to simple bounce-back.

use super::super::kernel::{KernelCtx, Link};
use super::super::lattice::{CX, CY, OPP, W};
use super::super::post::Post;

#[inline]
pub(crate) fn bouzidi(c: &KernelCtx, src: &Post, x: usize, y: usize, l: &Link) -> f32 {
    let k = l.k as usize;
    let i = OPP[k];
    let q = l.q;
    let moving = 6.0 * W[k] * (CX[k] as f32 * l.uw[0] + CY[k] as f32 * l.uw[1]);
    let gi = src.at(x, y, i);
    if q < 0.5 {
        match c.fluid_neighbour(x, y, CX[k], CY[k]) {
            Some((xb, yb)) => 2.0 * q * gi + (1.0 - 2.0 * q) * src.at(xb, yb, i) + moving,
            None => gi + moving,
        }
    } else {
        let gk = src.at(x, y, k);
        (gi + (2.0 * q - 1.0) * gk + moving) / (2.0 * q)
    }
}
