//! STREAM-style copy bandwidth (McCalpin): `b[i] = a[i]` over arrays far larger than the caches,
//! bytes counted as read + write (write-allocate traffic not counted, as in STREAM).
//!
//! Done as STREAM's C copy compiled with `gcc -O3 -march=native -fopenmp` does it: the arrays
//! are first touched in parallel in the partition the copy uses, each thread copies one
//! contiguous block with an ordinary vector loop ([`copy_ordinary`]), best of `reps`. gcc keeps
//! that loop as `vmovups` loads and stores; a Rust `copy_from_slice` of the whole block becomes
//! one `memcpy`, whose large-size path stores non-temporally and moves less on this machine
//! (about 26 against 30 GB/s with 2 threads). `make roofline` runs this beside that C program
//! (`benchmarks/stream/copy.c`), alternating, and prints the ratio.

use rayon::prelude::*;
use std::time::Instant;

/// Best-of-`reps` copy bandwidth in GB/s over `n` f32 values, in the current rayon pool.
pub fn stream_copy_gbs(n: usize, reps: usize) -> f64 {
    let threads = rayon::current_num_threads();
    let block = n.div_ceil(threads).max(1);
    // `vec![0.0; n]` maps zero pages lazily: the first touch happens below, per block.
    let mut a = vec![0.0f32; n];
    let mut b = vec![0.0f32; n];
    a.par_chunks_mut(block).enumerate().for_each(|(k, c)| {
        for (i, v) in c.iter_mut().enumerate() {
            *v = (k * block + i) as f32;
        }
    });
    b.par_chunks_mut(block).for_each(|c| c.fill(1.0));
    let mut best = f64::INFINITY;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        b.par_chunks_mut(block)
            .zip(a.par_chunks(block))
            .for_each(|(d, s)| copy_ordinary(d, s));
        best = best.min(t.elapsed().as_secs_f64());
    }
    // Keep the copy observable.
    assert_eq!(b[n / 2], a[n / 2]);
    2.0 * (n * 4) as f64 / best / 1e9
}

/// `dst = src` with ordinary (write-allocate) vector stores, 64 values at a time. Each block's
/// source goes through `black_box` so the loop is not recognised as one large `memcpy`, whose
/// non-temporal path is not what STREAM's C copy measures.
fn copy_ordinary(dst: &mut [f32], src: &[f32]) {
    let (d, d_rest) = dst.as_chunks_mut::<64>();
    let (s, s_rest) = src.as_chunks::<64>();
    for (d, s) in d.iter_mut().zip(s) {
        *d = *std::hint::black_box(s);
    }
    d_rest.copy_from_slice(s_rest);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The block copy copies every value, the remainder after the last full block included.
    #[test]
    fn copy_ordinary_copies_everything() {
        let src: Vec<f32> = (0..64 * 3 + 5).map(|i| i as f32).collect();
        let mut dst = vec![0.0; src.len()];
        copy_ordinary(&mut dst, &src);
        assert_eq!(dst, src);
    }
}
