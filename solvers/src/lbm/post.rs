//! Where the post-collision populations `f*_i(x)` of the current time live.
//!
//! The pull kernel keeps `f*_i(x)` at slot `(x, i)` of its array: the canonical form. The AA
//! pattern ([`super::aa`]) updates one array in place and leaves it, step by step in turn, in
//! one of two other forms:
//!
//! - swapped: `f*_i(x)` at `(x, opp i)`, every value at its own node;
//! - streamed: `f*_i(x)` at `(x + c_i, i)`, already at the node it streams to. A value whose
//!   target lies beyond a non-periodic edge goes to the halo, a frame one node wide around the
//!   grid (periodic axes wrap instead).
//!
//! [`Post`] reads `f*_i(x)` in any form, so that boundaries, forces, probes and checks are
//! written once for all of them.

use super::lattice::{CX, CY, OPP, Q};

/// The layout of the post-collision populations in the array (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Form {
    Canonical,
    Swapped,
    Streamed,
}

/// A slot of the array or of the halo.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Loc {
    Grid(usize),
    Halo(usize),
}

/// The grid's size and periodicity: how `(x, y, i)` maps to a location.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    pub nx: usize,
    pub ny: usize,
    pub periodic_x: bool,
    pub periodic_y: bool,
}

impl Frame {
    /// Values in the halo: a column of `ny + 2` nodes beyond the west and east edges and a row of
    /// `nx` nodes beyond the south and north ones, `Q` slots each.
    pub fn halo_len(&self) -> usize {
        Q * (2 * (self.ny + 2) + 2 * self.nx)
    }

    /// Slot `i` of node `(x, y)`, which may lie one node beyond an edge: wrapped on a periodic
    /// axis, in the halo on the others.
    #[inline]
    pub fn slot(&self, x: isize, y: isize, i: usize) -> Loc {
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let x = if self.periodic_x { x.rem_euclid(nx) } else { x };
        let y = if self.periodic_y { y.rem_euclid(ny) } else { y };
        if (0..nx).contains(&x) && (0..ny).contains(&y) {
            return Loc::Grid(((y as usize) * Q + i) * self.nx + x as usize);
        }
        debug_assert!((-1..=nx).contains(&x) && (-1..=ny).contains(&y), "({x}, {y}) beyond the halo");
        let column = self.ny + 2;
        let node = if x < 0 {
            (y + 1) as usize
        } else if x >= nx {
            column + (y + 1) as usize
        } else if y < 0 {
            2 * column + x as usize
        } else {
            2 * column + self.nx + x as usize
        };
        Loc::Halo(node * Q + i)
    }

    /// Where `f*_i(x, y)` lives in `form`.
    #[inline]
    pub fn locate(&self, form: Form, x: usize, y: usize, i: usize) -> Loc {
        match form {
            Form::Canonical => Loc::Grid((y * Q + i) * self.nx + x),
            Form::Swapped => Loc::Grid((y * Q + OPP[i]) * self.nx + x),
            Form::Streamed => self.slot(x as isize + CX[i] as isize, y as isize + CY[i] as isize, i),
        }
    }
}

/// Read access to `f*_i(x)` of the current time, whatever the form.
#[derive(Clone, Copy)]
pub(crate) struct Post<'a> {
    pub f: &'a [f32],
    pub halo: &'a [f32],
    pub form: Form,
    pub frame: Frame,
}

impl<'a> Post<'a> {
    /// The canonical array of the pull kernel (no halo).
    pub fn canonical(f: &'a [f32], frame: Frame) -> Self {
        Post {
            f,
            halo: &[],
            form: Form::Canonical,
            frame,
        }
    }

    /// `f*_i` of node `(x, y)`.
    #[inline]
    pub fn at(&self, x: usize, y: usize, i: usize) -> f32 {
        match self.frame.locate(self.form, x, y, i) {
            Loc::Grid(k) => self.f[k],
            Loc::Halo(k) => self.halo[k],
        }
    }

    /// The nine `f*_i` of node `(x, y)`.
    #[inline]
    pub fn node(&self, x: usize, y: usize) -> [f32; Q] {
        std::array::from_fn(|i| self.at(x, y, i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every node and direction has its own slot in each form: the map is one-to-one, and
    /// the halo holds exactly the values that leave through non-periodic edges.
    #[test]
    fn every_form_is_a_bijection() {
        for (periodic_x, periodic_y) in [(false, false), (true, false), (false, true), (true, true)] {
            let frame = Frame {
                nx: 5,
                ny: 4,
                periodic_x,
                periodic_y,
            };
            for form in [Form::Canonical, Form::Swapped, Form::Streamed] {
                let mut grid = vec![0u32; frame.nx * frame.ny * Q];
                let mut halo = vec![0u32; frame.halo_len()];
                for y in 0..frame.ny {
                    for x in 0..frame.nx {
                        for i in 0..Q {
                            match frame.locate(form, x, y, i) {
                                Loc::Grid(k) => grid[k] += 1,
                                Loc::Halo(k) => halo[k] += 1,
                            }
                        }
                    }
                }
                let label = format!("{form:?}, periodic {periodic_x} {periodic_y}");
                assert!(grid.iter().chain(&halo).all(|&n| n <= 1), "{label}: a slot is shared");
                let in_halo: u32 = halo.iter().sum();
                let leaving = |n: usize, periodic: bool| if periodic { 0 } else { 2 * 3 * n as u32 };
                let corners = if periodic_x || periodic_y { 0 } else { 4 };
                let want = if form == Form::Streamed {
                    leaving(frame.ny, periodic_x) + leaving(frame.nx, periodic_y) - corners
                } else {
                    0
                };
                assert_eq!(in_halo, want, "{label}");
            }
        }
    }
}
