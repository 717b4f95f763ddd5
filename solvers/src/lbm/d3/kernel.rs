//! The fused 3D stream-collide kernel (pull scheme, A-B arrays), one z plane at a time, row by
//! row.
//!
//! Layout: `f[((z Q + i) ny + y) nx + x]` ([`index`]): a plane holds `Q` contiguous direction
//! planes, so what direction `i` pulls into plane `z` is one contiguous block of plane `z - c_z`,
//! row after row, and the hardware prefetchers see `Q` long streams (with a row-interleaved
//! layout they saw `Q` short rows per row and the kernel stalled on memory latency: 9 MLUPS).
//! Node `x` pulls `f_i(x) = f*_i(x - c_i)`. The bulk loop runs `x = 0 .. nx-1` branch-free over
//! `Q` shifted source rows (along a periodic x the two ends with their wrapped pulls); the
//! row's specials (its two ends at a non-periodic x face, and every node that is solid or has a
//! link into a body) run the general path and replace their values before the row is written.

use rayon::prelude::*;
use wide::f32x8;

use super::super::collision::Relax;
use super::super::kernel::{nt_rows_possible, prefetch, store_fence, stream_lines};
use super::super::specials::{RowSpecials, Special};
use super::collision::{collide, collide_chunk, moments, Block, Chunk, Ends, CHUNK};
use super::lattice::Lattice3;
use super::sides::{face_source, face_value, face_value_planned, plan_face_pull, Faces};
use super::sponge::Layers;

/// A link from fluid node `node` whose streaming source in direction `k` (the node `node - c_k`)
/// is inside a body; the wall is at fraction `q` of the way towards it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Link {
    /// Node index `(z ny + y) nx + x`.
    pub node: u32,
    pub k: u8,
    pub q: f32,
    /// Wall velocity at the crossing, lattice units.
    pub uw: [f32; 3],
    pub body: u16,
}

/// What enters a special fluid node `k`-wards from beyond a face of the box, planned once.
/// Periodic, wall and free-slip faces copy population index `src` of the step's source (`face`
/// is [`FacePull::COPY`]; see [`face_source`]). Velocity and outlet faces compute the value
/// ([`face_value_planned`]) from population `src` (the node's opposite one, or the one across
/// the outlet) and the moments of node `at` of face `face`'s layer ([`FaceMoments`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct FacePull {
    pub src: u32,
    pub at: u32,
    pub k: u8,
    pub face: u8,
}

impl FacePull {
    pub const COPY: u8 = u8::MAX;
}

/// The moments `(rho - 1, j)` of the nodes of the outer layer of each face whose entering values
/// are computed (velocity: `rho` of the node itself; outlet: the moments of the node across the
/// face, which lies in the same layer), gathered once per step instead of once per entering
/// direction. Node `p` of face `f` is at [`FaceMoments::at`].
#[derive(Clone, Debug, Default)]
pub(crate) struct FaceMoments(pub [Vec<[f32; 4]>; 6]);

impl FaceMoments {
    /// Room for the computed faces of `faces` on `n` nodes.
    pub fn new(n: [usize; 3], faces: &Faces) -> Self {
        FaceMoments(std::array::from_fn(|f| {
            let a = f / 2;
            if faces.0[f].is_computed() {
                vec![[0.0; 4]; n[(a + 1) % 3] * n[(a + 2) % 3]]
            } else {
                Vec::new()
            }
        }))
    }

    /// Index of node `p` in the layer of face `f`.
    #[inline(always)]
    pub fn at(n: [usize; 3], f: usize, p: [usize; 3]) -> usize {
        let a = f / 2;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        p[c] * n[b] + p[b]
    }

    /// The nodes of face `f`'s layer on `n` nodes, in layer order (index [`Self::at`]).
    pub fn layer(n: [usize; 3], f: usize) -> impl Iterator<Item = [usize; 3]> {
        let b = (f / 2 + 1) % 3;
        (0..n[(f / 2 + 2) % 3]).flat_map(move |vc| (0..n[b]).map(move |vb| Self::node(n, f, vb, vc)))
    }

    /// Node `vc n_b + vb` of face `f`'s layer (`b`, `c` the axes after the face's own).
    #[inline(always)]
    fn node(n: [usize; 3], f: usize, vb: usize, vc: usize) -> [usize; 3] {
        let a = f / 2;
        let mut p = [0; 3];
        p[a] = if f.is_multiple_of(2) { 0 } else { n[a] - 1 };
        p[(a + 1) % 3] = vb;
        p[(a + 2) % 3] = vc;
        p
    }

    /// Gathers the moments of every computed face's layer from `src`, a line of the layer per
    /// task: each node's populations lie on as many cache lines, so the gather waits on memory.
    pub fn fill<const Q: usize, L: Lattice3<Q>>(&mut self, n: [usize; 3], src: &[f32]) {
        for (f, layer) in self.0.iter_mut().enumerate() {
            if layer.is_empty() {
                continue;
            }
            let nb = n[(f / 2 + 1) % 3];
            layer.par_chunks_mut(nb).enumerate().with_min_len(4).for_each(|(vc, line)| {
                for (vb, m) in line.iter_mut().enumerate() {
                    let p = Self::node(n, f, vb, vc);
                    let g: [f32; Q] = std::array::from_fn(|i| src[index::<Q>(n, p, i)]);
                    let (drho, j) = moments::<Q, L>(&g);
                    *m = [drho, j[0], j[1], j[2]];
                }
            });
        }
    }
}

/// Index of population `i` of node `p` on a grid of `n` nodes: `((z Q + i) ny + y) nx + x`.
#[inline(always)]
pub(crate) fn index<const Q: usize>(n: [usize; 3], p: [usize; 3], i: usize) -> usize {
    ((p[2] * Q + i) * n[1] + p[1]) * n[0] + p[0]
}

/// Read-only state shared by every row of one step.
pub(crate) struct Ctx<'a> {
    pub n: [usize; 3],
    pub periodic: [bool; 3],
    pub faces: &'a Faces,
    /// Multiplies every velocity face (inlet ramps, gusts).
    pub velocity_scale: f32,
    pub relax: Relax,
    pub force: [f32; 3],
    pub solid: &'a [bool],
    /// The specials of each row `r = z ny + y`.
    pub specials: &'a RowSpecials,
    /// Rows whose `y` and `z` neighbours all exist: the bulk loop runs there; the other rows
    /// (next to a non-periodic face) are specials from end to end.
    pub row_bulk: &'a [bool],
    pub links: &'a [Link],
    /// The face pulls of special `s` are `pulls[pull_start[s] .. pull_start[s + 1]]`.
    pub pulls: &'a [FacePull],
    pub pull_start: &'a [u32],
    /// `(rho - 1, j)` of every node of the outer layer of each velocity and outlet face, from
    /// the step's source (empty for the other faces; see [`FaceMoments`]).
    pub face_moments: &'a FaceMoments,
    /// Per velocity face, the factor on its velocity at each node of its layer (indexed as
    /// [`FaceMoments::at`]); empty: uniform.
    pub face_profiles: &'a [Vec<f32>; 6],
    /// Write the bulk with non-temporal stores (arrays larger than the caches).
    pub stream_stores: bool,
    /// The absorbing layers, applied after each collision.
    pub layers: Layers<'a>,
}

impl Ctx<'_> {
    /// Index of population `i` of node `p`.
    #[inline(always)]
    pub fn idx<const Q: usize>(&self, p: [usize; 3], i: usize) -> usize {
        index::<Q>(self.n, p, i)
    }

    /// The node `p + d` (`|d| <= 1` per axis), wrapped along periodic axes; `None` outside a
    /// non-periodic one.
    #[inline(always)]
    pub fn neighbour(&self, p: [usize; 3], d: [i32; 3]) -> Option<[usize; 3]> {
        let mut out = [0usize; 3];
        for a in 0..3 {
            let n = self.n[a];
            let v = p[a] as isize + d[a] as isize;
            out[a] = if v < 0 {
                if !self.periodic[a] {
                    return None;
                }
                (v + n as isize) as usize
            } else if v as usize >= n {
                if !self.periodic[a] {
                    return None;
                }
                v as usize - n
            } else {
                v as usize
            };
        }
        Some(out)
    }

    /// The factor of face `f`'s velocity at its node `p` (1 on a uniform face).
    #[inline(always)]
    pub fn face_profile(&self, f: usize, p: [usize; 3]) -> f32 {
        let profile = &self.face_profiles[f];
        if profile.is_empty() {
            1.0
        } else {
            profile[FaceMoments::at(self.n, f, p)]
        }
    }

    #[inline(always)]
    pub fn is_solid(&self, p: [usize; 3]) -> bool {
        self.solid[(p[2] * self.n[1] + p[1]) * self.n[0] + p[0]]
    }

    /// What direction `i` pulls into the nodes `x = 0 .. nx-1` of row `(y, z)`: element `x` is
    /// the source's value at `x - c_x` of row `(y - c_y, z - c_z)`, read from the padded source
    /// (logical element `k` at `k + PAD`). At `x = 0` or `nx - 1` that can be the neighbouring
    /// row's end or the padding, never out of bounds (see [`bulk`] for those two nodes). Also
    /// returns where the source row starts in the unpadded array.
    #[inline(always)]
    fn row_source<'s, const Q: usize, L: Lattice3<Q>>(&self, src_ext: &'s [f32], y: usize, z: usize, i: usize) -> (usize, &'s [f32]) {
        let c = L::C_REF[i];
        let ys = wrap(y, -c[1], self.n[1]);
        let zs = wrap(z, -c[2], self.n[2]);
        let row = index::<Q>(self.n, [0, ys, zs], i);
        let start = ((row + PAD) as isize - c[0] as isize) as usize;
        (row, &src_ext[start..start + self.n[0]])
    }
}

/// `v + d` wrapped into `0 .. n` for `|d| <= 1` (no division: this runs per row and direction).
#[inline(always)]
fn wrap(v: usize, d: i32, n: usize) -> usize {
    match d {
        1 if v + 1 == n => 0,
        1 => v + 1,
        -1 if v == 0 => n - 1,
        -1 => v - 1,
        _ => v,
    }
}

/// Padding (floats) before and after the population arrays, for [`Ctx::row_source`].
pub(crate) const PAD: usize = 16;

/// Interpolated bounce-back (linear Bouzidi, with the moving-wall term; see
/// [`crate::lbm::boundary`] for the formulas): the population `g_k(x, t+1)` that link `l` brings
/// back from the wall, from the post-collision source.
#[inline]
pub(crate) fn bouzidi<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], p: [usize; 3], l: &Link) -> f32 {
    let k = l.k as usize;
    let i = L::OPP_REF[k];
    let q = l.q;
    let ck = L::C_REF[k];
    let moving = 6.0 * L::W_REF[k] * (ck[0] as f32 * l.uw[0] + ck[1] as f32 * l.uw[1] + ck[2] as f32 * l.uw[2]);
    let gi = src[c.idx::<Q>(p, i)];
    if q < 0.5 {
        match c.neighbour(p, ck).filter(|&b| !c.is_solid(b)) {
            Some(b) => 2.0 * q * gi + (1.0 - 2.0 * q) * src[c.idx::<Q>(b, i)] + moving,
            None => gi + moving,
        }
    } else {
        let gk = src[c.idx::<Q>(p, k)];
        (gi + (2.0 * q - 1.0) * gk + moving) / (2.0 * q)
    }
}

/// The populations that stream into fluid node `p`: pulled from its neighbours, the ones from
/// outside the box given by its faces, the ones from inside a body by their bounce-back.
#[inline(always)]
pub(crate) fn gather<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], p: [usize; 3], links: &[Link]) -> [f32; Q] {
    let mut g = [0.0f32; Q];
    for (i, gi) in g.iter_mut().enumerate() {
        *gi = match c.neighbour(p, L::C_REF[i].map(|v| -v)) {
            Some(s) => src[c.idx::<Q>(s, i)],
            None => face_value::<Q, L>(c, src, p, i),
        };
    }
    for l in links {
        g[l.k as usize] = bouzidi::<Q, L>(c, src, p, l);
    }
    g
}

/// [`gather`] with the face values planned ([`FacePull`]): the same values, without working
/// out the face, the mirror direction and the source node of each one every step.
#[inline(always)]
fn gather_planned<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], p: [usize; 3], pulls: &[FacePull], links: &[Link]) -> [f32; Q] {
    let mut g = [0.0f32; Q];
    for (i, gi) in g.iter_mut().enumerate() {
        if let Some(s) = c.neighbour(p, L::C_REF[i].map(|v| -v)) {
            *gi = src[c.idx::<Q>(s, i)];
        }
    }
    for fp in pulls {
        g[fp.k as usize] = match fp.face {
            FacePull::COPY => src[fp.src as usize],
            _ => face_value_planned::<Q, L>(c, src, fp),
        };
    }
    for l in links {
        g[l.k as usize] = bouzidi::<Q, L>(c, src, p, l);
    }
    g
}

/// The face pulls of fluid node `p`: one per direction whose source lies beyond a face.
pub(crate) fn plan_pulls<const Q: usize, L: Lattice3<Q>>(c: &Ctx, p: [usize; 3], out: &mut Vec<FacePull>) {
    for i in 0..Q {
        if c.neighbour(p, L::C_REF[i].map(|v| -v)).is_none() {
            out.push(match face_source::<Q, L>(c, p, i) {
                Some(src) => FacePull {
                    src: src as u32,
                    at: 0,
                    k: i as u8,
                    face: FacePull::COPY,
                },
                None => plan_face_pull::<Q, L>(c, p, i),
            });
        }
    }
}

/// The bulk of row `(y, z)`: every node `x = 0 .. nx-1` in chunks of [`CHUNK`] nodes, collided
/// by [`collide_chunk`] into an L1-resident buffer (at most 27 x 128 x 4 = 14 KB) and written
/// out, with non-temporal stores when the arrays are larger than the caches (no
/// read-for-ownership of the destination: `2 Q 4` bytes of traffic per node instead of `3 Q 4`).
/// Along a periodic x the two ends' pulls across the axis are read separately ([`Ends`]);
/// otherwise the values at `x = 0` and `nx - 1` are wrong (their pulls run into the neighbouring
/// rows). The row's specials replace their nodes' values in the buffer before it is written, so
/// the row gets no ordinary stores after its non-temporal ones and needs no fence of its own
/// ([`plane`] fences once).
#[inline(always)]
fn bulk<B: Block, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    src_ext: &[f32],
    y: usize,
    z: usize,
    out: &mut [f32],
    buf: &mut [[f32; CHUNK]; Q],
) {
    let [nx, ny, _] = c.n;
    let (first_special, specials) = c.specials.row(z * ny + y);
    // Source rows, and along a periodic x the row's two ends' pulls across it (from the same
    // source rows). Plain loops: `array::from_fn` closures are not inlined here.
    let periodic_x = c.periodic[0];
    let mut s: [&[f32]; Q] = [&[]; Q];
    let (mut first, mut last) = ([0.0f32; Q], [0.0f32; Q]);
    for i in 0..Q {
        let (row, si) = c.row_source::<Q, L>(src_ext, y, z, i);
        s[i] = si;
        if periodic_x {
            let c_x = L::C_REF[i][0];
            if c_x == 1 {
                first[i] = src[row + nx - 1];
                // The next row's (usually `nx` on): a line no stream of this row reaches.
                prefetch(src.as_ptr().wrapping_add(row + 2 * nx - 1));
            }
            if c_x == -1 {
                last[i] = src[row];
            }
        }
    }
    let ends = if periodic_x {
        Ends {
            first: Some(&first),
            last: Some(&last),
        }
    } else {
        Ends::default()
    };
    let stream = c.stream_stores && nt_rows_possible(&out[y * nx..], nx);
    // The next of `specials` to put into the buffer.
    let mut k = 0;
    let mut c0 = 0;
    while c0 < nx {
        let c1 = (c0 + CHUNK).min(nx);
        let mut t: [&[f32]; Q] = [&[]; Q];
        for i in 0..Q {
            t[i] = &s[i][c0..c1];
        }
        let chunk = Chunk {
            src: &t,
            x0: c0,
            m: c1 - c0,
            n: nx,
            ends,
            relax: c.relax,
            f: c.force,
        };
        collide_chunk::<B, Q, L, OP, FORCED, LES>(&chunk, buf);
        c.layers.chunk(buf, c0, c1 - c0, y, z);
        while let Some(sp) = specials.get(k).filter(|sp| (sp.x as usize) < c1) {
            let g = special::<Q, L, OP, FORCED, LES>(c, src, first_special + k, sp, y, z);
            for (b, gi) in buf.iter_mut().zip(g) {
                b[sp.x as usize - c0] = gi;
            }
            k += 1;
        }
        for (i, b) in buf.iter().enumerate() {
            let row = (i * ny + y) * nx;
            let dst = &mut out[row + c0..row + c1];
            if stream {
                stream_lines(dst, &b[..c1 - c0]);
            } else {
                dst.copy_from_slice(&b[..c1 - c0]);
            }
        }
        c0 = c1;
    }
}

/// The populations special node number `s` (`sp`, in row `(y, z)`) takes in this step: zeros
/// for a solid node or a ghost node of a split box (the exchange fills it), otherwise its
/// pulls through walls and faces ([`gather_planned`]), collided and damped by the layers.
#[inline(always)]
fn special<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    s: usize,
    sp: &Special,
    y: usize,
    z: usize,
) -> [f32; Q] {
    if sp.solid {
        return [0.0; Q];
    }
    let p = [sp.x as usize, y, z];
    let links = &c.links[sp.link_start as usize..sp.link_end as usize];
    let pulls = &c.pulls[c.pull_start[s] as usize..c.pull_start[s + 1] as usize];
    let mut g = gather_planned::<Q, L>(c, src, p, pulls, links);
    collide::<Q, L, OP, FORCED, LES>(&mut g, c.relax, c.force);
    c.layers.node(&mut g, p);
    g
}

/// Plane `z` of the destination (`Q ny nx` values): each row's bulk loop on blocks of `B` with
/// its specials patched in, or, in a row next to a non-periodic y or z face, its specials
/// alone. One fence at the end orders the plane's non-temporal stores before the step's join
/// (a fence per row measured 5-10 % slower at 176^3, D3Q27, 2 threads).
#[inline(always)]
fn plane<B: Block, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    src_ext: &[f32],
    z: usize,
    out: &mut [f32],
) {
    let [nx, ny, _] = c.n;
    let mut buf = [[0.0f32; CHUNK]; Q];
    for y in 0..ny {
        let r = z * ny + y;
        if nx >= 3 && c.row_bulk[r] {
            bulk::<B, Q, L, OP, FORCED, LES>(c, src, src_ext, y, z, out, &mut buf);
            continue;
        }
        let (first, specials) = c.specials.row(r);
        for (s, sp) in (first..).zip(specials) {
            let g = special::<Q, L, OP, FORCED, LES>(c, src, s, sp, y, z);
            for (i, gi) in g.iter().enumerate() {
                out[(i * ny + y) * nx + sp.x as usize] = *gi;
            }
        }
    }
    store_fence();
}

/// [`plane`] on blocks of 8 nodes (`wide::f32x8`, AVX2), whatever the CPU.
pub(crate) fn plane_narrow<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    src_ext: &[f32],
    z: usize,
    out: &mut [f32],
) {
    plane::<f32x8, Q, L, OP, FORCED, LES>(c, src, src_ext, z, out)
}

/// [`plane`] on the widest blocks the CPU runs: 16 nodes with AVX-512F, else 8. Both give
/// bitwise the same populations (see [`super::avx512`]).
pub(crate) fn plane_widest<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    src_ext: &[f32],
    z: usize,
    out: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if super::super::kernel::avx512_available() {
        // SAFETY: the CPU has AVX-512F (checked just above), the only feature `plane_avx512`
        // enables.
        return unsafe { plane_avx512::<Q, L, OP, FORCED, LES>(c, src, src_ext, z, out) };
    }
    plane_narrow::<Q, L, OP, FORCED, LES>(c, src, src_ext, z, out)
}

/// [`plane`] on 16-node blocks, compiled with AVX-512F so that the block arithmetic inlined into
/// it runs on `zmm` registers (32 of them: the collision's temporaries no longer spill).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn plane_avx512<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    src_ext: &[f32],
    z: usize,
    out: &mut [f32],
) {
    plane::<super::avx512::F32x16, Q, L, OP, FORCED, LES>(c, src, src_ext, z, out)
}
