//! Errors of the lattice Boltzmann solver. Each names the fact and, where there is one, the fix.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum LbmError {
    /// A configuration that cannot run (checked before the first step).
    #[error("invalid LBM configuration, `{field}`: {message}")]
    Config { field: &'static str, message: String },

    /// The solution left the physically meaningful range.
    #[error("the solver diverged at step {step}: {reason} at node ({x}, {y})")]
    Diverged { step: u64, reason: String, x: usize, y: usize },

    /// The 3D solution left the physically meaningful range.
    #[error("the solver diverged at step {step}: {reason} at node ({}, {}, {})", at[0], at[1], at[2])]
    Diverged3 { step: u64, reason: String, at: [usize; 3] },

    /// A probe point outside the grid.
    #[error("probe point ({x:.4}, {y:.4}) lies outside the domain [{xmin:.4}, {xmax:.4}] x [{ymin:.4}, {ymax:.4}]")]
    ProbeOutside {
        x: f64,
        y: f64,
        xmin: f64,
        xmax: f64,
        ymin: f64,
        ymax: f64,
    },
}
