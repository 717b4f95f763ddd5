//! Helpers shared by the solver's integration tests.

use hgym_solvers::lbm::D2q9;

/// Mean squared density deviation `<(rho - 1)^2>` over the grid: the acoustic energy (in density;
/// a wave carries as much again in velocity).
pub fn acoustic_energy(s: &D2q9) -> f64 {
    let mut e = 0.0;
    for y in 0..s.ny() {
        for x in 0..s.nx() {
            let (rho, _, _) = s.node(x, y);
            e += ((rho - 1.0) as f64).powi(2);
        }
    }
    e / (s.nx() * s.ny()) as f64
}
