//! Scalar fields on the grid for plots and snapshots, and the vorticity of a solution.

use hgym_solvers::lbm::{D2q9, Units};

/// A scalar field on the grid, for plots (`NaN` inside bodies).
#[derive(Clone, Debug)]
pub struct Field {
    pub nx: usize,
    pub ny: usize,
    /// Physical extent `[x0, x1, y0, y1]`.
    pub extent: [f64; 4],
    pub values: Vec<f32>,
}

/// Vorticity `w = dv/dx - du/dy` by central differences, in units of U/L; NaN in bodies and
/// wherever the field is not finite.
pub fn vorticity_field(s: &D2q9, units: &Units, extent: [f64; 4]) -> Field {
    let (nx, ny) = (s.nx(), s.ny());
    let mut rho = vec![0.0f32; nx * ny];
    let mut ux = vec![0.0f32; nx * ny];
    let mut uy = vec![0.0f32; nx * ny];
    s.macroscopic(&mut rho, &mut ux, &mut uy);
    let mut w = vec![f32::NAN; nx * ny];
    for y in 1..ny - 1 {
        for x in 1..nx - 1 {
            if s.is_solid(x, y) {
                continue;
            }
            let dvdx = 0.5 * (uy[y * nx + x + 1] - uy[y * nx + x - 1]);
            let dudy = 0.5 * (ux[(y + 1) * nx + x] - ux[(y - 1) * nx + x]);
            w[y * nx + x] = units.vorticity((dvdx - dudy) as f64) as f32;
        }
    }
    Field { nx, ny, extent, values: w }
}

/// Spanwise vorticity `w_z = dv/dx - du/dy` in a z plane of a 3D flow, `plane` as
/// [`super::LbmFlow3::velocity_plane`] gathers it, `nx` by `ny` (central differences, units of
/// U/L; NaN in bodies).
pub fn plane_vorticity(plane: &[Option<[f64; 3]>], [nx, ny]: [usize; 2], units: &Units, extent: [f64; 4]) -> Field {
    let mut w = vec![f32::NAN; nx * ny];
    // Solid nodes count as resting fluid in the differences.
    let u = |x: usize, y: usize| plane[y * nx + x].unwrap_or([0.0; 3]);
    for y in 1..ny.saturating_sub(1) {
        for x in 1..nx.saturating_sub(1) {
            if plane[y * nx + x].is_none() {
                continue;
            }
            let dvdx = 0.5 * (u(x + 1, y)[1] - u(x - 1, y)[1]);
            let dudy = 0.5 * (u(x, y + 1)[0] - u(x, y - 1)[0]);
            w[y * nx + x] = units.vorticity(dvdx - dudy) as f32;
        }
    }
    Field { nx, ny, extent, values: w }
}
