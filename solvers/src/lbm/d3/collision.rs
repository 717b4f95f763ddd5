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

use wide::f32x8;

use super::super::collision::{Relax, OMEGA_BULK, OP_BGK};
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

/// One collision of `g` in place. `OP` selects BGK or the regularised operator (any other
/// code), `FORCED` adds Guo forcing with `f`, `LES` the Smagorinsky viscosity (regularised only).
#[inline(always)]
pub fn collide<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    g: &mut [f32; Q],
    relax: Relax,
    f: [f32; 3],
) {
    let (drho, j) = moments::<Q, L>(g);
    let rho = 1.0 + drho;
    let inv_rho = 1.0 / rho;
    let u = if FORCED {
        [0, 1, 2].map(|a| (j[a] + 0.5 * f[a]) * inv_rho)
    } else {
        j.map(|v| v * inv_rho)
    };
    let geq = equilibrium::<Q, L>(drho, u);
    let mut omega = relax.omega;
    if OP == OP_BGK {
        for i in 0..Q {
            g[i] -= omega * (g[i] - geq[i]);
        }
    } else {
        // Pi = sum c c (g - geq): xx, yy, zz, xy, xz, yz.
        let mut p = [0.0f32; 6];
        for i in 0..Q {
            let n = g[i] - geq[i];
            let c = L::C_REF[i].map(|v| v as f32);
            p[0] += c[0] * c[0] * n;
            p[1] += c[1] * c[1] * n;
            p[2] += c[2] * c[2] * n;
            p[3] += c[0] * c[1] * n;
            p[4] += c[0] * c[2] * n;
            p[5] += c[1] * c[2] * n;
        }
        if LES {
            let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + 2.0 * (p[3] * p[3] + p[4] * p[4] + p[5] * p[5])).sqrt();
            let tau = 0.5 * (relax.tau0 + (relax.tau0 * relax.tau0 + relax.les * norm * inv_rho).sqrt());
            omega = 1.0 / tau;
        }
        let k = 1.0 - omega;
        let third_tr = (p[0] + p[1] + p[2]) * (1.0 / 3.0);
        let bulk = (1.0 - OMEGA_BULK) * third_tr;
        let q = [
            k * (p[0] - third_tr) + bulk,
            k * (p[1] - third_tr) + bulk,
            k * (p[2] - third_tr) + bulk,
            k * p[3],
            k * p[4],
            k * p[5],
        ];
        let tr = q[0] + q[1] + q[2];
        for i in 0..Q {
            let c = L::C_REF[i].map(|v| v as f32);
            let qpi = c[0] * c[0] * q[0]
                + c[1] * c[1] * q[1]
                + c[2] * c[2] * q[2]
                + 2.0 * (c[0] * c[1] * q[3] + c[0] * c[2] * q[4] + c[1] * c[2] * q[5])
                - (1.0 / 3.0) * tr;
            g[i] = geq[i] + 4.5 * L::W_REF[i] * qpi;
            if FORCED {
                // First-order non-equilibrium -3 w_i c_i.F/2, relaxed by 1 - omega.
                let cf = c[0] * f[0] + c[1] * f[1] + c[2] * f[2];
                g[i] -= k * 1.5 * L::W_REF[i] * cf;
            }
        }
    }
    if FORCED {
        let s = 1.0 - 0.5 * omega;
        for i in 0..Q {
            let c = L::C_REF[i].map(|v| v as f32);
            let cu = c[0] * u[0] + c[1] * u[1] + c[2] * u[2];
            let mut sf = 0.0;
            for a in 0..3 {
                sf += (3.0 * (c[a] - u[a]) + 9.0 * cu * c[a]) * f[a];
            }
            g[i] += s * L::W_REF[i] * sf;
        }
    }
}

/// Nodes per chunk of [`collide_chunk`].
pub const CHUNK: usize = 128;

/// Nodes per vector block: one AVX register of f32.
const LANES: usize = 8;

/// The velocity set as plain values on the stack. Indexing an associated `const` array with a
/// run-time index makes the compiler copy the whole array each time (the direction loops are
/// not unrolled); these are built once per chunk.
pub struct Tables<const Q: usize> {
    c: [[f32; 3]; Q],
    w: [f32; Q],
}

impl<const Q: usize> Tables<Q> {
    #[inline(always)]
    pub fn of<L: Lattice3<Q>>() -> Self {
        Tables {
            c: L::C.map(|c| c.map(|v| v as f32)),
            w: L::W,
        }
    }
}

/// The shifted equilibrium of direction `c, w` for a block, the same expression as
/// [`equilibrium`] in every lane.
#[inline(always)]
fn eq_lanes(c: [f32; 3], w: f32, drho: f32x8, rho: f32x8, u: &[f32x8; 3], usq: f32x8) -> f32x8 {
    let cu = f32x8::splat(3.0) * (f32x8::splat(c[0]) * u[0] + f32x8::splat(c[1]) * u[1] + f32x8::splat(c[2]) * u[2]);
    f32x8::splat(w) * (drho + rho * (cu + f32x8::splat(0.5) * cu * cu - usq))
}

/// [`collide`] for a block of [`LANES`] nodes, `g[i]` direction `i` of the eight nodes, in place,
/// on explicit 8-wide vectors (`wide::f32x8`; the compiler left to itself shuffled lanes). The
/// loops over directions are not unrolled (`Q` is large); the block's moments and stresses stay in
/// registers across them. Every lane runs exactly the operations of [`collide`] in the same order
/// (IEEE single precision, no fused multiply-add), so the results are bitwise the same.
#[inline(always)]
fn collide_block<const Q: usize, const OP: u8, const FORCED: bool, const LES: bool>(
    g: &mut [f32x8; Q],
    t: &Tables<Q>,
    relax: Relax,
    f: [f32; 3],
) {
    let splat = f32x8::splat;
    let mut drho = splat(0.0);
    let mut u = [splat(0.0); 3];
    for i in 0..Q {
        drho += g[i];
        for a in 0..3 {
            if t.c[i][a] != 0.0 {
                u[a] += splat(t.c[i][a]) * g[i];
            }
        }
    }
    let rho = splat(1.0) + drho;
    let inv_rho = splat(1.0) / rho;
    for a in 0..3 {
        u[a] = if FORCED {
            (u[a] + splat(0.5 * f[a])) * inv_rho
        } else {
            u[a] * inv_rho
        };
    }
    let usq = splat(1.5) * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    let mut omega = splat(relax.omega);
    if OP == OP_BGK {
        for i in 0..Q {
            let e = eq_lanes(t.c[i], t.w[i], drho, rho, &u, usq);
            g[i] -= omega * (g[i] - e);
        }
    } else {
        let mut p = [splat(0.0); 6];
        for i in 0..Q {
            let c = t.c[i];
            let n = g[i] - eq_lanes(c, t.w[i], drho, rho, &u, usq);
            let cc = [c[0] * c[0], c[1] * c[1], c[2] * c[2], c[0] * c[1], c[0] * c[2], c[1] * c[2]];
            for k in 0..6 {
                p[k] += splat(cc[k]) * n;
            }
        }
        if LES {
            let norm = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + splat(2.0) * (p[3] * p[3] + p[4] * p[4] + p[5] * p[5])).sqrt();
            let tau0 = splat(relax.tau0);
            let tau = splat(0.5) * (tau0 + (tau0 * tau0 + splat(relax.les) * norm * inv_rho).sqrt());
            omega = splat(1.0) / tau;
        }
        let k = splat(1.0) - omega;
        let third_tr = (p[0] + p[1] + p[2]) * splat(1.0 / 3.0);
        let bulk = splat(1.0 - OMEGA_BULK) * third_tr;
        for a in 0..3 {
            p[a] = k * (p[a] - third_tr) + bulk;
        }
        for b in 3..6 {
            p[b] = k * p[b];
        }
        let tr = p[0] + p[1] + p[2];
        for i in 0..Q {
            let (c, w) = (t.c[i], t.w[i]);
            let e = eq_lanes(c, w, drho, rho, &u, usq);
            let qpi = splat(c[0] * c[0]) * p[0]
                + splat(c[1] * c[1]) * p[1]
                + splat(c[2] * c[2]) * p[2]
                + splat(2.0) * (splat(c[0] * c[1]) * p[3] + splat(c[0] * c[2]) * p[4] + splat(c[1] * c[2]) * p[5])
                - splat(1.0 / 3.0) * tr;
            g[i] = e + splat(4.5 * w) * qpi;
            if FORCED {
                let cf = c[0] * f[0] + c[1] * f[1] + c[2] * f[2];
                g[i] -= k * splat(1.5) * splat(w) * splat(cf);
            }
        }
    }
    if FORCED {
        let s = splat(1.0) - splat(0.5) * omega;
        for i in 0..Q {
            let (c, w) = (t.c[i], t.w[i]);
            let cu = splat(c[0]) * u[0] + splat(c[1]) * u[1] + splat(c[2]) * u[2];
            let mut sf = splat(0.0);
            for a in 0..3 {
                sf += (splat(3.0) * (splat(c[a]) - u[a]) + splat(9.0) * cu * splat(c[a])) * splat(f[a]);
            }
            g[i] += s * splat(w) * sf;
        }
    }
}

/// [`collide`] for `m <= CHUNK` consecutive nodes: node `k` reads direction `i` from `src[i][k]`
/// and writes it to `out[i][k]`, in blocks of [`LANES`] nodes ([`collide_block`]); a last,
/// partial block is padded with rest-state values that are computed and dropped.
#[inline(always)]
pub fn collide_chunk<const Q: usize, L: Lattice3<Q>, const OP: u8, const FORCED: bool, const LES: bool>(
    src: &[&[f32]; Q],
    m: usize,
    out: &mut [[f32; CHUNK]; Q],
    relax: Relax,
    f: [f32; 3],
) {
    let t = Tables::of::<L>();
    let mut x = 0;
    while x + LANES <= m {
        let mut g = [f32x8::splat(0.0); Q];
        for i in 0..Q {
            let v: [f32; LANES] = src[i][x..x + LANES].try_into().expect("a block is LANES long");
            g[i] = f32x8::new(v);
        }
        collide_block::<Q, OP, FORCED, LES>(&mut g, &t, relax, f);
        for i in 0..Q {
            out[i][x..x + LANES].copy_from_slice(&g[i].to_array());
        }
        x += LANES;
    }
    if x < m {
        let len = m - x;
        let mut g = [f32x8::splat(0.0); Q];
        for i in 0..Q {
            let mut v = [0.0f32; LANES];
            v[..len].copy_from_slice(&src[i][x..m]);
            g[i] = f32x8::new(v);
        }
        collide_block::<Q, OP, FORCED, LES>(&mut g, &t, relax, f);
        for i in 0..Q {
            out[i][x..m].copy_from_slice(&g[i].to_array()[..len]);
        }
    }
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

    #[test]
    fn collisions_conserve_mass_and_momentum() {
        conserves::<19, D3q19>();
        conserves::<27, D3q27>();
    }
}
