//! The AA pattern (Bailey, Myre, Walsh, Lilja & Bell, ICPP 2009): stream and collide in place
//! in one array, two kinds of step in turn, so that every node reads and writes the same nine
//! locations ([`super::post`] names the forms):
//!
//! - odd kind, swapped to streamed: node `x` reads `f_i(x) = f*_i(x - c_i)` at `(x - c_i, opp i)`,
//!   collides, and writes `f*_i(x)` to `(x + c_i, i)`;
//! - even kind, streamed to swapped: node `x` reads `f_i(x)` at `(x, i)`, collides, and writes
//!   `f*_i(x)` to `(x, opp i)`.
//!
//! In either kind the slots a node writes are the slots it reads (odd kind: node `x` writes
//! `(x + c_i, i)`, which is its read slot `(x - c_j, opp j)` of direction `j = opp i`), and no
//! slot belongs to two nodes, so rows update in parallel in place. Each line a node writes was
//! read just before: a node costs 72 bytes of memory traffic with neither write-allocate reads
//! nor non-temporal stores, and the grid needs one array instead of the A-B pair.
//!
//! Nodes on the list of specials (edges, links, solids) gather their arriving populations before
//! the sweep, with the pull kernel's boundary code reading the previous post-collision values
//! through [`Post`] ([`gather_specials`]); the sweep collides them and writes them to their
//! slots, beyond a non-periodic edge into the halo. The results are bitwise those of the pull
//! kernel: every node runs the same operations on the same values.

use std::marker::PhantomData;

use rayon::prelude::*;

use super::collision::{collide_les, Collision, OP_BGK, OP_REG, OP_RR};
use super::kernel::{avx512_available, collide_run, gather, KernelCtx};
use super::lattice::{CX, CY, OPP, Q};
use super::post::{Form, Loc, Post};
use super::sponge::{apply_span, SpongePlan};

/// How the fast D2Q9 kernel streams. Both give bitwise the same populations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Propagation {
    /// A-B arrays: each step pulls from one array into the other ([`super::kernel`]).
    Pull,
    /// In place in one array (this module); a grid split over ranks pulls.
    Aa,
}

/// The array and halo of one in-place sweep, shared by the threads that update its rows.
pub(crate) struct Cells<'a> {
    f: *mut f32,
    len: usize,
    halo: *mut f32,
    halo_len: usize,
    _borrow: PhantomData<&'a mut [f32]>,
}

// SAFETY: `Cells` is a pair of exclusive borrows handed to the rows of one sweep. Its methods
// bounds-check every access, so the only obligation left is the absence of data races: each
// row reads and writes only the slots of its own nodes (see the module docs: a node's read and
// write slots are the same, and no slot belongs to two nodes), which `aa_row` keeps.
unsafe impl Sync for Cells<'_> {}

impl<'a> Cells<'a> {
    pub fn new(f: &'a mut [f32], halo: &'a mut [f32]) -> Self {
        Cells {
            f: f.as_mut_ptr(),
            len: f.len(),
            halo: halo.as_mut_ptr(),
            halo_len: halo.len(),
            _borrow: PhantomData,
        }
    }

    /// `f[start .. start + n]`.
    ///
    /// # Safety
    /// No other thread writes these slots while the slice lives.
    #[inline(always)]
    unsafe fn slice(&self, start: usize, n: usize) -> &[f32] {
        assert!(start + n <= self.len, "AA sweep: read beyond the array");
        // SAFETY: in bounds (asserted); no concurrent writer (the caller's contract).
        unsafe { std::slice::from_raw_parts(self.f.add(start), n) }
    }

    /// Writes `v` to `f[start ..]`.
    ///
    /// # Safety
    /// No other thread reads or writes these slots during the sweep.
    #[inline(always)]
    unsafe fn write(&self, start: usize, v: &[f32]) {
        assert!(start + v.len() <= self.len, "AA sweep: write beyond the array");
        // SAFETY: in bounds (asserted), `v` is a different allocation (a stack buffer), and no
        // other thread touches these slots (the caller's contract).
        unsafe { std::ptr::copy_nonoverlapping(v.as_ptr(), self.f.add(start), v.len()) };
    }

    /// Writes one value to a slot of the array or the halo.
    ///
    /// # Safety
    /// As [`Self::write`].
    #[inline(always)]
    unsafe fn put(&self, loc: Loc, v: f32) {
        match loc {
            Loc::Grid(k) => {
                assert!(k < self.len, "AA sweep: write beyond the array");
                // SAFETY: in bounds (asserted); no other thread touches it (the contract).
                unsafe { *self.f.add(k) = v };
            }
            Loc::Halo(k) => {
                assert!(k < self.halo_len, "AA sweep: write beyond the halo");
                // SAFETY: as above, for the halo.
                unsafe { *self.halo.add(k) = v };
            }
        }
    }
}

/// The arriving populations of every non-solid special (`stash[j * Q ..][..Q]` for special `j`),
/// gathered from the previous post-collision values with the boundaries applied. Specials in
/// parallel; each depends on `post` alone.
pub(crate) fn gather_specials(c: &KernelCtx, post: &Post, stash: &mut [f32]) {
    let list = c.specials.list();
    stash.par_chunks_mut(Q).with_min_len(64).enumerate().for_each(|(j, g)| {
        let sp = &list[j];
        if !sp.solid {
            g.copy_from_slice(&gather(c, post, sp.x as usize, c.specials.row_of(j), sp));
        }
    });
}

/// One row of an AA sweep: `(context, cells, stash, sponges, y, odd kind)`.
pub(crate) type AaRowFn = fn(&KernelCtx, &Cells, &[f32], &[SpongePlan], usize, bool);

/// The row function for one operator, forcing and subgrid model (as [`super::kernel::row_fn`]).
pub(crate) fn aa_row_fn(collision: Collision, forced: bool, les: bool) -> AaRowFn {
    macro_rules! pick {
        ($op:expr) => {
            match (forced, les) {
                (false, false) => aa_row::<{ $op }, false, false>,
                (true, false) => aa_row::<{ $op }, true, false>,
                (false, true) => aa_row::<{ $op }, false, true>,
                (true, true) => aa_row::<{ $op }, true, true>,
            }
        };
    }
    match collision {
        Collision::Bgk if forced => aa_row::<OP_BGK, true, false>,
        Collision::Bgk => aa_row::<OP_BGK, false, false>,
        Collision::Regularized => pick!(OP_REG),
        Collision::Recursive => pick!(OP_RR),
    }
}

/// Grids larger than the caches (`stream_stores`) run the interior on 16 lanes where the CPU has
/// AVX-512F, with software prefetch; in-cache grids on 8 lanes (as the pull kernel, where 16
/// lanes measured slower in cache).
fn aa_row<const OP: u8, const FORCED: bool, const LES: bool>(
    c: &KernelCtx,
    cells: &Cells,
    stash: &[f32],
    sponges: &[SpongePlan],
    y: usize,
    odd: bool,
) {
    if c.stream_stores {
        #[cfg(target_arch = "x86_64")]
        if avx512_available() {
            // SAFETY: the CPU has AVX-512F (checked just above), the only feature enabled.
            return unsafe { aa_row_avx512::<OP, FORCED, LES>(c, cells, stash, sponges, y, odd) };
        }
        return aa_row_body::<OP, FORCED, LES, true>(c, cells, stash, sponges, y, odd);
    }
    aa_row_body::<OP, FORCED, LES, false>(c, cells, stash, sponges, y, odd)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn aa_row_avx512<const OP: u8, const FORCED: bool, const LES: bool>(
    c: &KernelCtx,
    cells: &Cells,
    stash: &[f32],
    sponges: &[SpongePlan],
    y: usize,
    odd: bool,
) {
    aa_row_body::<OP, FORCED, LES, true>(c, cells, stash, sponges, y, odd)
}

/// Nodes per chunk: the chunk's nine direction rows (9 KB) stay in L1 between the collision and
/// the write-out.
const CHUNK: usize = 256;

/// One row, chunk by chunk: the interior collides from its read slots into an L1 buffer, the
/// specials collide their gathered populations into the same buffer, the sponges act on it,
/// and it goes out to the write slots (the interior of a bulk row as nine contiguous copies, the
/// edge nodes and the nodes of an edge row one by one, to the halo where they leave the grid).
#[inline(always)]
fn aa_row_body<const OP: u8, const FORCED: bool, const LES: bool, const PREFETCH: bool>(
    c: &KernelCtx,
    cells: &Cells,
    stash: &[f32],
    sponges: &[SpongePlan],
    y: usize,
    odd: bool,
) {
    let (nx, ny) = (c.nx, c.ny);
    let bulk = c.periodic_y || (y > 0 && y + 1 < ny);
    let row_at = |dy: i32, i: usize| ((y as isize + dy as isize).rem_euclid(ny as isize) as usize * Q + i) * nx;
    // Read and write slot of direction i at node x: `read[i] + x` and `write[i] + x` (bulk rows).
    let mut read = [0isize; Q];
    let mut write = [0isize; Q];
    if bulk {
        for i in 0..Q {
            if odd {
                read[i] = row_at(-CY[i], OPP[i]) as isize - CX[i] as isize;
                write[i] = row_at(CY[i], i) as isize + CX[i] as isize;
            } else {
                read[i] = row_at(0, i) as isize;
                write[i] = row_at(0, OPP[i]) as isize;
            }
        }
    }
    let new_form = if odd { Form::Streamed } else { Form::Swapped };
    let (first, specials) = c.specials.row(y);
    let solid_row = &c.solid[y * nx..(y + 1) * nx];
    let mut buf = [[0.0f32; CHUNK]; Q];
    let mut next = 0;
    let mut c0 = 0;
    while c0 < nx {
        let c1 = (c0 + CHUNK).min(nx);
        let (lo, hi) = (c0.max(1), c1.min(nx - 1));
        if bulk && lo < hi {
            let off = lo - c0;
            let mut s: [&[f32]; Q] = [&[]; Q];
            for i in 0..Q {
                // SAFETY: the read slots of nodes lo..hi in direction i, which only this row's
                // nodes touch in this sweep (module docs); the slice ends before they are written.
                s[i] = unsafe { cells.slice((read[i] + lo as isize) as usize, hi - lo) };
            }
            let [b0, b1, b2, b3, b4, b5, b6, b7, b8] = &mut buf;
            let m = off..off + hi - lo;
            let d = [
                &mut b0[m.clone()],
                &mut b1[m.clone()],
                &mut b2[m.clone()],
                &mut b3[m.clone()],
                &mut b4[m.clone()],
                &mut b5[m.clone()],
                &mut b6[m.clone()],
                &mut b7[m.clone()],
                &mut b8[m],
            ];
            collide_run::<OP, FORCED, LES, PREFETCH>(c, s, d);
        }
        while next < specials.len() && (specials[next].x as usize) < c1 {
            let sp = &specials[next];
            let x = sp.x as usize - c0;
            if sp.solid {
                buf.iter_mut().for_each(|b| b[x] = 0.0);
            } else {
                let mut g: [f32; Q] = std::array::from_fn(|i| stash[(first + next) * Q + i]);
                collide_les::<OP, FORCED, LES>(&mut g, c.relax, c.fx, c.fy);
                for i in 0..Q {
                    buf[i][x] = g[i];
                }
            }
            next += 1;
        }
        if !sponges.is_empty() {
            apply_span(sponges, buf.as_flattened_mut(), CHUNK, c0..c1, y, nx, ny, solid_row);
        }
        let one_by_one = |x: usize| {
            for (i, b) in buf.iter().enumerate() {
                // SAFETY: node x's own write slot (module docs).
                unsafe { cells.put(c.frame.locate(new_form, x, y, i), b[x - c0]) };
            }
        };
        if bulk {
            if lo < hi {
                for (i, b) in buf.iter().enumerate() {
                    // SAFETY: the write slots of nodes lo..hi in direction i (module docs).
                    unsafe { cells.write((write[i] + lo as isize) as usize, &b[lo - c0..hi - c0]) };
                }
            }
            for x in [0, nx - 1] {
                if (c0..c1).contains(&x) {
                    one_by_one(x);
                }
            }
        } else {
            (c0..c1).for_each(one_by_one);
        }
        c0 = c1;
    }
}

/// Swaps slots `i` and `opp i` of every node (canonical and swapped forms into each other):
/// in the row-blocked layout, whole direction rows.
pub(crate) fn swap_directions(f: &mut [f32], nx: usize) {
    f.par_chunks_mut(Q * nx).for_each(|row| {
        for i in [1, 2, 5, 6] {
            let (a, b) = row.split_at_mut(OPP[i] * nx);
            a[i * nx..(i + 1) * nx].swap_with_slice(&mut b[..nx]);
        }
    });
}

/// Writes the canonical form of `post` into `out` (rows in parallel).
pub(crate) fn canonical_into(post: &Post, out: &mut [f32]) {
    let nx = post.frame.nx;
    out.par_chunks_mut(Q * nx).enumerate().for_each(|(y, row)| {
        for i in 0..Q {
            for x in 0..nx {
                row[i * nx + x] = post.at(x, y, i);
            }
        }
    });
}
