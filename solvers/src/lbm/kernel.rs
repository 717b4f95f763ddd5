//! The fused stream-collide kernel (pull scheme, A-B arrays), one grid row at a time.
//!
//! For node `x` the populations after streaming are `f_k(x) = f*_k(x - c_k)`, read from the
//! source array; the kernel collides them and stores `f*_k(x)` in the destination row. Interior
//! rows first run a branch-free loop over `x = 1 .. nx-2` that the compiler vectorises; the nodes
//! on the list of specials (domain edges, nodes with a link into a body, solid nodes) then run the
//! general path, which reads in order: load, boundaries, moments, collide, store.

use super::boundary::{bouzidi, side_value, InletReference};
use super::collision::{collide_les, Collision, Relax, OP_BGK, OP_REG, OP_RR};
use super::domain::Sides;
use super::lattice::{CX, CY, Q};
use super::post::{Frame, Post};
use super::specials::{RowSpecials, Special};

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
    pub specials: &'a RowSpecials,
    pub links: &'a [Link],
    pub velocity_scale: f32,
    /// Characteristic (non-reflecting) velocity edges: their reference densities; `None` for
    /// rigid ones.
    pub inlet_reference: Option<InletReference>,
    /// Write the interior with non-temporal stores (arrays larger than the caches).
    pub stream_stores: bool,
    /// Size and periodicity, for reading populations through [`Post`].
    pub frame: Frame,
}

impl KernelCtx<'_> {
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

/// Whether a row can be written with aligned 8-wide non-temporal stores: AVX, rows a multiple
/// of 8 floats long, and the row starting on a 32-byte boundary (the arrays are cache-line
/// aligned, see `AlignedVec`).
#[inline]
pub(crate) fn nt_rows_possible(row: &[f32], nx: usize) -> bool {
    cfg!(all(target_arch = "x86_64", target_feature = "avx")) && nx.is_multiple_of(8) && (row.as_ptr() as usize).is_multiple_of(32)
}

/// Collides the nodes of a run: node `k` pulls direction `i` from `src[i][k]` and its
/// post-collision value goes to `dst[i][k]` (slices of one length). The compiler vectorises the
/// loop at its target's width. With `PREFETCH` (arrays larger than the caches) the run goes in
/// blocks of 16 nodes, each first asking for the source lines [`PREFETCH_AHEAD`] floats on:
/// nine read streams plus nine written ones are more than the hardware prefetchers keep ahead
/// of (D2Q9 4096^2: about 5 % faster, measured interleaved).
#[inline(always)]
pub(crate) fn collide_run<const OP: u8, const FORCED: bool, const LES: bool, const PREFETCH: bool>(
    c: &KernelCtx,
    src: [&[f32]; Q],
    dst: [&mut [f32]; Q],
) {
    let m = dst[0].len();
    let [s0, s1, s2, s3, s4, s5, s6, s7, s8] = src;
    let [d0, d1, d2, d3, d4, d5, d6, d7, d8] = dst;
    // Equal lengths, stated once so that the loop runs without bounds checks.
    let (s0, s1, s2, s3, s4, s5, s6, s7, s8) = (
        &s0[..m],
        &s1[..m],
        &s2[..m],
        &s3[..m],
        &s4[..m],
        &s5[..m],
        &s6[..m],
        &s7[..m],
        &s8[..m],
    );
    let (d0, d1, d2, d3, d4, d5, d6, d7, d8) = (
        &mut d0[..m],
        &mut d1[..m],
        &mut d2[..m],
        &mut d3[..m],
        &mut d4[..m],
        &mut d5[..m],
        &mut d6[..m],
        &mut d7[..m],
        &mut d8[..m],
    );
    let mut x0 = 0;
    while x0 < m {
        let x1 = if PREFETCH { (x0 + 16).min(m) } else { m };
        if PREFETCH {
            for s in [s0, s1, s2, s3, s4, s5, s6, s7, s8] {
                prefetch(s.as_ptr().wrapping_add(x0 + PREFETCH_AHEAD));
            }
        }
        for x in x0..x1 {
            let mut g = [s0[x], s1[x], s2[x], s3[x], s4[x], s5[x], s6[x], s7[x], s8[x]];
            collide_les::<OP, FORCED, LES>(&mut g, c.relax, c.fx, c.fy);
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
        x0 = x1;
    }
}

/// The direction rows `i` of a destination row of `nx` nodes (`row[i nx .. (i + 1) nx]`),
/// nodes `lo .. hi` of each.
#[inline(always)]
fn dst_rows(row: &mut [f32], nx: usize, lo: usize, hi: usize) -> [&mut [f32]; Q] {
    let mut rows = row.chunks_exact_mut(nx).map(|r| &mut r[lo..hi]);
    std::array::from_fn(|_| rows.next().expect("a row holds Q direction rows"))
}

/// Interior of a row, ordinary stores: `x = 1 .. nx-2`, `s[i][x - 1]` streams into node `x`.
#[inline(always)]
fn bulk_row_plain<const OP: u8, const FORCED: bool, const LES: bool>(c: &KernelCtx, s: [&[f32]; Q], row: &mut [f32]) {
    let nx = c.nx;
    collide_run::<OP, FORCED, LES, false>(c, s, dst_rows(row, nx, 1, nx - 1));
}

/// Interior of a row through an L1-resident buffer written out with non-temporal stores: the
/// destination lines are not read before they are written (no write-allocate), so a node costs
/// 72 bytes of memory traffic instead of 108. Values are identical to [`bulk_row_plain`]; the
/// edge nodes `x = 0, nx-1` are written as zero here and overwritten by the general path.
#[inline(always)]
fn bulk_row_streamed<const OP: u8, const FORCED: bool, const LES: bool>(c: &KernelCtx, s: [&[f32]; Q], row: &mut [f32]) {
    const CHUNK: usize = 256;
    let nx = c.nx;
    let mut buf = [[0.0f32; CHUNK]; Q];
    let mut c0 = 0;
    while c0 < nx {
        let c1 = (c0 + CHUNK).min(nx);
        // Interior nodes of this chunk: x in [lo, hi), read at x - 1 from the shifted sources.
        let lo = c0.max(1);
        let hi = c1.min(nx - 1);
        // Plain loops and arrays: `map` and `each_mut().map` here measured 3-4 % slower at
        // 4096^2 (interleaved runs).
        let mut t: [&[f32]; Q] = [&[]; Q];
        for i in 0..Q {
            t[i] = &s[i][lo - 1..hi - 1];
        }
        let off = lo - c0;
        let [b0, b1, b2, b3, b4, b5, b6, b7, b8] = &mut buf;
        let m = off..off + hi - lo;
        let b = [
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
        collide_run::<OP, FORCED, LES, true>(c, t, b);
        let len = c1 - c0;
        for (i, b) in buf.iter_mut().enumerate() {
            if c0 == 0 {
                b[0] = 0.0;
            }
            if c1 == nx {
                b[len - 1] = 0.0;
            }
            stream_lines(&mut row[i * nx + c0..i * nx + c1], &b[..len]);
        }
        c0 = c1;
    }

    store_fence();
}

/// `dst.copy_from_slice(src)` with aligned 8-wide non-temporal stores (`vmovntps`). The caller
/// guarantees `dst` starts on a 32-byte boundary and has a length that is a multiple of 8.
#[inline(always)]
pub(crate) fn stream_aligned(dst: &mut [f32], src: &[f32]) {
    assert_eq!(dst.len(), src.len());
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use core::arch::x86_64::{_mm256_loadu_ps, _mm256_stream_ps};
        assert!(
            dst.len().is_multiple_of(8) && (dst.as_ptr() as usize).is_multiple_of(32),
            "stream_aligned: unaligned destination"
        );
        for k in (0..dst.len()).step_by(8) {
            // SAFETY: `k + 8 <= len` for both slices (equal lengths, a multiple of 8), so the
            // 32-byte read and write stay inside them; `dst[k]` is 32-byte aligned because
            // `dst` is (asserted above) and `k` is a multiple of 8 floats; AVX is enabled at
            // compile time (cfg above). The non-temporal store is ordered by `store_fence`
            // before anything reads it.
            unsafe { _mm256_stream_ps(dst.as_mut_ptr().add(k), _mm256_loadu_ps(src.as_ptr().add(k))) };
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    dst.copy_from_slice(src);
}

/// Whether this CPU runs AVX-512F (detected once by `std`, then a cached load).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx512_available() -> bool {
    std::arch::is_x86_feature_detected!("avx512f")
}

/// `dst.copy_from_slice(src)` with non-temporal stores: a whole cache line per store
/// (`vmovntps zmm`) where the CPU has AVX-512F and `dst` starts on a line and holds whole ones,
/// otherwise [`stream_aligned`]'s half lines (same conditions on `dst` as there).
#[inline]
pub(crate) fn stream_lines(dst: &mut [f32], src: &[f32]) {
    #[cfg(target_arch = "x86_64")]
    if dst.len().is_multiple_of(16) && (dst.as_ptr() as usize).is_multiple_of(64) && avx512_available() {
        // SAFETY: the CPU has AVX-512F (checked just above), the only feature
        // `stream_lines_avx512` enables.
        return unsafe { stream_lines_avx512(dst, src) };
    }
    stream_aligned(dst, src)
}

/// [`stream_lines`] on a CPU with AVX-512F, `dst` 64-byte aligned and a multiple of 16 long.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn stream_lines_avx512(dst: &mut [f32], src: &[f32]) {
    use core::arch::x86_64::{_mm512_loadu_ps, _mm512_stream_ps};
    assert_eq!(dst.len(), src.len());
    assert!(
        dst.len().is_multiple_of(16) && (dst.as_ptr() as usize).is_multiple_of(64),
        "stream_lines_avx512: unaligned destination"
    );
    for (d, s) in dst.chunks_exact_mut(16).zip(src.chunks_exact(16)) {
        // SAFETY: `d` and `s` are 16 floats each (`chunks_exact` of equal-length slices whose
        // length is a multiple of 16), all the load reads and the store writes; `d` is 64-byte
        // aligned because `dst` is (asserted above) and every chunk starts a multiple of 64
        // bytes after it; AVX-512F is enabled on this function, which its caller runs only
        // where the CPU has it. The non-temporal store is ordered by `store_fence` before
        // anything reads it.
        unsafe { _mm512_stream_ps(d.as_mut_ptr(), _mm512_loadu_ps(s.as_ptr())) };
    }
}

/// How far ahead (floats) of the block being loaded the streaming kernels prefetch each source
/// row (four cache lines; 128 and 256 measured no better in 2D, 256 worse in 3D).
pub(crate) const PREFETCH_AHEAD: usize = 64;

/// Asks for the cache line holding `p` (`prefetcht0`). A hint: it never faults and changes no
/// result, so `p` may point anywhere.
#[inline(always)]
pub(crate) fn prefetch(p: *const f32) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch reads no memory architecturally and cannot fault, whatever the address.
    unsafe {
        core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(p as *const i8)
    };
}

/// Orders the non-temporal stores before all later stores and loads of this thread (`sfence`,
/// SSE, so on every x86-64), so that ordinary stores to the same nodes (the 2D general path's
/// edge nodes) land after them and other threads see them once the step's join completes.
#[inline(always)]
pub(crate) fn store_fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `sfence` takes no operands, touches no memory and cannot fault.
    unsafe {
        core::arch::x86_64::_mm_sfence()
    };
}

/// A row function: `(context, source array, destination row, y)`.
pub(crate) type RowFn = fn(&KernelCtx, &[f32], &mut [f32], usize);

/// The row function compiled for one choice of operator, forcing and subgrid model (the
/// subgrid model exists only for the regularised operators); `reference` picks the slow oracle.
pub(crate) fn row_fn(collision: Collision, forced: bool, les: bool, reference: bool) -> RowFn {
    macro_rules! pick {
        ($op:expr, $forced:literal, $les:literal) => {
            if reference {
                row_reference::<{ $op }, $forced, $les>
            } else {
                row_kernel::<{ $op }, $forced, $les>
            }
        };
    }
    macro_rules! regularized {
        ($op:expr) => {
            match (forced, les) {
                (false, false) => pick!($op, false, false),
                (true, false) => pick!($op, true, false),
                (false, true) => pick!($op, false, true),
                (true, true) => pick!($op, true, true),
            }
        };
    }
    match (collision, forced) {
        (Collision::Bgk, false) => pick!(OP_BGK, false, false),
        (Collision::Bgk, true) => pick!(OP_BGK, true, false),
        (Collision::Regularized, _) => regularized!(OP_REG),
        (Collision::Recursive, _) => regularized!(OP_RR),
    }
}

/// One row of the step ([`row_body`]). On grids larger than the caches (streamed stores) and a
/// CPU with AVX-512F the interior runs on 16 lanes (`zmm`), else on 8: the same lane-wise IEEE
/// operations, so bitwise the same populations. In-cache grids stay on 8 lanes: there the
/// unaligned 64-byte loads and stores each split a cache line, and 16 lanes measured 10-20 %
/// slower (512 x 256).
fn row_kernel<const OP: u8, const FORCED: bool, const LES: bool>(c: &KernelCtx, src: &[f32], row: &mut [f32], y: usize) {
    if !c.stream_stores {
        return row_body::<OP, FORCED, LES, false>(c, src, row, y);
    }
    #[cfg(target_arch = "x86_64")]
    if avx512_available() {
        // SAFETY: the CPU has AVX-512F (checked just above), the only feature `row_avx512`
        // enables.
        return unsafe { row_avx512::<OP, FORCED, LES>(c, src, row, y) };
    }
    row_body::<OP, FORCED, LES, true>(c, src, row, y)
}

/// [`row_body`] with streamed stores, compiled with AVX-512F: the compiler vectorises the
/// interior loop on `zmm` registers (16 nodes per instruction, 32 registers: no spills of the
/// collision's temporaries).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn row_avx512<const OP: u8, const FORCED: bool, const LES: bool>(c: &KernelCtx, src: &[f32], row: &mut [f32], y: usize) {
    row_body::<OP, FORCED, LES, true>(c, src, row, y)
}

/// One row of the step: vectorised interior (through non-temporal stores with `STREAMED`, where
/// the row allows them), then the special nodes.
#[inline(always)]
fn row_body<const OP: u8, const FORCED: bool, const LES: bool, const STREAMED: bool>(
    c: &KernelCtx,
    src: &[f32],
    row: &mut [f32],
    y: usize,
) {
    let nx = c.nx;
    let bulk = c.periodic_y || (y > 0 && y + 1 < c.ny);
    if bulk {
        let mut s: [&[f32]; Q] = [&[]; Q];
        for (i, si) in s.iter_mut().enumerate() {
            *si = c.shifted(src, y, i);
        }
        if STREAMED && nt_rows_possible(row, nx) {
            bulk_row_streamed::<OP, FORCED, LES>(c, s, row);
        } else {
            bulk_row_plain::<OP, FORCED, LES>(c, s, row);
        }
    }
    for sp in c.specials.row(y).1 {
        general_node::<OP, FORCED, LES>(c, src, row, sp.x as usize, y, sp);
    }
}

/// The same row, every node through the general path (the slow oracle of the tests).
fn row_reference<const OP: u8, const FORCED: bool, const LES: bool>(c: &KernelCtx, src: &[f32], row: &mut [f32], y: usize) {
    let specials = c.specials.row(y).1;
    for x in 0..c.nx {
        let plain = Special {
            x: x as u32,
            solid: false,
            link_start: 0,
            link_end: 0,
        };
        let sp = specials.iter().find(|s| s.x as usize == x).unwrap_or(&plain);
        general_node::<OP, FORCED, LES>(c, src, row, x, y, sp);
    }
}

/// The general path for one node: load with boundaries, collide, store.
#[inline]
fn general_node<const OP: u8, const FORCED: bool, const LES: bool>(
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
    let mut g = gather(c, &Post::canonical(src, c.frame), x, y, sp);
    collide_les::<OP, FORCED, LES>(&mut g, c.relax, c.fx, c.fy);
    for i in 0..Q {
        row[i * nx + x] = g[i];
    }
}

/// The populations arriving at fluid node `(x, y)`, `f_k(x) = f*_k(x - c_k)`, with the
/// boundaries applied where `x - c_k` is solid (the node's links) or beyond an edge.
#[inline]
pub(crate) fn gather(c: &KernelCtx, src: &Post, x: usize, y: usize, sp: &Special) -> [f32; Q] {
    let nx = c.nx;
    let mut g = [0.0f32; Q];
    let mut missing = [false; Q];
    for k in 0..Q {
        match c.neighbour(x, y, -CX[k], -CY[k]) {
            Some((xs, ys)) if !c.solid[ys * nx + xs] => g[k] = src.at(xs, ys, k),
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
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The prefetch hint accepts any address, mapped or not, and changes nothing.
    #[test]
    fn prefetch_never_faults() {
        let v = [1.0f32; 4];
        prefetch(v.as_ptr().wrapping_add(2));
        prefetch(std::ptr::null());
        prefetch(usize::MAX as *const f32);
        prefetch(v.as_ptr().wrapping_add(1 << 40));
        assert_eq!(v, [1.0; 4]);
    }

    /// Whole-line and half-line non-temporal copies give the source exactly, and touch nothing
    /// outside the destination: a line-aligned destination of whole lines, one of half lines,
    /// and one starting half a line in.
    #[test]
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    fn stream_lines_copies_exactly() {
        let mut dst = crate::lbm::aligned::AlignedVec::zeros(96);
        let src: Vec<f32> = (0..96).map(|k| k as f32 * 0.5 - 7.0).collect();
        for (start, len) in [(0, 96), (0, 40), (8, 64)] {
            dst.fill(-1.0);
            stream_lines(&mut dst[start..start + len], &src[..len]);
            store_fence();
            for (k, v) in dst.iter().enumerate() {
                let want = if (start..start + len).contains(&k) { src[k - start] } else { -1.0 };
                assert_eq!(v.to_bits(), want.to_bits(), "start {start} len {len}: element {k}");
            }
        }
    }
}
