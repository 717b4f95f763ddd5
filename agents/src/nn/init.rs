//! Weight initialisation.

use serde::{Deserialize, Serialize};

use crate::rng::Rng;

/// How a dense layer's weights and biases start.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Init {
    /// Orthogonal rows or columns scaled by `gain`, zero biases (Saxe et al. 2014; the
    /// PPO implementations' default, e.g. gain sqrt(2) hidden, 0.01 policy head, 1 value head).
    Orthogonal { gain: f64 },
    /// PyTorch's `nn.Linear` default: weights and biases uniform in +-1/sqrt(fan_in)
    /// (what SB3's and CleanRL's TD3/DDPG use).
    FanIn,
}

impl Init {
    /// Samples `(W, b)` for a layer with `rows` outputs and `cols` inputs (W row-major).
    pub fn sample(self, rows: usize, cols: usize, rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
        match self {
            Init::FanIn => {
                let bound = 1.0 / (cols.max(1) as f64).sqrt();
                let w = (0..rows * cols).map(|_| bound * (2.0 * rng.uniform() - 1.0)).collect();
                let b = (0..rows).map(|_| bound * (2.0 * rng.uniform() - 1.0)).collect();
                (w, b)
            }
            Init::Orthogonal { gain } => (orthogonal(rows, cols, gain, rng), vec![0.0; rows]),
        }
    }
}

/// A `rows x cols` matrix with orthonormal rows (rows <= cols) or columns (rows > cols), scaled
/// by `gain`: modified Gram-Schmidt on a Gaussian matrix (the QR construction of Saxe et al.).
fn orthogonal(rows: usize, cols: usize, gain: f64, rng: &mut Rng) -> Vec<f64> {
    // Orthonormalise `k` vectors of length `len`.
    let (k, len) = if rows <= cols { (rows, cols) } else { (cols, rows) };
    let mut v: Vec<Vec<f64>> = (0..k).map(|_| (0..len).map(|_| rng.normal()).collect()).collect();
    for i in 0..k {
        for j in 0..i {
            let d: f64 = v[i].iter().zip(&v[j]).map(|(a, b)| a * b).sum();
            let vj = v[j].clone();
            v[i].iter_mut().zip(&vj).for_each(|(a, b)| *a -= d * b);
        }
        let n = v[i].iter().map(|a| a * a).sum::<f64>().sqrt().max(1e-300);
        v[i].iter_mut().for_each(|a| *a /= n);
    }
    let mut w = vec![0.0; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            w[r * cols + c] = gain * if rows <= cols { v[r][c] } else { v[c][r] };
        }
    }
    w
}
