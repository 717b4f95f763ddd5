//! STREAM-style copy bandwidth (McCalpin): `b[i] = a[i]` over arrays far larger than the caches,
//! bytes counted as read + write (write-allocate traffic not counted, as in STREAM).
//!
//! Done as STREAM's C copy compiled with `gcc -O3 -march=native -fopenmp` does it (gcc turns its
//! loop into one `memcpy` per thread, whose large copies use non-temporal stores): the arrays
//! are first touched in parallel in the partition the copy uses, each thread copies one
//! contiguous block with `copy_from_slice` (the same `memcpy`), best of `reps`. `make roofline`
//! runs this beside that C program (`benchmarks/stream/copy.c`), alternating, and prints the
//! ratio.

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
            .for_each(|(d, s)| d.copy_from_slice(s));
        best = best.min(t.elapsed().as_secs_f64());
    }
    // Keep the copy observable.
    assert_eq!(b[n / 2], a[n / 2]);
    2.0 * (n * 4) as f64 / best / 1e9
}
