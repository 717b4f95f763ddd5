//! A float array whose first element sits on a 64-byte boundary (a cache line), so that rows
//! whose length is a multiple of 8 floats start on 32-byte boundaries and can be written with
//! aligned non-temporal vector stores.

use std::ops::{Deref, DerefMut};

pub(crate) struct AlignedVec {
    data: Vec<f32>,
    off: usize,
    len: usize,
}

impl AlignedVec {
    pub fn zeros(len: usize) -> Self {
        let data = vec![0.0f32; len + 16];
        // `data` is 4-byte aligned, so the distance to the next 64-byte boundary is a multiple
        // of 4 bytes, i.e. a whole number of floats, at most 15.
        let off = ((64 - data.as_ptr() as usize % 64) % 64) / 4;
        AlignedVec { data, off, len }
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
        }
    }
}
