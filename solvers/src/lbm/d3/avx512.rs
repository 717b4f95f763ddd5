//! Sixteen nodes per block on CPUs with AVX-512F: [`F32x16`], one `zmm` register of f32, for
//! the bulk loop of the 3D kernel ([`super::kernel::plane_widest`]).
//!
//! The collision is the same sequence of IEEE single-precision operations on 8 or 16 lanes
//! (no fused multiply-add, negation as `0 - x` like `wide`'s), so both widths give bitwise
//! the same populations; which one runs is decided at run time and changes no result.
//!
//! Soundness: the methods of [`F32x16`] execute AVX-512F instructions. The type is private to
//! the 3D module; outside this file only [`super::kernel`]'s `plane_avx512` and a unit test of
//! `collision.rs` (`a_block_is_bitwise_its_nodes`) use it, both only after
//! [`avx512_available`](super::super::kernel::avx512_available) found the feature. The kernel
//! is tested against the oracle bitwise at both widths (`exact3d`).

use core::arch::x86_64::{
    __m512, _mm512_add_ps, _mm512_div_ps, _mm512_loadu_ps, _mm512_mul_ps, _mm512_set1_ps, _mm512_setzero_ps, _mm512_sqrt_ps,
    _mm512_storeu_ps, _mm512_sub_ps,
};
use std::ops::{Add, Div, Mul, Neg, Sub};

use super::collision::{Block, Lanes};

/// Sixteen f32 lanes in one AVX-512 register.
#[derive(Clone, Copy)]
pub(crate) struct F32x16(__m512);

macro_rules! binary {
    ($trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for F32x16 {
            type Output = Self;
            #[inline(always)]
            fn $method(self, rhs: Self) -> Self {
                // SAFETY: see the module's soundness note (AVX-512F is present wherever an
                // F32x16 exists); the operation reads only its two register operands.
                F32x16(unsafe { $intrinsic(self.0, rhs.0) })
            }
        }
    };
}

binary!(Add, add, _mm512_add_ps);
binary!(Sub, sub, _mm512_sub_ps);
binary!(Mul, mul, _mm512_mul_ps);
binary!(Div, div, _mm512_div_ps);

impl Neg for F32x16 {
    type Output = Self;
    /// `0 - x`, as `wide::f32x8` negates, so that both widths round alike.
    #[inline(always)]
    fn neg(self) -> Self {
        // SAFETY: see the module's soundness note; no memory is touched.
        F32x16(unsafe { _mm512_setzero_ps() }) - self
    }
}

impl Lanes for F32x16 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        // SAFETY: see the module's soundness note; no memory is touched.
        F32x16(unsafe { _mm512_set1_ps(v) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: see the module's soundness note; no memory is touched.
        F32x16(unsafe { _mm512_sqrt_ps(self.0) })
    }
}

impl Block for F32x16 {
    const LANES: usize = 16;
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        let s = &s[..16];
        // SAFETY: `s` holds 16 floats (the slicing above panics otherwise), all the unaligned
        // load reads; AVX-512F as in the module's soundness note.
        F32x16(unsafe { _mm512_loadu_ps(s.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, d: &mut [f32]) {
        let d = &mut d[..16];
        // SAFETY: `d` holds 16 floats (the slicing above panics otherwise), all the unaligned
        // store writes, and it is borrowed mutably; AVX-512F as in the module's soundness note.
        unsafe { _mm512_storeu_ps(d.as_mut_ptr(), self.0) }
    }
}
