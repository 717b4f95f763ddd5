//! STREAM-style copy bandwidth (McCalpin): `b[i] = a[i]` over arrays far larger than the caches,
//! bytes counted as read + write (write-allocate traffic not counted, as in STREAM).
//!
//! The loop stores with ordinary stores, like the LBM kernel and like STREAM's C loop: it is
//! written `b[i] = a[i] + 0.0` so the compiler cannot turn it into `memcpy`, whose non-temporal
//! stores skip the write-allocate read and would make the roofline one the kernel cannot use.

use rayon::prelude::*;
use std::time::Instant;

/// Best-of-`reps` copy bandwidth in GB/s over `n` f32 values, in the current rayon pool.
pub fn stream_copy_gbs(n: usize, reps: usize) -> f64 {
    let a: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let mut b = vec![0.0f32; n];
    let threads = rayon::current_num_threads();
    let chunk = n.div_ceil(threads * 4).max(1 << 16);
    let mut best = f64::INFINITY;
    for _ in 0..reps.max(1) {
        let t = Instant::now();
        b.par_chunks_mut(chunk)
            .zip(a.par_chunks(chunk))
            .for_each(|(d, s)| d.copy_from_slice(s));
        best = best.min(t.elapsed().as_secs_f64());
    }
    // Keep the copy observable.
    assert_eq!(b[n / 2], a[n / 2]);
    2.0 * (n * 4) as f64 / best / 1e9
}
