//! A float array whose first element sits on a 64-byte boundary (a cache line), so that rows
//! whose length is a multiple of 8 floats start on 32-byte boundaries and can be written with
//! aligned non-temporal vector stores.

use std::ops::{Deref, DerefMut};

pub(crate) struct AlignedVec {
    data: Vec<f32>,
    off: usize,
    len: usize,
    pad: usize,
}

impl AlignedVec {
    pub fn zeros(len: usize) -> Self {
        Self::zeros_padded(len, 0)
    }

    /// `len` values with `pad` zeros before and after them that [`AlignedVec::padded`] exposes
    /// (kernels that read a little past a row's ends without a bounds branch).
    pub fn zeros_padded(len: usize, pad: usize) -> Self {
        let data = vec![0.0f32; len + 2 * pad + 16];
        // `data` is 4-byte aligned, so the distance from `data[pad]` to the next 64-byte boundary
        // is a multiple of 4 bytes, i.e. a whole number of floats, at most 15.
        let off = pad + ((64 - data[pad..].as_ptr() as usize % 64) % 64) / 4;
        AlignedVec { data, off, len, pad }
    }

    /// The values with their padding: element `k` of the vector is element `k + pad` here.
    pub fn padded(&self) -> &[f32] {
        &self.data[self.off - self.pad..self.off + self.len + self.pad]
    }
}

impl Deref for AlignedVec {
    type Target = [f32];
    fn deref(&self) -> &[f32] {
        &self.data[self.off..self.off + self.len]
    }
}

impl DerefMut for AlignedVec {
    fn deref_mut(&mut self) -> &mut [f32] {
        &mut self.data[self.off..self.off + self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_on_a_cache_line() {
        for len in [1, 7, 100, 4096] {
            let v = AlignedVec::zeros(len);
            assert_eq!(v.as_ptr() as usize % 64, 0);
            assert_eq!(v.len(), len);
            let p = AlignedVec::zeros_padded(len, 16);
            assert_eq!(p.as_ptr() as usize % 64, 0);
            assert_eq!(p.padded().len(), len + 32);
            assert_eq!(p.padded()[16..].as_ptr(), p.as_ptr());
        }
    }
}
