//! `hgym envs`: the table of every ID (with its committed deviations from the literature), a
//! spec as TOML, and calibration of observation statistics.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

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
        #[arg(long, value_enum, default_value_t = Level::Default)]
        level: Level,
        /// Control intervals to average over.
        #[arg(long, default_value_t = 100)]
        actions: usize,
        /// The table to update.
        #[arg(long, default_value = "benchmarks/envs/normalization.toml")]
        table: PathBuf,
        #[arg(long)]
        threads: Option<usize>,
    },
}

/// The committed deviations of `s`'s uncontrolled flow at `level` from the literature
/// (`hgym validate --env ID --level L --record`), if measured on the flow registered now.
fn fidelity_entry(s: &hgym::env::any::AnySpec, level: Level) -> Option<&'static hgym::fidelity::Entry> {
    match s {
        hgym::env::any::AnySpec::Lbm(spec) => hgym::fidelity::committed(spec, level),
        hgym::env::any::AnySpec::Kolmogorov(_) => None,
    }
}

/// `St -2.7% C_D +13.7%`; `-` without references (the Kolmogorov flows' check is `hgym validate
/// kolmogorov`); `not measured`.
fn fidelity(s: &hgym::env::any::AnySpec, level: Level) -> String {
    match (s, fidelity_entry(s, level)) {
        (_, Some(e)) => e.summary(),
        (hgym::env::any::AnySpec::Lbm(spec), None) if hgym::fidelity::has_reference(spec) => "not measured".into(),
        _ => "-".into(),
    }
}

pub fn run(args: EnvsArgs) -> Result<Outcome> {
    match args.command {
        None => {
            let specs = hgym::env::any::all();
            let calibrated = |s: &hgym::env::any::AnySpec| match s {
                hgym::env::any::AnySpec::Lbm(s) => !s.normalization.mean.is_empty(),
                hgym::env::any::AnySpec::Kolmogorov(s) => s.statistics.u_rms > 0.0,
            };
            if args.json {
                let rows: Vec<serde_json::Value> = specs
                    .iter()
                    .map(|s| {
                        serde_json::json!({
                            "id": s.id(), "family": s.family(), "dimension": 2, "reynolds": s.reynolds(),
                            "observations": s.obs_dim(), "actions": s.act_dim(), "solver": s.solver(),
                            "differentiable": s.differentiable(),
                            "calibrated": calibrated(s), "spec_hash": s.hash(),
                            "fidelity": {
                                "coarse": fidelity_entry(s, Level::Coarse),
                                "default": fidelity_entry(s, Level::Default),
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
                        "2D",
                        s.reynolds(),
                        s.obs_dim(),
                        s.act_dim(),
                        s.solver(),
                        if calibrated(s) { "yes" } else { "no" },
                        fidelity(s, Level::Coarse),
                        fidelity(s, Level::Default)
                    );
                }
            }
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Show { id }) => {
            let spec = hgym::env::any::lookup(&id)?;
            println!("# {} (spec hash {})", spec.id(), spec.hash());
            print!("{}", spec.to_toml());
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Calibrate {
            id,
            level,
            actions,
            table: _,
            threads: _,
        }) if id.starts_with("Kolmogorov") => {
            let hgym::env::any::AnySpec::Kolmogorov(spec) = hgym::env::any::lookup(&id)? else {
                return Err(UsageError(format!("{id} is not a Kolmogorov flow")).into());
            };
            let table = PathBuf::from("benchmarks/envs/kolmogorov.toml");
            let text = std::fs::read_to_string(&table)
                .with_context(|| format!("cannot read {} (run from the repository root)", table.display()))?;
            let mut entries: std::collections::BTreeMap<String, hgym::env::kolmogorov::FlowStatistics> =
                toml::from_str(&text).with_context(|| format!("{} is malformed", table.display()))?;
            let pb = Progress::new(actions as u64, &id);
            let st = hgym::env::kolmogorov::calibrate(&spec, level, actions, &mut |k| pb.set_position(k as u64))
                .with_context(|| format!("calibrating {id}"))?;
            pb.finish_and_clear();
            println!(
                "{id}: u_rms {:.4}, dissipation {:.4} +- {:.4} (laminar {:.4}), TKE {:.4} over {} time units",
                st.u_rms,
                st.dissipation_mean,
                st.dissipation_std,
                spec.dissipation_laminar(),
                st.tke_mean,
                st.time
            );
            entries.insert(id.clone(), st);
            let header: String = text.lines().take_while(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
            let body = toml::to_string_pretty(&entries).context("cannot format the table")?;
            std::fs::write(&table, format!("{header}\n{body}")).with_context(|| format!("cannot write {}", table.display()))?;
            println!("wrote {} (rebuild to embed)", table.display());
            Ok(Outcome::Ok)
        }
        Some(EnvsCommand::Calibrate {
            id,
            level,
            actions,
            table,
            threads,
        }) => {
            let spec = hgym::env::spec(&id)?;
            if actions == 0 {
                return Err(UsageError("--actions must be at least 1".into()).into());
            }
            let text = std::fs::read_to_string(&table)
                .with_context(|| format!("cannot read {} (run from the repository root or pass --table)", table.display()))?;
            // Parsed now to fail fast on a broken table; read again before writing (below).
            hgym::env::calibrate::parse_table(&text).map_err(anyhow::Error::msg)?;
            let (pool, _) = thread_pool(threads)?;
            let pb = Progress::new(actions as u64, &id);
            let entry = pool
                .install(|| {
                    hgym::env::calibrate::calibrate(&spec, level, actions, hgym::env::default_cache_dir(), &mut |k, _| {
                        pb.set_position(k as u64)
                    })
                })
                .with_context(|| format!("calibrating {id}"))?;
            pb.finish_and_clear();
            if let Some([c_d, c_l]) = entry.mean_forces {
                println!("{id}: uncontrolled mean C_D {c_d:.4}, mean C_L {c_l:.4}");
            }
            // Re-read the table: other calibrations may have written their entries while this one
            // ran (several IDs are often calibrated at once); then write atomically.
            let text = std::fs::read_to_string(&table).with_context(|| format!("cannot read {}", table.display()))?;
            let mut entries = hgym::env::calibrate::parse_table(&text).map_err(anyhow::Error::msg)?;
            entries.insert(hgym::env::calibrate::table_key(&id, level), entry);
            let header: String = text.lines().take_while(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
            let body = toml::to_string_pretty(&entries).context("cannot format the table")?;
            let tmp = table.with_extension(format!("tmp.{}", std::process::id()));
            std::fs::write(&tmp, format!("{header}\n{body}")).with_context(|| format!("cannot write {}", tmp.display()))?;
            std::fs::rename(&tmp, &table).with_context(|| format!("cannot replace {}", table.display()))?;
            println!(
                "calibrated {id} at the {} level over {actions} actions; wrote {} (rebuild to embed)",
                level.name(),
                table.display()
            );
            Ok(Outcome::Ok)
        }
    }
}
