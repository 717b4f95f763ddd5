//! Transfer protocols (`benchmarks/protocols/transfer/*.toml`, `hgym transfer SOURCE TARGET`):
//! over the same seeds, a source policy (an ordinary run folder per seed) is evaluated zero-shot
//! on the target, fine-tuned there from its policy, and compared with training from scratch on
//! the target. Each arm of each seed is an ordinary run folder under
//! `<out>/<name>/{zeroshot,finetune,scratch}/seed<S>/`, so a protocol resumes where it stopped.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::mapping::MappingSpec;
use crate::flow::Level;
use crate::train::config::TrainConfig;

/// The protocols shipped with hgym (`hgym transfer --list`), by file name.
pub const BUNDLED: &[(&str, &str)] = &[
    (
        "cylinder_re200_re1000",
        include_str!("../../benchmarks/protocols/transfer/cylinder_re200_re1000.toml"),
    ),
    (
        "cylinder_re1000_re3900",
        include_str!("../../benchmarks/protocols/transfer/cylinder_re1000_re3900.toml"),
    ),
    (
        "cylinder_square_re200",
        include_str!("../../benchmarks/protocols/transfer/cylinder_square_re200.toml"),
    ),
    (
        "cylinder_2d_3d_re200",
        include_str!("../../benchmarks/protocols/transfer/cylinder_2d_3d_re200.toml"),
    ),
    (
        "channel_wing",
        include_str!("../../benchmarks/protocols/transfer/channel_wing.toml"),
    ),
];

/// The training configurations bundled protocols name in `config_file`, by that path: a
/// protocol reads them from here, so that `hgym transfer` runs from any folder.
const BUNDLED_CONFIGS: &[(&str, &str)] = &[(
    "benchmarks/train/TCFOpen_3D_Retau206-td3.toml",
    include_str!("../../benchmarks/train/TCFOpen_3D_Retau206-td3.toml"),
)];

/// The three arms, in the order they run.
pub const ARMS: [&str; 3] = ["zeroshot", "finetune", "scratch"];

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Protocol {
    pub name: String,
    pub description: String,
    /// Source and target environment IDs.
    pub source: String,
    pub target: String,
    /// Short names `hgym transfer` also accepts for the pair, e.g. ["channel", "naca0012"].
    #[serde(default)]
    pub alias: Vec<String>,
    pub algo: String,
    pub level: Level,
    pub seeds: Vec<u64>,
    /// The spec hash the source runs must have been trained on.
    pub source_spec_hash: String,
    /// The source run of each seed, `{seed}` standing for the seed: a `hgym train` folder
    /// (`results/train/<source>-<algo>-<level>/seed{seed}`) or another protocol's arm.
    pub source_runs: String,
    /// Fraction of the from-scratch arm's final gain over the uncontrolled flow that defines
    /// "reaching" it (samples and episodes to threshold).
    pub fraction: f64,
    #[serde(default)]
    pub mapping: MappingSpec,
    /// The fine-tuning arm also starts from the source's critics (and their targets, through
    /// the mapping; off-policy learners), read from each source run's checkpoint. Without them a
    /// TD3 actor is trained against a fresh critic and loses what it knew in its first updates.
    #[serde(default)]
    pub init_critics: bool,
    /// Training configuration of both training arms, and the source runs' own but for the step
    /// budget (`train.steps`, the arms'): a `[config]` table, or read from `config_file`.
    #[serde(default)]
    pub config: TrainConfig,
    /// The training configuration file `config` is read from (a path from the repository root,
    /// e.g. the source runs' `benchmarks/train/TCFOpen_3D_Retau206-td3.toml`), so that a
    /// protocol keeps no copy of it that could drift.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub config_file: Option<String>,
    /// A zero-shot deployment protocol: no training on the target, only the source policies
    /// deployed beside the uncontrolled flow and classical controllers ([`super::deploy`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deployment: Option<Deployment>,
}

/// The `[deployment]` table of a zero-shot protocol.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Deployment {
    /// Evaluation episodes (seeds `config.train.eval_seed` on) of every arm.
    pub episodes: u64,
    /// Actions of each episode before the measurement starts (the controlled layer's transient).
    #[serde(default)]
    pub settle_actions: usize,
    /// `[env]` overrides of the target for every arm (a baseline's own on top).
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub env: toml::Table,
    /// Classical controllers deployed the same way.
    #[serde(default)]
    pub baselines: Vec<BaselineArm>,
}

/// A classical controller of a deployment protocol: an `hgym eval --policy` baseline, with
/// `[env]` overrides of the target (e.g. net blowing through the wall).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaselineArm {
    /// Folder name and label, e.g. `opposition`.
    pub name: String,
    /// e.g. `wall-opposition`, `constant=0.02`.
    pub policy: String,
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub env: toml::Table,
}

/// A protocol file that cannot be used, or a pair without one (bad input).
#[derive(Debug, thiserror::Error)]
pub enum ProtocolError {
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{origin}: {message}")]
    Invalid { origin: String, message: String },
    #[error("{origin}: its config_file")]
    Config {
        origin: String,
        #[source]
        source: Box<crate::train::config::ConfigError>,
    },
    #[error("no transfer protocol from '{source_name}' to '{target}'; the protocols are:\n{list}")]
    UnknownPair { source_name: String, target: String, list: String },
}

/// The training configuration at `path`: a bundled one, else the file.
fn read_config(path: &str) -> Result<TrainConfig, crate::train::config::ConfigError> {
    match BUNDLED_CONFIGS.iter().find(|(p, _)| *p == path) {
        Some((_, text)) => TrainConfig::parse(text, path),
        None => TrainConfig::load(Path::new(path)),
    }
}

impl Protocol {
    /// Parses a protocol's text (`origin` names it in errors).
    pub fn parse(text: &str, origin: &str) -> Result<Protocol, ProtocolError> {
        let invalid = |message: String| ProtocolError::Invalid {
            origin: origin.to_string(),
            message,
        };
        let mut p: Protocol = toml::from_str(text).map_err(|e| invalid(e.to_string()))?;
        if let Some(file) = &p.config_file {
            // A second parse, as a table, only to see whether `[config]` was written: parsing
            // once to a table and converting it would cost every error its line and column.
            let table: toml::Table = toml::from_str(text).map_err(|e| invalid(e.to_string()))?;
            if table.contains_key("config") {
                return Err(invalid(format!(
                    "both config_file = \"{file}\" and a [config] table; keep one (the file, when the source runs were trained with it)"
                )));
            }
            p.config = read_config(file).map_err(|source| ProtocolError::Config {
                origin: origin.to_string(),
                source: Box::new(source),
            })?;
        }
        hgym_agents::learn::algorithm(&p.algo).map_err(|e| invalid(e.to_string()))?;
        p.config.algos = p.config.algos.complete().map_err(|e| invalid(e.to_string()))?;
        if p.seeds.is_empty() {
            return Err(invalid("seeds must list at least one seed".into()));
        }
        if !(p.fraction > 0.0 && p.fraction <= 1.0) {
            return Err(invalid(format!("fraction must be in (0, 1], got {}", p.fraction)));
        }
        if let Some(d) = &p.deployment {
            if d.episodes == 0 {
                return Err(invalid("[deployment] episodes must be at least 1".into()));
            }
            for b in &d.baselines {
                crate::train::eval::parse_policy(&b.policy).map_err(|e| invalid(format!("[deployment] baseline '{}': {e}", b.name)))?;
                if b.name.is_empty() || b.name.contains(['/', '\\']) || ARMS.contains(&b.name.as_str()) {
                    return Err(invalid(format!(
                        "[deployment] baseline name '{}' must be a plain folder name other than {ARMS:?}",
                        b.name
                    )));
                }
            }
        }
        if !p.alias.is_empty() && p.alias.len() != 2 {
            return Err(invalid(format!(
                "alias names the source and the target: two names, got {:?}",
                p.alias
            )));
        }
        Ok(p)
    }

    pub fn load(path: &Path) -> Result<Protocol, ProtocolError> {
        let text = std::fs::read_to_string(path).map_err(|source| ProtocolError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Every bundled protocol.
    pub fn bundled() -> Vec<Protocol> {
        BUNDLED
            .iter()
            .map(|(name, text)| Protocol::parse(text, name).expect("bundled protocols parse (tested)"))
            .collect()
    }

    /// The bundled protocol for the pair, by environment ID or alias (any case).
    pub fn find(source: &str, target: &str) -> Result<Protocol, ProtocolError> {
        let is = |a: &str, b: &str| a.eq_ignore_ascii_case(b);
        Self::bundled()
            .into_iter()
            .find(|p| {
                (is(&p.source, source) || p.alias.first().is_some_and(|a| is(a, source)))
                    && (is(&p.target, target) || p.alias.get(1).is_some_and(|a| is(a, target)))
            })
            .ok_or_else(|| ProtocolError::UnknownPair {
                source_name: source.into(),
                target: target.into(),
                list: Self::listing(),
            })
    }

    /// One line per bundled protocol: `SOURCE TARGET  description`.
    pub fn listing() -> String {
        Self::bundled()
            .iter()
            .map(|p| format!("  {} {}  ({})", p.source, p.target, p.description))
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// The source run of `seed`.
    pub fn source_dir(&self, seed: u64) -> PathBuf {
        PathBuf::from(self.source_runs.replace("{seed}", &seed.to_string()))
    }

    /// The folder of `arm` for `seed` under the protocol's root.
    pub fn arm_dir(&self, root: &Path, arm: &str, seed: u64) -> PathBuf {
        root.join(arm).join(format!("seed{seed}"))
    }

    /// The command that makes the source runs: the bundled protocol whose from-scratch arm
    /// they are, else `hgym train` with the configuration file `config` (a run's own when it is
    /// remade, else [`Protocol::config`]) into the folders `source_runs` names.
    pub fn source_command(&self, config: &Path) -> String {
        let seed = self.seeds[0];
        let dir = self.source_dir(seed);
        let arm = |p: &Protocol| Path::new(&p.name).join("scratch").join(format!("seed{seed}"));
        if let Some(p) = Self::bundled().iter().find(|p| dir.ends_with(arm(p))) {
            let root = dir.parent().and_then(Path::parent).and_then(Path::parent).unwrap_or(Path::new("."));
            return format!("hgym transfer {} {} --out {}", p.source, p.target, root.display());
        }
        let seeds: Vec<String> = self.seeds.iter().map(u64::to_string).collect();
        let root = dir.parent().and_then(Path::parent).unwrap_or(Path::new("."));
        format!(
            "hgym train --env {} --algo {} --res {} --seeds {} --config {} --out {}",
            self.source,
            self.algo,
            self.level.name(),
            seeds.join(","),
            config.display(),
            root.display()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bundled_protocols_parse_and_name_registered_environments() {
        for p in Protocol::bundled() {
            for id in [&p.source, &p.target] {
                crate::env::lookup(id).unwrap_or_else(|e| panic!("{}: {e}", p.name));
            }
            let target = crate::env::lookup(&p.target).unwrap();
            let seeds = if target.dimension() == 2 { 5 } else { 3 };
            assert!(
                p.seeds.len() >= seeds,
                "{}: a protocol to a {}D flow runs >= {seeds} seeds",
                p.name,
                target.dimension()
            );
            let spec = crate::train::resolve_spec(&p.source, &p.config).unwrap();
            assert_eq!(spec.hash(), p.source_spec_hash, "{}: pinned source hash", p.name);
            if let Some(file) = &p.config_file {
                assert!(
                    BUNDLED_CONFIGS.iter().any(|(path, _)| path == file),
                    "{}: config_file {file} is not in BUNDLED_CONFIGS, so `hgym transfer` would read it from the working folder",
                    p.name
                );
            }
        }
        assert_eq!(
            Protocol::find("cylinder_2d_re200", "Cylinder_2D_Re1000").unwrap().name,
            "cylinder_re200_re1000"
        );
        assert_eq!(Protocol::find("channel", "NACA0012").unwrap().name, "channel_wing");
        let e = Protocol::find("channel", "cylinder").unwrap_err().to_string();
        assert!(e.contains("Cylinder_2D_Re200 SquareCylinder_2D_Re200"), "{e}");
    }

    /// `config_file` gives the configuration of that file; given beside a `[config]` table, or
    /// naming no file, the protocol is refused with what to do.
    #[test]
    fn config_file_is_read_and_not_doubled() {
        let wing = Protocol::find("channel", "naca0012").unwrap();
        let file = wing.config_file.clone().unwrap();
        let text = std::fs::read_to_string(&file).unwrap();
        assert_eq!(wing.config, TrainConfig::parse(&text, &file).unwrap());
        let (_, bundled) = BUNDLED.iter().find(|(n, _)| *n == "channel_wing").unwrap();
        let doubled = format!("{bundled}\n[config.train]\nsteps = 10\n");
        let e = Protocol::parse(&doubled, "doubled").unwrap_err().to_string();
        assert!(e.contains("both config_file") && e.contains("keep one"), "{e}");
        let missing = bundled.replace(&file, "no/such/config.toml");
        let e = Protocol::parse(&missing, "missing").unwrap_err();
        let chain = format!("{e}: {}", std::error::Error::source(&e).unwrap());
        assert!(chain.contains("config_file") && chain.contains("no/such/config.toml"), "{chain}");
    }

    /// A protocol's configuration is the one its committed source runs were trained with, but
    /// for the step budget, which a protocol may set for its target's arms (what `hgym
    /// transfer` would remake them with, and what its train.toml records).
    #[test]
    fn bundled_protocols_configure_what_their_source_runs_used() {
        for p in Protocol::bundled() {
            for &seed in &p.seeds {
                let dir = p.source_dir(seed);
                if !dir.join("manifest.json").exists() {
                    continue;
                }
                let run = super::super::SourceRun::load(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
                let mut used = TrainConfig::parse(&run.config_toml, "manifest").unwrap();
                used.train.steps = p.config.train.steps;
                assert_eq!(
                    used.to_toml(),
                    p.config.to_toml(),
                    "{}: the configuration differs from the one {} was trained with",
                    p.name,
                    dir.display()
                );
            }
        }
    }
}
