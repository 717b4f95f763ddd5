//! Integral boundary-layer methods: the momentum thickness, shape factor and skin friction of a
//! layer under a given edge velocity `Ue(s)`, laminar by Thwaites' method up to a trip and
//! turbulent by Head's entrainment method after it (Cebeci & Bradshaw, "Momentum Transfer in
//! Boundary Layers", 1977, secs. 5.2 and 8.2; White, "Viscous Fluid Flow", 3rd ed., 2006,
//! secs. 4-6.6 and 6-8.1).
//!
//! - Thwaites: `theta^2 = 0.45 nu Ue^-6 int_0^s Ue^5 ds`, `lambda = theta^2 Ue' / nu`, `H(lambda)`
//!   and `C_f = 2 nu l(lambda) / (Ue theta)` from Cebeci & Bradshaw's fits.
//! - Head: `d theta/ds = C_f/2 - (H + 2) theta Ue'/Ue`, `d(Ue theta H1)/ds = Ue 0.0306 (H1 - 3)^-0.6169`,
//!   `H1(H)` from Head's fits, `C_f = 0.246 10^(-0.678 H) Re_theta^-0.268` (Ludwieg & Tillmann),
//!   advanced by classical RK4 between the given stations (`Ue` linear between them).
//!
//! The trip keeps `theta` and starts the turbulent layer at `H = 1.4` (a developed layer's value
//! at low `Re_theta`).

/// The layer at one station.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Station {
    pub s: f64,
    pub ue: f64,
    pub theta: f64,
    /// Shape factor `delta* / theta`.
    pub h: f64,
    pub c_f: f64,
    pub turbulent: bool,
}

impl Station {
    pub fn re_theta(&self, nu: f64) -> f64 {
        self.ue * self.theta / nu
    }
    /// Friction velocity `Ue sqrt(C_f / 2)`.
    pub fn u_tau(&self) -> f64 {
        self.ue * (0.5 * self.c_f).sqrt()
    }
}

/// Shape factor a turbulent layer starts at after the trip.
pub const H_TRIP: f64 = 1.4;

/// Thwaites' `H(lambda)` and shear parameter `l(lambda)` (Cebeci & Bradshaw's fits, valid for
/// `-0.1 <= lambda <= 0.1`; clamped to that range).
pub fn thwaites(lambda: f64) -> (f64, f64) {
    let l = lambda.clamp(-0.1, 0.1);
    if l >= 0.0 {
        (2.61 - 3.75 * l + 5.24 * l * l, 0.22 + 1.57 * l - 1.8 * l * l)
    } else {
        (2.088 + 0.0731 / (l + 0.14), 0.22 + 1.402 * l + 0.018 * l / (l + 0.107))
    }
}

/// Head's mass-flow shape factor `H1 = (delta - delta*) / theta` of `H`.
pub fn head_h1(h: f64) -> f64 {
    if h <= 1.6 {
        3.3 + 0.8234 * (h - 1.1).powf(-1.287)
    } else {
        3.3 + 1.5501 * (h - 0.6778).powf(-3.064)
    }
}

/// The inverse of [`head_h1`].
pub fn head_h(h1: f64) -> f64 {
    let split = head_h1(1.6);
    if h1 >= split {
        1.1 + ((h1 - 3.3) / 0.8234).powf(-1.0 / 1.287)
    } else {
        0.6778 + ((h1 - 3.3) / 1.5501).powf(-1.0 / 3.064)
    }
}

/// Ludwieg & Tillmann's skin friction.
pub fn ludwieg_tillmann(h: f64, re_theta: f64) -> f64 {
    0.246 * 10f64.powf(-0.678 * h) * re_theta.powf(-0.268)
}

/// The layer at stations `s` (increasing, from a stagnation point or a leading edge where
/// `Ue(s_0)` may be 0) under edge velocities `ue`, viscosity `nu`, tripped at `s_trip` (use
/// `f64::INFINITY` for a laminar layer, `s[0]` for a turbulent one from the start, which then
/// needs `theta0 > 0`). `theta0` is the momentum thickness at `s[0]` of a turbulent start.
pub fn develop(s: &[f64], ue: &[f64], nu: f64, s_trip: f64, theta0: f64) -> Vec<Station> {
    let n = s.len().min(ue.len());
    let mut out = Vec::with_capacity(n);
    let mut integral = 0.0;
    let mut state: Option<[f64; 2]> = None;
    for k in 0..n {
        if k > 0 {
            integral += 0.5 * (ue[k - 1].powi(5) + ue[k].powi(5)) * (s[k] - s[k - 1]);
        }
        let due = if k + 1 < n {
            (ue[k + 1] - ue[k]) / (s[k + 1] - s[k])
        } else {
            (ue[k] - ue[k - 1]) / (s[k] - s[k - 1])
        };
        if state.is_none() && s[k] >= s_trip {
            let theta = if k == 0 {
                theta0
            } else {
                out.last().map_or(theta0, |p: &Station| p.theta)
            };
            state = Some([theta, ue[k] * theta * head_h1(H_TRIP)]);
        } else if let Some(y) = state {
            state = Some(head_step(y, s[k - 1], s[k], [ue[k - 1], ue[k]], nu));
        }
        out.push(match state {
            None => {
                let theta = if ue[k] > 0.0 {
                    (0.45 * nu * integral / ue[k].powi(6)).sqrt()
                } else {
                    0.0
                };
                // At a stagnation point theta^2 -> 0.075 nu / Ue' (the limit of the integral).
                let theta = if ue[k] > 0.0 {
                    theta
                } else {
                    (0.075 * nu / due.max(f64::MIN_POSITIVE)).sqrt()
                };
                let (h, l) = thwaites(theta * theta * due / nu);
                let c_f = if ue[k] > 0.0 { 2.0 * nu * l / (ue[k] * theta) } else { 0.0 };
                Station {
                    s: s[k],
                    ue: ue[k],
                    theta,
                    h,
                    c_f,
                    turbulent: false,
                }
            }
            Some([theta, y]) => {
                let h = head_h(y / (ue[k] * theta));
                Station {
                    s: s[k],
                    ue: ue[k],
                    theta,
                    h,
                    c_f: ludwieg_tillmann(h, ue[k] * theta / nu),
                    turbulent: true,
                }
            }
        });
    }
    out
}

/// Head's equations for `(theta, Ue theta H1)` from `s0` to `s1`, `Ue` linear in between.
fn head_step(y: [f64; 2], s0: f64, s1: f64, ue: [f64; 2], nu: f64) -> [f64; 2] {
    let ds = s1 - s0;
    let slope = (ue[1] - ue[0]) / ds;
    let f = |t: f64, y: [f64; 2]| -> [f64; 2] {
        let u = ue[0] + slope * t;
        let theta = y[0];
        let h1 = (y[1] / (u * theta)).max(3.0 + 1e-6);
        let h = head_h(h1);
        let c_f = ludwieg_tillmann(h, u * theta / nu);
        [0.5 * c_f - (h + 2.0) * theta * slope / u, u * 0.0306 * (h1 - 3.0).powf(-0.6169)]
    };
    let add = |y: [f64; 2], k: [f64; 2], a: f64| [y[0] + a * k[0], y[1] + a * k[1]];
    let k1 = f(0.0, y);
    let k2 = f(0.5 * ds, add(y, k1, 0.5 * ds));
    let k3 = f(0.5 * ds, add(y, k2, 0.5 * ds));
    let k4 = f(ds, add(y, k3, ds));
    [
        y[0] + ds / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        y[1] + ds / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn head_fits_invert() {
        for h in [1.3, 1.4, 1.55, 1.6, 1.8, 2.2] {
            assert!((head_h(head_h1(h)) - h).abs() < 1e-12, "{h}");
        }
    }

    #[test]
    fn thwaites_on_the_flat_plate_is_within_its_known_one_percent_of_blasius() {
        // Thwaites: theta = 0.6708 sqrt(nu x / U) against Blasius' 0.6641; l(0) = 0.22 against 0.2205.
        let nu = 1e-5;
        let s: Vec<f64> = (0..=200).map(|k| k as f64 * 0.005).collect();
        let st = develop(&s, &vec![1.0; s.len()], nu, f64::INFINITY, 0.0);
        let last = st.last().unwrap();
        let blasius = 0.664_115 * (nu * last.s).sqrt();
        assert!((last.theta / blasius - 1.01).abs() < 0.002, "{}", last.theta / blasius);
        assert!((last.h - 2.61).abs() < 1e-12 && !last.turbulent);
        let cf_blasius = 0.664_115 / (last.s / nu).sqrt();
        assert!((last.c_f / cf_blasius - 1.0).abs() < 0.02, "{}", last.c_f / cf_blasius);
    }

    #[test]
    fn head_on_the_flat_plate_follows_the_coles_fernholz_friction_law() {
        // Nagib, Chauhan & Monkewitz (2007): C_f = 2 [ln(Re_theta) / 0.384 + 4.127]^-2, fitted to
        // zero-pressure-gradient layers from Re_theta 1e3 to 1e5. Head's method with Ludwieg &
        // Tillmann's law is an engineering estimate: within 3 % of it from Re_theta 1500 to 7000.
        let nu = 1e-6;
        let s: Vec<f64> = (0..=4000).map(|k| k as f64 * 0.001).collect();
        let st = develop(&s, &vec![1.0; s.len()], nu, 0.0, 5e-4);
        let mut checked = 0;
        for p in st.iter().filter(|p| p.re_theta(nu) > 1500.0) {
            let re = p.re_theta(nu);
            let coles = 2.0 / (re.ln() / 0.384 + 4.127).powi(2);
            assert!((p.c_f / coles - 1.0).abs() < 0.03, "C_f {} against {coles} at Re_theta {re}", p.c_f);
            assert!((1.3..1.45).contains(&p.h), "H = {}", p.h);
            checked += 1;
        }
        assert!(checked > 1000);
    }
}
