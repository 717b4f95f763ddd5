//! The west inlet: its velocity profile, which speed U is, a start-up ramp, and the
//! non-reflecting (characteristic) option.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    #[default]
    Uniform,
    /// `u(y) = u_max 4 (y - y0)(y1 - y) / (y1 - y0)^2` across the whole domain height.
    Parabolic,
}

/// Which inlet velocity U is (for Re and the coefficients) when the profile is parabolic.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum VelocityReference {
    #[default]
    Mean,
    Max,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct InletSpec {
    #[serde(default)]
    pub profile: Profile,
    #[serde(default)]
    pub reference_velocity: VelocityReference,
    /// Smooth ramp of the inlet from 0 to full speed over this time (0: impulsive start).
    #[serde(default)]
    pub ramp: f64,
    /// Non-reflecting (characteristic) inlet: the inflow's normal velocity follows outgoing
    /// pressure waves, `u_n = U - c_s (rho - rho_ref)`, with `rho_ref` the inlet's mean density
    /// averaged over this time (L/U); 0 (the default) keeps the rigid velocity inlet, which
    /// reflects them. See `hgym_solvers::lbm::boundary::InletReference`.
    #[serde(default)]
    pub characteristic_time: f64,
}

impl InletSpec {
    /// Peak inlet speed over U.
    pub fn peak_factor(&self) -> f64 {
        match (self.profile, self.reference_velocity) {
            (Profile::Parabolic, VelocityReference::Mean) => 1.5,
            _ => 1.0,
        }
    }

    /// The inlet speed over U at `eta`, the fraction of the domain's height (0 at the south
    /// edge, 1 at the north): 1, or `4 k eta (1 - eta)` with `k` the peak factor.
    pub fn shape(&self, eta: f64) -> f64 {
        match self.profile {
            Profile::Uniform => 1.0,
            Profile::Parabolic => 4.0 * self.peak_factor() * eta * (1.0 - eta),
        }
    }
}
