//! `hgym transfer`: a transfer protocol's three arms over its seeds, then their comparison.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use hgym::train::eval::{evaluate, uncontrolled};
use hgym::train::{resolve_spec, TrainOptions};
use hgym::transfer::protocol::{Protocol, ARMS};
use hgym::transfer::SourceRun;

use crate::cli::train::{finished_run, init_from, install_interrupt, protocol_run, EvalRun};
use crate::{thread_pool, Outcome, UsageError};

#[derive(Args)]
pub struct TransferArgs {
    /// Source environment (ID or the protocol's short name), e.g. Cylinder_2D_Re200.
    #[arg(required_unless_present_any = ["protocol", "list"], requires = "target")]
    source: Option<String>,
    /// Target environment, e.g. Cylinder_2D_Re1000.
    target: Option<String>,
    /// Any protocol file instead of a bundled pair (see benchmarks/protocols/transfer/).
    #[arg(long, conflicts_with_all = ["source", "list"])]
    protocol: Option<PathBuf>,
    /// List the bundled protocols and exit.
    #[arg(long)]
    list: bool,
    /// Where the arms and the comparison go: <out>/<name>/{zeroshot,finetune,scratch}/seed<S>/,
    /// comparison.json, transfer.png.
    #[arg(long, default_value = "results/transfer")]
    out: PathBuf,
    /// Only recompute the comparison from finished arms.
    #[arg(long)]
    analyse_only: bool,
    /// Print the comparison as JSON.
    #[arg(long)]
    json: bool,
    /// Worker threads (default: all cores); results are bitwise repeatable for the same seed and thread count.
    #[arg(long)]
    threads: Option<usize>,
}

fn usage(e: impl std::fmt::Display) -> anyhow::Error {
    UsageError(e.to_string()).into()
}

pub fn run(args: TransferArgs) -> Result<Outcome> {
    if args.list {
        println!("{}", Protocol::listing());
        return Ok(Outcome::Ok);
    }
    let p = match (&args.protocol, &args.source, &args.target) {
        (Some(file), _, _) => Protocol::load(file).map_err(usage)?,
        (None, Some(s), Some(t)) => Protocol::find(s, t).map_err(usage)?,
        _ => return Err(usage("give SOURCE TARGET, --protocol FILE or --list")),
    };
    let root = args.out.join(&p.name);
    std::fs::create_dir_all(&root).with_context(|| format!("cannot create {}", root.display()))?;
    let config_file = root.join("train.toml");
    std::fs::write(&config_file, p.config.to_toml()).with_context(|| format!("cannot write {}", config_file.display()))?;
    let target = resolve_spec(&p.target, &p.config).map_err(usage)?;
    resolve_spec(&p.source, &p.config).map_err(usage)?;
    let mut sources = vec![];
    for &seed in &p.seeds {
        let dir = p.source_dir(seed);
        if !dir.join("policy.json").exists() {
            return Err(usage(format!(
                "{}: the source run of seed {seed} is missing ({}); make the source runs with:\n  {}",
                p.name,
                dir.display(),
                p.source_command(&config_file)
            )));
        }
        let src = SourceRun::load(&dir).map_err(usage)?;
        // A run to remake is remade with the configuration it was trained with.
        let remake = || -> Result<String> {
            let file = root.join("source-train.toml");
            std::fs::write(&file, &src.config_toml).with_context(|| format!("cannot write {}", file.display()))?;
            Ok(p.source_command(&file))
        };
        if p.init_critics && !dir.join(hgym::train::checkpoint::FILE).exists() {
            return Err(usage(format!(
                "{}: the fine-tuning arm starts from the source's critics, and {} has no checkpoint (run folders commit \
                 their policy, not their 50 MB checkpoint); move the source run folders away and make them again here, \
                 checkpoints included (on the CPU and thread count their manifests record they come out bitwise the \
                 same, elsewhere as other runs of the same set-up):\n  {}",
                p.name,
                dir.display(),
                remake()?
            )));
        }
        if src.spec_hash != p.source_spec_hash || src.env_id != p.source || src.algo != p.algo {
            return Err(usage(format!(
                "{}: {} is {} {} on spec {}, the protocol's source is {} {} on spec {}; retrain it with:\n  {}",
                p.name,
                dir.display(),
                src.env_id,
                src.algo,
                &src.spec_hash[..8.min(src.spec_hash.len())],
                p.source,
                p.algo,
                &p.source_spec_hash[..8.min(p.source_spec_hash.len())],
                remake()?
            )));
        }
        sources.push(src);
    }
    let (pool, threads) = thread_pool(args.threads)?;
    if let Some(d) = &p.deployment {
        // Ctrl-C ends a deployment at once: the arms on disk are whole, the one in progress reruns.
        return crate::cli::deployment::run(&p, d, &sources, &target, &root, &pool, threads, args.analyse_only, args.json);
    }
    install_interrupt();
    if !args.analyse_only {
        let total = ARMS.len() * p.seeds.len();
        let mut k = 0;
        for arm in ARMS {
            for (src, &seed) in sources.iter().zip(&p.seeds) {
                k += 1;
                let dir = p.arm_dir(&root, arm, seed);
                let label = format!("{arm} s{seed} ({k}/{total})");
                if arm == "zeroshot" {
                    if dir.join("metrics.json").exists() {
                        eprintln!("{label}: done already ({})", dir.display());
                        continue;
                    }
                    pool.install(|| zeroshot(&p, src, &target, &dir, threads))?;
                    eprintln!("{label}: evaluated ({})", dir.display());
                    continue;
                }
                let init = match arm {
                    "finetune" => Some(init_from(src, &target, &p.mapping, p.init_critics, false)?),
                    _ => None,
                };
                let opts = TrainOptions {
                    env_id: p.target.clone(),
                    algo: p.algo.clone(),
                    seed,
                    level: p.level,
                    config: p.config.clone(),
                    out: dir.clone(),
                    cache: hgym::env::default_cache_dir(),
                    init,
                };
                if finished_run(&opts)?.is_some() {
                    eprintln!("{label}: done already ({})", dir.display());
                    continue;
                }
                protocol_run(&pool, opts, &label)?;
                eprintln!("{label}: finished ({})", dir.display());
            }
        }
    }
    let r0 = pool.install(|| hgym::train::compare::uncontrolled_return(&p.target, p.level, &p.config))?;
    let cmp = hgym::transfer::compare::analyse(&p, &root, r0, crate::cli::deployment::episode_actions(&target)? as usize)?;
    std::fs::write(root.join("comparison.json"), serde_json::to_string_pretty(&cmp)? + "\n")?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&cmp)?);
        return Ok(Outcome::Ok);
    }
    let threshold = match cmp.threshold.is_finite() {
        true => format!(
            "threshold {:.2} ({:.0} % of scratch's gain over the uncontrolled {:.2})",
            cmp.threshold,
            100.0 * p.fraction,
            cmp.uncontrolled_return
        ),
        false => format!(
            "no threshold: training from scratch ends at {:.2}, not above the uncontrolled {:.2}",
            cmp.scratch_final_return, cmp.uncontrolled_return
        ),
    };
    println!(
        "{}: {} -> {} ({}, {}), seeds {:?}; {threshold}",
        p.name,
        p.source,
        p.target,
        p.algo,
        p.level.name(),
        p.seeds,
    );
    for a in &cmp.arms {
        let measured = cmp.runs.iter().filter(|r| r.arm == a.arm).all(|r| r.core_hours_measured);
        println!(
            "  {:<9} drag reduction {:+6.2} % +- {:.2}   episodes to threshold {:6.1} +- {:.1} ({} of {} seeds)   wall {:6.0} s   {:.2} core-h ({})",
            a.arm,
            a.final_drag_reduction_pct.mean,
            a.final_drag_reduction_pct.std,
            a.episodes_to_threshold.mean,
            a.episodes_to_threshold.std,
            a.seeds_reaching,
            p.seeds.len(),
            a.wall_s.mean,
            a.core_hours,
            if measured { "CPU time" } else { "wall x threads" }
        );
    }
    if cmp.episode_saving_pct.is_finite() {
        println!(
            "  fine-tuning saves {:.0} % of the episodes and {:.0} % of the core-hours to the threshold",
            cmp.episode_saving_pct, cmp.cost_saving_pct
        );
    } else if cmp.threshold.is_finite() {
        println!("  no saving to report: the fine-tuning or the from-scratch arm never stays above the threshold");
    } else {
        println!("  no saving to report: there is no gain over the uncontrolled flow to reach a fraction of");
    }
    println!("  results: {}", root.display());
    Ok(Outcome::Ok)
}

/// The zero-shot arm of one seed: the source policy, mapped, on the target's final evaluation
/// episodes, written as an `hgym eval --out` folder (metrics.json, manifest.json).
fn zeroshot(p: &Protocol, src: &SourceRun, target: &hgym::env::Spec, dir: &std::path::Path, threads: usize) -> Result<()> {
    let started = Instant::now();
    let cpu = hgym::report::manifest::CpuClock::start();
    let init = init_from(src, target, &p.mapping, false, false)?;
    let mut policy = init.policy;
    let n = p.config.train.final_eval_episodes.max(1) as u64;
    let seeds: Vec<u64> = (0..n).map(|k| p.config.train.eval_seed + k).collect();
    let mut env = target.make(p.level, hgym::env::default_cache_dir())?;
    let reference = uncontrolled(&mut env, &seeds)?;
    let name = format!("{} ({}, zero-shot)", src.algo, src.dir.display());
    let report = evaluate(
        &mut env,
        &mut policy,
        &name,
        target.id(),
        &target.hash(),
        p.level.name(),
        &seeds,
        &reference,
        None,
        &mut |_| {},
    )?;
    let run = EvalRun {
        spec: target,
        level: p.level,
        policy: &src.dir.display().to_string(),
        eval_seed: p.config.train.eval_seed,
        episodes: n,
        config_toml: None,
    };
    run.write(dir, &report, threads, started.elapsed().as_secs_f64(), cpu.total(Some(0.0)))
}
