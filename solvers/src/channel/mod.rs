//! Incompressible wall-bounded DNS: the plane channel (periodic in x and z, walls in y; or a
//! free-slip top for the open channel), second-order finite differences on a staggered grid
//! stretched towards the walls, FFT + tridiagonal pressure solve, low-storage RK3 with a
//! projection per stage (the method of CaNS, Costa 2018).
//!
//! - [`grid`]: the staggered grid and its wall closures;
//! - [`operators`]: advection, diffusion, divergence and gradient, plane by plane;
//! - [`poisson`]: the direct pressure solver;
//! - [`fringe`]: the fringe forcing that turns the periodic box into a spatially developing flow;
//! - [`plate`]: a flat-plate boundary layer under a given edge velocity (fringe, outflow, trip);
//! - [`trip`]: the random volume force that trips a boundary layer;
//! - [`solver`]: [`Channel`], time stepping, drive, transpiration and diagnostics;
//! - [`stats`]: plane-averaged means and second moments.

// Index loops over grid points read like the stencils they implement.
#![allow(clippy::needless_range_loop, clippy::too_many_arguments)]

pub mod error;
pub mod fringe;
pub mod grid;
pub mod layer;
pub mod operators;
pub mod plate;
pub mod poisson;
pub mod solver;
pub mod stats;
pub mod trip;
pub mod wing_plate;

pub use error::ChannelError;
pub use fringe::{BaseFlow, Fringe, FringeSpec};
pub use grid::{Grid, Top};
pub use layer::{LayerSums, Station};
pub use solver::{viscous_dt_limit, Channel, ChannelConfig, ChannelState, Drive};
pub use stats::{PlaneSums, Profiles};
pub use trip::{Trip, TripSpec};
