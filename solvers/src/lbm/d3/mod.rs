//! Lattice Boltzmann in three dimensions: D3Q19 and D3Q27 on a box whose faces are periodic,
//! walls, free-slip, velocity inlets or outlets, with immersed bodies (interpolated bounce-back
//! from signed distances, moving walls, momentum-exchange forces per body and per spanwise
//! segment), absorbing layers on any face and trilinear probes.
//!
//! Same habits as the 2D kernel: shifted FP32 storage, structure of arrays (`f[((z Q + i) ny +
//! y) nx + x]`), one fused pull-scheme stream-collide pass per step over two arrays (absorbing
//! layers applied inside it, before the store), rayon over
//! z planes, no allocation in a step, and a slow oracle ([`Lbm3::step_reference`]) the fast
//! kernel is tested against bitwise. After a step, `f` holds the post-collision populations.
//!
//! Split over ranks ([`Lbm3::new_split`], a [`Comm`](crate::comm::Comm)), each rank steps a slab
//! along y or z (not x, the kernel's row) with ghost layers exchanged after every step; forces,
//! probes and the blow-up scan come out bitwise the same as one process's.

// Loops over directions `i` and axes `a` index several arrays at once, as the sums in the
// equations do.
#![allow(clippy::needless_range_loop)]

#[cfg(target_arch = "x86_64")]
mod avx512;
mod collision;
mod kernel;
pub mod lattice;
mod refine;
mod sides;
mod solver;
mod sponge;
pub mod thermal;

pub use super::part::split_axis;
pub use lattice::{D3q19, D3q27, Lattice3};
pub use refine::{Patch3, Refined3};
pub use sides::{Face, Faces};
pub use solver::{D3Config, Grid3, Lbm3};
pub use sponge::Sponge3;
pub use thermal::Thermal3;
