//! Subcommands of the binary that grew past a few lines: `train`, `eval`, `bench agents`;
//! `export`, `push`.

pub mod data;

pub mod train;
