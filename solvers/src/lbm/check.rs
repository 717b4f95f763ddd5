//! Blow-up detection: per-row extremes of density and speed, and the first NaN.

use super::collision::moments;
use super::post::Post;

#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RowStat {
    pub nan_at: Option<usize>,
    /// (value, x)
    pub rho_min: (f32, usize),
    pub rho_max: (f32, usize),
    pub u2_max: (f32, usize),
}

pub(crate) fn scan_row(f: &Post, solid: &[bool], nx: usize, y: usize) -> RowStat {
    let mut st = RowStat {
        nan_at: None,
        rho_min: (f32::INFINITY, 0),
        rho_max: (f32::NEG_INFINITY, 0),
        u2_max: (0.0, 0),
    };
    for x in 0..nx {
        if solid[y * nx + x] {
            continue;
        }
        let g = f.node(x, y);
        if g.iter().any(|v| !v.is_finite()) {
            st.nan_at = Some(x);
            return st;
        }
        let (drho, jx, jy) = moments(&g);
        let rho = 1.0 + drho;
        let u2 = (jx * jx + jy * jy) / (rho * rho);
        if rho < st.rho_min.0 {
            st.rho_min = (rho, x);
        }
        if rho > st.rho_max.0 {
            st.rho_max = (rho, x);
        }
        if u2 > st.u2_max.0 {
            st.u2_max = (u2, x);
        }
    }
    st
}
