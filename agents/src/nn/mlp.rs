//! A multilayer perceptron with a hand-written backward pass (reverse-mode through dense layers
//! `y = act(x W^T + b)`), batched, whose matrix products call `matrixmultiply`'s GEMM.
//!
//! Parameters live in one flat vector (per layer: `W` out x in row-major, then `b`), so Adam,
//! soft target updates and checkpoints are loops over one slice. Activations of the last
//! forward pass live in a [`Tape`] that is reused between calls: after the first call at a batch
//! size, forward and backward allocate nothing.

use serde::{Deserialize, Serialize};

use super::init::Init;
use super::scalar::Scalar;
use crate::rng::Rng;

/// Elementwise nonlinearity; its derivative is written in terms of the output `y`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    Identity,
    Tanh,
    Relu,
}

impl Activation {
    fn apply<T: Scalar>(self, y: &mut [T]) {
        match self {
            Activation::Identity => {}
            Activation::Tanh => y.iter_mut().for_each(|v| *v = v.tanh()),
            Activation::Relu => y.iter_mut().for_each(|v| {
                if *v < T::ZERO {
                    *v = T::ZERO
                }
            }),
        }
    }

    /// `delta <- delta * act'(.)` where the derivative is expressed through the output `y`:
    /// tanh' = 1 - y^2, relu' = [y > 0].
    fn backprop<T: Scalar>(self, y: &[T], delta: &mut [T]) {
        match self {
            Activation::Identity => {}
            Activation::Tanh => delta.iter_mut().zip(y).for_each(|(d, y)| *d *= T::ONE - *y * *y),
            Activation::Relu => delta.iter_mut().zip(y).for_each(|(d, y)| {
                if *y <= T::ZERO {
                    *d = T::ZERO
                }
            }),
        }
    }
}

/// Dense layers `sizes[0] -> sizes[1] -> ... -> sizes[L]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(bound = "")]
pub struct Mlp<T: Scalar> {
    pub sizes: Vec<usize>,
    pub hidden: Activation,
    pub output: Activation,
    pub params: Vec<T>,
}

/// Activations of one forward pass and scratch for the backward pass.
#[derive(Clone, Debug, Default)]
pub struct Tape<T: Scalar> {
    batch: usize,
    /// `acts[0]` the input, `acts[l + 1]` the output of layer `l` (after its activation).
    acts: Vec<Vec<T>>,
    delta: Vec<T>,
    delta_next: Vec<T>,
}

impl<T: Scalar> Tape<T> {
    pub fn new() -> Self {
        Tape {
            batch: 0,
            acts: vec![],
            delta: vec![],
            delta_next: vec![],
        }
    }

    /// The network's output of the last forward pass (batch x out, row-major).
    pub fn output(&self) -> &[T] {
        self.acts.last().map(|v| &v[..]).unwrap_or(&[])
    }
}

impl<T: Scalar> Mlp<T> {
    /// A network with hidden layers initialised by `hidden_init` and the last layer by
    /// `output_init`.
    pub fn new(sizes: &[usize], hidden: Activation, output: Activation, hidden_init: Init, output_init: Init, rng: &mut Rng) -> Self {
        assert!(sizes.len() >= 2, "an MLP needs an input and an output size");
        let n: usize = sizes.windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        let mut net = Mlp {
            sizes: sizes.to_vec(),
            hidden,
            output,
            params: vec![T::ZERO; n],
        };
        let layers = net.layers();
        for l in 0..layers {
            let (fan_in, fan_out) = (sizes[l], sizes[l + 1]);
            let init = if l + 1 == layers { output_init } else { hidden_init };
            let (w, b) = init.sample(fan_out, fan_in, rng);
            let (wo, bo) = net.offsets(l);
            for (p, v) in net.params[wo..wo + w.len()].iter_mut().zip(&w) {
                *p = T::from_f64(*v);
            }
            for (p, v) in net.params[bo..bo + b.len()].iter_mut().zip(&b) {
                *p = T::from_f64(*v);
            }
        }
        net
    }

    /// Whether a network read from a file can run: at least an input and an output size, every
    /// width 1 to 65536, as many parameters as the sizes need (counted without overflow), all
    /// finite. The message names what is wrong.
    pub fn check(&self) -> Result<(), String> {
        if self.sizes.len() < 2 {
            return Err(format!("sizes {:?}: a network needs an input and an output size", self.sizes));
        }
        if let Some(w) = self.sizes.iter().find(|&&w| !(1..=1 << 16).contains(&w)) {
            return Err(format!("sizes {:?}: a width of {w} (each must be 1 to 65536)", self.sizes));
        }
        let n = self
            .sizes
            .windows(2)
            .try_fold(0usize, |n, w| n.checked_add(w[0].checked_mul(w[1])?.checked_add(w[1])?));
        if n != Some(self.params.len()) {
            return Err(format!(
                "sizes {:?} need {} parameters, the file has {}",
                self.sizes,
                n.map_or("more than can be counted".to_string(), |n| n.to_string()),
                self.params.len()
            ));
        }
        if self.params.iter().any(|p| !p.to_f64().is_finite()) {
            return Err("a parameter is not a finite number".into());
        }
        Ok(())
    }

    pub fn layers(&self) -> usize {
        self.sizes.len() - 1
    }

    pub fn input_dim(&self) -> usize {
        self.sizes[0]
    }

    pub fn output_dim(&self) -> usize {
        self.sizes[self.sizes.len() - 1]
    }

    /// The network with its first layer's inputs and its last layer's outputs remapped (for
    /// transfer between environments of other layouts): new input `c` of the first layer has
    /// the weights `sum_{(i, w) in inputs[c]} w W[:, i]`, new output `k` of the last layer has the
    /// weights and bias `s W[j, :]`, `s b[j]` for `outputs[k] = Some((j, s))`, and zeros for `None`.
    /// Indices must be below the old input and output sizes.
    pub fn remapped(&self, inputs: &[Vec<(usize, T)>], outputs: &[Option<(usize, T)>]) -> Mlp<T> {
        let mut sizes = self.sizes.clone();
        let last = self.layers() - 1;
        sizes[0] = inputs.len();
        sizes[last + 1] = outputs.len();
        let n: usize = sizes.windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        let mut net = Mlp {
            sizes,
            hidden: self.hidden,
            output: self.output,
            params: vec![T::ZERO; n],
        };
        for l in 0..self.layers() {
            let (wo, bo) = self.offsets(l);
            let (nwo, nbo) = net.offsets(l);
            let (n_in, n_in_new, n_out_new) = (self.sizes[l], net.sizes[l], net.sizes[l + 1]);
            for r in 0..n_out_new {
                let (row, sign) = match (l == last, outputs.get(r)) {
                    (true, Some(Some((j, s)))) => (*j, *s),
                    (true, _) => continue,
                    (false, _) => (r, T::ONE),
                };
                let w = |i: usize| self.params[wo + row * n_in + i];
                let new_row = &mut net.params[nwo + r * n_in_new..nwo + (r + 1) * n_in_new];
                for (c, out) in new_row.iter_mut().enumerate() {
                    let v = if l == 0 {
                        inputs[c].iter().fold(None, |acc: Option<T>, (i, g)| {
                            let t = *g * w(*i);
                            Some(acc.map_or(t, |a| a + t))
                        })
                    } else {
                        Some(w(c))
                    };
                    *out = v.map_or(T::ZERO, |v| sign * v);
                }
                net.params[nbo + r] = sign * self.params[bo + row];
            }
        }
        net
    }

    /// Offsets of layer `l`'s weights and biases in `params`.
    fn offsets(&self, l: usize) -> (usize, usize) {
        let w: usize = self.sizes[..=l].windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        (w, w + self.sizes[l] * self.sizes[l + 1])
    }

    fn activation(&self, l: usize) -> Activation {
        if l + 1 == self.layers() {
            self.output
        } else {
            self.hidden
        }
    }

    /// Sizes the tape for `batch` rows; allocates only when the batch size changes.
    fn prepare(&self, tape: &mut Tape<T>, batch: usize) {
        if tape.batch == batch
            && tape.acts.len() == self.sizes.len()
            && tape.acts.iter().zip(&self.sizes).all(|(a, s)| a.len() == batch * s)
        {
            return;
        }
        tape.batch = batch;
        tape.acts = self.sizes.iter().map(|s| vec![T::ZERO; batch * s]).collect();
        let widest = self.sizes.iter().copied().max().unwrap_or(0);
        tape.delta = vec![T::ZERO; batch * widest];
        tape.delta_next = vec![T::ZERO; batch * widest];
    }

    /// Forward pass of `batch` rows `x` (batch x in, row-major); returns the output
    /// (batch x out) and keeps every activation in `tape` for [`Mlp::backward`].
    pub fn forward<'t>(&self, x: &[T], batch: usize, tape: &'t mut Tape<T>) -> &'t [T] {
        assert_eq!(x.len(), batch * self.input_dim(), "input has the wrong size");
        self.prepare(tape, batch);
        tape.acts[0].copy_from_slice(x);
        for l in 0..self.layers() {
            let (nin, nout) = (self.sizes[l], self.sizes[l + 1]);
            let (wo, bo) = self.offsets(l);
            let (w, b) = (&self.params[wo..bo], &self.params[bo..bo + nout]);
            let (before, after) = tape.acts.split_at_mut(l + 1);
            let (xin, y) = (&before[l], &mut after[0]);
            if batch == 1 {
                // One row: a matrix-vector product (GEMM packing would cost more than the work).
                for ((y, row), b) in y.iter_mut().zip(w.chunks_exact(nin)).zip(b) {
                    *y = *b + T::dot(row, xin);
                }
            } else {
                for row in y.chunks_exact_mut(nout) {
                    row.copy_from_slice(b);
                }
                // y (batch x out) += x (batch x in) . W^T (W stored out x in)
                T::gemm(
                    batch,
                    nin,
                    nout,
                    T::ONE,
                    xin,
                    nin as isize,
                    1,
                    w,
                    1,
                    nin as isize,
                    T::ONE,
                    y,
                    nout as isize,
                    1,
                );
            }
            self.activation(l).apply(y);
        }
        tape.output()
    }

    /// Reverse pass after [`Mlp::forward`]: given `dy` = dL/d(output) (batch x out), adds
    /// dL/d(params) into `grad` (if given) and writes dL/d(input) into `dx` (if given).
    pub fn backward(&self, tape: &mut Tape<T>, dy: &[T], mut grad: Option<&mut [T]>, dx: Option<&mut [T]>) {
        let batch = tape.batch;
        assert_eq!(dy.len(), batch * self.output_dim(), "upstream gradient has the wrong size");
        if let Some(g) = grad.as_deref() {
            assert_eq!(g.len(), self.params.len(), "gradient buffer has the wrong size");
        }
        let last = self.layers() - 1;
        tape.delta[..dy.len()].copy_from_slice(dy);
        self.activation(last).backprop(&tape.acts[last + 1], &mut tape.delta[..dy.len()]);
        for l in (0..self.layers()).rev() {
            let (nin, nout) = (self.sizes[l], self.sizes[l + 1]);
            let (wo, bo) = self.offsets(l);
            let xin = &tape.acts[l];
            let delta = &tape.delta[..batch * nout];
            if let Some(g) = grad.as_deref_mut() {
                let (gw, gb) = g[wo..bo + nout].split_at_mut(bo - wo);
                // dW (out x in) += delta^T (out x batch) . x (batch x in)
                T::gemm(
                    nout,
                    batch,
                    nin,
                    T::ONE,
                    delta,
                    1,
                    nout as isize,
                    xin,
                    nin as isize,
                    1,
                    T::ONE,
                    gw,
                    nin as isize,
                    1,
                );
                for row in delta.chunks_exact(nout) {
                    for (g, d) in gb.iter_mut().zip(row) {
                        *g += *d;
                    }
                }
            }
            if l == 0 && dx.is_none() {
                break;
            }
            // delta_prev (batch x in) = delta (batch x out) . W (out x in)
            let w = &self.params[wo..bo];
            let next = &mut tape.delta_next[..batch * nin];
            T::gemm(
                batch,
                nout,
                nin,
                T::ONE,
                delta,
                nout as isize,
                1,
                w,
                nin as isize,
                1,
                T::ZERO,
                next,
                nin as isize,
                1,
            );
            if l > 0 {
                self.activation(l - 1).backprop(&tape.acts[l], next);
            }
            std::mem::swap(&mut tape.delta, &mut tape.delta_next);
        }
        if let Some(dx) = dx {
            let n = batch * self.input_dim();
            assert_eq!(dx.len(), n, "input gradient buffer has the wrong size");
            dx.copy_from_slice(&tape.delta[..n]);
        }
    }

    /// Polyak averaging `self <- tau * source + (1 - tau) * self` (soft target update).
    pub fn soft_update(&mut self, source: &Mlp<T>, tau: f64) {
        let (tau, keep) = (T::from_f64(tau), T::from_f64(1.0 - tau));
        for (p, s) in self.params.iter_mut().zip(&source.params) {
            *p = tau * *s + keep * *p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loss(net: &Mlp<f64>, x: &[f64], batch: usize, w: &[f64]) -> f64 {
        let mut tape = Tape::new();
        net.forward(x, batch, &mut tape).iter().zip(w).map(|(y, w)| y * w).sum()
    }

    /// Backward pass against central finite differences (f64), for parameters and inputs, for
    /// every activation.
    #[test]
    #[allow(clippy::needless_range_loop)]
    fn gradients_match_finite_differences() {
        for act in [Activation::Tanh, Activation::Relu, Activation::Identity] {
            let mut rng = Rng::seed(7);
            let net: Mlp<f64> = Mlp::new(
                &[5, 7, 6, 3],
                act,
                Activation::Tanh,
                Init::FanIn,
                Init::Orthogonal { gain: 1.0 },
                &mut rng,
            );
            for batch in [1, 4] {
                let x: Vec<f64> = (0..batch * 5).map(|_| rng.normal()).collect();
                let w: Vec<f64> = (0..batch * 3).map(|_| rng.normal()).collect();
                let mut tape = Tape::new();
                net.forward(&x, batch, &mut tape);
                let mut grad = vec![0.0; net.params.len()];
                let mut dx = vec![0.0; x.len()];
                net.backward(&mut tape, &w, Some(&mut grad), Some(&mut dx));
                let h = 1e-6;
                let mut worst: f64 = 0.0;
                for i in 0..net.params.len() {
                    let (mut p, mut m) = (net.clone(), net.clone());
                    p.params[i] += h;
                    m.params[i] -= h;
                    let fd = (loss(&p, &x, batch, &w) - loss(&m, &x, batch, &w)) / (2.0 * h);
                    worst = worst.max((fd - grad[i]).abs() / (1e-6 + fd.abs().max(grad[i].abs())));
                }
                for i in 0..x.len() {
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[i] += h;
                    xm[i] -= h;
                    let fd = (loss(&net, &xp, batch, &w) - loss(&net, &xm, batch, &w)) / (2.0 * h);
                    worst = worst.max((fd - dx[i]).abs() / (1e-6 + fd.abs().max(dx[i].abs())));
                }
                println!("{act:?}, batch {batch}: worst relative gradient error {worst:.2e}");
                // ReLU kinks are measure-zero; random inputs do not sit within h of one.
                assert!(worst < 1e-6, "{act:?}: worst relative error {worst:e}");
            }
        }
    }

    #[test]
    fn orthogonal_init_has_orthonormal_rows() {
        let mut rng = Rng::seed(3);
        let net: Mlp<f64> = Mlp::new(
            &[8, 4],
            Activation::Identity,
            Activation::Identity,
            Init::FanIn,
            Init::Orthogonal { gain: 1.0 },
            &mut rng,
        );
        for i in 0..4 {
            for j in 0..4 {
                let d: f64 = (0..8).map(|k| net.params[i * 8 + k] * net.params[j * 8 + k]).sum();
                assert!((d - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn soft_update_interpolates() {
        let mut rng = Rng::seed(1);
        let a: Mlp<f32> = Mlp::new(
            &[2, 3, 1],
            Activation::Relu,
            Activation::Identity,
            Init::FanIn,
            Init::FanIn,
            &mut rng,
        );
        let mut b: Mlp<f32> = Mlp::new(
            &[2, 3, 1],
            Activation::Relu,
            Activation::Identity,
            Init::FanIn,
            Init::FanIn,
            &mut rng,
        );
        let before = b.params.clone();
        b.soft_update(&a, 0.25);
        for ((x, y), z) in b.params.iter().zip(&a.params).zip(&before) {
            assert!((x - (0.25 * y + 0.75 * z)).abs() < 1e-6);
        }
    }
}
