//! `hgym validate`: bundled cases of a family (`hgym validate cylinder`), case files
//! (`--case FILE`), or environments' own uncontrolled flows (`--env ID`, see `hgym::fidelity`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use super::progress::Progress;
use crate::{thread_pool, Outcome, UsageError};
use hgym::fidelity::{self, Entry};
use hgym::flow::Level;
use hgym::validate::{self, LoadedCase, Options, ValidationReport};

#[derive(Args)]
pub struct ValidateArgs {
    /// Families of bundled cases (e.g. `cylinder`) or bundled cases by name (e.g.
    /// `cylinder_re100`) to run; omit them with --case, --env or --list.
    names: Vec<String>,
    /// Case file(s) to run instead of a bundled family (repeatable).
    #[arg(long = "case", value_name = "FILE")]
    cases: Vec<PathBuf>,
    /// Environment ID(s) whose own uncontrolled flow (its domain, its grid at --level) to compare
    /// with its family's literature references (repeatable); `all` runs every ID that has them,
    /// each distinct flow once. Reports go to `<out>/envs/<ID>-<level>.json`.
    #[arg(long = "env", value_name = "ID")]
    envs: Vec<String>,
    /// With --env: record the deviations in the table `hgym envs` shows.
    #[arg(long)]
    record: bool,
    /// The table --record writes (rebuild to embed it).
    #[arg(long, default_value = "benchmarks/envs/fidelity.toml")]
    table: PathBuf,
    /// Resolution level (cells per reference length as given in each case file or spec).
    #[arg(long, value_enum, default_value_t = Level::Default)]
    level: Level,
    /// Output folder for `<case>.json` and `<case>/*.png`.
    #[arg(long, default_value = "results/validation")]
    out: PathBuf,
    /// Worker threads (default: all cores). Results are bitwise identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// Print the reports as a JSON array on stdout instead of tables.
    #[arg(long)]
    json: bool,
    /// List the bundled cases and exit.
    #[arg(long)]
    list: bool,
}

/// `hgym validate`: bundled cases of a family, case files, or environments' own flows.
pub fn run(args: ValidateArgs) -> Result<Outcome> {
    if !args.envs.is_empty() {
        if !args.names.is_empty() || !args.cases.is_empty() {
            return Err(UsageError("give a family, --case FILE or --env ID, one of them".into()).into());
        }
        return run_envs(&args);
    }
    if args.record {
        return Err(UsageError("--record writes the environments' table: use it with --env ID".into()).into());
    }
    if args.names == ["kolmogorov"] {
        let (pool, _) = thread_pool(args.threads)?;
        let case = hgym::fidelity::kolmogorov::case().context("the bundled case benchmarks/validation/kolmogorov_re40.toml")?;
        let pb = Progress::new((case.time / case.sample_interval) as u64, "kolmogorov Re 40");
        let r = pool
            .install(|| hgym::fidelity::kolmogorov::validate(args.level, &args.out, &mut |k, _| pb.set_position(k as u64)))
            .context("Kolmogorov validation")?;
        pb.finish_and_clear();
        if args.json {
            println!("{}", serde_json::to_string_pretty(&r)?);
        } else {
            println!(
                "kolmogorov_re40 ({}, {}^2, dt {}, {} time units): D/D_lam mean {:.4} std {:.4} max {:.3}; {} bursts above {:.3} ({:.2} % of the time, {:.1} time units each)",
                r.level, r.n, r.dt, r.time, r.mean_d_over_dlam, r.std_d_over_dlam, r.max_d_over_dlam, r.bursts,
                r.threshold_d_over_dlam, 100.0 * r.burst_time_fraction, r.mean_burst_duration
            );
            for (c, ok) in &r.checks {
                println!("  {} {c}", if *ok { "pass" } else { "FAIL" });
            }
            println!("  results: {}", args.out.join("kolmogorov_re40.json").display());
        }
        return Ok(if r.pass { Outcome::Ok } else { Outcome::CheckFailed });
    }
    if args.names == ["channel"] || args.names == ["channel_retau180"] {
        return run_channel(&args);
    }
    if args.names == ["tbl"] || args.names == ["tbl_zpg"] {
        return run_tbl(&args);
    }
    if args.list {
        for c in validate::bundled()? {
            println!("{:<10} {:<18} {}", c.case.case.family, c.case.case.name, c.case.case.description);
        }
        // The cases with formats of their own (spectral and finite-difference solvers).
        let k = hgym::fidelity::kolmogorov::case().context("the bundled case kolmogorov_re40.toml")?;
        println!("{:<10} {:<18} {}", "kolmogorov", k.case, k.description);
        let c = hgym::validate::channel::case().context("the bundled case channel_retau180.toml")?;
        println!("{:<10} {:<18} {}", "channel", c.case, c.description);
        let t = hgym::validate::plate::case().context("the bundled case tbl_zpg.toml")?;
        println!("{:<10} {:<18} {}", "tbl", t.case, t.description);
        return Ok(Outcome::Ok);
    }
    for own in ["kolmogorov", "channel", "tbl"] {
        if args.names.len() > 1 && args.names.iter().any(|n| n == own) {
            return Err(UsageError(format!("run `hgym validate {own}` on its own")).into());
        }
    }
    let cases: Vec<LoadedCase> = match (args.names.is_empty(), args.cases.is_empty()) {
        (false, false) => return Err(UsageError("give either families or --case FILE, not both".into()).into()),
        (true, true) => {
            let known = validate::families()?.join(", ");
            return Err(UsageError(format!(
                "nothing to validate: name a family ({known}) or give --case FILE; --list shows the bundled cases"
            ))
            .into());
        }
        (false, true) => {
            let mut cases: Vec<LoadedCase> = vec![];
            for name in &args.names {
                for c in validate::family_cases(name)? {
                    if !cases.iter().any(|k| k.case.case.name == c.case.case.name) {
                        cases.push(c);
                    }
                }
            }
            cases
        }
        (true, false) => args.cases.iter().map(|p| validate::load_file(p)).collect::<Result<_, _>>()?,
    };
    let reports = run_cases(&cases, &args, &args.out)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&reports)?);
    }
    let all_pass = reports.iter().all(|r| r.status.is_ok());
    Ok(if all_pass { Outcome::Ok } else { Outcome::CheckFailed })
}

/// Runs cases one after the other with a progress bar each, printing each report's table.
fn run_cases(cases: &[LoadedCase], args: &ValidateArgs, out: &std::path::Path) -> Result<Vec<ValidationReport>> {
    // Refuse unrunnable parameters for every case before running any.
    for c in cases {
        validate::plan(c, args.level)?;
    }
    let (pool, threads) = thread_pool(args.threads)?;
    let opts = Options {
        level: args.level,
        out: out.to_path_buf(),
        threads,
    };
    let mut reports = Vec::new();
    for c in cases {
        let plan = validate::plan(c, args.level)?;
        if !args.json && hgym::flow::ranks::leader() {
            let ranks = match hgym::flow::ranks::rank().1 {
                1 => String::new(),
                n => format!(", split over {n} MPI ranks"),
            };
            eprintln!(
                "{} ({}): {}, {} steps{ranks}",
                c.case.case.name,
                args.level.name(),
                plan.flow.describe(),
                plan.total_steps
            );
        }
        let pb = Progress::new(plan.total_steps, &c.case.case.name);
        let report = pool
            .install(|| validate::validate_case(c, &opts, &mut |done, _| pb.set_position(done)))
            .with_context(|| format!("validation case '{}'", c.case.case.name))?;
        pb.finish_and_clear();
        if !args.json {
            print!("{}", report.table());
            println!("  report: {}", out.join(format!("{}.json", report.case)).display());
            println!();
        }
        reports.push(report);
    }
    Ok(reports)
}

/// `--env ID...`: each environment's flow with its family's references; `all`: every ID with
/// references, each distinct flow run once and its row recorded for every ID that shares it.
fn run_envs(args: &ValidateArgs) -> Result<Outcome> {
    use hgym::env::registry::{lbm_flow, LbmFlowSpec};
    let all = hgym::env::registry::all();
    let specs: Vec<&dyn LbmFlowSpec> = if args.envs.iter().any(|e| e == "all") {
        all.iter().filter_map(lbm_flow).filter(|s| fidelity::has_reference(*s)).collect()
    } else {
        let mut specs = Vec::new();
        for id in &args.envs {
            let s = hgym::env::lookup(id)?;
            let Some(flow) = all.iter().find(|a| a.id() == s.id()).and_then(lbm_flow) else {
                return Err(hgym::env::EnvInputError::NotLbm {
                    id: id.clone(),
                    solver: s.solver(),
                }
                .into());
            };
            specs.push(flow);
        }
        specs
    };
    let mut flows: Vec<(String, Vec<&dyn LbmFlowSpec>)> = Vec::new();
    for &s in &specs {
        let h = s.flow_setup().hash();
        match flows.iter_mut().find(|(k, _)| *k == h) {
            Some((_, ids)) => ids.push(s),
            None => flows.push((h, vec![s])),
        }
    }
    let mut cases = Vec::new();
    for (_, ids) in &flows {
        cases.push(fidelity::env_case(ids[0], args.level)?);
    }
    let loaded: Vec<LoadedCase> = cases.iter().map(|(c, _)| c.clone()).collect();
    let reports = run_cases(&loaded, args, &args.out.join("envs"))?;
    let mut rows = Vec::new();
    for (((_, ids), (_, case)), report) in flows.iter().zip(&cases).zip(&reports) {
        for &s in ids {
            let e = Entry::from_report(s, report, case);
            if !args.json {
                println!("{:<30} {:<8} {} ({case}, {:?})", s.id(), args.level.name(), e.summary(), e.status);
            }
            rows.push((fidelity::key(s.id(), args.level), e));
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&reports)?);
    }
    if args.record {
        fidelity::record(&args.table, &rows)?;
        if !args.json {
            println!("recorded {} rows in {} (rebuild to embed)", rows.len(), args.table.display());
        }
    }
    let all_pass = reports.iter().all(|r| r.status.is_ok());
    Ok(if all_pass { Outcome::Ok } else { Outcome::CheckFailed })
}

/// `hgym validate tbl`: the zero-pressure-gradient turbulent boundary layer against DNS.
fn run_tbl(args: &ValidateArgs) -> Result<Outcome> {
    use hgym::validate::plate;
    let (pool, _) = thread_pool(args.threads)?;
    let case = plate::case().context("the bundled case benchmarks/validation/tbl_zpg.toml")?;
    let l = case.level(args.level).clone();
    let cache = hgym::env::default_cache_dir();
    if !args.json {
        eprintln!(
            "tbl_zpg ({}): {}x{}x{} cells on {} x {} x {} delta*_0 (Re_delta*_0 {}), dt {}; spin-up {} (cached after the first run), average {} delta*_0/U",
            args.level.name(), l.n[0], l.n[1], l.n[2], case.length[0], case.length[1], case.length[2], case.re_delta_star, l.dt, l.spin_up, l.average
        );
    }
    let r = with_progress(
        &pool,
        ("boundary layer", "boundary-layer validation"),
        |p| plate::validate(args.level, &args.out, cache.as_deref(), p),
        |e| matches!(e, plate::PlateValidationError::Unrunnable(_)),
    )?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        println!(
            "tbl_zpg ({}, {}x{}x{}, {} samples over {} delta*_0/U; dx+ {:.1}, dz+ {:.1}, first cell y+ {:.2}; Ue spread {:.2} %):",
            r.level,
            r.n[0],
            r.n[1],
            r.n[2],
            r.samples,
            r.average,
            r.dx_plus,
            r.dz_plus,
            r.first_cell_y_plus,
            100.0 * r.ue_spread
        );
        print_checks(&r.checks);
        println!("  results: {}", args.out.join("tbl_zpg.json").display());
    }
    Ok(if r.pass { Outcome::Ok } else { Outcome::CheckFailed })
}

/// Runs a finite-difference validation on `pool` behind a progress bar (`label`) of its solver
/// steps; an error `unrunnable` says is the user's (the level cannot run: exit 2), any other one
/// is reported under `context`.
fn with_progress<R: Send, E: std::error::Error + Send + Sync + 'static>(
    pool: &rayon::ThreadPool,
    (label, context): (&str, &'static str),
    run: impl FnOnce(&mut dyn FnMut(u64, u64)) -> Result<R, E> + Send,
    unrunnable: impl Fn(&E) -> bool,
) -> Result<R> {
    let mut pb: Option<Progress> = None;
    let r = pool.install(|| run(&mut |done, total| pb.get_or_insert_with(|| Progress::new(total, label)).set_position(done)));
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    r.map_err(|e| match unrunnable(&e) {
        true => UsageError(e.to_string()).into(),
        false => anyhow::Error::new(e).context(context),
    })
}

fn print_checks(checks: &[hgym::validate::channel::Check]) {
    for c in checks {
        println!(
            "  {} {:<40} {:>10.5} (reference {:.5}, tolerance {})",
            if c.pass { "pass" } else { "FAIL" },
            c.name,
            c.value,
            c.reference,
            c.tolerance
        );
    }
}

/// `hgym validate channel`: the turbulent channel at Re_tau 180 against the DNS databases.
fn run_channel(args: &ValidateArgs) -> Result<Outcome> {
    use hgym::validate::channel;
    let (pool, _) = thread_pool(args.threads)?;
    let case = channel::case().context("the bundled case benchmarks/validation/channel_retau180.toml")?;
    let l = case.level(args.level).clone();
    let cache = hgym::env::default_cache_dir();
    if !args.json {
        eprintln!(
            "channel_retau180 ({}): {}x{}x{} cells on {:.2} x {:.0} x {:.2} h, dt {} h/U_b; spin-up {} (cached after the first run), average {} h/U_b",
            args.level.name(), l.n[0], l.n[1], l.n[2], case.length[0], case.length[1], case.length[2], l.dt, l.spin_up, l.average
        );
    }
    let r = with_progress(
        &pool,
        ("channel Re_tau 180", "channel validation"),
        |p| channel::validate(args.level, &args.out, cache.as_deref(), p),
        |e| matches!(e, channel::ChannelValidationError::Unrunnable(_)),
    )?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
    } else {
        println!(
            "channel_retau180 ({}, {}x{}x{}, {} samples over {} h/U_b; first cell y+ {:.2}):",
            r.level, r.n[0], r.n[1], r.n[2], r.samples, r.average, r.first_cell_y_plus
        );
        print_checks(&r.checks);
        println!("  results: {}", args.out.join("channel_retau180.json").display());
    }
    Ok(if r.pass { Outcome::Ok } else { Outcome::CheckFailed })
}
