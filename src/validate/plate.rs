//! Validation of the zero-pressure-gradient turbulent boundary layer (`hgym validate tbl`): the
//! tripped plate of [`hgym_solvers::channel::plate`] under a uniform free stream, averaged over a
//! window after a spin-up, against the DNS of Schlatter & Orlu (2010): the skin friction `C_f`
//! and the shape factor `H12` at matched momentum-thickness Reynolds number `Re_theta`.
//!
//! The base flow the fringe restores and the top's outflow come from the integral estimate of
//! the layer ([`hgym_solvers::bl_integral::develop`]): Blasius' profile up to the trip, the power
//! law of [`layer_shape`] after it, so the outflow carries a turbulent layer's displacement growth
//! and the free stream stays uniform. The measured edge velocity's spread over the compared
//! stations is reported beside the checks.
//!
//! At each reference `Re_theta` the measured `C_f` and `H12` are a straight line fitted against
//! `Re_theta` over the stations within `window` of it (the stations are noisy one by one). The
//! case is data: `benchmarks/validation/tbl_zpg.toml`, the DNS values
//! `benchmarks/validation/data/tbl_zpg_schlatter_orlu_2010.csv`. The developed state is cached
//! as the channel's is. Writes `<out>/tbl_zpg.json` and `<out>/tbl_zpg/{c_f,h12}.png`.

use std::path::Path;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::channel::{cache_path, columns, restore_cached, store, Check, LevelSpec};
use crate::flow::level::PerLevel;
use crate::flow::Level;
use crate::report::plots;
use hgym_solvers::bl_integral::develop;
use hgym_solvers::blasius::Blasius;
use hgym_solvers::channel::plate::{layer_shape, plate, PlateSpec};
use hgym_solvers::channel::{viscous_dt_limit, ChannelError, FringeSpec, Grid, LayerSums, Top, TripSpec};

/// The committed case file.
pub const CASE: &str = include_str!("../../benchmarks/validation/tbl_zpg.toml");
const DNS: &str = include_str!("../../benchmarks/validation/data/tbl_zpg_schlatter_orlu_2010.csv");
/// Changes whenever a change of the solver or the set-up invalidates cached developed states.
const SOLVER_VERSION: &str = "channel-fd2-rk3-v1-plate1";

#[derive(Debug, Error)]
pub enum PlateValidationError {
    #[error("the case file tbl_zpg.toml: {0}")]
    Case(String),
    #[error("the case cannot run at this level: {0}")]
    Unrunnable(String),
    #[error(transparent)]
    Solver(#[from] ChannelError),
    #[error("{path}: {message}")]
    Output { path: String, message: String },
}

/// The fringe: the last `length` of the box; `rise` and `fall` are fractions of it.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FringeCase {
    pub length: f64,
    pub rise: f64,
    pub fall: f64,
    pub lambda_max: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Checks {
    /// Reference `Re_theta` values (rows of the DNS table).
    pub re_theta: Vec<f64>,
    /// Relative tolerances.
    pub c_f: f64,
    pub h12: f64,
    /// Relative half-width in `Re_theta` of the stations fitted at each reference.
    pub window: f64,
}

#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub case: String,
    pub description: String,
    pub reference: String,
    pub re_delta_star: f64,
    pub length: [f64; 3],
    pub stretch: f64,
    pub modes: usize,
    pub fringe: FringeCase,
    pub trip: TripSpec,
    pub levels: PerLevel<LevelSpec>,
    pub checks: Checks,
}

impl Case {
    pub fn level(&self, level: Level) -> &LevelSpec {
        self.levels.at(level)
    }

    pub fn nu(&self) -> f64 {
        1.0 / self.re_delta_star
    }

    pub fn plate_spec(&self, level: Level) -> PlateSpec {
        let l = self.level(level);
        let lx = self.length[0];
        let f = &self.fringe;
        PlateSpec {
            n: l.n,
            length: self.length,
            stretch: self.stretch,
            nu: self.nu(),
            dt: l.dt,
            fringe: FringeSpec {
                x_start: lx - f.length,
                x_end: lx,
                rise: f.rise * f.length,
                fall: f.fall * f.length,
                lambda_max: f.lambda_max,
            },
            modes: self.modes,
            trip: Some(self.trip),
        }
    }
}

pub fn case() -> Result<Case, PlateValidationError> {
    toml::from_str(CASE).map_err(|e| PlateValidationError::Case(e.to_string()))
}

/// The layer along the plate, one entry per `u` position upstream of the fringe.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Development {
    pub x: Vec<f64>,
    pub ue: Vec<f64>,
    pub re_theta: Vec<f64>,
    pub c_f: Vec<f64>,
    pub h12: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PlateValidation {
    pub schema: String,
    pub case: String,
    pub level: String,
    pub n: [usize; 3],
    pub length: [f64; 3],
    pub stretch: f64,
    pub dt: f64,
    pub re_delta_star: f64,
    pub spin_up: f64,
    pub spin_up_cached: bool,
    pub average: f64,
    pub samples: u64,
    /// Grid spacings in wall units at the first reference station.
    pub dx_plus: f64,
    pub dz_plus: f64,
    pub first_cell_y_plus: f64,
    /// Largest relative deviation of the edge velocity from its mean over the stations from the
    /// first to the last compared window (a measure of how uniform the free stream is).
    pub ue_spread: f64,
    pub checks: Vec<Check>,
    pub pass: bool,
    pub development: Development,
    pub manifest: crate::report::manifest::Manifest,
}

/// Least-squares line through `(x, y)`, evaluated at `x0` (`None` for fewer than two points).
fn line_at(xs: &[f64], ys: &[f64], x0: f64) -> Option<f64> {
    let n = xs.len() as f64;
    if xs.len() < 2 {
        return None;
    }
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    Some(my + slope * (x0 - mx))
}

/// `(Re_theta, C_f, H12)` of the DNS at each of the case's reference `Re_theta`.
fn references(c: &Case) -> Result<Vec<(f64, f64, f64)>, PlateValidationError> {
    let col = |k| {
        columns(DNS, 0, k)
            .map(|t| t.1)
            .map_err(|e| PlateValidationError::Case(e.to_string()))
    };
    let (re, h, cf) = (col(0)?, col(3)?, col(4)?);
    c.checks
        .re_theta
        .iter()
        .map(|&r| match re.iter().position(|&v| (v - r).abs() < 1e-6 * r) {
            Some(row) => Ok((r, cf[row], h[row])),
            None => Err(PlateValidationError::Case(format!(
                "checks.re_theta {r} is not a row of the DNS table"
            ))),
        })
        .collect()
}

/// The layer the base flow starts from and the fringe restores: Blasius' up to the trip, then
/// the power law with the integral estimate's `theta` and `H` (a uniform free stream).
fn base_shape(c: &Case, b: &Blasius) -> impl Fn(f64, f64) -> f64 {
    let nu = c.nu();
    let x0 = b.x_of_displacement(1.0, 1.0, nu);
    let ds = 0.25;
    let s: Vec<f64> = (0..=((x0 + c.length[0]) / ds).ceil() as usize).map(|k| k as f64 * ds).collect();
    let stations = develop(&s, &vec![1.0; s.len()], nu, x0 + c.trip.x0, 0.0);
    let b = b.clone();
    move |x: f64, y: f64| {
        let k = (((x0 + x) / ds).round() as usize).min(stations.len() - 1);
        let p = stations[k];
        match p.turbulent {
            true => layer_shape(&b, p.theta, p.h, true, y),
            false => b.velocity(x0 + x, y, 1.0, nu).0,
        }
    }
}

/// Runs the case at `level` and writes its report and plots under `out`. `progress(done, total)`
/// reports solver steps (spin-up, unless cached, then averaging).
pub fn validate(
    level: Level,
    out: &Path,
    cache: Option<&Path>,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<PlateValidation, PlateValidationError> {
    let started = std::time::Instant::now();
    let cpu = crate::report::manifest::CpuClock::start();
    let c = case()?;
    let l = c.level(level).clone();
    let spec = c.plate_spec(level);
    let nu = c.nu();
    let g = Grid::new(spec.n, spec.length, spec.stretch, Top::FreeSlip)?;
    let limit = viscous_dt_limit(&g, nu);
    if l.dt > limit {
        return Err(PlateValidationError::Unrunnable(format!(
            "dt {} exceeds the viscous limit {limit:.4} of this grid: lower dt in the case file",
            l.dt
        )));
    }
    let refs = references(&c)?;
    let b = Blasius::solve();
    let (mut ch, _) = plate(&spec, |_| 1.0, base_shape(&c, &b))?;
    let steps_of = |t: f64| (t / l.dt).round() as u64;
    let path = cache.map(|d| cache_path(d, CASE, &c.case, level, SOLVER_VERSION));
    let cached = restore_cached(&mut ch, path.as_deref())?;
    let total = steps_of(l.average) + if cached { 0 } else { steps_of(l.spin_up) };
    if !cached {
        for _ in 0..steps_of(l.spin_up) {
            ch.step()?;
            progress(ch.steps(), total);
        }
        store(&ch, path.as_deref());
    }
    let s0 = total - steps_of(l.average);
    let every = (l.sample_interval / l.dt).round().max(1.0) as u64;
    let mut sums = LayerSums::new(&g);
    for steps in 1..=steps_of(l.average) {
        ch.step()?;
        if steps.is_multiple_of(every) {
            sums.add(&ch);
        }
        progress(s0 + steps, total);
    }
    if sums.samples == 0 {
        return Err(PlateValidationError::Case("the averaging window holds no sample".into()));
    }
    let mut d = Development::default();
    let stations: Vec<_> = (0..g.nx)
        .filter(|&i| (i as f64) * g.dx < spec.fringe.x_start)
        .map(|i| sums.station(&g, i))
        .collect();
    for s in &stations {
        d.x.push(s.x);
        d.ue.push(s.ue);
        d.re_theta.push(s.ue * s.theta / nu);
        d.c_f.push(s.c_f());
        d.h12.push(s.shape_factor());
    }
    // Downstream of the trip's own disturbance only (Re_theta is not monotone through it).
    let after_trip = |k: usize| d.x[k] > c.trip.x0 + 3.0 * c.trip.lx;
    let mut checks = vec![];
    let mut compared: Vec<usize> = vec![];
    let mut resolution = None;
    for &(re, cf_ref, h_ref) in &refs {
        let near: Vec<usize> = (0..d.x.len())
            .filter(|&k| after_trip(k) && (d.re_theta[k] / re - 1.0).abs() <= c.checks.window)
            .collect();
        let fit = |v: &[f64]| {
            let xs: Vec<f64> = near.iter().map(|&k| d.re_theta[k]).collect();
            let ys: Vec<f64> = near.iter().map(|&k| v[k]).collect();
            line_at(&xs, &ys, re).unwrap_or(f64::NAN)
        };
        let (cf, h) = (fit(&d.c_f), fit(&d.h12));
        if resolution.is_none() {
            if let Some(&k) = near.first() {
                let u_tau = stations[k].u_tau();
                resolution = Some((g.dx * u_tau / nu, g.dz * u_tau / nu, g.yc[0] * u_tau / nu));
            }
        }
        compared.extend(&near);
        let reached = if near.is_empty() { " (not reached)" } else { "" };
        let rel = |name: &str, value: f64, reference: f64, tol: f64| Check {
            name: format!("{name} at Re_theta {re:.0}{reached}"),
            value,
            reference,
            tolerance: format!("{} %", 100.0 * tol),
            pass: (value / reference - 1.0).abs() <= tol,
        };
        checks.push(rel("C_f", cf, cf_ref, c.checks.c_f));
        checks.push(rel("H12", h, h_ref, c.checks.h12));
    }
    let ue_spread = match (compared.iter().min(), compared.iter().max()) {
        (Some(&a), Some(&z)) => {
            let ue = &d.ue[a..=z];
            let mean = ue.iter().sum::<f64>() / ue.len() as f64;
            ue.iter().map(|u| (u / mean - 1.0).abs()).fold(0.0, f64::max)
        }
        _ => f64::NAN,
    };
    let (dx_plus, dz_plus, first_cell_y_plus) = resolution.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let pass = checks.iter().all(|c| c.pass);
    let report = PlateValidation {
        schema: "hgym/tbl-validation/v1".into(),
        case: c.case.clone(),
        level: level.name().into(),
        n: l.n,
        length: c.length,
        stretch: c.stretch,
        dt: l.dt,
        re_delta_star: c.re_delta_star,
        spin_up: l.spin_up,
        spin_up_cached: cached,
        average: l.average,
        samples: sums.samples as u64,
        dx_plus,
        dz_plus,
        first_cell_y_plus,
        ue_spread,
        checks,
        pass,
        development: d,
        manifest: crate::report::manifest::manifest(rayon::current_num_threads(), started.elapsed().as_secs_f64())
            .with_cpu(cpu.total(Some(0.0))),
    };
    write(&report, &refs, out)?;
    Ok(report)
}

fn write(r: &PlateValidation, refs: &[(f64, f64, f64)], out: &Path) -> Result<(), PlateValidationError> {
    let dir = out.join(&r.case);
    let fail = |p: &Path| {
        let path = p.display().to_string();
        move |message: String| PlateValidationError::Output { path, message }
    };
    std::fs::create_dir_all(&dir).map_err(|e| fail(&dir)(e.to_string()))?;
    let json = out.join(format!("{}.json", r.case));
    let text = serde_json::to_string_pretty(r).map_err(|e| fail(&json)(e.to_string()))?;
    std::fs::write(&json, text + "\n").map_err(|e| fail(&json)(e.to_string()))?;
    let d = &r.development;
    let re_refs: Vec<f64> = refs.iter().map(|x| x.0).collect();
    for (name, ours, reference, what) in [
        ("c_f.png", &d.c_f, refs.iter().map(|x| x.1).collect::<Vec<f64>>(), "C_f"),
        ("h12.png", &d.h12, refs.iter().map(|x| x.2).collect::<Vec<f64>>(), "H12"),
    ] {
        let png = dir.join(name);
        plots::lines(
            &png,
            &format!("Zero-pressure-gradient boundary layer ({}x{}x{}): {what}", r.n[0], r.n[1], r.n[2]),
            "Re_theta",
            what,
            &[
                plots::Line {
                    label: "hgym (each station)",
                    x: &d.re_theta,
                    y: ours,
                    band: None,
                },
                plots::Line {
                    label: "Schlatter & Orlu 2010 DNS",
                    x: &re_refs,
                    y: &reference,
                    band: None,
                },
            ],
        )
        .map_err(|e| fail(&png)(crate::report::chain(&e)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_case_and_its_reference_rows_parse() {
        let c = case().unwrap();
        let refs = references(&c).unwrap();
        assert_eq!(refs[0], (677.452, 0.004777047, 1.473324));
    }

    #[test]
    fn a_line_fit_is_exact_on_a_line() {
        let xs = [1.0, 2.0, 4.0];
        let ys: Vec<f64> = xs.iter().map(|x| 3.0 - 0.5 * x).collect();
        assert!((line_at(&xs, &ys, 3.0).unwrap() - 1.5).abs() < 1e-12);
        assert_eq!(line_at(&xs[..1], &ys[..1], 3.0), None);
    }

    #[test]
    fn every_level_resolves_the_wall_and_meets_the_viscous_limit() {
        let c = case().unwrap();
        for level in Level::ALL {
            let s = c.plate_spec(level);
            let g = Grid::new(s.n, s.length, s.stretch, Top::FreeSlip).unwrap();
            // u_tau at Re_theta 677 (C_f 0.0048): y+ of the first cell centre.
            let y_plus = g.yc[0] * (0.0024f64).sqrt() / c.nu();
            assert!(y_plus <= 1.0, "{level:?}: first cell at y+ {y_plus}");
            assert!(
                s.dt <= viscous_dt_limit(&g, c.nu()),
                "{level:?}: dt {} above the viscous limit {} (y+ {y_plus})",
                s.dt,
                viscous_dt_limit(&g, c.nu())
            );
        }
    }

    #[test]
    fn the_base_layer_is_blasius_before_the_trip_and_turbulent_after() {
        let c = case().unwrap();
        let b = Blasius::solve();
        let shape = base_shape(&c, &b);
        // At the inflow the displacement thickness is 1 (the length unit).
        let dy = 1e-3;
        let ds: f64 = (0..20_000).map(|k| dy * (1.0 - shape(0.0, (k as f64 + 0.5) * dy))).sum();
        assert!((ds - 1.0).abs() < 2e-3, "delta* at the inflow {ds}");
        // Downstream of the trip the fuller turbulent profile: larger u near the wall.
        let y = 0.3;
        assert!(shape(c.trip.x0 + 50.0, y) > shape(c.trip.x0 - 1.0, y) + 0.1);
    }
}
