//! Collision operators for D2Q9, in shifted variables `g_i = f_i - w_i`.
//!
//! Equilibrium (second-order Hermite, Qian et al. 1992):
//! `f_i^eq = w_i rho (1 + 3 c_i.u + 9/2 (c_i.u)^2 - 3/2 u.u)`, so in shifted form
//! `g_i^eq = w_i (drho + rho (3 c_i.u + 9/2 (c_i.u)^2 - 3/2 u.u))` with `drho = rho - 1`.
//!
//! - **BGK**: `g_i* = g_i - omega (g_i - g_i^eq) + S_i`.
//! - **Regularised** (Latt & Chopard, Math. Comput. Simul. 72, 2006): the non-equilibrium part is
//!   replaced by its projection on the second-order Hermite polynomial,
//!   `f_i^neq,reg = w_i / (2 c_s^4) Q_i:Pi^neq`, `Q_i = c_i c_i - c_s^2 I`,
//!   `Pi^neq = sum_i c_i c_i f_i^neq`, and `g_i* = g_i^eq + (1 - omega) f_i^neq,reg + S_i`.
//!   Dropping the ghost (non-hydrodynamic) moments is what keeps it stable at `tau -> 1/2`
//!   (Re 1000-3900 on coarse grids), where BGK blows up. The trace of `Pi^neq` is relaxed with
//!   its own rate [`OMEGA_BULK`] = 1, i.e. a bulk viscosity `c_s^2 (1/omega_b - 1/2) = 1/6`
//!   independent of the shear viscosity (Dellar, PRE 64, 031203, 2001): acoustic waves (the
//!   start-up pulse, the echoes of vortices leaving the domain) die out within a few passes
//!   instead of ringing in the forces, and the incompressible dynamics (div u = O(Ma^2)) are
//!   unchanged.
//! - **Recursive regularised** (Malaspinas, arXiv:1505.06900, 2015; Coreixas, Wissocq, Puigt,
//!   Boussuge & Sagaut, PRE 96, 033306, 2017): the regularised operator plus every Hermite
//!   polynomial D2Q9 can carry beyond second order, `H_xxy`, `H_xyy` and `H_xxyy`. Their equilibrium
//!   coefficients are `rho ux^2 uy`, `rho ux uy^2`, `rho ux^2 uy^2`; their non-equilibrium
//!   coefficients follow recursively from the (relaxed) second-order one,
//!   `a1_xxy = 2 ux a1_xy + uy a1_xx`, `a1_xyy = 2 uy a1_xy + ux a1_yy`,
//!   `a1_xxyy = ux^2 a1_yy + uy^2 a1_xx + 4 ux uy a1_xy`, and
//!   `f_i += w_i [(H_xxy a_xxy + H_xyy a_xyy) / (2 c_s^6) + H_xxyy a_xxyy / (4 c_s^8)]`. The
//!   extra terms are orthogonal to mass, momentum and stress, so the hydrodynamics are those of
//!   the regularised operator; what changes is that the third- and fourth-order moments no longer
//!   sit at the wrong (second-order-equilibrium) values, which is what limits the regularised
//!   operator's stability as `tau -> 1/2`.
//! - **Forcing** (Guo, Zheng & Shi, PRE 65, 2002): `u = (j + F/2) / rho`,
//!   `S_i = (1 - omega/2) w_i [3 (c_i - u) + 9 (c_i.u) c_i] . F`, added after either operator; the
//!   regularised operator keeps the first-order part `-F/2` of `f^neq` (relaxed by `1 - omega`),
//!   so its momentum and stress after collision are those of BGK.
//!
//! `omega = 1 / tau`, kinematic viscosity `nu = c_s^2 (tau - 1/2)`.

use serde::{Deserialize, Serialize};

use super::lattice::{CX, CY, Q, W};

/// Relaxation rate of the trace of the non-equilibrium stress in the regularised operator
/// (bulk viscosity `(1/OMEGA_BULK - 1/2) / 3`).
pub const OMEGA_BULK: f32 = 1.0;

/// Which collision operator the kernel runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Collision {
    /// Single-relaxation-time BGK.
    Bgk,
    /// Regularised BGK (Latt & Chopard 2006).
    #[default]
    Regularized,
    /// Recursive regularised BGK (Malaspinas 2015; Coreixas et al. 2017).
    Recursive,
}

/// Operator codes for the kernels' const generic `OP` (a `Collision` as a number).
pub const OP_BGK: u8 = 0;
/// See [`OP_BGK`].
pub const OP_REG: u8 = 1;
/// See [`OP_BGK`].
pub const OP_RR: u8 = 2;
/// No collision (free streaming), for `hgym bench lbm` only: the 3D kernel's memory traffic with
/// none of its arithmetic, the ceiling its access pattern allows (see `Lbm3::step_streaming_only`).
pub const OP_STREAM: u8 = u8::MAX;

impl Collision {
    /// Smallest `tau - 1/2` the operator is allowed to run with. Below it the scheme has no
    /// stability margin left on any grid this machine can run; the caller refuses the case and
    /// suggests a finer grid or a lower lattice velocity.
    pub fn min_tau_margin(self) -> f64 {
        match self {
            Collision::Bgk => 0.005,
            Collision::Regularized | Collision::Recursive => 2.0e-4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Collision::Bgk => "bgk",
            Collision::Regularized => "regularized",
            Collision::Recursive => "recursive",
        }
    }

    /// Whether the operator filters the non-equilibrium part through Hermite polynomials (and so
    /// accepts the Smagorinsky model).
    pub fn is_regularized(self) -> bool {
        !matches!(self, Collision::Bgk)
    }
}

/// Density deviation and momentum of shifted populations: `drho = sum g_i`, `j = sum c_i g_i`.
#[inline(always)]
pub fn moments(g: &[f32; Q]) -> (f32, f32, f32) {
    let drho = ((g[0] + g[1]) + (g[2] + g[3])) + ((g[4] + g[5]) + (g[6] + g[7])) + g[8];
    let jx = (g[1] - g[3]) + (g[5] - g[6]) + (g[8] - g[7]);
    let jy = (g[2] - g[4]) + (g[5] + g[6]) - (g[7] + g[8]);
    (drho, jx, jy)
}

/// Shifted equilibrium `g_i^eq` for all nine directions, by opposite pairs `(i, j)`: with
/// `cu = 3 c_i.u`, the even part `w (drho + rho (cu^2/2 - 3/2 u.u))` plus or minus the odd part
/// `w rho cu` (the products with the zero components of `c_i` do not fold away in a loop over
/// the directions).
#[inline(always)]
pub fn equilibrium(drho: f32, ux: f32, uy: f32) -> [f32; Q] {
    equilibrium_plus(drho, ux, uy, [0.0; 5])
}

/// [`equilibrium`] plus a part `r` that is even in `c_i`, given per direction class: rest, the
/// x pair, the y pair, the `(1, 1)` diagonal pair, the `(-1, 1)` diagonal pair.
#[inline(always)]
fn equilibrium_plus(drho: f32, ux: f32, uy: f32, r: [f32; 5]) -> [f32; Q] {
    let rho = 1.0 + drho;
    let d = drho - rho * (1.5 * (ux * ux + uy * uy));
    let half_rho = 0.5 * rho;
    let mut e = [0.0f32; Q];
    let mut pair = |i: usize, j: usize, cu: f32, r: f32| {
        let even = W[i] * (d + half_rho * cu * cu) + r;
        let odd = W[i] * rho * cu;
        e[i] = even + odd;
        e[j] = even - odd;
    };
    pair(1, 3, 3.0 * ux, r[1]);
    pair(2, 4, 3.0 * uy, r[2]);
    pair(5, 7, 3.0 * (ux + uy), r[3]);
    pair(6, 8, 3.0 * (uy - ux), r[4]);
    e[0] = W[0] * d + r[0];
    e
}

/// One collision of the shifted populations `g` in place.
///
/// `OP` selects the operator ([`OP_BGK`], [`OP_REG`], [`OP_RR`]), `FORCED` adds Guo forcing with
/// `(fx, fy)`.
#[inline(always)]
pub fn collide<const OP: u8, const FORCED: bool>(g: &mut [f32; Q], omega: f32, fx: f32, fy: f32) {
    collide_les::<OP, FORCED, false>(
        g,
        Relax {
            omega,
            tau0: 1.0 / omega,
            les: 0.0,
        },
        fx,
        fy,
    )
}

/// Relaxation parameters of one collision: `omega = 1/tau0` and the Smagorinsky coefficient
/// `les = 18 sqrt(2) C_s^2` (zero: no subgrid model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relax {
    pub omega: f32,
    pub tau0: f32,
    pub les: f32,
}

impl Relax {
    pub fn new(tau: f64, smagorinsky: f64) -> Self {
        Relax {
            omega: (1.0 / tau) as f32,
            tau0: tau as f32,
            les: (18.0 * 2f64.sqrt() * smagorinsky * smagorinsky) as f32,
        }
    }
}

/// [`collide`] with an optional Smagorinsky subgrid viscosity (`LES`, regularised operators only):
/// `nu_t = (C_s dx)^2 |S|`, with the strain rate taken from the non-equilibrium stress, so the
/// local relaxation time solves `tau^2 - tau0 tau - C_s^2 |Pi^neq| / (sqrt(2) rho c_s^4) = 0`:
/// `tau = (tau0 + sqrt(tau0^2 + 18 sqrt(2) C_s^2 |Pi^neq| / rho)) / 2` (Hou, Sterling, Chen &
/// Doolen, Fields Inst. Commun. 6, 1996; Malaspinas & Sagaut, J. Fluid Mech. 700, 2012). It
/// vanishes in resolved laminar flow and keeps under-resolved flows at Re 1000-3900 stable.
#[inline(always)]
pub fn collide_les<const OP: u8, const FORCED: bool, const LES: bool>(g: &mut [f32; Q], relax: Relax, fx: f32, fy: f32) {
    let omega = relax.omega;
    let (drho, jx, jy) = moments(g);
    let rho = 1.0 + drho;
    let inv_rho = 1.0 / rho;
    let (ux, uy) = if FORCED {
        ((jx + 0.5 * fx) * inv_rho, (jy + 0.5 * fy) * inv_rho)
    } else {
        (jx * inv_rho, jy * inv_rho)
    };
    if OP != OP_BGK {
        let [pxx, pyy, pxy] = non_equilibrium_stress(g, drho, ux, uy);
        let omega = if LES {
            let norm = (pxx * pxx + pyy * pyy + 2.0 * pxy * pxy).sqrt();
            let tau = 0.5 * (relax.tau0 + (relax.tau0 * relax.tau0 + relax.les * norm * inv_rho).sqrt());
            1.0 / tau
        } else {
            omega
        };
        let k = 1.0 - omega;
        // Shear part relaxed with omega, trace (bulk) part with OMEGA_BULK.
        let half_dev = 0.5 * k * (pxx - pyy);
        let half_tr = 0.5 * (1.0 - OMEGA_BULK) * (pxx + pyy);
        let (qxx, qyy, qxy) = (half_tr + half_dev, half_tr - half_dev, k * pxy);
        *g = equilibrium_plus(drho, ux, uy, hermite_part([qxx, qyy, qxy]));
        if OP == OP_RR {
            add_third_and_fourth_order(g, rho, ux, uy, [qxx, qyy, qxy]);
        }
        if FORCED {
            // The non-equilibrium part also has a first-order Hermite component, -F/2 (the
            // equilibrium carries the half-force-shifted momentum); BGK relaxes it by (1 - omega),
            // so keep it here too, or the momentum gains (1 - omega) F / 2 per step.
            // With its own bulk rate the trace of the forcing's stress is relaxed like the rest
            // of the trace (Guo forcing in moment space: (1 - omega_b/2) instead of
            // (1 - omega/2) on the isotropic part `(F.u) I`), added below with the source.
            let bulk = 0.5 * (omega - OMEGA_BULK) * (fx * ux + fy * uy);
            for i in 0..Q {
                let (cx, cy) = (CX[i] as f32, CY[i] as f32);
                g[i] += -k * 1.5 * W[i] * (cx * fx + cy * fy) + bulk * 4.5 * W[i] * (cx * cx + cy * cy - 2.0 / 3.0);
            }
        }
    } else {
        let geq = equilibrium(drho, ux, uy);
        for i in 0..Q {
            g[i] += omega * (geq[i] - g[i]);
        }
    }
    if FORCED {
        let pre = 1.0 - 0.5 * omega;
        // (with LES, `omega` here is the molecular one: the forcing term is a small correction)
        let uf = ux * fx + uy * fy;
        for i in 0..Q {
            let cx = CX[i] as f32;
            let cy = CY[i] as f32;
            let cf = cx * fx + cy * fy;
            let cu = cx * ux + cy * uy;
            g[i] += pre * W[i] * (3.0 * (cf - uf) + 9.0 * cu * cf);
        }
    }
}

/// The recursive-regularised operator's terms beyond second order: equilibrium plus relaxed
/// non-equilibrium coefficients of `H_xxy`, `H_xyy` and `H_xxyy` (module docs), from the density,
/// the velocity and the relaxed second-order non-equilibrium coefficient `q = [xx, yy, xy]`.
///
/// `w_i [(H_xxy a_xxy + H_xyy a_xyy) / (2 c_s^6) + H_xxyy a_xxyy / (4 c_s^8)]` evaluated per
/// direction with `c_s^2 = 1/3` (a test checks it against the formula): rest `a4`; axes
/// `-(a4 + cx a_xyy + cy a_xxy) / 2`; diagonals `(a4 + cy a_xxy + cx a_xyy) / 4`.
/// Written out because floating-point products with the zero components of `c_i` do not fold
/// away, and the loop form cost a third of the kernel's speed.
#[inline(always)]
pub fn add_third_and_fourth_order(g: &mut [f32; Q], rho: f32, ux: f32, uy: f32, q: [f32; 3]) {
    let [qxx, qyy, qxy] = q;
    let (uxx, uyy, uxy) = (ux * ux, uy * uy, ux * uy);
    let a_xxy = rho * uxx * uy + 2.0 * ux * qxy + uy * qxx;
    let a_xyy = rho * uyy * ux + 2.0 * uy * qxy + ux * qyy;
    let a4 = rho * uxx * uyy + uxx * qyy + uyy * qxx + 4.0 * uxy * qxy;
    let (h4, hx, hy) = (0.5 * a4, 0.5 * a_xyy, 0.5 * a_xxy);
    let (d4, dx, dy) = (0.25 * a4, 0.25 * a_xyy, 0.25 * a_xxy);
    g[0] += a4;
    g[1] -= h4 + hx;
    g[3] -= h4 - hx;
    g[2] -= h4 + hy;
    g[4] -= h4 - hy;
    g[5] += d4 + (dy + dx);
    g[6] += d4 + (dy - dx);
    g[7] += d4 - (dy + dx);
    g[8] += d4 - (dy - dx);
}

/// Density deviation, velocity (no forcing) and second-order Hermite projection of the
/// non-equilibrium stress of shifted populations: `Pi^neq = sum_i c_i c_i (g_i - g_i^eq)` as
/// `[xx, yy, xy]`. Applied to post-collision populations of the regularised operator it returns
/// the stress it relaxed to, `(1 - omega) Pi^neq` (trace relaxed by [`OMEGA_BULK`]).
#[inline(always)]
pub fn hermite_stress(g: &[f32; Q]) -> (f32, f32, f32, [f32; 3]) {
    let (drho, jx, jy) = moments(g);
    let inv_rho = 1.0 / (1.0 + drho);
    let (ux, uy) = (jx * inv_rho, jy * inv_rho);
    (drho, ux, uy, non_equilibrium_stress(g, drho, ux, uy))
}

/// `Pi^neq = sum_i c_i c_i (g_i - g_i^eq)` as `[xx, yy, xy]`, computed as `Pi(g) - Pi(g^eq)` with
/// `Pi(g^eq) = drho/3 I + rho u u` (D2Q9 carries the equilibrium's second moments exactly; the
/// shift by `w_i` removes `I/3`).
#[inline(always)]
fn non_equilibrium_stress(g: &[f32; Q], drho: f32, ux: f32, uy: f32) -> [f32; 3] {
    let rho = 1.0 + drho;
    let (s13, s24, s5678) = ((g[1] + g[3]), (g[2] + g[4]), (g[5] + g[6]) + (g[7] + g[8]));
    let third = (1.0 / 3.0) * drho;
    [
        (s13 + s5678) - (third + rho * ux * ux),
        (s24 + s5678) - (third + rho * uy * uy),
        ((g[5] - g[6]) + (g[7] - g[8])) - rho * ux * uy,
    ]
}

/// Shifted populations with density deviation `drho`, velocity `u` and non-equilibrium stress
/// `q = [xx, yy, xy]` carried by the second-order Hermite polynomials only:
/// `g_i = g_i^eq + w_i / (2 c_s^4) Q_i : q` (the inverse of [`hermite_stress`], and exactly the
/// form the regularised collision writes).
#[inline]
pub fn hermite_populations(drho: f32, ux: f32, uy: f32, q: [f32; 3]) -> [f32; Q] {
    equilibrium_plus(drho, ux, uy, hermite_part(q))
}

/// `w_i / (2 c_s^4) Q_i : q` for the stress `q = [xx, yy, xy]`, per direction class (rest, x
/// pair, y pair, `(1, 1)` pair, `(-1, 1)` pair; even in `c_i`, so one value per pair).
#[inline(always)]
fn hermite_part(q: [f32; 3]) -> [f32; 5] {
    let [qxx, qyy, qxy] = q;
    let tr = qxx + qyy;
    [
        -(2.0 / 3.0) * tr,
        (1.0 / 3.0) * qxx - (1.0 / 6.0) * qyy,
        (1.0 / 3.0) * qyy - (1.0 / 6.0) * qxx,
        (1.0 / 12.0) * tr + 0.25 * qxy,
        (1.0 / 12.0) * tr - 0.25 * qxy,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> [f32; Q] {
        let mut g = equilibrium(0.01, 0.05, -0.03);
        let noise = [0.001, -0.002, 0.0015, 0.0007, -0.0011, 0.0003, -0.0004, 0.0009, -0.0002];
        for i in 0..Q {
            g[i] += noise[i] * W[i];
        }
        g
    }

    fn check_conservation<const OP: u8>() {
        let g0 = sample();
        let (r0, jx0, jy0) = moments(&g0);
        let mut g = g0;
        collide::<OP, false>(&mut g, 1.7, 0.0, 0.0);
        let (r1, jx1, jy1) = moments(&g);
        assert!((r1 - r0).abs() < 1e-7, "mass {r0} -> {r1}");
        assert!((jx1 - jx0).abs() < 1e-7 && (jy1 - jy0).abs() < 1e-7);
    }

    #[test]
    fn collisions_conserve_mass_and_momentum() {
        check_conservation::<OP_BGK>();
        check_conservation::<OP_REG>();
        check_conservation::<OP_RR>();
    }

    #[test]
    fn hermite_stress_inverts_hermite_populations_and_reads_the_regularised_collision() {
        let q = [2.0e-3, -1.5e-3, 7.0e-4];
        let g = hermite_populations(0.01, 0.05, -0.03, q);
        let (drho, ux, uy, p) = hermite_stress(&g);
        assert!((drho - 0.01).abs() < 1e-7 && (ux - 0.05).abs() < 1e-6 && (uy + 0.03).abs() < 1e-6);
        for k in 0..3 {
            assert!((p[k] - q[k]).abs() < 1e-7, "{p:?} vs {q:?}");
        }
        // After a regularised collision the stress is (1 - omega) times the deviatoric part
        // (the trace is relaxed with OMEGA_BULK = 1), so rebuilding from it is the identity.
        let mut c = sample();
        collide::<OP_REG, false>(&mut c, 1.7, 0.0, 0.0);
        let (drho, ux, uy, p) = hermite_stress(&c);
        let back = hermite_populations(drho, ux, uy, p);
        for i in 0..Q {
            assert!((back[i] - c[i]).abs() < 1e-7, "direction {i}: {} vs {}", back[i], c[i]);
        }
    }

    /// The pair form of the regularised collision equals the textbook operator evaluated in f64:
    /// `f_i^eq` from `rho, u`, `Pi^neq = sum c c (g - g^eq)`, the deviatoric part relaxed by
    /// `1 - omega` and the trace by `1 - OMEGA_BULK`, `g_i* = g_i^eq + w_i / (2 c_s^4) Q_i : Pi`.
    /// On a state far from equilibrium (a 0.3 instead of 0.25 in one coefficient errs by 1e-5).
    #[test]
    #[allow(clippy::needless_range_loop)] // the sums over directions read like the formulas
    fn the_pair_form_is_the_textbook_regularised_collision() {
        let mut far = equilibrium(0.01, 0.05, -0.03);
        let noise = [0.02, -0.04, 0.03, 0.014, -0.022, 0.006, -0.008, 0.018, -0.004];
        for i in 0..Q {
            far[i] += noise[i] * W[i];
        }
        for omega in [0.6f32, 1.7, 1.98] {
            let g0 = far;
            let mut g = g0;
            collide::<OP_REG, false>(&mut g, omega, 0.0, 0.0);
            let g0 = g0.map(f64::from);
            let drho: f64 = g0.iter().sum();
            let rho = 1.0 + drho;
            let c = |i: usize| [CX[i] as f64, CY[i] as f64];
            let ux = (0..Q).map(|i| c(i)[0] * g0[i]).sum::<f64>() / rho;
            let uy = (0..Q).map(|i| c(i)[1] * g0[i]).sum::<f64>() / rho;
            let w = |i: usize| W[i] as f64;
            let feq = |i: usize| {
                let cu = c(i)[0] * ux + c(i)[1] * uy;
                w(i) * (drho + rho * (3.0 * cu + 4.5 * cu * cu - 1.5 * (ux * ux + uy * uy)))
            };
            let mut pi = [[0.0; 2]; 2];
            for i in 0..Q {
                for (a, row) in pi.iter_mut().enumerate() {
                    for (b, v) in row.iter_mut().enumerate() {
                        *v += c(i)[a] * c(i)[b] * (g0[i] - feq(i));
                    }
                }
            }
            let (k, kb) = (1.0 - omega as f64, 1.0 - OMEGA_BULK as f64);
            let half_tr = 0.5 * (pi[0][0] + pi[1][1]);
            let dev = [[pi[0][0] - half_tr, pi[0][1]], [pi[1][0], pi[1][1] - half_tr]];
            let q = |a: usize, b: usize| k * dev[a][b] + if a == b { kb * half_tr } else { 0.0 };
            for i in 0..Q {
                let mut qq = 0.0;
                for a in 0..2 {
                    for b in 0..2 {
                        let delta = if a == b { 1.0 / 3.0 } else { 0.0 };
                        qq += (c(i)[a] * c(i)[b] - delta) * q(a, b);
                    }
                }
                let textbook = feq(i) + w(i) * 4.5 * qq;
                assert!(
                    (g[i] as f64 - textbook).abs() < 2e-8,
                    "omega {omega}, direction {i}: {} vs {textbook}",
                    g[i]
                );
            }
        }
    }

    #[test]
    fn equilibrium_is_a_fixed_point() {
        let e = equilibrium(0.02, 0.04, 0.01);
        for reg in [false, true] {
            let mut g = e;
            if reg {
                collide::<OP_REG, false>(&mut g, 1.9, 0.0, 0.0);
            } else {
                collide::<OP_BGK, false>(&mut g, 1.9, 0.0, 0.0);
            }
            for i in 0..Q {
                assert!((g[i] - e[i]).abs() < 1e-8);
            }
        }
    }

    /// The written-out terms equal `w_i [(H_xxy a_xxy + H_xyy a_xyy) / (2 c_s^6) + H_xxyy a_xxyy /
    /// (4 c_s^8)]` with the Hermite polynomials evaluated on each `c_i`.
    #[test]
    fn third_and_fourth_order_terms_match_the_hermite_formula() {
        let (rho, ux, uy, q) = (1.02f32, 0.07f32, -0.04f32, [1.3e-3f32, -0.7e-3, 0.9e-3]);
        let mut g = [0.0f32; Q];
        add_third_and_fourth_order(&mut g, rho, ux, uy, q);
        let (ux, uy, rho) = (ux as f64, uy as f64, rho as f64);
        let (qxx, qyy, qxy) = (q[0] as f64, q[1] as f64, q[2] as f64);
        let a_xxy = rho * ux * ux * uy + 2.0 * ux * qxy + uy * qxx;
        let a_xyy = rho * ux * uy * uy + 2.0 * uy * qxy + ux * qyy;
        let a4 = rho * ux * ux * uy * uy + ux * ux * qyy + uy * uy * qxx + 4.0 * ux * uy * qxy;
        let cs2 = 1.0 / 3.0f64;
        for i in 0..Q {
            let (cx, cy) = (CX[i] as f64, CY[i] as f64);
            let h_xxy = (cx * cx - cs2) * cy;
            let h_xyy = (cy * cy - cs2) * cx;
            let h4 = (cx * cx - cs2) * (cy * cy - cs2);
            let expect = W[i] as f64 * ((h_xxy * a_xxy + h_xyy * a_xyy) / (2.0 * cs2.powi(3)) + h4 * a4 / (4.0 * cs2.powi(4)));
            assert!((g[i] as f64 - expect).abs() < 1e-9, "direction {i}: {} vs {expect}", g[i]);
        }
    }

    /// The shifted equilibrium of the recursive-regularised operator: [`equilibrium`] plus the
    /// third- and fourth-order Hermite terms D2Q9 carries (`rho ux^2 uy`, `rho ux uy^2`,
    /// `rho ux^2 uy^2`).
    fn equilibrium_extended(drho: f32, ux: f32, uy: f32) -> [f32; Q] {
        let mut e = equilibrium(drho, ux, uy);
        add_third_and_fourth_order(&mut e, 1.0 + drho, ux, uy, [0.0; 3]);
        e
    }

    #[test]
    fn the_extended_equilibrium_is_the_recursive_operators_fixed_point() {
        let e = equilibrium_extended(0.02, 0.04, 0.01);
        let mut g = e;
        collide::<OP_RR, false>(&mut g, 1.9, 0.0, 0.0);
        for i in 0..Q {
            assert!((g[i] - e[i]).abs() < 1e-8, "direction {i}: {} vs {}", g[i], e[i]);
        }
        // and the second-order equilibrium is not: D2Q9 carries rho ux^2 uy etc.
        let e2 = equilibrium(0.02, 0.04, 0.01);
        assert!((0..Q).any(|i| (e[i] - e2[i]).abs() > 1e-7));
    }

    /// After a recursive collision the third-order Hermite moment is
    /// `a_xxy = rho ux^2 uy + 2 ux q_xy + uy q_xx` with `q = (1 - omega) Pi^neq` the relaxed stress
    /// (a traceless stress, so the bulk rate plays no part).
    #[test]
    fn recursive_third_order_moments_follow_the_recursion() {
        let (drho, ux, uy) = (0.01f32, 0.05f32, -0.03f32);
        // A purely deviatoric, traceless non-equilibrium stress, relaxed with omega alone.
        let q = [1.0e-3, -1.0e-3, 6.0e-4];
        let mut g = hermite_populations(drho, ux, uy, q);
        let omega = 1.6f32;
        collide::<OP_RR, false>(&mut g, omega, 0.0, 0.0);
        let rho = 1.0 + drho;
        let k = 1.0 - omega;
        // Hermite moment a_xxy = sum (cx^2 - c_s^2) cy g_i (the shifted weights' part is zero).
        let cs2 = 1.0 / 3.0f64;
        let m_xxy: f64 = (0..Q).map(|i| g[i] as f64 * (CX[i] * CX[i]) as f64 * CY[i] as f64).sum::<f64>()
            - cs2 * (0..Q).map(|i| g[i] as f64 * CY[i] as f64).sum::<f64>();
        let expect = rho * ux * ux * uy + k * (2.0 * ux * q[2] + uy * q[0]);
        assert!((m_xxy - expect as f64).abs() < 1e-7, "a_xxy {m_xxy} vs {expect}");
    }

    #[test]
    fn guo_forcing_adds_the_force_to_the_momentum() {
        for op in [OP_BGK, OP_REG, OP_RR] {
            let mut g = sample();
            let (_, jx0, jy0) = moments(&g);
            match op {
                OP_BGK => collide::<OP_BGK, true>(&mut g, 1.2, 1e-4, -2e-4),
                OP_REG => collide::<OP_REG, true>(&mut g, 1.2, 1e-4, -2e-4),
                _ => collide::<OP_RR, true>(&mut g, 1.2, 1e-4, -2e-4),
            }
            let (_, jx1, jy1) = moments(&g);
            assert!((jx1 - jx0 - 1e-4).abs() < 1e-8, "operator {op}: {}", jx1 - jx0);
            assert!((jy1 - jy0 + 2e-4).abs() < 1e-8);
        }
    }
}
