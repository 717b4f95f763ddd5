//! Lattice Boltzmann method, D2Q9 (this module) and D3Q19/D3Q27 ([`d3`]).
//!
//! The source is modular (lattice, collision, one file per boundary) and fused at run time: one
//! pull-scheme stream-collide pass per step that, for every node, loads the nine populations from
//! its neighbours, applies boundaries where a neighbour is a wall or outside the domain, computes
//! the moments, collides and stores (A-B pattern, two arrays). Interior rows run a branch-free,
//! vectorised loop; the few nodes next to walls and domain edges run the general per-node path
//! after it and overwrite the row's values there.
//!
//! Both arrays hold *post-collision* populations: after a step, `f` holds `f*(x, t+1)`. Moments
//! (density, momentum) are invariant under collision, so they can be read from either.
//!
//! Grids larger than the caches step with the AA pattern instead ([`aa`]): the same per-node
//! operations in place in one array, two kinds of step in turn, which saves the write-allocate
//! and non-temporal-store traffic of the second array (D2Q9 4096^2: 1.1-1.35 times the pull
//! kernel's rate, measured interleaved). The array then holds the populations in another layout
//! ([`post`]); everything outside the kernels reads them through [`post::Post`].

mod aa;
mod aligned;
pub mod boundary;
mod check;
pub mod collision;
pub mod d3;
mod domain;
mod error;
mod forces;
mod kernel;
pub mod lattice;
mod part;
mod post;
pub(crate) mod probes;
mod refine;
mod solver;
mod specials;
pub mod sponge;
pub mod thermal;
mod units;

pub use aa::Propagation;
pub use aligned::advise_huge_pages;
pub use collision::Collision;
pub use domain::{Edge, Grid, Side, Sides};
pub use error::LbmError;
pub use refine::{Patch, Refined};
pub use solver::{D2q9, D2q9Config, WallPoint, ON_WALL};
pub use sponge::Sponge;
pub use units::Units;
