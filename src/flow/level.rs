//! Resolution levels: a level is a number of cells per reference length, never a different flow.

use serde::{Deserialize, Serialize};

/// Resolution level: a number of cells per reference length, never a different case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Level {
    Coarse,
    Default,
    Fine,
}

impl Level {
    pub fn name(self) -> &'static str {
        match self {
            Level::Coarse => "coarse",
            Level::Default => "default",
            Level::Fine => "fine",
        }
    }
}

/// Cells per reference length at each level.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ResolutionSpec {
    pub coarse: u32,
    pub default: u32,
    pub fine: u32,
}

impl ResolutionSpec {
    pub fn at(&self, level: Level) -> u32 {
        match level {
            Level::Coarse => self.coarse,
            Level::Default => self.default,
            Level::Fine => self.fine,
        }
    }
}
