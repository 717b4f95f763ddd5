//! The force history of a validation run as CSV (`<out>/<case>/forces.csv`), so that a run can
//! be re-analysed (other windows, spectra, filters) without running it again.
//!
//! Columns: `t` (L/U), `c_d`, `c_l` (totals), then `c_d_<i>`, `c_l_<i>` per body (1-based, in
//! the case file's order) when there are several. The solver samples every lattice step; the
//! file keeps one sample in every `stride` steps, `stride` the largest whole number of steps
//! within [`SAMPLES_PER_TIME`]^-1 L/U, which resolves frequencies far above any shedding
//! harmonic (St < 5) while keeping a 180 L/U run near 1 MB. Opens in pandas (`read_csv`).

use std::io::Write;
use std::path::Path;

use super::run::RunOutput;

/// Samples kept per convective time unit L/U (at least: every step when steps are coarser).
pub const SAMPLES_PER_TIME: f64 = 100.0;

/// Steps between kept samples for a run whose first sample is at `t0` = one step.
pub fn stride(t0: f64) -> usize {
    if t0 > 0.0 && t0.is_finite() {
        ((1.0 / (SAMPLES_PER_TIME * t0)).floor() as usize).max(1)
    } else {
        1
    }
}

/// Writes the history (up to a divergence, if the run diverged) to `path`.
pub fn write_forces_csv(out: &RunOutput, path: &Path) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut w = std::io::BufWriter::new(file);
    let per_body = out.cd_bodies.len() > 1;
    let mut header = String::from("t,c_d,c_l");
    if per_body {
        for b in 1..=out.cd_bodies.len() {
            header += &format!(",c_d_{b},c_l_{b}");
        }
    }
    writeln!(w, "{header}")?;
    let step = stride(out.t.first().copied().unwrap_or(0.0));
    // Sample i is step i + 1: keep the steps that are multiples of the stride.
    for i in (step - 1..out.t.len()).step_by(step) {
        let mut line = format!("{:.6},{:.7e},{:.7e}", out.t[i], out.cd[i], out.cl[i]);
        if per_body {
            for (cd, cl) in out.cd_bodies.iter().zip(&out.cl_bodies) {
                line += &format!(",{:.7e},{:.7e}", cd[i], cl[i]);
            }
        }
        writeln!(w, "{line}")?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stride_keeps_at_least_the_stated_rate() {
        // 800 steps per L/U (40 cells, U = 0.05): every 8th step, 100 per L/U.
        assert_eq!(stride(1.0 / 800.0), 8);
        // 250 steps per L/U: every 2nd step, 125 per L/U.
        assert_eq!(stride(1.0 / 250.0), 2);
        // Steps coarser than the rate: every step.
        assert_eq!(stride(0.05), 1);
        assert_eq!(stride(0.0), 1);
    }
}
