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

    pub const ALL: [Level; 3] = [Level::Coarse, Level::Default, Level::Fine];
}

/// A level name that is not `coarse`, `default` or `fine`.
#[derive(Debug, thiserror::Error)]
#[error("level '{0}' is not one of 'coarse', 'default', 'fine'")]
pub struct UnknownLevel(pub String);

impl std::str::FromStr for Level {
    type Err = UnknownLevel;

    fn from_str(name: &str) -> Result<Self, Self::Err> {
        Level::ALL
            .into_iter()
            .find(|l| l.name() == name)
            .ok_or_else(|| UnknownLevel(name.to_string()))
    }
}

/// One value per level (a grid, a time step, a window): `[coarse]`, `[default]`, `[fine]`
/// tables or keys in a file.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PerLevel<T> {
    pub coarse: T,
    pub default: T,
    pub fine: T,
}

impl<T> PerLevel<T> {
    pub fn at(&self, level: Level) -> &T {
        match level {
            Level::Coarse => &self.coarse,
            Level::Default => &self.default,
            Level::Fine => &self.fine,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_others_are_refused() {
        for level in Level::ALL {
            assert_eq!(level.name().parse::<Level>().ok(), Some(level));
        }
        let err = "medium".parse::<Level>().unwrap_err().to_string();
        assert!(err.contains("'medium'") && err.contains("'coarse', 'default', 'fine'"), "{err}");
    }
}
