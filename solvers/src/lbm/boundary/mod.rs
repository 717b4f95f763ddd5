//! Boundaries, one file per kind: interpolated bounce-back on curved walls ([`bouzidi`]) and the
//! domain edges ([`sides`], with the non-reflecting inlets of [`characteristic`]). Each computes the population `g_k(x)` that cannot be streamed
//! because its source `x - c_k` is a wall or outside the domain, from the source array of
//! post-collision populations `f*(t)`.

mod bouzidi;
mod characteristic;
mod sides;

pub(crate) use bouzidi::bouzidi;
pub use characteristic::InletReference;
pub(crate) use sides::side_value;
