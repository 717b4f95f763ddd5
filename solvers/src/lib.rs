//! # hgym-solvers: numerics only
//!
//! Conventions fixed once for the whole crate:
//!
//! - **Lattice units.** Solvers speak lattice units: node spacing 1, time step 1, reference
//!   density 1, speed of sound `c_s = 1/sqrt(3)`. [`lbm::Units`] converts to and from the
//!   non-dimensional units of the environments (D = 1, U_inf = 1, time in D/U_inf).
//! - **Array order.** D2Q9 populations are stored row-blocked structure-of-arrays:
//!   `f[(y * 9 + i) * nx + x]`, so a row of the grid holds nine contiguous direction arrays.
//!   Node `(x, y)` sits at integer coordinates; domain walls sit half-way between nodes, at
//!   `x = -1/2`, `x = nx - 1/2` (and likewise in y).
//! - **Shifted storage.** The stored value is `g_i = f_i - w_i` (the deviation from the rest
//!   state), which keeps FP32 round-off far below the density fluctuations of a low-Mach flow
//!   (the "DDF shifting" of Lehmann, FluidX3D, 2022).
//! - **No RL vocabulary here.** Nothing in this crate knows of agents, rewards or episodes.
//!
//! Errors are typed ([`lbm::LbmError`]); nothing here panics on user input.

pub mod bl_integral;
pub mod blasius;
pub mod channel;
pub mod comm;
pub mod geometry;
pub mod lbm;
pub mod panel;
pub mod spectral;
pub mod suction_side;
