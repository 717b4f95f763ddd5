//! Validation of the turbulent channel at Re_tau 180 (`hgym validate channel`): the channel DNS
//! (`hgym_solvers::channel`) at constant flow rate, Re_b = 2800, averaged over a window after a
//! spin-up, against the DNS databases: Re_tau, U_b+, U_c+, C_f, the peak of u_rms+ and its y+,
//! and the whole U+ profile above y+ = 5 (Moser, Kim & Mansour 1999; del Alamo & Jimenez 2003).
//!
//! The case (box, grids, windows, tolerances) is data: `benchmarks/validation/channel_retau180.toml`;
//! the DNS profiles are `benchmarks/validation/data/*.csv` (provenance in their headers). The
//! developed state after the spin-up is cached (`$HGYM_CACHE` or `~/.cache/hgym/states`), so a
//! second run only averages. Writes `<out>/channel_retau180.json`
//! (`schemas/channel-validation.schema.json`) and `<out>/channel_retau180/{u_plus,rms}.png`.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use thiserror::Error;

use crate::flow::level::PerLevel;
use crate::flow::Level;
use crate::report::plots;
use hgym_agents::rng::Rng;
use hgym_solvers::channel::{Channel, ChannelConfig, ChannelError, ChannelState, Drive, PlaneSums, Top};

/// The committed case file.
pub const CASE: &str = include_str!("../../benchmarks/validation/channel_retau180.toml");
const MKM_MEAN: &str = include_str!("../../benchmarks/validation/data/channel_retau180_mkm_mean.csv");
const DNS_PROFILES: &str = include_str!("../../benchmarks/validation/data/channel_retau180_dns.csv");
/// Changes whenever a change of the solver invalidates cached developed states.
const SOLVER_VERSION: &str = "channel-fd2-rk3-v1";

#[derive(Debug, Error)]
pub enum ChannelValidationError {
    #[error("the case file channel_retau180.toml: {0}")]
    Case(String),
    #[error("the case cannot run at this level: {0}")]
    Unrunnable(String),
    #[error(transparent)]
    Solver(#[from] ChannelError),
    #[error("{path}: {message}")]
    Output { path: String, message: String },
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LevelSpec {
    pub n: [usize; 3],
    pub dt: f64,
    pub spin_up: f64,
    pub average: f64,
    pub sample_interval: f64,
}

/// `[reference, relative tolerance]` pairs, except where noted.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Checks {
    pub re_tau: [f64; 2],
    pub u_bulk_plus: [f64; 2],
    pub u_centre_plus: [f64; 2],
    pub c_f: [f64; 2],
    pub u_rms_peak: [f64; 2],
    /// Absolute tolerance in wall units.
    pub u_rms_peak_y_plus: f64,
    /// `[y+ above which, relative tolerance]`.
    pub profile_u_plus: [f64; 2],
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub case: String,
    pub description: String,
    pub reference: String,
    pub reynolds_bulk: f64,
    pub length: [f64; 3],
    pub stretch: f64,
    pub seed: u64,
    pub perturbation: f64,
    pub levels: PerLevel<LevelSpec>,
    pub checks: Checks,
}

impl Case {
    pub fn level(&self, level: Level) -> &LevelSpec {
        self.levels.at(level)
    }

    pub fn config(&self, level: Level) -> ChannelConfig {
        let l = self.level(level);
        ChannelConfig {
            n: l.n,
            length: self.length,
            stretch: self.stretch,
            top: Top::Wall,
            nu: 1.0 / self.reynolds_bulk,
            dt: l.dt,
            drive: Drive::FlowRate(1.0),
            check_interval: 10,
        }
    }
}

pub fn case() -> Result<Case, ChannelValidationError> {
    toml::from_str(CASE).map_err(|e| ChannelValidationError::Case(e.to_string()))
}

/// One compared quantity.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Check {
    pub name: String,
    pub value: f64,
    pub reference: f64,
    pub tolerance: String,
    pub pass: bool,
}

/// Half-channel profiles in wall units (both halves averaged).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct WallProfiles {
    pub y_plus: Vec<f64>,
    pub u_plus: Vec<f64>,
    pub u_rms_plus: Vec<f64>,
    pub v_rms_plus: Vec<f64>,
    pub w_rms_plus: Vec<f64>,
    pub uv_plus: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChannelValidation {
    pub schema: String,
    pub case: String,
    pub level: String,
    pub n: [usize; 3],
    pub length: [f64; 3],
    pub stretch: f64,
    pub dt: f64,
    pub reynolds_bulk: f64,
    /// First cell centre in wall units.
    pub first_cell_y_plus: f64,
    pub spin_up: f64,
    pub spin_up_cached: bool,
    pub average: f64,
    pub samples: u64,
    pub re_tau: f64,
    pub u_bulk_plus: f64,
    pub u_centre_plus: f64,
    pub c_f: f64,
    pub u_rms_peak: f64,
    pub u_rms_peak_y_plus: f64,
    pub profile_max_deviation: f64,
    pub checks: Vec<Check>,
    pub pass: bool,
    pub profiles: WallProfiles,
    pub manifest: crate::report::manifest::Manifest,
}

/// Where a case's developed state at `level` is cached: the name changes with the case file's
/// text (`case_text`) and the solver's version, so an edit of either starts a new spin-up.
pub(crate) fn cache_path(dir: &Path, case_text: &str, case: &str, level: Level, solver_version: &str) -> PathBuf {
    let mut h = Sha256::new();
    h.update(case_text.as_bytes());
    h.update(level.name().as_bytes());
    h.update(solver_version.as_bytes());
    let hex: String = h.finalize().iter().take(8).map(|b| format!("{b:02x}")).collect();
    dir.join(format!("{case}-{}-{hex}.bin", level.name()))
}

/// Restores the state cached at `path` into `ch` if there is one of its size (`true`).
pub(crate) fn restore_cached(ch: &mut Channel, path: Option<&Path>) -> Result<bool, ChannelError> {
    let cached = path
        .and_then(|p| std::fs::read(p).ok())
        .and_then(|b| bincode::deserialize::<ChannelState>(&b).ok())
        .filter(|s| s.n == ch.config().n);
    match cached {
        Some(s) => ch.restore(&s).map(|_| true),
        None => Ok(false),
    }
}

/// Caches the state of `ch` at `path`; a cache that cannot be written only costs the next run
/// its spin-up.
pub(crate) fn store(ch: &Channel, path: Option<&Path>) {
    if let Some(p) = path {
        if let Some(dir) = p.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Ok(bytes) = bincode::serialize(&ch.state()) {
            let _ = std::fs::write(p, bytes);
        }
    }
}

/// `(x, y)` table columns `cx`, `cy` of a CSV with `#` comment lines and a header.
pub(crate) fn columns(text: &str, cx: usize, cy: usize) -> Result<(Vec<f64>, Vec<f64>), ChannelValidationError> {
    let (mut xs, mut ys) = (vec![], vec![]);
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let get = |c: usize| -> Result<f64, ChannelValidationError> {
            f.get(c)
                .and_then(|s| s.trim().parse().ok())
                .ok_or_else(|| ChannelValidationError::Case(format!("reference data line '{line}': no number in column {c}")))
        };
        xs.push(get(cx)?);
        ys.push(get(cy)?);
    }
    Ok((xs, ys))
}

/// Linear interpolation in a table sorted by `x` (clamped at the ends).
fn interp(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let i = xs.partition_point(|&v| v < x).clamp(1, xs.len() - 1);
    let t = ((x - xs[i - 1]) / (xs[i] - xs[i - 1])).clamp(0.0, 1.0);
    ys[i - 1] + t * (ys[i] - ys[i - 1])
}

/// Maximum of a sampled curve refined by the parabola through the largest sample and its two
/// neighbours: `(x at the maximum, maximum)`.
fn peak(xs: &[f64], ys: &[f64]) -> (f64, f64) {
    let m = (0..ys.len()).max_by(|&a, &b| ys[a].total_cmp(&ys[b])).unwrap_or(0);
    if m == 0 || m + 1 >= ys.len() {
        return (xs[m], ys[m]);
    }
    let (x0, x1, x2) = (xs[m - 1], xs[m], xs[m + 1]);
    let (y0, y1, y2) = (ys[m - 1], ys[m], ys[m + 1]);
    // Divided differences of the interpolating parabola y = y1 + b (x - x1) + c (x - x1)^2.
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let c = (d12 - d01) / (x2 - x0);
    let b = d01 + c * (x1 - x0);
    if !(c < 0.0) {
        return (x1, y1);
    }
    let dx = -b / (2.0 * c);
    (x1 + dx, y1 + b * dx + c * dx * dx)
}

/// Runs the case at `level` and writes its report and plots under `out`. `progress(done, total)`
/// reports solver steps (spin-up, unless cached, then averaging).
pub fn validate(
    level: Level,
    out: &Path,
    cache: Option<&Path>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<ChannelValidation, ChannelValidationError> {
    let started = std::time::Instant::now();
    let c = case()?;
    let l = c.level(level).clone();
    let cfg = c.config(level);
    let mut ch = Channel::new(cfg.clone())?;
    let g = ch.grid().clone();
    let nu = cfg.nu;
    let target_re_tau = c.checks.re_tau[0];
    let first_plus = g.yc[0] * target_re_tau;
    if first_plus > 1.0 {
        return Err(ChannelValidationError::Unrunnable(format!(
            "the first cell centre sits at y+ = {first_plus:.2} at Re_tau {target_re_tau}: a wall-resolved DNS needs y+ <= 1 \
             (more cells in y or a stronger stretching)"
        )));
    }
    let steps_of = |t: f64| (t / l.dt).round() as u64;
    let path = cache.map(|d| cache_path(d, CASE, &c.case, level, SOLVER_VERSION));
    let cached = restore_cached(&mut ch, path.as_deref())?;
    let total = steps_of(l.average) + if cached { 0 } else { steps_of(l.spin_up) };
    if !cached {
        let mut rng = Rng::seed(c.seed);
        ch.set_disturbed_laminar(c.perturbation, || 2.0 * rng.uniform() - 1.0);
        while ch.time() < l.spin_up - 0.5 * l.dt {
            ch.step()?;
            progress(ch.steps(), total);
        }
        store(&ch, path.as_deref());
    }
    let s0 = total - steps_of(l.average);
    let every = (l.sample_interval / l.dt).round().max(1.0) as u64;
    let mut sums = PlaneSums::new(g.ny);
    let n_wall = g.nx * g.nz;
    let (mut bottom, mut top) = (vec![0.0; n_wall], vec![0.0; n_wall]);
    let mut tau_sum = 0.0;
    // Counted in steps, not by the clock, so a run from the cache takes the same steps.
    for steps in 1..=steps_of(l.average) {
        ch.step()?;
        if steps.is_multiple_of(every) {
            sums.add(&g, ch.u(), ch.v(), ch.w());
            ch.wall_shear(&mut bottom, &mut top);
            tau_sum += (bottom.iter().sum::<f64>() + top.iter().sum::<f64>()) / (2 * n_wall) as f64;
        }
        progress(s0 + steps, total);
    }
    let samples = sums.samples;
    if samples == 0 {
        return Err(ChannelValidationError::Case("the averaging window holds no sample".into()));
    }
    let u_tau = (tau_sum / samples as f64).sqrt();
    let p = sums.profiles();
    // Both halves, mirrored onto the lower one.
    let ny = g.ny;
    let half = ny.div_ceil(2);
    let mut wp = WallProfiles::default();
    for j in 0..half {
        let m = ny - 1 - j;
        let avg = |a: f64, b: f64| 0.5 * (a + b);
        wp.y_plus.push(g.yc[j] * u_tau / nu);
        wp.u_plus.push(avg(p.mean[j][0], p.mean[m][0]) / u_tau);
        wp.u_rms_plus.push(avg(p.var[j][0], p.var[m][0]).max(0.0).sqrt() / u_tau);
        wp.v_rms_plus.push(avg(p.var[j][1], p.var[m][1]).max(0.0).sqrt() / u_tau);
        wp.w_rms_plus.push(avg(p.var[j][2], p.var[m][2]).max(0.0).sqrt() / u_tau);
        wp.uv_plus.push(avg(p.uv[j], -p.uv[m]) / (u_tau * u_tau));
    }
    let centre = if ny % 2 == 1 {
        p.mean[ny / 2][0]
    } else {
        0.5 * (p.mean[ny / 2 - 1][0] + p.mean[ny / 2][0])
    };
    let re_tau = u_tau / nu;
    let u_bulk_plus = 1.0 / u_tau;
    let u_centre_plus = centre / u_tau;
    let c_f = 2.0 * u_tau * u_tau;
    let (peak_y, peak_u) = peak(&wp.y_plus, &wp.u_rms_plus);
    let (mkm_y, mkm_u) = columns(MKM_MEAN, 1, 2)?;
    let (dns_y, dns_urms) = columns(DNS_PROFILES, 1, 3)?;
    let (ref_peak_y, _) = peak(&dns_y, &dns_urms);
    let [y_above, profile_tol] = c.checks.profile_u_plus;
    let profile_dev = wp
        .y_plus
        .iter()
        .zip(&wp.u_plus)
        .filter(|(y, _)| **y > y_above)
        .map(|(y, u)| {
            let r = interp(&mkm_y, &mkm_u, *y);
            (u - r).abs() / r
        })
        .fold(0.0, f64::max);
    let k = &c.checks;
    let rel = |name: &str, value: f64, [reference, tol]: [f64; 2]| Check {
        name: name.into(),
        value,
        reference,
        tolerance: format!("{} %", 100.0 * tol),
        pass: (value / reference - 1.0).abs() <= tol,
    };
    let checks = vec![
        rel("Re_tau", re_tau, k.re_tau),
        rel("U_b+", u_bulk_plus, k.u_bulk_plus),
        rel("U_c+", u_centre_plus, k.u_centre_plus),
        rel("C_f", c_f, k.c_f),
        rel("peak u_rms+", peak_u, k.u_rms_peak),
        Check {
            name: "y+ of the u_rms+ peak".into(),
            value: peak_y,
            reference: ref_peak_y,
            tolerance: format!("{} wall units", k.u_rms_peak_y_plus),
            pass: (peak_y - ref_peak_y).abs() <= k.u_rms_peak_y_plus,
        },
        Check {
            name: format!("U+ profile above y+ {y_above} (largest deviation)"),
            value: profile_dev,
            reference: 0.0,
            tolerance: format!("{} %", 100.0 * profile_tol),
            pass: profile_dev <= profile_tol,
        },
    ];
    let pass = checks.iter().all(|c| c.pass);
    let report = ChannelValidation {
        schema: "hgym/channel-validation/v1".into(),
        case: c.case.clone(),
        level: level.name().into(),
        n: l.n,
        length: c.length,
        stretch: c.stretch,
        dt: l.dt,
        reynolds_bulk: c.reynolds_bulk,
        first_cell_y_plus: g.yc[0] * re_tau,
        spin_up: l.spin_up,
        spin_up_cached: cached,
        average: l.average,
        samples,
        re_tau,
        u_bulk_plus,
        u_centre_plus,
        c_f,
        u_rms_peak: peak_u,
        u_rms_peak_y_plus: peak_y,
        profile_max_deviation: profile_dev,
        checks,
        pass,
        profiles: wp,
        manifest: crate::report::manifest::manifest(rayon::current_num_threads(), started.elapsed().as_secs_f64()),
    };
    write(&report, out)?;
    Ok(report)
}

fn write(r: &ChannelValidation, out: &Path) -> Result<(), ChannelValidationError> {
    let dir = out.join(&r.case);
    let fail = |p: &Path| {
        let path = p.display().to_string();
        move |message: String| ChannelValidationError::Output { path, message }
    };
    std::fs::create_dir_all(&dir).map_err(|e| fail(&dir)(e.to_string()))?;
    let json = out.join(format!("{}.json", r.case));
    let text = serde_json::to_string_pretty(r).map_err(|e| fail(&json)(e.to_string()))?;
    std::fs::write(&json, text + "\n").map_err(|e| fail(&json)(e.to_string()))?;
    let (mkm_y, mkm_u) = columns(MKM_MEAN, 1, 2)?;
    let log = |v: &[f64]| v.iter().map(|y| if *y > 0.0 { y.log10() } else { f64::NAN }).collect::<Vec<f64>>();
    let p = &r.profiles;
    let png = dir.join("u_plus.png");
    plots::lines(
        &png,
        &format!("Channel Re_tau {:.1} ({}x{}x{}): mean velocity", r.re_tau, r.n[0], r.n[1], r.n[2]),
        "log10 y+",
        "U+",
        &[
            plots::Line {
                label: "hgym",
                x: &log(&p.y_plus),
                y: &p.u_plus,
                band: None,
            },
            plots::Line {
                label: "Moser, Kim & Mansour 1999",
                x: &log(&mkm_y),
                y: &mkm_u,
                band: None,
            },
        ],
    )
    .map_err(|e| fail(&png)(crate::report::chain(&e)))?;
    let dns: Vec<(Vec<f64>, Vec<f64>)> = (3..=6).map(|c| columns(DNS_PROFILES, 1, c)).collect::<Result<_, _>>()?;
    let neg = |v: &[f64]| v.iter().map(|x| -x).collect::<Vec<f64>>();
    let (ours_uv, dns_uv) = (neg(&p.uv_plus), neg(&dns[3].1));
    let png = dir.join("rms.png");
    plots::lines(
        &png,
        &format!(
            "Channel Re_tau {:.1}: rms velocities and -uv (lines hgym, DNS del Alamo & Jimenez)",
            r.re_tau
        ),
        "y+",
        "wall units",
        &[
            plots::Line {
                label: "u_rms+",
                x: &p.y_plus,
                y: &p.u_rms_plus,
                band: None,
            },
            plots::Line {
                label: "v_rms+",
                x: &p.y_plus,
                y: &p.v_rms_plus,
                band: None,
            },
            plots::Line {
                label: "w_rms+",
                x: &p.y_plus,
                y: &p.w_rms_plus,
                band: None,
            },
            plots::Line {
                label: "-uv+",
                x: &p.y_plus,
                y: &ours_uv,
                band: None,
            },
            plots::Line {
                label: "u_rms+ DNS",
                x: &dns[0].0,
                y: &dns[0].1,
                band: None,
            },
            plots::Line {
                label: "v_rms+ DNS",
                x: &dns[1].0,
                y: &dns[1].1,
                band: None,
            },
            plots::Line {
                label: "w_rms+ DNS",
                x: &dns[2].0,
                y: &dns[2].1,
                band: None,
            },
            plots::Line {
                label: "-uv+ DNS",
                x: &dns[3].0,
                y: &dns_uv,
                band: None,
            },
        ],
    )
    .map_err(|e| fail(&png)(crate::report::chain(&e)))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_case_and_its_reference_data_parse() {
        let c = case().unwrap();
        assert_eq!(c.reynolds_bulk, 2800.0);
        let (y, u) = columns(MKM_MEAN, 1, 2).unwrap();
        assert!(y.len() > 60 && (interp(&y, &u, 0.0)).abs() < 1e-12);
        let (y, urms) = columns(DNS_PROFILES, 1, 3).unwrap();
        let (py, pu) = peak(&y, &urms);
        assert!((13.0..16.0).contains(&py) && (2.6..2.7).contains(&pu), "{py} {pu}");
    }

    #[test]
    fn the_parabolic_peak_is_exact_for_a_parabola() {
        let xs = [0.0, 1.0, 2.5, 3.0, 4.5];
        let ys: Vec<f64> = xs.iter().map(|x| 2.0 - (x - 2.2f64).powi(2)).collect();
        let (x, y) = peak(&xs, &ys);
        assert!((x - 2.2).abs() < 1e-12 && (y - 2.0).abs() < 1e-12);
    }

    #[test]
    fn every_level_resolves_the_wall() {
        let c = case().unwrap();
        for level in Level::ALL {
            let cfg = c.config(level);
            let g = hgym_solvers::channel::Grid::new(cfg.n, cfg.length, cfg.stretch, cfg.top).unwrap();
            assert!(g.yc[0] * c.checks.re_tau[0] <= 1.0, "{level:?}");
        }
    }
}
