//! Second-order staggered operators of the channel: the momentum right-hand side
//! `-div(u u) + nu lap u + G e_x` (advection in divergence form, centred), the divergence of the
//! velocity and the pressure-gradient correction. Each works on one grid row `(j, k)` (`nx`
//! values) so the caller runs rows in parallel; nothing here allocates.
//!
//! Interpolation to a face between two centres is the plain average (faces sit half-way between
//! centres, see [`super::grid`]); `v` is interpolated from its faces to a centre linearly in `y`.
//! At a no-slip wall `u = w = 0` and `v` is the prescribed transpiration; the wall-normal
//! derivative of `u` and `w` there is that of the quadratic through the wall value and the first
//! two centres, so a quadratic profile (laminar Poiseuille flow) is reproduced exactly. At a
//! free-slip top `v` is prescribed (zero unless a boundary layer's outflow is set) and the
//! derivatives of `u` and `w` vanish.

use super::grid::Grid;

/// Read-only view of the velocity for the operators.
pub struct Fields<'a> {
    pub u: &'a [f64],
    pub v: &'a [f64],
    pub w: &'a [f64],
}

#[inline(always)]
fn next(i: usize, n: usize) -> usize {
    if i + 1 == n {
        0
    } else {
        i + 1
    }
}

#[inline(always)]
fn prev(i: usize, n: usize) -> usize {
    if i == 0 {
        n - 1
    } else {
        i - 1
    }
}

/// Row `(j, k)` of a centre field.
#[inline(always)]
fn row<'a>(g: &Grid, a: &'a [f64], j: usize, k: usize) -> &'a [f64] {
    &a[g.at(0, j, k)..][..g.nx]
}

/// Row `(j, k)` of the face field `v`.
#[inline(always)]
fn row_v<'a>(g: &Grid, a: &'a [f64], j: usize, k: usize) -> &'a [f64] {
    &a[g.at_v(0, j, k)..][..g.nx]
}

/// Right-hand sides of `u` and `w` on cell row `(j, k)`.
pub fn rhs_uw_row(g: &Grid, f: &Fields, nu: f64, drive: f64, j: usize, k: usize, ru: &mut [f64], rw: &mut [f64]) {
    let (nx, nz) = (g.nx, g.nz);
    let (kp, km) = (next(k, nz), prev(k, nz));
    let (idx, idz, idy) = (1.0 / g.dx, 1.0 / g.dz, 1.0 / g.dyf[j]);
    let (idx2, idz2) = (idx * idx, idz * idz);
    let st = &g.stencil[j];
    let (u0, um, up) = (row(g, f.u, j, k), row(g, f.u, st.jm, k), row(g, f.u, st.jp, k));
    let (ukp, ukm) = (row(g, f.u, j, kp), row(g, f.u, j, km));
    let (w0, wm, wp) = (row(g, f.w, j, k), row(g, f.w, st.jm, k), row(g, f.w, st.jp, k));
    let (wkp, wkm) = (row(g, f.w, j, kp), row(g, f.w, j, km));
    let (vlo, vhi) = (row_v(g, f.v, j, k), row_v(g, f.v, j + 1, k));
    let (vlo_km, vhi_km) = (row_v(g, f.v, j, km), row_v(g, f.v, j + 1, km));
    for i in 0..nx {
        let (ip, im) = (next(i, nx), prev(i, nx));

        // u at (x-face i, centre j, centre k).
        let c = u0[i];
        let ue = 0.5 * (c + u0[ip]);
        let uw = 0.5 * (u0[im] + c);
        let conv_x = (ue * ue - uw * uw) * idx;
        let lo = st.lo[0] * c + st.lo[1] * um[i];
        let dlo = st.dlo[0] * c + st.dlo[1] * um[i] + st.dlo[2] * up[i];
        let hi = st.hi[0] * c + st.hi[1] * up[i];
        let dhi = st.dhi[0] * c + st.dhi[1] * up[i] + st.dhi[2] * um[i];
        let conv_y = (hi * 0.5 * (vhi[im] + vhi[i]) - lo * 0.5 * (vlo[im] + vlo[i])) * idy;
        let wt = 0.5 * (wkp[im] + wkp[i]);
        let wb = 0.5 * (w0[im] + w0[i]);
        let conv_z = (0.5 * (c + ukp[i]) * wt - 0.5 * (ukm[i] + c) * wb) * idz;
        let lap = (u0[ip] - 2.0 * c + u0[im]) * idx2 + (dhi - dlo) * idy + (ukp[i] - 2.0 * c + ukm[i]) * idz2;
        ru[i] = -(conv_x + conv_y + conv_z) + nu * lap + drive;

        // w at (centre i, centre j, z-face k).
        let c = w0[i];
        let wn = 0.5 * (c + wkp[i]);
        let ws = 0.5 * (wkm[i] + c);
        let conv_z = (wn * wn - ws * ws) * idz;
        let lo = st.lo[0] * c + st.lo[1] * wm[i];
        let dlo = st.dlo[0] * c + st.dlo[1] * wm[i] + st.dlo[2] * wp[i];
        let hi = st.hi[0] * c + st.hi[1] * wp[i];
        let dhi = st.dhi[0] * c + st.dhi[1] * wp[i] + st.dhi[2] * wm[i];
        let conv_y = (hi * 0.5 * (vhi_km[i] + vhi[i]) - lo * 0.5 * (vlo_km[i] + vlo[i])) * idy;
        let ue = 0.5 * (ukm[ip] + u0[ip]);
        let uw = 0.5 * (ukm[i] + u0[i]);
        let conv_x = (0.5 * (c + w0[ip]) * ue - 0.5 * (w0[im] + c) * uw) * idx;
        let lap = (w0[ip] - 2.0 * c + w0[im]) * idx2 + (dhi - dlo) * idy + (wkp[i] - 2.0 * c + wkm[i]) * idz2;
        rw[i] = -(conv_x + conv_y + conv_z) + nu * lap;
    }
}

/// Right-hand side of `v` on interior face row `(j, k)`, `0 < j < ny`.
pub fn rhs_v_row(g: &Grid, f: &Fields, nu: f64, j: usize, k: usize, rv: &mut [f64]) {
    let (nx, nz) = (g.nx, g.nz);
    let (kp, km) = (next(k, nz), prev(k, nz));
    let (idx, idz) = (1.0 / g.dx, 1.0 / g.dz);
    let (idx2, idz2) = (idx * idx, idz * idz);
    let (hp, hm) = (g.dyf[j], g.dyf[j - 1]);
    let lap_y = 2.0 / (hp + hm);
    let idyc = 1.0 / g.dyc[j];
    // Weights of the linear interpolation of v from faces to the centres j and j - 1.
    let th = (g.yc[j] - g.yf[j]) / hp;
    let tl = (g.yc[j - 1] - g.yf[j - 1]) / hm;
    let (v0, vjp, vjm) = (row_v(g, f.v, j, k), row_v(g, f.v, j + 1, k), row_v(g, f.v, j - 1, k));
    let (vkp, vkm) = (row_v(g, f.v, j, kp), row_v(g, f.v, j, km));
    let (u0, um) = (row(g, f.u, j, k), row(g, f.u, j - 1, k));
    let (w0, wm, w0p, wmp) = (row(g, f.w, j, k), row(g, f.w, j - 1, k), row(g, f.w, j, kp), row(g, f.w, j - 1, kp));
    for i in 0..nx {
        let (ip, im) = (next(i, nx), prev(i, nx));
        let c = v0[i];
        let ue = 0.5 * (um[ip] + u0[ip]);
        let uw = 0.5 * (um[i] + u0[i]);
        let conv_x = (ue * 0.5 * (c + v0[ip]) - uw * 0.5 * (v0[im] + c)) * idx;
        let vch = c + th * (vjp[i] - c);
        let vcl = vjm[i] + tl * (c - vjm[i]);
        let conv_y = (vch * vch - vcl * vcl) * idyc;
        let wn = 0.5 * (wmp[i] + w0p[i]);
        let ws = 0.5 * (wm[i] + w0[i]);
        let conv_z = (wn * 0.5 * (c + vkp[i]) - ws * 0.5 * (vkm[i] + c)) * idz;
        let lap = (v0[ip] - 2.0 * c + v0[im]) * idx2 + lap_y * ((vjp[i] - c) / hp - (c - vjm[i]) / hm) + (vkp[i] - 2.0 * c + vkm[i]) * idz2;
        rv[i] = -(conv_x + conv_y + conv_z) + nu * lap;
    }
}

/// Divergence of the velocity in cell row `(j, k)`.
pub fn divergence_row(g: &Grid, f: &Fields, j: usize, k: usize, div: &mut [f64]) {
    let nx = g.nx;
    let (idx, idz, idy) = (1.0 / g.dx, 1.0 / g.dz, 1.0 / g.dyf[j]);
    let (u0, w0, wkp) = (row(g, f.u, j, k), row(g, f.w, j, k), row(g, f.w, j, next(k, g.nz)));
    let (vlo, vhi) = (row_v(g, f.v, j, k), row_v(g, f.v, j + 1, k));
    for i in 0..nx {
        div[i] = (u0[next(i, nx)] - u0[i]) * idx + (vhi[i] - vlo[i]) * idy + (wkp[i] - w0[i]) * idz;
    }
}

/// Subtracts `grad phi` from `u` and `w` on cell row `(j, k)`.
pub fn correct_uw_row(g: &Grid, phi: &[f64], j: usize, k: usize, u: &mut [f64], w: &mut [f64]) {
    let nx = g.nx;
    let (idx, idz) = (1.0 / g.dx, 1.0 / g.dz);
    let (p0, pkm) = (row(g, phi, j, k), row(g, phi, j, prev(k, g.nz)));
    for i in 0..nx {
        u[i] -= (p0[i] - p0[prev(i, nx)]) * idx;
        w[i] -= (p0[i] - pkm[i]) * idz;
    }
}

/// Subtracts `grad phi` from `v` on interior face row `(j, k)`, `0 < j < ny`.
pub fn correct_v_row(g: &Grid, phi: &[f64], j: usize, k: usize, v: &mut [f64]) {
    let idy = 1.0 / g.dyc[j];
    let (p0, pm) = (row(g, phi, j, k), row(g, phi, j - 1, k));
    for ((v, a), b) in v.iter_mut().zip(p0).zip(pm) {
        *v -= (a - b) * idy;
    }
}
