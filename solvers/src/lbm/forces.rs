//! Force on bodies by momentum exchange, Galilean-invariant form of Wen, Zhang, Tu, Wang & Fang,
//! J. Comput. Phys. 266 (2014): for every link from fluid node `x` towards the wall (direction
//! `i`, wall velocity `u_w`)
//!
//! `F += (c_i - u_w) f*_i(x, t) - (c_k - u_w) f_k(x, t+1)`, with `k = opp(i)`,
//!
//! where `f_k(x, t+1)` is the population the wall sends back (the Bouzidi value, before the
//! collision at `t+1`). Summed in link order, serially, per body and row: the per-row sums are
//! then added in row order (over the ranks, when the grid is split: see [`super::part`]), so the
//! result depends neither on the thread count nor on the rank count.
//!
//! The populations are stored shifted, `g = f - w`, and the sum uses `g` directly: the shift's
//! own contribution, `(c_i - u_w) w_i - (c_k - u_w) w_k = 2 w_i c_i` per link, is the force of
//! the uniform reference pressure `rho_0 c_s^2`. Over a closed body it sums to exactly zero; on an
//! open body (a plate running through the domain's edges, the open cavity) it is a large constant
//! that is not part of the aerodynamic force, so leaving it out gives the force relative to the
//! reference pressure for every body, and fewer cancelling terms in the sum.

use super::boundary::bouzidi;
use super::kernel::KernelCtx;
use super::lattice::{CX, CY, OPP};
use super::post::Post;

/// Each link's exchange, in link order, into `partial[(body * rows + row) * 2 + a]`, `row` the
/// global row `global_row(y)` of the link's node.
pub(crate) fn link_forces(c: &KernelCtx, src: &Post, global_row: impl Fn(usize) -> usize, rows: usize, partial: &mut [f64]) {
    partial.iter_mut().for_each(|f| *f = 0.0);
    let nx = c.nx;
    for l in c.links {
        let x = l.cell as usize % nx;
        let y = l.cell as usize / nx;
        let k = l.k as usize;
        let i = OPP[k];
        let out = src.at(x, y, i) as f64;
        let back = bouzidi(c, src, x, y, l) as f64;
        let (ci, ck) = ([CX[i] as f64, CY[i] as f64], [CX[k] as f64, CY[k] as f64]);
        let uw = [l.uw[0] as f64, l.uw[1] as f64];
        let f = &mut partial[(l.body as usize * rows + global_row(y)) * 2..][..2];
        f[0] += (ci[0] - uw[0]) * out - (ck[0] - uw[0]) * back;
        f[1] += (ci[1] - uw[1]) * out - (ck[1] - uw[1]) * back;
    }
}
