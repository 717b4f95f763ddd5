//! Subcommands of the binary that grew past a few lines: `train`, `eval`, `bench agents`.

pub mod train;
