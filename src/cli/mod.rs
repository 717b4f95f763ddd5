//! Subcommands of the binary that grew past a few lines: `train`, `eval`, `bench agents`;
//! `export`, `push`; progress reports for long runs.

pub mod data;
pub mod out;
pub mod progress;

pub mod train;
pub mod validate;
