//! `hgym transfer` on a zero-shot deployment protocol (a `[deployment]` table; the channel ->
//! wing): the uncontrolled flow, the source policy of each seed and the classical controllers
//! deployed on the target ([`hgym::transfer::deploy`]), then their comparison
//! ([`hgym::transfer::summary`]). Each arm is a folder with `deployment.json`, `tau_w.png` and an
//! evaluation's `metrics.json` and `manifest.json`. An arm whose folder holds the
//! `deployment.json` of the same set-up (spec, policy, settle actions, episodes) is not run
//! again, so Ctrl-C loses only the arm in progress; one of another set-up is refused.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use hgym::env::wing_tbl::WingTblSpec;
use hgym::env::Spec;
use hgym::report::manifest::CpuClock;
use hgym::report::plots;
use hgym::train::eval::{parse_policy, NamedPolicy};
use hgym::transfer::deploy::{deploy, ArmRecord, DeployEpisode};
use hgym::transfer::protocol::{Deployment, Protocol};
use hgym::transfer::summary::{analyse, arm_dirs};
use hgym::transfer::SourceRun;
use hgym_agents::baselines::{Baseline, BaselinePolicy};
use hgym_agents::policy::Policy;

use crate::cli::progress::Progress;
use crate::cli::train::{init_from, EvalRun};
use crate::{Outcome, UsageError};

/// Runs the arms not yet on disk, then writes `comparison.json` and the figures.
#[allow(clippy::too_many_arguments)]
pub fn run(
    p: &Protocol,
    d: &Deployment,
    sources: &[SourceRun],
    target: &Spec,
    root: &Path,
    pool: &rayon::ThreadPool,
    threads: usize,
    analyse_only: bool,
    json: bool,
) -> Result<Outcome> {
    let target = &target
        .with_overrides(&d.env)
        .map_err(|e| UsageError(format!("{}: [deployment] env: {e}", p.name)))?;
    let seeds: Vec<u64> = (0..d.episodes).map(|k| p.config.train.eval_seed + k).collect();
    let arms = arm_dirs(p, root);
    for (k, (arm, seed, dir)) in arms.iter().enumerate() {
        let label = format!(
            "{arm}{} ({}/{})",
            seed.map(|s| format!(" s{s}")).unwrap_or_default(),
            k + 1,
            arms.len()
        );
        let mut source_sha: Option<String> = None;
        let (spec, mut policy, name): (Spec, Box<dyn Policy + Send>, String) = match (arm.as_str(), seed) {
            ("uncontrolled", _) => (target.clone(), Box::new(BaselinePolicy::new(Baseline::Zero, 0)), "zero".into()),
            ("zeroshot", Some(s)) => {
                let src = sources
                    .iter()
                    .find(|src| src.seed == *s)
                    .with_context(|| format!("no source run of seed {s}"))?;
                let init = init_from(src, target, &p.mapping, false, false)?;
                source_sha = Some(src.policy_sha256.clone());
                (target.clone(), Box::new(init.policy), src.dir.display().to_string())
            }
            _ => {
                let b = d
                    .baselines
                    .iter()
                    .find(|b| &b.name == arm)
                    .with_context(|| format!("no baseline {arm}"))?;
                let spec = target
                    .with_overrides(&b.env)
                    .map_err(|e| UsageError(format!("{}: baseline {arm}: {e}", p.name)))?;
                let policy = match parse_policy(&b.policy).map_err(|e| UsageError(e.to_string()))? {
                    NamedPolicy::Baseline(b) => BaselinePolicy::new(b, p.config.train.eval_seed),
                    NamedPolicy::Trained(_) => {
                        return Err(UsageError(format!("{}: baseline {arm} names a run folder, not a baseline", p.name)).into())
                    }
                };
                (spec, Box::new(policy), b.policy.clone())
            }
        };
        if dir.join("deployment.json").exists() {
            let r = read_record(dir)?;
            let made = (r.spec_hash.as_str(), r.policy.as_str(), r.settle_actions, r.episodes.len() as u64);
            if made != (spec.hash().as_str(), name.as_str(), d.settle_actions, d.episodes) {
                return Err(UsageError(format!(
                    "{}: {} was made by another set-up (spec {}, policy {}, settle_actions {}, {} episodes; the protocol \
                     now asks for spec {}, policy {name}, settle_actions {}, {} episodes); move it away to deploy again",
                    p.name,
                    dir.display(),
                    &r.spec_hash[..8.min(r.spec_hash.len())],
                    r.policy,
                    r.settle_actions,
                    r.episodes.len(),
                    &spec.hash()[..8],
                    d.settle_actions,
                    d.episodes
                ))
                .into());
            }
            // Records from before the hash was kept carry none and are taken at their word.
            if let (Some(made), Some(now)) = (&r.policy_sha256, &source_sha) {
                if made != now {
                    return Err(UsageError(format!(
                        "{}: {} deployed another policy.json of {} (SHA-256 {}, now {}): the source was retrained; move \
                         the arm away to deploy the new policy",
                        p.name,
                        dir.display(),
                        name,
                        &made[..8.min(made.len())],
                        &now[..8]
                    ))
                    .into());
                }
            }
            eprintln!("{label}: done already ({})", dir.display());
            continue;
        }
        if analyse_only {
            return Err(UsageError(format!(
                "{}: the arm {label} has not run ({} has no deployment.json); run the protocol without --analyse-only",
                p.name,
                dir.display()
            ))
            .into());
        }
        let reference: Option<Vec<DeployEpisode>> = match arm.as_str() {
            "uncontrolled" => None,
            _ => {
                let r: ArmRecord = read_record(&root.join("uncontrolled"))?;
                Some(r.episodes)
            }
        };
        let started = Instant::now();
        let cpu = CpuClock::start();
        let mut env = spec.make(p.level, hgym::env::default_cache_dir())?;
        let actions = d.episodes * episode_actions(&spec)?;
        let bar = Progress::counting(actions, &label, "actions");
        let deployed = pool.install(|| {
            deploy(
                env.as_mut(),
                policy.as_mut(),
                &seeds,
                d.settle_actions,
                reference.as_deref(),
                &mut |n| bar.set_position(n as u64),
            )
        })?;
        bar.finish_and_clear();
        let (wall, cpu_s) = (started.elapsed().as_secs_f64(), cpu.total(Some(0.0)));
        let ids = [name.as_str(), spec.id(), &spec.hash(), p.level.name()];
        let mut record = deployed.record(arm, *seed, ids, d.settle_actions, cpu_s.unwrap_or(f64::NAN));
        record.policy_sha256 = source_sha;
        let report = hgym::train::eval::EvalReport::of(deployed.eval.clone(), &name, spec.id(), &spec.hash(), p.level.name());
        let config_toml = arm_env_toml(p, arm);
        let run = EvalRun {
            spec: &spec,
            level: p.level,
            policy: &name,
            eval_seed: p.config.train.eval_seed,
            episodes: d.episodes,
            config_toml,
        };
        run.write(dir, &report, threads, wall, cpu_s)?;
        if let Some(f) = &deployed.field {
            let vmax = plots::abs_quantile(&f.values, 0.98);
            let title = format!("{label}: time-mean {} (colour range +-{vmax:.2})", f.name);
            plots::field(&dir.join("tau_w.png"), &title, f.nx, f.ny, f.extent, &f.values, vmax)?;
        }
        std::fs::write(dir.join("deployment.json"), serde_json::to_string_pretty(&record)? + "\n")?;
        eprintln!(
            "{label}: local friction {:+.2} %, plate drag {:+.2} % ({})",
            record.local_friction_reduction_pct.mean,
            record.plate_drag_reduction_pct.mean,
            dir.display()
        );
    }
    let check = match target.downcast::<WingTblSpec>() {
        Some(w) => w.target_check(p.level).map_err(|e| UsageError(format!("{}: {e}", p.name)))?,
        None => None,
    };
    let cmp = analyse(p, root, sources, check)?;
    std::fs::write(root.join("comparison.json"), serde_json::to_string_pretty(&cmp)? + "\n")?;
    if json {
        println!("{}", serde_json::to_string_pretty(&cmp)?);
        return Ok(Outcome::Ok);
    }
    println!(
        "{}: {} -> {} zero-shot ({}, {} episodes each)",
        p.name,
        p.source,
        p.target,
        p.level.name(),
        d.episodes
    );
    for a in &cmp.arms {
        println!(
            "  {:<16} local friction {:+6.2} % +- {:.2}   plate drag {:+6.2} % +- {:.2}   v_rms+ {:.3}   ({} deployment{})",
            a.arm,
            a.local_friction_reduction_pct.mean,
            a.local_friction_reduction_pct.std,
            a.plate_drag_reduction_pct.mean,
            a.plate_drag_reduction_pct.std,
            a.actuation_rms_plus.mean,
            a.deployments,
            if a.deployments == 1 { "" } else { "s" }
        );
    }
    if let Some(t) = &cmp.target {
        println!(
            "  uncontrolled target ({}): <Re_theta> {:.0} over the region (integral estimate {:.0}, the paper's LES {:.0}), <u_tau> {:.5} (estimate {:.5})",
            t.level, t.mean_re_theta, t.mean_re_theta_estimate, t.mean_re_theta_paper, t.mean_u_tau, t.mean_u_tau_estimate
        );
    }
    let c = &cmp.cost;
    println!(
        "  cost: training in {} {:.2} core-h ({:.0} episodes); on {} {:.2} core-h extrapolated ({:.4} core-h an episode): {:.1} x",
        p.source,
        c.source_core_hours.mean,
        c.source_episodes,
        p.target,
        c.target_training_core_hours,
        c.target_core_hours_per_episode,
        c.ratio
    );
    println!("  results: {}", root.display());
    Ok(Outcome::Ok)
}

fn read_record(dir: &Path) -> Result<ArmRecord> {
    let path = dir.join("deployment.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not a deployment record", path.display()))
}

/// An arm's `[env]` overrides (the deployment's, then a baseline's) as the manifest's
/// `config_toml` (`None`: the registered spec).
fn arm_env_toml(p: &Protocol, arm: &str) -> Option<String> {
    let d = p.deployment.as_ref()?;
    let mut env = d.env.clone();
    if let Some(b) = d.baselines.iter().find(|b| b.name == arm) {
        env.extend(b.env.clone());
    }
    match env.is_empty() {
        true => None,
        false => Some(format!("[env]\n{}", toml::to_string(&env).ok()?)),
    }
}

/// Episode length in actions, from the spec.
pub fn episode_actions(spec: &Spec) -> Result<u64> {
    spec.to_json()?["episode_actions"]
        .as_u64()
        .with_context(|| format!("{} has no episode_actions", spec.id()))
}
