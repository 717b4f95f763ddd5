//! NACA 4-digit aerofoil (Abbott & von Doenhoff, "Theory of Wing Sections", 1959, sec. 6.4).

use super::Shape;

/// NACA `mpxx` aerofoil: maximum camber `m` (fraction of chord) at `p` (fraction of chord),
/// thickness `t` (fraction of chord), chord `chord`, leading edge at `leading_edge`, rotated
/// nose-up by the angle of attack `aoa_deg` about the leading edge.
#[derive(Clone, Debug)]
pub struct Naca4 {
    pub m: f64,
    pub p: f64,
    pub t: f64,
    pub chord: f64,
    pub leading_edge: [f64; 2],
    pub aoa_deg: f64,
    /// Closed outline in body coordinates (x along the chord), counter-clockwise.
    outline: Vec<[f64; 2]>,
}

impl Naca4 {
    /// Builds the aerofoil from its four digits, e.g. `"0012"`, with the closed trailing edge
    /// (coefficient -0.1036) so that the outline is a closed curve.
    pub fn from_digits(digits: &str, chord: f64, leading_edge: [f64; 2], aoa_deg: f64) -> Option<Self> {
        let d: Vec<u32> = digits.chars().map(|c| c.to_digit(10)).collect::<Option<_>>()?;
        if d.len() != 4 {
            return None;
        }
        let m = d[0] as f64 / 100.0;
        let p = d[1] as f64 / 10.0;
        let t = (d[2] * 10 + d[3]) as f64 / 100.0;
        Some(Self::new(m, p, t, chord, leading_edge, aoa_deg))
    }

    pub fn new(m: f64, p: f64, t: f64, chord: f64, leading_edge: [f64; 2], aoa_deg: f64) -> Self {
        let n = 400;
        let mut upper = Vec::with_capacity(n + 1);
        let mut lower = Vec::with_capacity(n + 1);
        for k in 0..=n {
            // Cosine spacing clusters points at the leading and trailing edges.
            let beta = std::f64::consts::PI * k as f64 / n as f64;
            let x = 0.5 * (1.0 - beta.cos());
            let yt = Self::half_thickness(t, x).0;
            let (yc, dyc) = if m == 0.0 || p == 0.0 {
                (0.0, 0.0)
            } else if x < p {
                (m / (p * p) * (2.0 * p * x - x * x), 2.0 * m / (p * p) * (p - x))
            } else {
                (
                    m / ((1.0 - p) * (1.0 - p)) * (1.0 - 2.0 * p + 2.0 * p * x - x * x),
                    2.0 * m / ((1.0 - p) * (1.0 - p)) * (p - x),
                )
            };
            let th = dyc.atan();
            upper.push([(x - yt * th.sin()) * chord, (yc + yt * th.cos()) * chord]);
            lower.push([(x + yt * th.sin()) * chord, (yc - yt * th.cos()) * chord]);
        }
        // Counter-clockwise: trailing edge -> upper surface -> leading edge -> lower surface.
        let mut outline: Vec<[f64; 2]> = upper.into_iter().rev().collect();
        outline.extend(lower.into_iter().skip(1));
        Self {
            m,
            p,
            t,
            chord,
            leading_edge,
            aoa_deg,
            outline,
        }
    }

    /// The closed outline in body coordinates (chord along x from the leading edge at the
    /// origin), counter-clockwise from the trailing edge over the upper surface; 400 cosine-spaced
    /// points per side.
    pub fn outline(&self) -> &[[f64; 2]] {
        &self.outline
    }

    /// Half-thickness `y_t(x)` of a section of thickness `t` (fractions of the chord, closed
    /// trailing edge) and its slope `dy_t/dx`.
    pub fn half_thickness(t: f64, x: f64) -> (f64, f64) {
        let yt = 5.0 * t * (0.2969 * x.sqrt() - 0.1260 * x - 0.3516 * x * x + 0.2843 * x.powi(3) - 0.1036 * x.powi(4));
        let dyt = 5.0 * t * (0.5 * 0.2969 / x.sqrt() - 0.1260 - 2.0 * 0.3516 * x + 3.0 * 0.2843 * x * x - 4.0 * 0.1036 * x.powi(3));
        (yt, dyt)
    }

    /// Body coordinates (x along the chord from the leading edge) -> physical: the nose-up
    /// rotation about the leading edge, then the translation (the inverse of `to_body`).
    pub fn to_physical(&self, b: [f64; 2]) -> [f64; 2] {
        let a = self.aoa_deg.to_radians();
        [
            self.leading_edge[0] + b[0] * a.cos() + b[1] * a.sin(),
            self.leading_edge[1] - b[0] * a.sin() + b[1] * a.cos(),
        ]
    }

    /// Physical point -> body coordinates (undo translation and the nose-up rotation).
    fn to_body(&self, q: [f64; 2]) -> [f64; 2] {
        let a = self.aoa_deg.to_radians();
        let dx = q[0] - self.leading_edge[0];
        let dy = q[1] - self.leading_edge[1];
        // Nose-up rotation by +alpha turns the chord clockwise; invert it.
        [dx * a.cos() - dy * a.sin(), dx * a.sin() + dy * a.cos()]
    }
}

impl Shape for Naca4 {
    /// Distance to the outline polygon, negative inside (even-odd crossing rule).
    fn sdf(&self, q: [f64; 2]) -> f64 {
        let p = self.to_body(q);
        let mut d2 = f64::INFINITY;
        let mut inside = false;
        let n = self.outline.len();
        for k in 0..n {
            let a = self.outline[k];
            let b = self.outline[(k + 1) % n];
            let e = [b[0] - a[0], b[1] - a[1]];
            let w = [p[0] - a[0], p[1] - a[1]];
            let ee = e[0] * e[0] + e[1] * e[1];
            let t = if ee > 0.0 {
                ((w[0] * e[0] + w[1] * e[1]) / ee).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let r = [w[0] - t * e[0], w[1] - t * e[1]];
            d2 = d2.min(r[0] * r[0] + r[1] * r[1]);
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let xc = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < xc {
                    inside = !inside;
                }
            }
        }
        if inside {
            -d2.sqrt()
        } else {
            d2.sqrt()
        }
    }

    fn bounding_box(&self) -> [f64; 4] {
        let mut bb = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
        let a = self.aoa_deg.to_radians();
        for p in &self.outline {
            // body -> physical
            let x = p[0] * a.cos() + p[1] * a.sin() + self.leading_edge[0];
            let y = -p[0] * a.sin() + p[1] * a.cos() + self.leading_edge[1];
            bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x), bb[3].max(y)];
        }
        bb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn naca0012_thickness_and_chord() {
        let f = Naca4::from_digits("0012", 1.0, [0.0, 0.0], 0.0).unwrap();
        // Maximum thickness 12 % of the chord near x = 0.3.
        assert!(f.sdf([0.3, 0.0]) < -0.059 && f.sdf([0.3, 0.0]) > -0.061);
        assert!(f.sdf([0.3, 0.061]) > 0.0);
        assert!(f.sdf([1.01, 0.0]) > 0.0 && f.sdf([0.99, 0.0]) < 0.0);
        assert!(f.sdf([-0.01, 0.0]) > 0.0 && f.sdf([0.01, 0.0]) < 0.0);
        let bb = f.bounding_box();
        assert!((bb[2] - 1.0).abs() < 1e-9 && bb[0].abs() < 1e-9);
    }

    #[test]
    fn angle_of_attack_pitches_the_nose_up() {
        let f = Naca4::from_digits("0012", 1.0, [0.0, 0.0], 20.0).unwrap();
        // The trailing edge moves below the chord line.
        let a = 20f64.to_radians();
        assert!(f.sdf([0.9 * a.cos(), -0.9 * a.sin()]) < 0.0);
        assert!(f.sdf([0.9, 0.0]) > 0.0);
    }
}
