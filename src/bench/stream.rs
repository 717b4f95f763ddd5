//! The machine's copy bandwidth (McCalpin's STREAM copy, `b[i] = a[i]`) over arrays far larger
//! than the caches, bytes counted as read + write (write-allocate traffic not counted, as in
//! STREAM).
//!
//! Two copies are timed and the faster one is the limit, because which one reaches the memory
//! system's limit depends on the processor:
//! - [`CopyMethod::Stream`]: STREAM's C copy as `gcc -O3 -march=native -fopenmp` compiles it, an
//!   ordinary vector loop in ascending order ([`copy_ordinary`]). Each store first reads its
//!   line (write-allocate). On AMD EPYC (Zen) it is the faster copy.
//! - [`CopyMethod::Memcpy`]: the C library's `memcpy` of each thread's block. For blocks this
//!   large glibc prefetches in software and stores non-temporally, so no line is read before it
//!   is written: on an Intel Xeon (Emerald Rapids) it moves 1.7 times as much as the ordinary
//!   loop (about 42 against 25 GB/s with 2 threads, 21 against 12.5 with 1).
//!
//! The arrays are first touched in parallel in the partition the copy uses; each thread copies
//! one contiguous block; best of `reps` per method, the methods alternating. `make roofline`
//! runs this beside STREAM's C copy (`benchmarks/stream/copy.c`) and prints the ratio.

use hgym_solvers::lbm::advise_huge_pages;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How a copy writes its destination.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CopyMethod {
    /// Ordinary vector stores in ascending order (STREAM's C copy).
    Stream,
    /// The C library's `memcpy`.
    Memcpy,
}

impl CopyMethod {
    pub fn name(self) -> &'static str {
        match self {
            CopyMethod::Stream => "stream",
            CopyMethod::Memcpy => "memcpy",
        }
    }
}

/// The best copy bandwidth and the copy that reached it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CopyBandwidth {
    /// GB/s, read + write.
    pub gbs: f64,
    pub method: CopyMethod,
    /// Each method's best, GB/s.
    pub stream_gbs: f64,
    pub memcpy_gbs: f64,
}

/// Best-of-`reps` copy bandwidth over `n` f32 values, in the current rayon pool: the faster of
/// the ordinary loop and `memcpy`.
pub fn stream_copy_gbs(n: usize, reps: usize) -> CopyBandwidth {
    let threads = rayon::current_num_threads();
    let block = n.div_ceil(threads).max(1);
    // `vec![0.0; n]` maps zero pages lazily: the first touch happens below, per block. The
    // arrays ask for huge pages, as the solvers' population arrays do.
    let mut a = vec![0.0f32; n];
    let mut b = vec![0.0f32; n];
    advise_huge_pages(&a);
    advise_huge_pages(&b);
    a.par_chunks_mut(block).enumerate().for_each(|(k, c)| {
        for (i, v) in c.iter_mut().enumerate() {
            *v = (k * block + i) as f32;
        }
    });
    b.par_chunks_mut(block).for_each(|c| c.fill(1.0));
    let methods = [CopyMethod::Stream, CopyMethod::Memcpy];
    let mut best = [f64::INFINITY; 2];
    for _ in 0..reps.max(1) {
        for (m, method) in methods.iter().enumerate() {
            b.par_chunks_mut(block).for_each(|c| c[0] = -1.0);
            let t = Instant::now();
            b.par_chunks_mut(block).zip(a.par_chunks(block)).for_each(|(d, s)| match method {
                CopyMethod::Stream => copy_ordinary(d, s),
                CopyMethod::Memcpy => d.copy_from_slice(s),
            });
            best[m] = best[m].min(t.elapsed().as_secs_f64());
            // Keep the copy observable.
            assert_eq!(b[0], a[0]);
            assert_eq!(b[n - 1], a[n - 1]);
        }
    }
    let [stream_gbs, memcpy_gbs] = best.map(|t| 2.0 * (n * 4) as f64 / t / 1e9);
    let (gbs, method) = match memcpy_gbs > stream_gbs {
        true => (memcpy_gbs, CopyMethod::Memcpy),
        false => (stream_gbs, CopyMethod::Stream),
    };
    CopyBandwidth {
        gbs,
        method,
        stream_gbs,
        memcpy_gbs,
    }
}

/// `dst = src` with ordinary (write-allocate) 8-wide vector stores in ascending order, as gcc
/// compiles STREAM's loop. Each 8-value block's source goes through `black_box`, so the loop is
/// not recognised as one `memcpy`, and each iteration is one load and one store (with larger
/// blocks LLVM emits a block's stores in descending order).
fn copy_ordinary(dst: &mut [f32], src: &[f32]) {
    let (d, d_rest) = dst.as_chunks_mut::<8>();
    let (s, s_rest) = src.as_chunks::<8>();
    for (d, s) in d.iter_mut().zip(s) {
        *d = *std::hint::black_box(s);
    }
    d_rest.copy_from_slice(s_rest);
}

/// The size of the largest cache in bytes (Linux sysfs, CPU 0); 32 MB where it cannot be read.
pub fn last_level_cache_bytes() -> usize {
    let sizes = std::fs::read_dir("/sys/devices/system/cpu/cpu0/cache").into_iter().flatten();
    sizes
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path().join("size")).ok())
        .filter_map(|s| parse_cache_size(s.trim()))
        .max()
        .unwrap_or(32 << 20)
}

/// A sysfs cache size (`"32768K"`, `"2M"`, `"512"`) in bytes.
fn parse_cache_size(s: &str) -> Option<usize> {
    let (digits, unit) = match s.char_indices().find(|(_, c)| !c.is_ascii_digit()) {
        Some((i, _)) => s.split_at(i),
        None => (s, ""),
    };
    let n: usize = digits.parse().ok()?;
    match unit {
        "" => Some(n),
        "K" => Some(n << 10),
        "M" => Some(n << 20),
        "G" => Some(n << 30),
        _ => None,
    }
}

/// f32 values per copy array: each array at least twice the last-level cache (2^26, 256 MB, at
/// least), so the copy's 4 x cache bytes cannot stay cached under any replacement policy.
pub fn default_copy_values() -> usize {
    (2 * last_level_cache_bytes() / 4).next_power_of_two().max(1 << 26)
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

    #[test]
    fn cache_sizes_parse_in_sysfs_units() {
        assert_eq!(parse_cache_size("32768K"), Some(32 << 20));
        assert_eq!(parse_cache_size("2M"), Some(2 << 20));
        assert_eq!(parse_cache_size("512"), Some(512));
        assert_eq!(parse_cache_size("K"), None);
        assert_eq!(parse_cache_size("3X"), None);
    }

    /// Both copies copy; the reported bandwidth is the faster method's.
    #[test]
    fn the_limit_is_the_faster_copy() {
        let c = stream_copy_gbs(1 << 16, 2);
        assert!([c.stream_gbs, c.memcpy_gbs].iter().all(|g| g.is_finite() && *g > 0.0));
        assert_eq!(c.gbs, c.stream_gbs.max(c.memcpy_gbs));
        assert_eq!(
            c.gbs,
            if c.method == CopyMethod::Stream {
                c.stream_gbs
            } else {
                c.memcpy_gbs
            }
        );
    }
}
