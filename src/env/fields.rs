//! Flow-field snapshots of a running environment (`u`, `v`, `vorticity` on the solver's grid,
//! non-dimensional), for trajectory files (`--fields-every K`). Bodies and non-finite cells are
//! NaN. Lattice-Boltzmann flows: velocities in units of U, vorticity `dv/dx - du/dy` by central
//! differences in U/D (as in the validation plots); Kolmogorov flows: the spectral fields on
//! the periodic square `[0, 2 pi]^2`.

use crate::data::field::Snapshot;
use crate::env::LbmEnv;
use crate::flow::vorticity_field;

/// An environment that can show its flow.
pub trait FlowFields {
    /// The current fields; `episode`, `step` and `t` are left for the trajectory writer.
    fn snapshot(&mut self) -> Snapshot;
}

impl FlowFields for LbmEnv {
    fn snapshot(&mut self) -> Snapshot {
        let s = self.solver();
        let (nx, ny) = (s.nx(), s.ny());
        let d = &self.spec().domain;
        let extent = [d.x[0], d.x[1], d.y[0], d.y[1]];
        let mut rho = vec![0.0f32; nx * ny];
        let mut u = vec![0.0f32; nx * ny];
        let mut v = vec![0.0f32; nx * ny];
        s.macroscopic(&mut rho, &mut u, &mut v);
        let scale = self.units().velocity(1.0) as f32;
        for y in 0..ny {
            for x in 0..nx {
                let c = y * nx + x;
                if s.is_solid(x, y) {
                    (u[c], v[c]) = (f32::NAN, f32::NAN);
                } else {
                    (u[c], v[c]) = (u[c] * scale, v[c] * scale);
                }
            }
        }
        let w = vorticity_field(s, self.units(), extent).values;
        Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx,
            ny,
            extent,
            fields: vec![("u".into(), u), ("v".into(), v), ("vorticity".into(), w)],
        }
    }
}

impl FlowFields for crate::env::kolmogorov::KolmogorovEnv {
    fn snapshot(&mut self) -> Snapshot {
        let s = self.solver();
        let n = s.n();
        let (u, v) = s.velocity();
        let w = s.vorticity();
        let f32s = |x: Vec<f64>| x.into_iter().map(|v| v as f32).collect::<Vec<f32>>();
        let l = 2.0 * std::f64::consts::PI;
        Snapshot {
            episode: 0,
            step: 0,
            t: 0.0,
            nx: n,
            ny: n,
            extent: [0.0, l, 0.0, l],
            fields: vec![("u".into(), f32s(u)), ("v".into(), f32s(v)), ("vorticity".into(), f32s(w))],
        }
    }
}

impl<E: FlowFields + ?Sized> FlowFields for Box<E> {
    fn snapshot(&mut self) -> Snapshot {
        (**self).snapshot()
    }
}
