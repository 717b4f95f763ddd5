//! The fused 3D stream-collide kernel (pull scheme, A-B arrays), one grid row (fixed `y`, `z`)
//! at a time.
//!
//! Layout: `f[((z ny + y) Q + i) nx + x]`, so a row holds `Q` contiguous direction arrays. Node
//! `x` pulls `f_i(x) = f*_i(x - c_i)` from the source array. The bulk loop runs `x = 1 .. nx-2`
//! branch-free over `Q` shifted source rows; the row's specials (its two ends, where `x` wraps,
//! and every node that is solid or has a link into a body) then run the general path and
//! overwrite their values.

use super::super::collision::Relax;
use super::collision::collide;
use super::lattice::Lattice3;
use super::sides::{face_value, Faces};

/// A node that needs the general path.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Special {
    pub x: u32,
    pub solid: bool,
    /// Range of this node's links in the link list.
    pub link_start: u32,
    pub link_end: u32,
}

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
    pub specials: &'a [Special],
    pub row_start: &'a [u32],
    /// Rows whose `y` and `z` neighbours all exist: the bulk loop runs there; the other rows
    /// (next to a non-periodic face) are specials from end to end.
    pub row_bulk: &'a [bool],
    pub links: &'a [Link],
}

impl Ctx<'_> {
    /// Index of population `i` of node `p`.
    #[inline(always)]
    pub fn idx<const Q: usize>(&self, p: [usize; 3], i: usize) -> usize {
        ((p[2] * self.n[1] + p[1]) * Q + i) * self.n[0] + p[0]
    }

    /// The node `p + d`, wrapped along periodic axes; `None` outside a non-periodic one.
    #[inline(always)]
    pub fn neighbour(&self, p: [usize; 3], d: [i32; 3]) -> Option<[usize; 3]> {
        let mut out = [0usize; 3];
        for a in 0..3 {
            let v = p[a] as isize + d[a] as isize;
            let n = self.n[a] as isize;
            out[a] = if (0..n).contains(&v) {
                v as usize
            } else if self.periodic[a] {
                v.rem_euclid(n) as usize
            } else {
                return None;
            };
        }
        Some(out)
    }

    #[inline(always)]
    pub fn is_solid(&self, p: [usize; 3]) -> bool {
        self.solid[(p[2] * self.n[1] + p[1]) * self.n[0] + p[0]]
    }

    /// Row `(y, z)` of direction `i` of the source, shifted so that element `x - 1` is the
    /// value that streams into node `x`, for `x = 1 .. nx-2`.
    #[inline(always)]
    fn shifted<'s, const Q: usize, L: Lattice3<Q>>(&self, src: &'s [f32], y: usize, z: usize, i: usize) -> &'s [f32] {
        let c = L::C[i];
        let ys = (y as isize - c[1] as isize).rem_euclid(self.n[1] as isize) as usize;
        let zs = (z as isize - c[2] as isize).rem_euclid(self.n[2] as isize) as usize;
        let start = ((zs * self.n[1] + ys) * Q + i) * self.n[0] + (1 - c[0]) as usize;
        &src[start..start + self.n[0] - 2]
    }
}

/// Interpolated bounce-back (linear Bouzidi, with the moving-wall term; see
/// [`crate::lbm::boundary`] for the formulas): the population `g_k(x, t+1)` that link `l` brings
/// back from the wall, from the post-collision source.
#[inline]
pub(crate) fn bouzidi<const Q: usize, L: Lattice3<Q>>(c: &Ctx, src: &[f32], p: [usize; 3], l: &Link) -> f32 {
    let k = l.k as usize;
    let i = L::OPP[k];
    let q = l.q;
    let ck = L::C[k];
    let moving = 6.0 * L::W[k] * (ck[0] as f32 * l.uw[0] + ck[1] as f32 * l.uw[1] + ck[2] as f32 * l.uw[2]);
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
        *gi = match c.neighbour(p, L::C[i].map(|v| -v)) {
            Some(s) => src[c.idx::<Q>(s, i)],
            None => face_value::<Q, L>(c, src, p, i),
        };
    }
    for l in links {
        g[l.k as usize] = bouzidi::<Q, L>(c, src, p, l);
    }
    g
}

/// One row `r = z ny + y` of the destination: the bulk loop, then the specials.
#[inline(always)]
pub(crate) fn row<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    c: &Ctx,
    src: &[f32],
    r: usize,
    out: &mut [f32],
) {
    let nx = c.n[0];
    let (y, z) = (r % c.n[1], r / c.n[1]);
    if nx >= 3 && c.row_bulk[r] {
        let n = nx - 2;
        let s: [&[f32]; Q] = std::array::from_fn(|i| &c.shifted::<Q, L>(src, y, z, i)[..n]);
        let mut chunks = out.chunks_exact_mut(nx);
        let o: [&mut [f32]; Q] = std::array::from_fn(|_| chunks.next().expect("a row holds Q direction arrays"));
        for x in 0..n {
            let mut g = [0.0f32; Q];
            for i in 0..Q {
                g[i] = s[i][x];
            }
            collide::<Q, L, OP, FORCED, LES>(&mut g, c.relax, c.force);
            for i in 0..Q {
                o[i][x + 1] = g[i];
            }
        }
    }
    let specials = &c.specials[c.row_start[r] as usize..c.row_start[r + 1] as usize];
    for sp in specials {
        let x = sp.x as usize;
        if sp.solid {
            for i in 0..Q {
                out[i * nx + x] = 0.0;
            }
            continue;
        }
        let links = &c.links[sp.link_start as usize..sp.link_end as usize];
        let mut g = gather::<Q, L>(c, src, [x, y, z], links);
        collide::<Q, L, OP, FORCED, LES>(&mut g, c.relax, c.force);
        for (i, gi) in g.iter().enumerate() {
            out[i * nx + x] = *gi;
        }
    }
}
