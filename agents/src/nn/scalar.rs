//! The floating-point types a network can be built on. Training uses `f32`; gradient checks
//! against finite differences use `f64` (the same code, generic).

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real number with the operations a dense layer needs, and a GEMM from `matrixmultiply`.
pub trait Scalar:
    Copy
    + Debug
    + Default
    + PartialOrd
    + Send
    + Sync
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + serde::Serialize
    + for<'de> serde::Deserialize<'de>
    + 'static
{
    const ZERO: Self;
    const ONE: Self;
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn tanh(self) -> Self;
    fn exp(self) -> Self;
    fn sqrt(self) -> Self;
    /// `sum_i a_i b_i` over the common length.
    fn dot(a: &[Self], b: &[Self]) -> Self;

    /// `C <- alpha * A B + beta * C` with `A` m x k, `B` k x n, `C` m x n, each given by its
    /// row and column strides (so transposes are free).
    #[allow(clippy::too_many_arguments)]
    fn gemm(
        m: usize,
        k: usize,
        n: usize,
        alpha: Self,
        a: &[Self],
        rsa: isize,
        csa: isize,
        b: &[Self],
        rsb: isize,
        csb: isize,
        beta: Self,
        c: &mut [Self],
        rsc: isize,
        csc: isize,
    );
}

/// Largest offset a strided `rows x cols` view touches, plus one (for bounds checks).
fn extent(rows: usize, cols: usize, rs: isize, cs: isize) -> usize {
    if rows == 0 || cols == 0 {
        return 0;
    }
    (rows as isize - 1) as usize * rs.unsigned_abs() + (cols as isize - 1) as usize * cs.unsigned_abs() + 1
}

macro_rules! impl_scalar {
    ($t:ty, $gemm:path, $dot:path) => {
        impl Scalar for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn tanh(self) -> Self {
                <$t>::tanh(self)
            }
            fn exp(self) -> Self {
                <$t>::exp(self)
            }
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            fn dot(a: &[Self], b: &[Self]) -> Self {
                $dot(a, b)
            }
            fn gemm(
                m: usize,
                k: usize,
                n: usize,
                alpha: Self,
                a: &[Self],
                rsa: isize,
                csa: isize,
                b: &[Self],
                rsb: isize,
                csb: isize,
                beta: Self,
                c: &mut [Self],
                rsc: isize,
                csc: isize,
            ) {
                assert!(rsa >= 0 && csa >= 0 && rsb >= 0 && csb >= 0 && rsc >= 0 && csc >= 0);
                assert!(a.len() >= extent(m, k, rsa, csa), "gemm: A too short");
                assert!(b.len() >= extent(k, n, rsb, csb), "gemm: B too short");
                assert!(c.len() >= extent(m, n, rsc, csc), "gemm: C too short");
                if m == 0 || n == 0 {
                    return;
                }
                // SAFETY: the asserts above prove that every element the m x k, k x n and m x n
                // strided views address lies inside `a`, `b` and `c` (non-negative strides,
                // largest offset < len). `c` is a unique borrow, so it aliases neither input.
                unsafe {
                    $gemm(
                        m,
                        k,
                        n,
                        alpha,
                        a.as_ptr(),
                        rsa,
                        csa,
                        b.as_ptr(),
                        rsb,
                        csb,
                        beta,
                        c.as_mut_ptr(),
                        rsc,
                        csc,
                    )
                }
            }
        }
    };
}

impl_scalar!(f32, matrixmultiply::sgemm, dot_f32);
impl_scalar!(f64, matrixmultiply::dgemm, dot_portable);

/// Dot product in the order: four independent partial sums per lane group, then the remainder.
fn dot_portable<T: Copy + Default + Add<Output = T> + Mul<Output = T>>(a: &[T], b: &[T]) -> T {
    let n = a.len().min(b.len());
    let mut acc = [T::default(); 4];
    let (ca, cb) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] = acc[k] + x[k] * y[k];
        }
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s = s + *x * *y;
    }
    s
}

/// `f32` dot product with AVX2 + FMA (four 8-wide accumulators hide the FMA latency; LLVM does
/// not find this from portable code). The build enables these features (`.cargo/config.toml`:
/// x86-64-v3); other targets use the portable loop.
#[cfg(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma"))]
fn dot_f32(a: &[f32], b: &[f32]) -> f32 {
    use std::arch::x86_64::*;
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (ca, cb) = (a.chunks_exact(32), b.chunks_exact(32));
    let tail = n - ca.remainder().len();
    // SAFETY: AVX2 and FMA are enabled at compile time (cfg above), so the intrinsics are
    // available; every load reads 8 floats at offsets 0, 8, 16, 24 of a chunk of exactly 32,
    // so it stays inside the slice; `loadu` has no alignment requirement.
    let mut s = unsafe {
        let (mut s0, mut s1, mut s2, mut s3) = (_mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps());
        for (x, y) in ca.zip(cb) {
            let (px, py) = (x.as_ptr(), y.as_ptr());
            s0 = _mm256_fmadd_ps(_mm256_loadu_ps(px), _mm256_loadu_ps(py), s0);
            s1 = _mm256_fmadd_ps(_mm256_loadu_ps(px.add(8)), _mm256_loadu_ps(py.add(8)), s1);
            s2 = _mm256_fmadd_ps(_mm256_loadu_ps(px.add(16)), _mm256_loadu_ps(py.add(16)), s2);
            s3 = _mm256_fmadd_ps(_mm256_loadu_ps(px.add(24)), _mm256_loadu_ps(py.add(24)), s3);
        }
        let v = _mm256_add_ps(_mm256_add_ps(s0, s1), _mm256_add_ps(s2, s3));
        let mut lanes = [0f32; 8];
        _mm256_storeu_ps(lanes.as_mut_ptr(), v);
        ((lanes[0] + lanes[4]) + (lanes[1] + lanes[5])) + ((lanes[2] + lanes[6]) + (lanes[3] + lanes[7]))
    };
    for (x, y) in a[tail..].iter().zip(&b[tail..]) {
        s += x * y;
    }
    s
}

#[cfg(not(all(target_arch = "x86_64", target_feature = "avx2", target_feature = "fma")))]
fn dot_f32(a: &[f32], b: &[f32]) -> f32 {
    dot_portable(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vectorised dot product against an f64 sum, at lengths around the 32-wide blocks.
    #[test]
    fn dot_matches_f64_sum() {
        for n in [0, 1, 7, 31, 32, 33, 60, 64, 255, 256, 257] {
            let a: Vec<f32> = (0..n).map(|i| ((i * 37 % 101) as f32 - 50.0) / 17.0).collect();
            let b: Vec<f32> = (0..n).map(|i| ((i * 53 % 89) as f32 - 44.0) / 13.0).collect();
            let exact: f64 = a.iter().zip(&b).map(|(x, y)| *x as f64 * *y as f64).sum();
            let d = f32::dot(&a, &b) as f64;
            assert!((d - exact).abs() <= 1e-5 * (1.0 + exact.abs()), "n {n}: {d} vs {exact}");
            assert!(
                (f64::dot(
                    &a.iter().map(|v| *v as f64).collect::<Vec<_>>(),
                    &b.iter().map(|v| *v as f64).collect::<Vec<_>>()
                ) - exact)
                    .abs()
                    < 1e-9
            );
        }
    }

    /// GEMM with transposed views against a naive triple loop.
    #[test]
    fn gemm_matches_naive_with_transposes() {
        let (m, k, n) = (3, 4, 5);
        let a: Vec<f64> = (0..m * k).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..n * k).map(|i| (i as f64 * 0.71).cos()).collect();
        // C = A B^T where B is stored n x k row-major.
        let mut c = vec![1.0; m * n];
        f64::gemm(m, k, n, 2.0, &a, k as isize, 1, &b, 1, k as isize, 0.5, &mut c, n as isize, 1);
        for i in 0..m {
            for j in 0..n {
                let s: f64 = (0..k).map(|p| a[i * k + p] * b[j * k + p]).sum();
                assert!((c[i * n + j] - (2.0 * s + 0.5)).abs() < 1e-12);
            }
        }
    }
}
