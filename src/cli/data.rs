//! `hgym export` and `hgym push`: trajectory files to a Hugging Face dataset folder, and that
//! folder to the Hub.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use hgym::data::hf::{export, ExportOptions};
use hgym::data::hub::{self, HubConfig};

use crate::{Outcome, UsageError};

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum ExportFormat {
    /// Hugging Face dataset folder: Parquet shards + README.md dataset card.
    Hf,
}

#[derive(Args)]
pub struct ExportArgs {
    /// Target format.
    #[arg(long = "to", value_enum, default_value = "hf")]
    to: ExportFormat,
    /// A folder searched recursively for *.mcap trajectories (e.g. results/train), or one file.
    dir: PathBuf,
    /// The dataset folder to write (new, empty, or an earlier export, whose data it replaces).
    out: PathBuf,
    /// Rows per Parquet shard of the step tables.
    #[arg(long, default_value_t = 100_000)]
    shard_rows: usize,
    /// Licence in the dataset card (SPDX ID as the Hub lists them).
    #[arg(long, default_value = "cc-by-4.0")]
    license: String,
    /// Dataset title in the card.
    #[arg(long)]
    name: Option<String>,
    /// Print what was written as JSON (the content of OUT/hgym_export.json).
    #[arg(long)]
    json: bool,
}

pub fn run_export(args: ExportArgs) -> Result<Outcome> {
    let ExportFormat::Hf = args.to;
    if args.shard_rows == 0 {
        return Err(UsageError("--shard-rows must be at least 1".into()).into());
    }
    let opts = ExportOptions {
        shard_rows: args.shard_rows,
        license: args.license.clone(),
        pretty_name: args.name.clone(),
        ..ExportOptions::default()
    };
    let paths = hgym::data::hf::find_trajectories(&args.dir)?;
    let pb = super::progress::Progress::counting(paths.len() as u64, "reading", "files");
    let report = export(&args.dir, &args.out, &opts, &mut |k, _| pb.set_position(k as u64))?;
    pb.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "exported {} control steps{} from {} trajectory files into {}",
            report.rows,
            if report.snapshots > 0 {
                format!(" and {} flow-field snapshots", report.snapshots)
            } else {
                String::new()
            },
            report.runs.len(),
            args.out.display()
        );
        println!("  configs: {}", report.configs.join(", "));
        println!("  files:   {}", report.files.len() + 2);
        println!(
            "  check it: python -c \"import pandas; print(pandas.read_parquet('{}/data/{}'))\"",
            args.out.display(),
            report.configs.first().map(|s| s.as_str()).unwrap_or("ENV")
        );
        println!("  upload:  hgym push {} --repo USER/NAME", args.out.display());
    }
    Ok(Outcome::Ok)
}

#[derive(Args)]
pub struct PushArgs {
    /// The dataset folder (`hgym export --to hf DIR OUT` writes one).
    dir: PathBuf,
    /// Dataset repository on the Hub, user/name or org/name; created if it does not exist.
    #[arg(long)]
    repo: String,
    /// Create the repository private (an existing repository keeps its visibility).
    #[arg(long)]
    private: bool,
    /// Commit message.
    #[arg(long, default_value = "Upload hgym dataset")]
    message: String,
    /// Retries per request on 429, 5xx, network failures and time-outs (exponential backoff from
    /// 0.5 s, or the server's Retry-After up to 60 s).
    #[arg(long, default_value_t = 5)]
    retries: u32,
    /// Seconds one request may take (connecting: at most 10 of them), plus one second per MB it
    /// uploads; a server silent for longer has timed out.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u64).range(1..=3600))]
    timeout: u64,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run_push(args: PushArgs) -> Result<Outcome> {
    hub::check_repo(&args.repo)?;
    let cfg = HubConfig::from_env(args.retries, Duration::from_secs(args.timeout))?;
    let json = args.json;
    let report = hub::push(&args.dir, &args.repo, args.private, &args.message, &cfg, &mut |m| {
        if !json {
            eprintln!("{m}");
        }
    })?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "pushed {} files ({} bytes, {} through LFS) to {}{}",
            report.files,
            report.bytes,
            report.lfs_files,
            report.url,
            if report.created { " (new repository)" } else { "" }
        );
    }
    Ok(Outcome::Ok)
}

#[derive(Subcommand)]
pub enum DataCommand {
    /// Copy every complete chunk (and the metadata) of a damaged MCAP file into a valid one.
    Recover {
        file: PathBuf,
        /// Output file (default: <file>.recovered.mcap).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print what was recovered as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// `hgym data recover`.
pub fn run_data(cmd: DataCommand) -> Result<Outcome> {
    let DataCommand::Recover { file, out, json } = cmd;
    let out = out.unwrap_or_else(|| file.with_extension("recovered.mcap"));
    if !file.is_file() {
        return Err(UsageError(format!("{} is not a file (give a trajectory.mcap to salvage)", file.display())).into());
    }
    let r = hgym::data::trajectory::recover(&file, &out)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        println!(
            "recovered {} messages and {} metadata records from {} into {}{}",
            r.messages,
            r.metadata,
            file.display(),
            out.display(),
            if r.complete {
                "\n  nothing lost: the file was complete".to_string()
            } else {
                format!(
                    "\n  lost: the file was cut; {} of its {} bytes were whole records, and the messages after the last complete chunk are gone (compressed, so they cannot be counted){}",
                    r.bytes_read,
                    r.bytes_total,
                    r.stopped_at.as_ref().map(|e| format!("; reading stopped: {e}")).unwrap_or_default()
                )
            }
        );
    }
    Ok(Outcome::Ok)
}
