//! Spaces (Gymnasium's `Box`): bounded boxes of `f64` vectors.

use serde::{Deserialize, Serialize};

/// A box `[low_i, high_i]` per component (Gymnasium `spaces.Box`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxSpace {
    pub low: Vec<f64>,
    pub high: Vec<f64>,
}

impl BoxSpace {
    /// `[low, high]^n`.
    pub fn uniform(n: usize, low: f64, high: f64) -> Self {
        BoxSpace {
            low: vec![low; n],
            high: vec![high; n],
        }
    }

    /// The action space of every hgym environment: `[-1, 1]^n`.
    pub fn unit(n: usize) -> Self {
        Self::uniform(n, -1.0, 1.0)
    }

    pub fn dim(&self) -> usize {
        self.low.len()
    }

    /// Whether `x` has the right length and lies inside the box.
    pub fn contains(&self, x: &[f64]) -> bool {
        x.len() == self.dim()
            && x.iter()
                .zip(self.low.iter().zip(&self.high))
                .all(|(v, (l, h))| *v >= *l && *v <= *h)
    }

    /// `x` clipped into the box; returns how many components were clipped.
    pub fn clip(&self, x: &mut [f64]) -> usize {
        let mut n = 0;
        for (v, (l, h)) in x.iter_mut().zip(self.low.iter().zip(&self.high)) {
            if *v < *l || *v > *h {
                *v = v.clamp(*l, *h);
                n += 1;
            }
        }
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_counts_and_contains() {
        let s = BoxSpace::unit(3);
        let mut a = [0.5, -2.0, 1.5];
        assert!(!s.contains(&a));
        assert_eq!(s.clip(&mut a), 2);
        assert_eq!(a, [0.5, -1.0, 1.0]);
        assert!(s.contains(&a));
        assert!(!s.contains(&[0.0]));
    }
}
