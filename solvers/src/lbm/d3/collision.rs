//! Collision in 3D, for any [`Lattice3`], in shifted variables `g_i = f_i - w_i`. The operators
//! are those of the 2D kernel (see [`crate::lbm::collision`] for the references), written once
//! for D3Q19 and D3Q27:
//!
//! - equilibrium `g_i^eq = w_i (drho + rho (3 c_i.u + 9/2 (c_i.u)^2 - 3/2 u.u))`;
//! - **BGK** `g_i* = g_i - omega (g_i - g_i^eq)`;
//! - **regularised** (Latt & Chopard 2006): `g_i* = g_i^eq + w_i 9/2 Q_i : Pi'`, with
//!   `Q_i = c_i c_i - c_s^2 I`, `Pi = sum_i c_i c_i (g_i - g_i^eq)`, its deviatoric part relaxed
//!   with `1 - omega` and its trace with `1 - OMEGA_BULK` (bulk viscosity 1/6, Dellar 2001);
//! - **Smagorinsky** subgrid viscosity on the regularised operator (Hou et al. 1996):
//!   `tau = (tau0 + sqrt(tau0^2 + 18 sqrt(2) C_s^2 |Pi| / rho)) / 2`;
//! - **Guo forcing** `S_i = (1 - omega/2) w_i [3 (c_i - u) + 9 (c_i.u) c_i] . F` with
//!   `u = (j + F/2) / rho`; the regularised operator keeps the first-order part
//!   `-3 w_i c_i.F/2` of the non-equilibrium, relaxed by `1 - omega`, so that its momentum after
//!   collision is that of BGK.
//!
//! The recursive-regularised terms of the 2D kernel are not carried over: D3Q19 lacks `H_xyz`
//! and the fourth-order polynomials, so the recursion would be incomplete there.

use std::ops::{Add, Div, Mul, Neg, Sub};

use wide::f32x8;

use super::super::collision::{Relax, OMEGA_BULK, OP_BGK, OP_STREAM};
use super::super::kernel::{prefetch, PREFETCH_AHEAD};
use super::lattice::Lattice3;

/// Density deviation and momentum: `drho = sum g_i`, `j = sum c_i g_i`.
#[inline(always)]
pub fn moments<const Q: usize, L: Lattice3<Q>>(g: &[f32; Q]) -> (f32, [f32; 3]) {
    let mut drho = 0.0f32;
    let mut j = [0.0f32; 3];
    for i in 0..Q {
        drho += g[i];
        for a in 0..3 {
            if L::C_REF[i][a] != 0 {
                j[a] += L::C_REF[i][a] as f32 * g[i];
            }
        }
    }
    (drho, j)
}

/// Shifted equilibrium for every direction.
#[inline(always)]
pub fn equilibrium<const Q: usize, L: Lattice3<Q>>(drho: f32, u: [f32; 3]) -> [f32; Q] {
    let rho = 1.0 + drho;
    let usq = 1.5 * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    let mut e = [0.0f32; Q];
    for i in 0..Q {
        let c = L::C_REF[i];
        let cu = 3.0 * (c[0] as f32 * u[0] + c[1] as f32 * u[1] + c[2] as f32 * u[2]);
        e[i] = L::W_REF[i] * (drho + rho * (cu + 0.5 * cu * cu - usq));
    }
    e
}

/// Arithmetic the collision runs on: one node (`f32`) or a block of [`LANES`] nodes
/// (`wide::f32x8`, lane-wise IEEE single precision, no fused multiply-add), so that both run the
/// same operations in the same order and give bitwise the same results.
pub trait Lanes: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> + Neg<Output = Self> {
    fn splat(v: f32) -> Self;
    fn sqrt(self) -> Self;
}

impl Lanes for f32 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
}

impl Lanes for f32x8 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
    }
}

/// `acc + s x` for a sign `s` in {-1, 0, 1}. `s` is a constant of the velocity set, so after
/// inlining only the addition or subtraction is left (or nothing).
#[inline(always)]
fn add_signed<V: Lanes>(acc: V, s: i32, x: V) -> V {
    match s {
        0 => acc,
        1 => acc + x,
        _ => acc - x,
    }
}

/// `c . v` for a lattice velocity `c` (components in {-1, 0, 1}) with additions only. Starts
/// from -0, which is exact (`-0 + x = x`) and folds away.
#[inline(always)]
fn dot<V: Lanes>(c: [i32; 3], v: [V; 3]) -> V {
    let mut acc = V::splat(-0.0);
    for a in 0..3 {
        acc = add_signed(acc, c[a], v[a]);
    }
    acc
}

/// Runs `$body` once for each index `$i` below `$n` (at most 27: a direction of D3Q27 or one of
/// its 13 opposite pairs), unrolled. Each `$i` is a literal, so a pair's velocity is a constant in
/// its copy of the body and the sign tests fold away, and a block's populations indexed by it stay
/// in registers instead of a stack array (a loop over 9, 13 or 27 is not unrolled by the
/// compiler, and a dynamic index keeps an array in memory).
macro_rules! unrolled {
    ($n:expr, |$i:ident| $body:block) => {
        unrolled!(@ $n, $i, $body, 0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26)
    };
    (@ $n:expr, $i:ident, $body:block, $($k:literal)*) => {
        $(
            if $k < $n {
                let $i: usize = $k;
                $body
            }
        )*
    };
}

/// One collision of `g` in place, on one node or a block of nodes. `OP` selects BGK, none
/// ([`OP_STREAM`], for the benchmark) or the regularised operator (any other code), `FORCED` adds
/// Guo forcing with `f`, `LES` the Smagorinsky viscosity (regularised only).
///
/// Written on the opposite pairs `(i, i + 1)` of the velocity set ([`Lattice3::PAIRED`]):
/// with `s = g_i + g_o` and `d = g_i - g_o`, the moments are `drho = g_0 + sum s`,
/// `j = sum c d`, `Pi(g) = sum c c s`; the equilibrium of a pair is `a +- b` with the even part
/// `a = w (drho - rho 3/2 u.u + 9/2 rho (c.u)^2)` and the odd part `b = 3 w rho c.u`. The
/// regularised operator's non-equilibrium stress is `Pi(g) - Pi(g^eq)` with the closed form
/// `Pi(g^eq) = drho/3 I + rho u u` (exact for both sets, which are isotropic to fourth order), and
/// its reconstruction `9/2 w Q_i : Pi'` is even in `c`.
#[inline(always)]
pub fn collide_lanes<V: Lanes, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    g: &mut [V; Q],
    relax: Relax,
    f: [f32; 3],
) {
    if OP == OP_STREAM {
        return;
    }
    let () = L::PAIRED;
    let splat = V::splat;
    let pairs = (Q - 1) / 2;
    let c_of = |p: usize| L::C_REF[2 * p + 1];
    let w_of = |p: usize| L::W_REF[2 * p + 1];
    // Moments.
    let mut drho = g[0];
    let mut j = [splat(-0.0); 3];
    let mut pi = [splat(-0.0); 6];
    unrolled!(pairs, |p| {
        let c = c_of(p);
        let s = g[2 * p + 1] + g[2 * p + 2];
        let d = g[2 * p + 1] - g[2 * p + 2];
        drho = drho + s;
        for a in 0..3 {
            j[a] = add_signed(j[a], c[a], d);
            pi[a] = add_signed(pi[a], c[a] * c[a], s);
        }
        pi[3] = add_signed(pi[3], c[0] * c[1], s);
        pi[4] = add_signed(pi[4], c[0] * c[2], s);
        pi[5] = add_signed(pi[5], c[1] * c[2], s);
    });
    let rho = splat(1.0) + drho;
    let inv_rho = splat(1.0) / rho;
    // Explicit arrays throughout (`array::from_fn` and `map` with closures are not inlined
    // into this loop body: a call per element).
    let mut u = j;
    for a in 0..3 {
        u[a] = if FORCED {
            (j[a] + splat(0.5 * f[a])) * inv_rho
        } else {
            j[a] * inv_rho
        };
    }
    let usq = splat(1.5) * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    // Equilibrium of a pair: even part w (base + h (c.u)^2), odd part w (c . r3u).
    let base = drho - rho * usq;
    let h = splat(4.5) * rho;
    let r3u = [splat(3.0) * rho * u[0], splat(3.0) * rho * u[1], splat(3.0) * rho * u[2]];
    let fv = [splat(f[0]), splat(f[1]), splat(f[2])];
    let mut omega = splat(relax.omega);
    if OP == OP_BGK {
        g[0] = g[0] - omega * (g[0] - splat(L::W_REF[0]) * base);
        unrolled!(pairs, |p| {
            let (c, w) = (c_of(p), splat(w_of(p)));
            let cu = dot(c, u);
            let even = w * (base + h * (cu * cu));
            let odd = w * dot(c, r3u);
            let (i, o) = (2 * p + 1, 2 * p + 2);
            g[i] = g[i] - omega * (g[i] - (even + odd));
            g[o] = g[o] - omega * (g[o] - (even - odd));
        });
    } else {
        // Non-equilibrium stress: xx, yy, zz, xy, xz, yz.
        let third_drho = drho * splat(1.0 / 3.0);
        for k in 0..3 {
            pi[k] = pi[k] - (third_drho + rho * (u[k] * u[k]));
        }
        pi[3] = pi[3] - rho * (u[0] * u[1]);
        pi[4] = pi[4] - rho * (u[0] * u[2]);
        pi[5] = pi[5] - rho * (u[1] * u[2]);
        if LES {
            let norm =
                (pi[0] * pi[0] + pi[1] * pi[1] + pi[2] * pi[2] + splat(2.0) * (pi[3] * pi[3] + pi[4] * pi[4] + pi[5] * pi[5])).sqrt();
            let tau0 = splat(relax.tau0);
            let tau = splat(0.5) * (tau0 + (tau0 * tau0 + splat(relax.les) * norm * inv_rho).sqrt());
            omega = splat(1.0) / tau;
        }
        // Relaxed stress times 9/2: deviatoric part by 1 - omega, trace by 1 - OMEGA_BULK;
        // off-diagonal entries doubled (each appears twice in Q : Pi).
        let k = splat(1.0) - omega;
        let third_tr = (pi[0] + pi[1] + pi[2]) * splat(1.0 / 3.0);
        let bulk = splat(1.0 - OMEGA_BULK) * third_tr;
        let mut q = [splat(0.0); 6];
        for m in 0..3 {
            q[m] = splat(4.5) * (k * (pi[m] - third_tr) + bulk);
        }
        for m in 3..6 {
            q[m] = splat(9.0) * (k * pi[m]);
        }
        let q_tr = (q[0] + q[1] + q[2]) * splat(1.0 / 3.0);
        g[0] = splat(L::W_REF[0]) * (base - q_tr);
        unrolled!(pairs, |p| {
            let (c, w) = (c_of(p), splat(w_of(p)));
            let cu = dot(c, u);
            let mut qpi = -q_tr;
            for m in 0..3 {
                qpi = add_signed(qpi, c[m] * c[m], q[m]);
            }
            qpi = add_signed(qpi, c[0] * c[1], q[3]);
            qpi = add_signed(qpi, c[0] * c[2], q[4]);
            qpi = add_signed(qpi, c[1] * c[2], q[5]);
            let even = w * (base + h * (cu * cu) + qpi);
            let mut odd = w * dot(c, r3u);
            if FORCED {
                // First-order non-equilibrium -3 w c.F/2, relaxed by 1 - omega.
                odd = odd - k * (splat(1.5) * w * dot(c, fv));
            }
            g[2 * p + 1] = even + odd;
            g[2 * p + 2] = even - odd;
        });
    }
    if FORCED {
        // Guo: S_i = (1 - omega/2) w [3 (c - u) + 9 (c.u) c] . F, even part
        // (1 - omega/2) w (9 (c.u)(c.F) - 3 u.F), odd part (1 - omega/2) w 3 c.F.
        let sf = splat(1.0) - splat(0.5) * omega;
        let uf3 = splat(3.0) * (u[0] * fv[0] + u[1] * fv[1] + u[2] * fv[2]);
        g[0] = g[0] - sf * splat(L::W_REF[0]) * uf3;
        unrolled!(pairs, |p| {
            let (c, w) = (c_of(p), splat(w_of(p)));
            let cf = dot(c, fv);
            let even = sf * w * (splat(9.0) * dot(c, u) * cf - uf3);
            let odd = sf * w * (splat(3.0) * cf);
            g[2 * p + 1] = g[2 * p + 1] + (even + odd);
            g[2 * p + 2] = g[2 * p + 2] + (even - odd);
        });
    }
}

/// [`collide_lanes`] on one node: the specials' path and the oracle's.
#[inline(always)]
pub fn collide<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    g: &mut [f32; Q],
    relax: Relax,
    f: [f32; 3],
) {
    collide_lanes::<f32, Q, L, OP, FORCED, LES>(g, relax, f)
}

/// A block of nodes the bulk loop collides at once: [`Lanes`] arithmetic on `LANES` nodes,
/// loaded from and stored to the first `LANES` floats of a slice. `wide::f32x8` (AVX2) on every
/// machine; `F32x16` (AVX-512F, [`super::avx512`]) where the CPU has it.
pub trait Block: Lanes {
    const LANES: usize;
    fn load(s: &[f32]) -> Self;
    fn store(self, d: &mut [f32]);
}

impl Block for f32x8 {
    const LANES: usize = 8;
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        f32x8::new(s[..8].try_into().expect("a slice of 8"))
    }
    #[inline(always)]
    fn store(self, d: &mut [f32]) {
        d[..8].copy_from_slice(&self.to_array());
    }
}

/// The pulls across a periodic x axis, which a row's source slices do not hold: `first[i]` for
/// the directions with `c_x = 1` at the row's first node, `last[i]` for `c_x = -1` at its last.
#[derive(Clone, Copy, Default)]
pub struct Ends<'a, const Q: usize> {
    pub first: Option<&'a [f32; Q]>,
    pub last: Option<&'a [f32; Q]>,
}

/// Nodes per chunk of [`collide_chunk`].
pub const CHUNK: usize = 128;

/// The nodes [`collide_chunk`] collides: `m <= CHUNK` consecutive nodes of a row of `n`, from
/// node `x0` on; node `k` reads direction `i` from `src[i][k]` (or from `ends` at the row's two
/// ends).
#[derive(Clone, Copy)]
pub struct Chunk<'a, const Q: usize> {
    pub src: &'a [&'a [f32]; Q],
    pub x0: usize,
    pub m: usize,
    pub n: usize,
    pub ends: Ends<'a, Q>,
    pub relax: Relax,
    pub f: [f32; 3],
}

/// [`collide`] for the nodes of a [`Chunk`], node `k` written to `out[i][k]`: in blocks of
/// `B::LANES` nodes ([`collide_lanes`] on `B`), what is left in blocks of 8 (so a 16-lane `B`
/// wastes no more lanes on a short row than `f32x8` does), and a last, partial block padded with
/// zeros (the rest state) that are computed and dropped. The chunk goes through a buffer in L1
/// rather than straight to the rows: full cache lines, one direction after the other, are what
/// the non-temporal stores need (32-byte stores to 19 or 27 rows at once measured 10-15 % slower,
/// with ordinary stores too).
#[inline(always)]
pub fn collide_chunk<B: Block, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    ch: &Chunk<Q>,
    out: &mut [[f32; CHUNK]; Q],
) {
    let x = full_blocks::<B, Q, L, OP, FORCED, LES>(ch, 0, out);
    let x = full_blocks::<f32x8, Q, L, OP, FORCED, LES>(ch, x, out);
    let (src, m) = (ch.src, ch.m);
    if x < m {
        let len = m - x;
        let mut g = [f32x8::ZERO; Q];
        let mut v = [0.0f32; 8];
        for i in 0..Q {
            v[..len].copy_from_slice(&src[i][x..m]);
            g[i] = f32x8::new(v);
        }
        patch_ends::<f32x8, Q, L>(&mut g, ch.x0 + x, len, ch.n, ch.ends);
        collide_lanes::<f32x8, Q, L, OP, FORCED, LES>(&mut g, ch.relax, ch.f);
        for i in 0..Q {
            out[i][x..m].copy_from_slice(&g[i].to_array()[..len]);
        }
    }
}

/// The whole blocks of `B::LANES` nodes of [`collide_chunk`] from chunk node `x` on; returns
/// where they end.
#[inline(always)]
fn full_blocks<B: Block, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    ch: &Chunk<Q>,
    mut x: usize,
    out: &mut [[f32; CHUNK]; Q],
) -> usize {
    let (src, x0, n) = (ch.src, ch.x0, ch.n);
    let lanes = B::LANES;
    while x + lanes <= ch.m {
        let mut g = [B::splat(0.0); Q];
        unrolled!(Q, |i| {
            g[i] = B::load(&src[i][x..]);
            prefetch(src[i].as_ptr().wrapping_add(x + PREFETCH_AHEAD));
        });
        if x0 + x == 0 || x0 + x + lanes == n {
            patch_ends::<B, Q, L>(&mut g, x0 + x, lanes, n, ch.ends);
        }
        collide_lanes::<B, Q, L, OP, FORCED, LES>(&mut g, ch.relax, ch.f);
        unrolled!(Q, |i| {
            g[i].store(&mut out[i][x..]);
        });
        x += lanes;
    }
    x
}

/// Puts [`Ends`] into the block of `len` nodes at `x` of a row of `m`: lane 0 of the row's first
/// node for the directions that pull across `x = 0` (`c_x = 1`), the last node's lane for those
/// that pull across the other end (`c_x = -1`).
#[inline(always)]
fn patch_ends<B: Block, const Q: usize, L: Lattice3<Q>>(g: &mut [B; Q], x: usize, len: usize, m: usize, ends: Ends<Q>) {
    unrolled!(Q, |i| {
        let c_x = L::C_REF[i][0];
        let lane = match (c_x, ends.first, ends.last) {
            (1, Some(first), _) if x == 0 => Some((0, first[i])),
            (-1, _, Some(last)) if x + len == m => Some((len - 1, last[i])),
            _ => None,
        };
        if let Some((l, v)) = lane {
            // Room for the widest block (16 lanes).
            let mut a = [0.0f32; 16];
            g[i].store(&mut a);
            a[l] = v;
            g[i] = B::load(&a);
        }
    });
}

#[cfg(test)]
mod tests {
    use super::super::lattice::{D3q19, D3q27};
    use super::*;
    use crate::lbm::collision::OP_REG;

    /// Mass and momentum are invariant under every operator (plus `F` with forcing), and the
    /// regularised operator gives BGK's stress when the populations carry no ghost moments.
    fn conserves<const Q: usize, L: Lattice3<Q>>() {
        let relax = Relax::new(0.8, 0.0);
        let u = [0.05, -0.03, 0.02];
        let base = equilibrium::<Q, L>(0.01, u);
        // A traceless stress (second-order Hermite), no mass or momentum: the regularised
        // operator's bulk rate does not enter.
        let mut g = base;
        for i in 0..Q {
            let c = L::C_REF[i].map(|v| v as f32);
            g[i] += 1e-3 * L::W_REF[i] * (c[0] * c[1] + 0.5 * (c[2] * c[2] - c[1] * c[1]));
        }
        let (m0, j0) = moments::<Q, L>(&g);
        let f = [1e-4, 2e-4, -1e-4];
        let mut bgk = g;
        collide::<Q, L, OP_BGK, true, false>(&mut bgk, relax, f);
        let mut reg = g;
        collide::<Q, L, OP_REG, true, false>(&mut reg, relax, f);
        for out in [bgk, reg] {
            let (m, j) = moments::<Q, L>(&out);
            assert!((m - m0).abs() < 1e-7, "{} mass", L::NAME);
            for a in 0..3 {
                assert!(
                    (j[a] - (j0[a] + f[a])).abs() < 1e-7,
                    "{} momentum {a}: {} vs {}",
                    L::NAME,
                    j[a],
                    j0[a] + f[a]
                );
            }
        }
        // Without forcing (whose second-order part has a trace, which only the regularised
        // operator relaxes at the bulk rate) the two agree.
        let (mut bgk, mut reg) = (g, g);
        collide::<Q, L, OP_BGK, false, false>(&mut bgk, relax, [0.0; 3]);
        collide::<Q, L, OP_REG, false, false>(&mut reg, relax, [0.0; 3]);
        for i in 0..Q {
            assert!(
                (bgk[i] - reg[i]).abs() < 2e-7,
                "{} direction {i}: BGK {} regularised {}",
                L::NAME,
                bgk[i],
                reg[i]
            );
        }
    }

    /// The operators as their textbook formulas, direction by direction in double precision
    /// (equilibrium, `Pi = sum c c (g - g^eq)`, `g^eq + 9/2 w Q : Pi'`, Guo's source): the
    /// reference the pair-wise single-precision form is checked against.
    fn direct<const Q: usize, L: Lattice3<Q>>(g: &[f32; Q], op: u8, relax: Relax, f: [f64; 3], les: bool) -> [f64; Q] {
        let c = |i: usize| L::C[i].map(|v| v as f64);
        let w = |i: usize| L::W[i] as f64;
        let g = g.map(|v| v as f64);
        let drho: f64 = g.iter().sum();
        let rho = 1.0 + drho;
        let u: [f64; 3] = std::array::from_fn(|a| ((0..Q).map(|i| c(i)[a] * g[i]).sum::<f64>() + 0.5 * f[a]) / rho);
        let usq = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
        let geq: Vec<f64> = (0..Q)
            .map(|i| {
                let cu = c(i)[0] * u[0] + c(i)[1] * u[1] + c(i)[2] * u[2];
                w(i) * (drho + rho * (3.0 * cu + 4.5 * cu * cu - 1.5 * usq))
            })
            .collect();
        let mut omega = relax.omega as f64;
        let mut out = [0.0; Q];
        if op == OP_BGK {
            for i in 0..Q {
                out[i] = g[i] - omega * (g[i] - geq[i]);
            }
        } else {
            let mut pi = [[0.0; 3]; 3];
            for i in 0..Q {
                for a in 0..3 {
                    for b in 0..3 {
                        pi[a][b] += c(i)[a] * c(i)[b] * (g[i] - geq[i]);
                    }
                }
            }
            if les {
                let norm = pi.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
                let tau0 = relax.tau0 as f64;
                omega = 2.0 / (tau0 + (tau0 * tau0 + relax.les as f64 * norm / rho).sqrt());
            }
            let tr = (pi[0][0] + pi[1][1] + pi[2][2]) / 3.0;
            let mut relaxed = pi;
            for a in 0..3 {
                for b in 0..3 {
                    let iso = if a == b { tr } else { 0.0 };
                    relaxed[a][b] = (1.0 - omega) * (pi[a][b] - iso) + (1.0 - OMEGA_BULK as f64) * iso;
                }
            }
            for i in 0..Q {
                let mut qpi = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        let delta = if a == b { 1.0 / 3.0 } else { 0.0 };
                        qpi += (c(i)[a] * c(i)[b] - delta) * relaxed[a][b];
                    }
                }
                let cf = c(i)[0] * f[0] + c(i)[1] * f[1] + c(i)[2] * f[2];
                out[i] = geq[i] + 4.5 * w(i) * qpi - (1.0 - omega) * 1.5 * w(i) * cf;
            }
        }
        for i in 0..Q {
            let cu = c(i)[0] * u[0] + c(i)[1] * u[1] + c(i)[2] * u[2];
            let s: f64 = (0..3).map(|a| (3.0 * (c(i)[a] - u[a]) + 9.0 * cu * c(i)[a]) * f[a]).sum();
            out[i] += (1.0 - 0.5 * omega) * w(i) * s;
        }
        out
    }

    /// A state near equilibrium with a random velocity and random non-equilibrium parts, from
    /// a fixed linear congruential sequence.
    fn state<const Q: usize, L: Lattice3<Q>>(seed: u64) -> [f32; Q] {
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let u = [0.2 * next(), 0.2 * next(), 0.2 * next()];
        let mut g = equilibrium::<Q, L>(0.05 * next(), u);
        for (i, gi) in g.iter_mut().enumerate() {
            *gi += 0.02 * L::W[i] * next();
        }
        g
    }

    fn matches_direct<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>() {
        let relax = Relax::new(0.56, if LES { 0.17 } else { 0.0 });
        let f = if FORCED { [2e-4, -1e-4, 3e-4] } else { [0.0; 3] };
        let mut worst = 0.0f64;
        for seed in 0..200 {
            let g0 = state::<Q, L>(seed);
            let mut g = g0;
            collide::<Q, L, OP, FORCED, LES>(&mut g, relax, f);
            let want = direct::<Q, L>(&g0, OP, relax, f.map(|v| v as f64), LES);
            for i in 0..Q {
                worst = worst.max((g[i] as f64 - want[i]).abs() / L::W[i] as f64);
            }
        }
        // Single-precision round-off on values of order w: a wrong term (a sign, a factor, a
        // missing part of the stress) is of order 1e-3 of w or more.
        assert!(worst < 2e-6, "{} op {OP} forced {FORCED} les {LES}: off by {worst:.2e} w", L::NAME);
    }

    #[test]
    fn pairwise_collision_matches_the_direct_formulas() {
        fn all<const Q: usize, L: Lattice3<Q>>() {
            matches_direct::<Q, L, OP_BGK, false, false>();
            matches_direct::<Q, L, OP_BGK, true, false>();
            matches_direct::<Q, L, OP_REG, false, false>();
            matches_direct::<Q, L, OP_REG, true, false>();
            matches_direct::<Q, L, OP_REG, false, true>();
            matches_direct::<Q, L, OP_REG, true, true>();
        }
        all::<19, D3q19>();
        all::<27, D3q27>();
    }

    /// Different nodes collided as one vector block give, lane by lane, what each gives alone,
    /// for every operator and both block widths (16 lanes only where the CPU has AVX-512F).
    fn block_is_its_nodes<B: Block, const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>() {
        let relax = Relax::new(0.56, if LES { 0.17 } else { 0.0 });
        let f = [2e-4, -1e-4, 3e-4];
        let nodes: Vec<[f32; Q]> = (0..B::LANES as u64).map(state::<Q, L>).collect();
        let mut block = [B::splat(0.0); Q];
        for i in 0..Q {
            let lanes: Vec<f32> = nodes.iter().map(|g| g[i]).collect();
            block[i] = B::load(&lanes);
        }
        collide_lanes::<B, Q, L, OP, FORCED, LES>(&mut block, relax, f);
        for (l, node) in nodes.iter().enumerate() {
            let mut g = *node;
            collide::<Q, L, OP, FORCED, LES>(&mut g, relax, f);
            for i in 0..Q {
                let mut out = vec![0.0f32; B::LANES];
                block[i].store(&mut out);
                assert_eq!(
                    out[l].to_bits(),
                    g[i].to_bits(),
                    "{} {} lanes, op {OP} forced {FORCED} les {LES}: lane {l} direction {i}",
                    L::NAME,
                    B::LANES
                );
            }
        }
    }

    fn blocks_are_their_nodes<B: Block>() {
        fn all<B: Block, const Q: usize, L: Lattice3<Q>>() {
            block_is_its_nodes::<B, Q, L, OP_BGK, false, false>();
            block_is_its_nodes::<B, Q, L, OP_BGK, true, false>();
            block_is_its_nodes::<B, Q, L, OP_REG, false, false>();
            block_is_its_nodes::<B, Q, L, OP_REG, true, true>();
        }
        all::<B, 19, D3q19>();
        all::<B, 27, D3q27>();
    }

    #[test]
    fn a_block_is_bitwise_its_nodes() {
        blocks_are_their_nodes::<f32x8>();
        #[cfg(target_arch = "x86_64")]
        if super::super::super::kernel::avx512_available() {
            blocks_are_their_nodes::<super::super::avx512::F32x16>();
        } else {
            eprintln!("no AVX-512F on this CPU: the 16-lane block is not tested");
        }
    }

    #[test]
    fn collisions_conserve_mass_and_momentum() {
        conserves::<19, D3q19>();
        conserves::<27, D3q27>();
    }
}
