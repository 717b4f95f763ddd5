//! Conversion between the paper's non-dimensional units (reference length L = 1, reference
//! velocity U = 1, time in L/U, pressure in rho U^2) and lattice units (dx = dt = 1, rho0 = 1).

use serde::{Deserialize, Serialize};

/// Lattice resolution of one reference length, lattice value of the reference velocity, and the
/// Reynolds number `Re = U L / nu`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// Cells per reference length (e.g. cells per cylinder diameter).
    pub cells_per_length: f64,
    /// Reference velocity in lattice units (`U dt / dx`, i.e. the lattice Mach number times
    /// `c_s`).
    pub u_lattice: f64,
    pub reynolds: f64,
}

impl Units {
    /// Lattice kinematic viscosity `nu = U L / Re`.
    pub fn nu(&self) -> f64 {
        self.u_lattice * self.cells_per_length / self.reynolds
    }

    /// BGK relaxation time `tau = 3 nu + 1/2`.
    pub fn tau(&self) -> f64 {
        3.0 * self.nu() + 0.5
    }

    /// Lattice Mach number `U / c_s`.
    pub fn mach(&self) -> f64 {
        self.u_lattice * 3f64.sqrt()
    }

    /// Non-dimensional time advanced by one lattice step: `dt U / L`.
    pub fn time_per_step(&self) -> f64 {
        self.u_lattice / self.cells_per_length
    }

    /// Number of lattice steps in a non-dimensional time span (rounded to nearest).
    pub fn steps(&self, time: f64) -> u64 {
        (time / self.time_per_step()).round().max(0.0) as u64
    }

    /// Physical length of one cell.
    pub fn dx(&self) -> f64 {
        1.0 / self.cells_per_length
    }

    /// Force coefficient `C = F / (1/2 rho U^2 L)` of a lattice force per unit depth.
    pub fn force_coefficient(&self, f_lattice: f64) -> f64 {
        f_lattice / (0.5 * self.u_lattice * self.u_lattice * self.cells_per_length)
    }

    /// Non-dimensional velocity of a lattice velocity.
    pub fn velocity(&self, u_lattice: f64) -> f64 {
        u_lattice / self.u_lattice
    }

    /// Lattice velocity of a non-dimensional velocity.
    pub fn lattice_velocity(&self, u: f64) -> f64 {
        u * self.u_lattice
    }

    /// Non-dimensional pressure deviation `p / (rho U^2)` of a lattice density:
    /// `p - p0 = c_s^2 (rho - 1)`.
    pub fn pressure(&self, rho: f64) -> f64 {
        (rho - 1.0) / 3.0 / (self.u_lattice * self.u_lattice)
    }

    /// Non-dimensional vorticity of a lattice vorticity (units 1/dt): `omega L / U`.
    pub fn vorticity(&self, w_lattice: f64) -> f64 {
        w_lattice * self.cells_per_length / self.u_lattice
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips() {
        let u = Units {
            cells_per_length: 20.0,
            u_lattice: 0.05,
            reynolds: 100.0,
        };
        assert!((u.nu() - 0.01).abs() < 1e-15);
        assert!((u.tau() - 0.53).abs() < 1e-12);
        assert_eq!(u.steps(1.0), 400);
        assert!((u.velocity(u.lattice_velocity(0.7)) - 0.7).abs() < 1e-15);
    }
}
