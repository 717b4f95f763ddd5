//! The fused stream-collide kernel (pull scheme, A-B arrays), one grid row at a time.
//!
//! For node `x` the populations after streaming are `f_k(x) = f*_k(x - c_k)`, read from the
//! source array; the kernel collides them and stores `f*_k(x)` in the destination row. Interior
//! rows first run a branch-free loop over `x = 1 .. nx-2` that the compiler vectorises; the nodes
//! on the list of specials (domain edges, nodes with a link into a body, solid nodes) then run the
//! general path, which reads in order: load, boundaries, moments, collide, store.

use super::boundary::{bouzidi, side_value};
use super::collision::{collide_les, Relax};
use super::domain::Sides;
use super::lattice::{CX, CY, Q};

/// A node that needs the general path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Special {
    pub x: u32,
    pub solid: bool,
    /// Range of this node's links in the link list.
    pub link_start: u32,
    pub link_end: u32,
}

/// A lattice link from fluid node `cell` whose streaming source in direction `k` (the node
/// `cell - c_k`) is inside a body; the wall is at fraction `q` of the way from the node towards
/// `cell - c_k`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Link {
    pub cell: u32,
    pub k: u8,
    pub q: f32,
    /// Wall velocity at the crossing, lattice units.
    pub uw: [f32; 2],
    pub body: u16,
}

/// Read-only state shared by all rows of one step.
pub(crate) struct KernelCtx<'a> {
    pub nx: usize,
    pub ny: usize,
    pub relax: Relax,
    pub fx: f32,
    pub fy: f32,
    pub periodic_x: bool,
    pub periodic_y: bool,
    pub sides: &'a Sides,
    pub solid: &'a [bool],
    pub specials: &'a [Special],
    pub row_start: &'a [u32],
    pub links: &'a [Link],
    pub velocity_scale: f32,
}

impl KernelCtx<'_> {
    /// Index of population `i` of node `(x, y)`.
    #[inline(always)]
    pub fn idx(&self, x: usize, y: usize, i: usize) -> usize {
        (y * Q + i) * self.nx + x
    }

    /// `v` wrapped into `0..n` on a periodic axis, `None` if outside a non-periodic one.
    #[inline]
    fn wrap(v: isize, n: usize, periodic: bool) -> Option<usize> {
        if v >= 0 && (v as usize) < n {
            Some(v as usize)
        } else if periodic {
            Some(v.rem_euclid(n as isize) as usize)
        } else {
            None
        }
    }

    /// The node `(x + dx, y + dy)` if it exists (after periodic wrapping).
    #[inline]
    pub fn neighbour(&self, x: usize, y: usize, dx: i32, dy: i32) -> Option<(usize, usize)> {
        let xs = Self::wrap(x as isize + dx as isize, self.nx, self.periodic_x)?;
        let ys = Self::wrap(y as isize + dy as isize, self.ny, self.periodic_y)?;
        Some((xs, ys))
    }

    /// The neighbour if it exists and is fluid.
    #[inline]
    pub fn fluid_neighbour(&self, x: usize, y: usize, dx: i32, dy: i32) -> Option<(usize, usize)> {
        self.neighbour(x, y, dx, dy).filter(|&(xs, ys)| !self.solid[ys * self.nx + xs])
    }

    /// Row `ys` of the source array for direction `i`, shifted so that element `x - 1` is the
    /// value that streams into node `x`, for `x = 1 .. nx-2`.
    #[inline(always)]
    fn shifted<'s>(&self, src: &'s [f32], y: usize, i: usize) -> &'s [f32] {
        let ys = (y as isize - CY[i] as isize).rem_euclid(self.ny as isize) as usize;
        let start = (ys * Q + i) * self.nx + (1 - CX[i]) as usize;
        &src[start..start + self.nx - 2]
    }
}

/// One row of the step: vectorised interior, then the special nodes.
pub(crate) fn row_kernel<const REG: bool, const FORCED: bool, const LES: bool>(c: &KernelCtx, src: &[f32], row: &mut [f32], y: usize) {
    let nx = c.nx;
    let bulk = c.periodic_y || (y > 0 && y + 1 < c.ny);
    if bulk {
        let n = nx - 2;
        let s: [&[f32]; Q] = std::array::from_fn(|i| c.shifted(src, y, i));
        let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = s;
        let (s0, s1, s2, s3, s4, s5, s6, s7, s8) = (
            &s0[..n],
            &s1[..n],
            &s2[..n],
            &s3[..n],
            &s4[..n],
            &s5[..n],
            &s6[..n],
            &s7[..n],
            &s8[..n],
        );
        let (d0, rest) = row.split_at_mut(nx);
        let (d1, rest) = rest.split_at_mut(nx);
        let (d2, rest) = rest.split_at_mut(nx);
        let (d3, rest) = rest.split_at_mut(nx);
        let (d4, rest) = rest.split_at_mut(nx);
        let (d5, rest) = rest.split_at_mut(nx);
        let (d6, rest) = rest.split_at_mut(nx);
        let (d7, d8) = rest.split_at_mut(nx);
        let (d0, d1, d2, d3, d4, d5, d6, d7, d8) = (
            &mut d0[1..=n],
            &mut d1[1..=n],
            &mut d2[1..=n],
            &mut d3[1..=n],
            &mut d4[1..=n],
            &mut d5[1..=n],
            &mut d6[1..=n],
            &mut d7[1..=n],
            &mut d8[1..=n],
        );
        for x in 0..n {
            let mut g = [s0[x], s1[x], s2[x], s3[x], s4[x], s5[x], s6[x], s7[x], s8[x]];
            collide_les::<REG, FORCED, LES>(&mut g, c.relax, c.fx, c.fy);
            d0[x] = g[0];
            d1[x] = g[1];
            d2[x] = g[2];
            d3[x] = g[3];
            d4[x] = g[4];
            d5[x] = g[5];
            d6[x] = g[6];
            d7[x] = g[7];
            d8[x] = g[8];
        }
    }
    let specials = &c.specials[c.row_start[y] as usize..c.row_start[y + 1] as usize];
    for sp in specials {
        general_node::<REG, FORCED, LES>(c, src, row, sp.x as usize, y, sp);
    }
}

/// The same row, every node through the general path (the slow oracle of the tests).
pub(crate) fn row_reference<const REG: bool, const FORCED: bool, const LES: bool>(c: &KernelCtx, src: &[f32], row: &mut [f32], y: usize) {
    let specials = &c.specials[c.row_start[y] as usize..c.row_start[y + 1] as usize];
    for x in 0..c.nx {
        let plain = Special {
            x: x as u32,
            solid: false,
            link_start: 0,
            link_end: 0,
        };
        let sp = specials.iter().find(|s| s.x as usize == x).unwrap_or(&plain);
        general_node::<REG, FORCED, LES>(c, src, row, x, y, sp);
    }
}

/// The general path for one node: load with boundaries, collide, store.
#[inline]
fn general_node<const REG: bool, const FORCED: bool, const LES: bool>(
    c: &KernelCtx,
    src: &[f32],
    row: &mut [f32],
    x: usize,
    y: usize,
    sp: &Special,
) {
    let nx = c.nx;
    if sp.solid {
        for i in 0..Q {
            row[i * nx + x] = 0.0;
        }
        return;
    }
    let mut g = [0.0f32; Q];
    let mut missing = [false; Q];
    for k in 0..Q {
        match c.neighbour(x, y, -CX[k], -CY[k]) {
            Some((xs, ys)) if !c.solid[ys * nx + xs] => g[k] = src[c.idx(xs, ys, k)],
            _ => missing[k] = true,
        }
    }
    for l in &c.links[sp.link_start as usize..sp.link_end as usize] {
        let k = l.k as usize;
        g[k] = bouzidi(c, src, x, y, l);
        missing[k] = false;
    }
    for k in 1..Q {
        if missing[k] {
            g[k] = side_value(c, src, x, y, k);
        }
    }
    collide_les::<REG, FORCED, LES>(&mut g, c.relax, c.fx, c.fy);
    for i in 0..Q {
        row[i * nx + x] = g[i];
    }
}
