//! A small neural-network module: dense layers, activations, backward pass, Adam.
//! General deep-learning crates cost 10-30x the arithmetic at policy sizes (see issue notes).

mod adam;
mod init;
mod mlp;
mod scalar;

pub use adam::{clip_grad_norm, Adam};
pub use init::Init;
pub use mlp::{Activation, Mlp, Tape};
pub use scalar::Scalar;
