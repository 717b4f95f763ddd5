//! One process's share of the grid when a solver is split over ranks: a slab along the
//! longer of y and z (a 2D grid is a box one node thick in z, so it is split along y), with one
//! ghost layer on each side that has a neighbouring rank. Not along x, even where x is the
//! longest axis: x is the kernels' row, and slabs of it leave rows whose length is not a
//! multiple of 8, so the kernel loses its non-temporal stores (the sphere at 160 x 96 x 96 on
//! two ranks: 51 MLUPS split along x, against 70 for one process); the faces between slabs are
//! larger (y z against x z), which the exchange pays once per step. A rank plans and steps its
//! slab and ghosts as a grid of its own; after each step the layers next to its neighbours are
//! sent into their ghosts, so every owned node pulls exactly what it would pull in the whole grid.
//!
//! Sums that must come out bitwise the same on any number of ranks (forces, mass) are taken per
//! index along the split axis first, each index held by one rank, and then added in index order;
//! one process does the same.

use std::ops::Range;

/// The axis a box is split along: the longer of y and z (y of equals), or x if both are one
/// node thick.
pub fn split_axis(n: [usize; 3]) -> usize {
    match (n[1], n[2]) {
        (1, 1) => 0,
        (ny, nz) if nz > ny => 2,
        _ => 1,
    }
}

/// A rank's slab of the global box.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Part {
    pub axis: usize,
    pub n_global: [usize; 3],
    /// Global index (along `axis`, before wrapping) of local index 0.
    pub offset: isize,
    /// Local indices along `axis` this rank owns; the others are ghosts.
    pub own: Range<usize>,
    /// The ranks holding the layer before local index 0 and after the last local index.
    pub below: Option<usize>,
    pub above: Option<usize>,
}

impl Part {
    /// The whole box on one process.
    pub fn whole(n: [usize; 3]) -> Self {
        let axis = split_axis(n);
        Part {
            axis,
            n_global: n,
            offset: 0,
            own: 0..n[axis],
            below: None,
            above: None,
        }
    }

    /// Rank `rank` of `size`: slabs of `n / size` nodes (the first `n % size` ranks one more),
    /// neighbours wrapping around a periodic axis. `Err` names the limit when there are more ranks
    /// than nodes along the axis.
    pub fn of(n: [usize; 3], periodic: [bool; 3], rank: usize, size: usize) -> Result<Self, String> {
        let axis = split_axis(n);
        let len = n[axis];
        if size > len {
            return Err(format!(
                "{size} ranks but only {len} nodes along {}, the axis the box is split along; use at most {len} ranks",
                ["x", "y", "z"][axis]
            ));
        }
        if size <= 1 {
            return Ok(Self::whole(n));
        }
        let start = |r: usize| r * len / size;
        let (lo, hi) = (start(rank), start(rank + 1));
        let below = if rank > 0 {
            Some(rank - 1)
        } else {
            periodic[axis].then_some(size - 1)
        };
        let above = if rank + 1 < size {
            Some(rank + 1)
        } else {
            periodic[axis].then_some(0)
        };
        let ghost_lo = usize::from(below.is_some());
        Ok(Part {
            axis,
            n_global: n,
            offset: lo as isize - ghost_lo as isize,
            own: ghost_lo..ghost_lo + hi - lo,
            below,
            above,
        })
    }

    /// Nodes along each axis of the local box (slab and ghosts).
    pub fn local_n(&self) -> [usize; 3] {
        let mut n = self.n_global;
        n[self.axis] = self.own.end + usize::from(self.above.is_some());
        n
    }

    pub fn is_split(&self) -> bool {
        self.below.is_some() || self.above.is_some()
    }

    /// Global index along the split axis of local index `i`, wrapped.
    pub fn global_index(&self, i: usize) -> usize {
        (self.offset + i as isize).rem_euclid(self.n_global[self.axis] as isize) as usize
    }

    /// Global index along axis `a` of local index `i` (wrapped along the split axis).
    pub fn global_index_along(&self, a: usize, i: usize) -> usize {
        if a == self.axis {
            self.global_index(i)
        } else {
            i
        }
    }

    /// Global node of local node `p`.
    pub fn global(&self, mut p: [usize; 3]) -> [usize; 3] {
        p[self.axis] = self.global_index(p[self.axis]);
        p
    }

    /// Local node of global node `g` if this rank holds it (owned or ghost).
    pub fn local(&self, mut g: [usize; 3]) -> Option<[usize; 3]> {
        let n = self.n_global[self.axis] as isize;
        let local_len = self.local_n()[self.axis];
        // The candidates: `g` itself and its images one period away (ghosts across a wrap).
        let i = [0, -n, n]
            .into_iter()
            .map(|shift| g[self.axis] as isize + shift - self.offset)
            .find(|&i| (0..local_len as isize).contains(&i))?;
        g[self.axis] = i as usize;
        Some(g)
    }

    /// Whether this rank owns local node `p` (not a ghost).
    pub fn owns(&self, p: [usize; 3]) -> bool {
        self.own.contains(&p[self.axis])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_cover_the_axis_once_and_ghosts_wrap_only_when_periodic() {
        let n = [10, 1, 1];
        for periodic in [false, true] {
            let mut owners = vec![0; 10];
            for r in 0..3 {
                let p = Part::of(n, [periodic, false, false], r, 3).unwrap();
                for i in p.own.clone() {
                    owners[p.global_index(i)] += 1;
                    assert_eq!(p.local(p.global([i, 0, 0])), Some([i, 0, 0]));
                }
                let ghosts = p.local_n()[0] - p.own.len();
                // Two ghost layers on a ring or in the middle; one at the ends of a line.
                assert_eq!(ghosts, if periodic || r == 1 { 2 } else { 1 });
            }
            assert_eq!(owners, vec![1; 10]);
        }
        assert_eq!([split_axis([9, 5, 7]), split_axis([9, 7, 7]), split_axis([9, 1, 1])], [2, 1, 0]);
        let last = Part::of(n, [true, false, false], 2, 3).unwrap();
        assert_eq!(
            last.global([last.local_n()[0] - 1, 0, 0]),
            [0, 0, 0],
            "the top ghost wraps to node 0"
        );
        assert!(Part::of(n, [false; 3], 0, 11).unwrap_err().contains("at most 10 ranks"));
    }
}
