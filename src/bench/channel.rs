//! `hgym bench channel`: the channel DNS's speed as steps per second and, more usefully,
//! simulated viscous time `t+` per wall-clock second, at the minimal box (`TCFMini_3D_Retau180`)
//! and the full box (`TCF_3D_Retau180`) on their default grids, with 1 and 2 threads; each at the
//! step its environment takes (half the RK3 Courant limit, inside the viscous limit).
//!
//! With a peer (HydroGym's JAX channel, [`super::peer`]), both run the peer's own box and grid
//! (72^3), alternating, each at its own Reynolds number and step (both stated): the ratio is
//! simulated time per wall-clock second in bulk units `h/U_b`, ours over the peer's (the peer's
//! viscous scale is not defined by its set-up: it holds its bulk velocity at 8 with nu 1.9e-3,
//! which is not Re_tau 180, so viscous units would need a turbulence statistic of its run).
//! Target: at least 5x.

use std::time::Instant;

use hgym_solvers::channel::{Channel, ChannelConfig, Drive, Top};
use serde::{Deserialize, Serialize};

use super::peer::{Pairs, Peer, PeerError};
use super::BenchError;
use crate::env::channel::{self as family, ChannelSpec};
use crate::flow::Level;

/// hgym's speed-up per simulated time unit the peer comparison is judged against.
pub const TARGET_SPEEDUP: f64 = 5.0;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChannelRow {
    pub case: String,
    pub n: [usize; 3],
    pub length: [f64; 3],
    pub threads: usize,
    /// The step in outer units `h/U_b` and in viscous units (nominal `u_tau`).
    pub dt: f64,
    pub dt_plus: f64,
    pub steps_per_s: f64,
    pub t_plus_per_s: f64,
    /// Simulated bulk time units `h/U_b` per second.
    pub bulk_time_per_s: f64,
    /// Wall time per cell and RK3 step.
    pub ns_per_cell_step: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChannelPeer {
    /// The peer's own description (versions, grid, box, step, precision, threads).
    pub about: serde_json::Value,
    pub n: [usize; 3],
    pub length: [f64; 3],
    /// Each solver's step in its bulk units `h/U_b` on this grid.
    pub dt_ours: f64,
    pub dt_peer: f64,
    /// Simulated `h/U_b` per wall-clock second, and steps per second, ours against the peer's.
    pub pairs: Vec<Pairs>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChannelBench {
    pub rows: Vec<ChannelRow>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peer: Option<ChannelPeer>,
    pub target_speedup: f64,
    /// Whether the peer comparison reaches the target (true without a peer: nothing is judged).
    pub pass: bool,
}

/// `spec`'s flow on the grid `n` from a disturbed laminar start (a step costs the same on any
/// field), and its environment's step.
fn solver(spec: &ChannelSpec, n: [usize; 3]) -> Result<(Channel, f64), BenchError> {
    let mut s = spec.clone();
    s.grid.default = n;
    let (_, dt) = s.steps(Level::Default).map_err(BenchError::Input)?;
    let cfg = ChannelConfig {
        n,
        length: s.length,
        stretch: s.stretch,
        top: s.top,
        nu: s.nu(),
        dt,
        drive: Drive::FlowRate(1.0),
        check_interval: 10,
    };
    let mut c = Channel::new(cfg).map_err(|e| BenchError::Input(e.to_string()))?;
    let mut rng = hgym_agents::rng::Rng::seed(7);
    c.set_disturbed_laminar(0.3, || 2.0 * rng.uniform() - 1.0);
    for _ in 0..5 {
        c.step().map_err(|e| BenchError::Check(e.to_string()))?;
    }
    Ok((c, dt))
}

/// Seconds per step: the best of three timings of at least `seconds` each.
fn time_steps(c: &mut Channel, seconds: f64) -> Result<f64, BenchError> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut k = 0u32;
        while k < 3 || start.elapsed().as_secs_f64() < seconds {
            c.step().map_err(|e| BenchError::Check(e.to_string()))?;
            k += 1;
        }
        best = best.min(start.elapsed().as_secs_f64() / k as f64);
    }
    Ok(best)
}

fn row(spec: &ChannelSpec, n: [usize; 3], threads: usize, seconds: f64) -> Result<ChannelRow, BenchError> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    pool.install(|| {
        let (mut c, dt) = solver(spec, n)?;
        let per_step = time_steps(&mut c, seconds)?;
        let plus = spec.u_tau_nominal().powi(2) / spec.nu();
        Ok(ChannelRow {
            case: spec.id.clone(),
            n,
            length: spec.length,
            threads,
            dt,
            dt_plus: dt * plus,
            steps_per_s: 1.0 / per_step,
            t_plus_per_s: dt * plus / per_step,
            bulk_time_per_s: dt / per_step,
            ns_per_cell_step: per_step * 1e9 / (n[0] * n[1] * n[2]) as f64,
        })
    })
}

/// The full channel at Re_tau 180 on the peer's box and grid.
fn peer_spec(length: [f64; 3]) -> Result<ChannelSpec, BenchError> {
    let mut s = family::all()
        .into_iter()
        .find(|s| s.id == "TCF_3D_Retau180")
        .ok_or_else(|| BenchError::Input("TCF_3D_Retau180 is not registered".into()))?;
    s.length = length;
    s.top = Top::Wall;
    Ok(s)
}

pub fn bench_channel(quick: bool, threads: usize, peer: Option<&mut Peer>) -> Result<ChannelBench, BenchError> {
    let seconds = if quick { 0.05 } else { 1.0 };
    let mut rows = vec![];
    for spec in family::all().into_iter().filter(|s| s.id != "TCFOpen_3D_Retau206") {
        let level = if quick { Level::Coarse } else { Level::Default };
        for t in [1, threads.max(1)].into_iter().collect::<std::collections::BTreeSet<_>>() {
            rows.push(row(&spec, spec.n(level), t, seconds)?);
        }
    }
    let peer = match peer {
        None => None,
        Some(p) => Some(with_peer(p, quick, threads).map_err(|e| BenchError::Check(e.to_string()))?),
    };
    let pass = peer.as_ref().is_none_or(|p| p.pairs[0].median_speedup >= TARGET_SPEEDUP);
    Ok(ChannelBench {
        rows,
        peer,
        target_speedup: TARGET_SPEEDUP,
        pass,
    })
}

/// Alternating pairs: our simulated time per second on the peer's grid against the peer's.
fn with_peer(p: &mut Peer, quick: bool, threads: usize) -> Result<ChannelPeer, PeerError> {
    let failed = |m: String| PeerError::Failed {
        script: "hydrogym_channel.py".into(),
        message: m,
    };
    let about = p.about.clone();
    let grid = |key: &str| -> Result<[f64; 3], PeerError> {
        let v = about
            .get(key)
            .and_then(|v| v.as_array())
            .filter(|a| a.len() == 3)
            .ok_or_else(|| failed(format!("its 'ready' answer has no 3-vector '{key}': {about}")))?;
        let mut out = [0.0; 3];
        for (o, x) in out.iter_mut().zip(v) {
            *o = x.as_f64().ok_or_else(|| failed(format!("'{key}' is not numeric: {about}")))?;
        }
        Ok(out)
    };
    let (n, length) = (grid("n")?, grid("length")?);
    let n = n.map(|v| v as usize);
    let spec = peer_spec(length).map_err(|e| failed(e.to_string()))?;
    let number = |key: &str| {
        about
            .get(key)
            .and_then(|v| v.as_f64())
            .ok_or_else(|| failed(format!("no number '{key}': {about}")))
    };
    let dt_peer = number("dt")? * number("u_bulk")? / (0.5 * length[1]);
    let (mut time, mut steps, mut dt_ours) = (vec![], vec![], f64::NAN);
    let seconds = if quick { 0.2 } else { 2.0 };
    for _ in 0..if quick { 1 } else { 3 } {
        let r = row(&spec, n, threads, seconds).map_err(|e| failed(format!("hgym on the peer's grid: {e}")))?;
        let [bulk_time_per_s, steps_per_s] = p.numbers("run", ["bulk_time_per_s", "steps_per_s"])?;
        time.push((r.bulk_time_per_s, bulk_time_per_s));
        steps.push((r.steps_per_s, steps_per_s));
        dt_ours = r.dt;
    }
    Ok(ChannelPeer {
        about,
        n,
        length,
        dt_ours,
        dt_peer,
        pairs: vec![
            Pairs::new("simulated h/U_b per second", "h/U_b/s", &time, true),
            Pairs::new("steps per second", "steps/s", &steps, true),
        ],
    })
}

pub fn table(b: &ChannelBench) -> String {
    let mut s = String::from(match b.peer {
        None => "Channel DNS (no peer measured in this run, so no ratio to HydroGym's JAX channel; --peer runs it)\n",
        Some(_) => "Channel DNS (the peer's pairs below)\n",
    });
    s += "case                  grid            threads  dt+      steps/s   t+ per s   ns/cell/step\n";
    for r in &b.rows {
        s += &format!(
            "{:<21} {:<15} {:>7} {:>7.4} {:>9.1} {:>10.2} {:>13.1}\n",
            r.case,
            format!("{}x{}x{}", r.n[0], r.n[1], r.n[2]),
            r.threads,
            r.dt_plus,
            r.steps_per_s,
            r.t_plus_per_s,
            r.ns_per_cell_step
        );
    }
    if let Some(p) = &b.peer {
        s += &format!(
            "against {} on its grid {}x{}x{}, box {:.3} x {:.3} x {:.3} (same run, alternating pairs):\n",
            super::peer::describe(&p.about),
            p.n[0],
            p.n[1],
            p.n[2],
            p.length[0],
            p.length[1],
            p.length[2]
        );
        for pair in &p.pairs {
            s += &format!("  {}\n", pair.line("HydroGym"));
        }
        s += &format!(
            "  steps in h/U_b: hgym {:.4} (RK3, half its Courant limit; Re_b 2800, float64), HydroGym {:.4} (RK4, its own)\n  \
             target {}x per simulated time: {}\n",
            p.dt_ours,
            p.dt_peer,
            b.target_speedup,
            if b.pass { "PASS" } else { "SHORT of target" }
        );
    }
    s
}
