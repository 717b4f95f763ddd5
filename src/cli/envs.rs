//! `hgym envs`: the table of every ID (with its committed deviations from the literature), a
//! spec as TOML, and calibration of observation statistics.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use hgym::env::family::CalibrateError;

use super::progress::Progress;
use crate::{thread_pool, Outcome, UsageError};
use hgym::flow::Level;

#[derive(Args)]
pub struct EnvsArgs {
    #[command(subcommand)]
    command: Option<EnvsCommand>,
    /// Print the table as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Subcommand)]
pub enum EnvsCommand {
    /// Print the full spec of an ID as TOML.
    Show { id: String },
    /// Compute observation statistics from an uncontrolled run and record them.
    Calibrate {
        id: String,
        /// Resolution level of the run (the statistics are recorded per level).
        #[arg(long, value_enum, default_value_t = Level::Default)]
        level: Level,
        /// Control intervals to average over.
        #[arg(long, default_value_t = 100)]
        actions: usize,
        /// The table to update (default: the family's committed table,
        /// benchmarks/envs/normalization.toml or benchmarks/envs/kolmogorov.toml).
        #[arg(long)]
        table: Option<PathBuf>,
        /// Worker threads (default: all cores); results are bitwise repeatable for the same seed and thread count.
        #[arg(long)]
        threads: Option<usize>,
    },
}

pub fn run(args: EnvsArgs) -> Result<Outcome> {
    match args.command {
        None => {
            let specs = hgym::env::registry::all();
            if args.json {
                let rows: Vec<serde_json::Value> = specs
                    .iter()
                    .map(|s| {
                        serde_json::json!({
                            "id": s.id(), "family": s.family(), "dimension": s.dimension(), "reynolds": s.reynolds(),
                            "observations": s.obs_dim(), "actions": s.act_dim(), "solver": s.solver(),
                            "differentiable": s.differentiable(),
                            "calibrated": s.calibrated(), "spec_hash": s.hash(),
                            "fidelity": {
                                "coarse": hgym::fidelity::known(s, Level::Coarse).entry(),
                                "default": hgym::fidelity::known(s, Level::Default).entry(),
                            },
                        })
                    })
                    .collect();
                println!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                println!(
                    "{:<30} {:>3} {:>7} {:>5} {:>5} {:<11} {:<10} {:<22} {}",
                    "ID", "dim", "Re", "obs", "act", "solver", "calibrated", "vs literature: coarse", "default"
                );
                for s in &specs {
                    println!(
                        "{:<30} {:>3} {:>7} {:>5} {:>5} {:<11} {:<10} {:<22} {}",
                        s.id(),
                        format!("{}D", s.dimension()),
                        s.reynolds(),
                        s.obs_dim(),
                        s.act_dim(),
                        s.solver(),
                        if s.calibrated() { "yes" } else { "no" },
                        hgym::fidelity::known(s, Level::Coarse).summary(),
                        hgym::fidelity::known(s, Level::Default).summary()
                    );
                }
            }
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Show { id }) => {
            let spec = hgym::env::lookup(&id)?;
            println!("# {} (spec hash {})", spec.id(), spec.hash());
            print!("{}", spec.to_toml());
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Calibrate {
            id,
            level,
            actions,
            table,
            threads,
        }) => {
            let spec = hgym::env::lookup(&id)?;
            let (pool, _) = thread_pool(threads)?;
            // Made at the first action's report, so that its clock leaves out the spin-up (which
            // reports on its own).
            let mut pb: Option<Progress> = None;
            let result = pool.install(|| {
                spec.calibrate(level, actions, hgym::env::default_cache_dir(), table.as_deref(), &mut |k| {
                    pb.get_or_insert_with(|| Progress::counting(actions as u64, &id, "actions"))
                        .set_position(k as u64)
                })
            });
            if let Some(pb) = &pb {
                pb.finish_and_clear();
            }
            let (summary, written) = match result {
                Err(CalibrateError::Table(e)) => {
                    return Err(UsageError(format!("{e} (run from the repository root, or pass --table)")).into())
                }
                other => other.with_context(|| format!("calibrating {id}"))?,
            };
            println!("{summary}");
            println!(
                "calibrated {id} at the {} level over {actions} actions; wrote {} (rebuild to embed)",
                level.name(),
                written.display()
            );
            Ok(Outcome::Ok)
        }
    }
}
