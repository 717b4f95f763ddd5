//! Adam (Kingma & Ba 2015) with bias correction, as PyTorch implements it, and global-norm
//! gradient clipping.

use serde::{Deserialize, Serialize};

use super::scalar::Scalar;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Adam<T: Scalar> {
    pub lr: f64,
    pub beta1: f64,
    pub beta2: f64,
    pub eps: f64,
    m: Vec<T>,
    v: Vec<T>,
    t: u64,
}

impl<T: Scalar> Adam<T> {
    pub fn new(n: usize, lr: f64) -> Self {
        Adam {
            lr,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            m: vec![T::ZERO; n],
            v: vec![T::ZERO; n],
            t: 0,
        }
    }

    /// `m <- b1 m + (1-b1) g; v <- b2 v + (1-b2) g^2; p <- p - lr mhat / (sqrt(vhat) + eps)`.
    pub fn step(&mut self, params: &mut [T], grad: &[T]) {
        assert_eq!(params.len(), self.m.len());
        assert_eq!(grad.len(), self.m.len());
        self.t += 1;
        let (b1, b2) = (T::from_f64(self.beta1), T::from_f64(self.beta2));
        let (c1, c2) = (T::ONE - b1, T::ONE - b2);
        let bc1 = 1.0 - self.beta1.powi(self.t.min(i32::MAX as u64) as i32);
        let bc2 = 1.0 - self.beta2.powi(self.t.min(i32::MAX as u64) as i32);
        let step = T::from_f64(self.lr / bc1);
        let bc2_sqrt = T::from_f64(bc2.sqrt());
        let eps = T::from_f64(self.eps);
        for (((p, g), m), v) in params.iter_mut().zip(grad).zip(&mut self.m).zip(&mut self.v) {
            *m = b1 * *m + c1 * *g;
            *v = b2 * *v + c2 * *g * *g;
            *p -= step * *m / (v.sqrt() / bc2_sqrt + eps);
        }
    }
}

/// Scales `grad` so that its Euclidean norm is at most `max_norm`; returns the norm before.
pub fn clip_grad_norm<T: Scalar>(grad: &mut [T], max_norm: f64) -> f64 {
    let norm = grad.iter().map(|g| g.to_f64() * g.to_f64()).sum::<f64>().sqrt();
    if norm > max_norm && norm > 0.0 {
        let s = T::from_f64(max_norm / norm);
        grad.iter_mut().for_each(|g| *g *= s);
    }
    norm
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Adam minimises a quadratic; the first step moves every coordinate by lr (sign of grad).
    #[test]
    fn adam_first_step_and_convergence() {
        let mut p = vec![1.0f64, -2.0];
        let mut opt = Adam::new(2, 0.1);
        opt.step(&mut p, &[4.0, -0.5]);
        assert!((p[0] - 0.9).abs() < 1e-6 && (p[1] + 1.9).abs() < 1e-6);
        for _ in 0..2000 {
            let g = [2.0 * p[0], 2.0 * p[1]];
            opt.step(&mut p, &g);
        }
        assert!(p[0].abs() < 1e-3 && p[1].abs() < 1e-3, "{p:?}");
    }

    #[test]
    fn clipping_bounds_the_norm() {
        let mut g = vec![3.0f32, 4.0];
        assert_eq!(clip_grad_norm(&mut g, 1.0), 5.0);
        assert!((g[0] - 0.6).abs() < 1e-6 && (g[1] - 0.8).abs() < 1e-6);
    }
}
