//! One sentence per environment and level on how its uncontrolled flow stands against the
//! literature, for the leaderboard: the committed row of `hgym validate --env` for the
//! lattice-Boltzmann flows with references; for the channels, the calibrated wall shear stress
//! (`hgym envs calibrate`) as `Re_tau` and `C_f` against their references; for the Kolmogorov flow
//! at Re 40, the calibrated mean dissipation against the quiet level of its burst case; otherwise
//! a statement that hgym bundles no reference for the flow.

use super::{known, Known};
use crate::env::channel::ChannelSpec;
use crate::env::kolmogorov::KolmogorovSpec;
use crate::env::Spec;
use crate::flow::Level;

/// The sentence for `spec`'s uncontrolled flow at `level` (see the module's doc).
pub fn sentence(spec: &Spec, level: Level) -> String {
    if let Some(s) = spec.downcast::<ChannelSpec>() {
        return channel(s);
    }
    if let Some(s) = spec.downcast::<KolmogorovSpec>() {
        return kolmogorov(s);
    }
    match known(spec, level) {
        Known::Measured(e) => e.describe(),
        Known::NotMeasured => format!(
            "not measured against the literature (`hgym validate --env {} --level {}` measures it)",
            spec.id(),
            level.name()
        ),
        Known::NoReference => no_reference(spec.id()),
    }
}

fn no_reference(id: &str) -> String {
    format!("hgym bundles no literature reference for the uncontrolled flow of {id}")
}

fn not_calibrated(id: &str) -> String {
    format!("its uncontrolled statistics are not calibrated (`hgym envs calibrate {id}` measures them)")
}

fn pct(measured: f64, reference: f64) -> String {
    format!("{:+.1} %", 100.0 * (measured / reference - 1.0))
}

/// `Re_tau = u_tau h / nu = sqrt(tau_w) Re_b` and `C_f = tau_w / (U_b^2 / 2)` in outer units
/// (`h = U_b = 1`), against the spec's nominal `Re_tau` and, for the closed channel at the
/// validation case's `Re_b`, Moser, Kim & Mansour's `C_f`.
fn channel(s: &ChannelSpec) -> String {
    let st = &s.statistics;
    if st.tau_w <= 0.0 {
        return not_calibrated(&s.id);
    }
    let re_tau = st.tau_w.sqrt() * s.reynolds_bulk;
    let c_f = 2.0 * st.tau_w;
    let mut text = format!("Re_tau {re_tau:.1} ({} against the nominal {:.0})", pct(re_tau, s.re_tau), s.re_tau);
    if let Ok(case) = crate::validate::channel::case() {
        if s.top == hgym_solvers::channel::Top::Wall && s.reynolds_bulk == case.reynolds_bulk {
            let reference = case.checks.c_f[0];
            text += &format!(
                ", C_f {c_f:.2e} ({} against the {reference:.2e} of the {} case)",
                pct(c_f, reference),
                case.case
            );
        }
    }
    format!(
        "{text}, over {:.0} h/U_b at the {} level (`hgym envs calibrate {}`); `hgym validate channel` checks the solver against the DNS profiles",
        st.time, st.level, s.id
    )
}

/// The mean of `D / D_lam`, `D_lam = Re / (2 k_f^2)`, against the burst case's quiet range.
fn kolmogorov(s: &KolmogorovSpec) -> String {
    let case = match super::kolmogorov::case() {
        Ok(c) if c.reynolds as f64 == s.reynolds => c,
        _ => return no_reference(&s.id),
    };
    let st = &s.statistics;
    if st.dissipation_mean <= 0.0 {
        return not_calibrated(&s.id);
    }
    let d_lam = s.reynolds / (2.0 * (s.kf as f64).powi(2));
    let ratio = st.dissipation_mean / d_lam;
    let [lo, hi] = case.checks.mean_d_over_dlam;
    let verdict = if (lo..=hi).contains(&ratio) { "within" } else { "outside" };
    format!(
        "mean D/D_lam {ratio:.3} over {:.0} time units at the {} level (`hgym envs calibrate {}`), {verdict} the quiet range [{lo}, {hi}] of the {} case; `hgym validate kolmogorov` checks its bursts",
        st.time, st.level, s.id, case.case
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every registered environment gets a sentence; the calibrated channel's names its
    /// `Re_tau` against the nominal value, and a flow without references says so.
    #[test]
    fn every_environment_has_a_sentence() {
        for spec in crate::env::registry::all() {
            assert!(!sentence(&spec, Level::Coarse).is_empty(), "{}", spec.id());
        }
        let tcf = crate::env::lookup("TCF_3D_Retau180").unwrap();
        let s = tcf.downcast::<ChannelSpec>().unwrap();
        let text = sentence(&tcf, Level::Default);
        if s.statistics.tau_w > 0.0 {
            let re_tau = s.statistics.tau_w.sqrt() * s.reynolds_bulk;
            assert!(text.starts_with(&format!("Re_tau {re_tau:.1}")), "{text}");
            assert!(text.contains("C_f"), "{text}");
        }
        let cavity = crate::env::lookup("Cavity_3D_Re4200").unwrap();
        assert!(sentence(&cavity, Level::Coarse).contains("no literature reference"));
    }
}
