//! Errors of the channel solver. Each names the fact and, where there is one, the fix.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ChannelError {
    /// A configuration that cannot run (checked before the first step).
    #[error("invalid channel configuration, `{field}`: {message}")]
    Config { field: &'static str, message: String },

    /// Wall transpiration whose net volume flux is not zero: the incompressible flow has nowhere to
    /// put it (the mean pressure equation has no solution).
    #[error(
        "the wall transpiration has a net volume flux of {net:.3e} (blowing minus suction, per unit \
         area); subtract its mean to make it zero-net-mass-flux"
    )]
    NetTranspiration { net: f64 },

    /// A field array of the wrong size handed to the solver.
    #[error("`{what}` has {got} values, the grid needs {want}")]
    Size { what: &'static str, got: usize, want: usize },

    /// The solution left the stable range.
    #[error(
        "the channel solver diverged at step {step} (t = {time:.4}): CFL number {cfl:.3} (the RK3 \
         limit is about 1.7); lower dt"
    )]
    Diverged { step: u64, time: f64, cfl: f64 },
}

impl ChannelError {
    pub(crate) fn config(field: &'static str, message: impl Into<String>) -> Self {
        ChannelError::Config {
            field,
            message: message.into(),
        }
    }
}
