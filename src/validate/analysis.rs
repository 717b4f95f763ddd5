//! Statistics of force histories: Strouhal number from the lift signal, means and amplitudes over
//! whole shedding periods.
//!
//! Periods come from upward zero crossings of the fluctuating lift `C_L - mean(C_L)` (linear
//! interpolation between samples, with a hysteresis of a tenth of the standard deviation so noise
//! does not count as a crossing): `St = f L / U = 1 / T` in units of L/U. Means and amplitudes are
//! taken between the first and the last crossing, i.e. over whole periods. The lift spectrum
//! (Hann window, zero-padded FFT, peak refined by a parabola through the log-magnitudes) gives a
//! second, independent frequency estimate.
//!
//! The frequency sought is the fundamental (the inverse of the period), which need not be the
//! tallest peak: the fluidic pinball's total lift at Re 100 has its third harmonic above its
//! fundamental, as the lifts of the three cylinders partly cancel. The spectral estimate is
//! therefore the lowest peak of at least a quarter of the tallest one of which the tallest is a
//! harmonic (2nd to 6th, within 3 %) and every other such peak a multiple (a periodic signal's
//! spectrum; a broadband one keeps its tallest peak), and the crossings are counted on the lift low-passed by two
//! centred moving averages over a half and a third of that period, which null the 2nd and 3rd
//! harmonics (and their multiples) and leave the timing of the fundamental's crossings unchanged.
//! The level crossed is the lift's centred moving average over one period (which nulls the
//! fundamental and all harmonics), not its overall mean: a chaotic wake (the pinball at Re 150)
//! drifts slowly, and cycles riding on a drift never cross the overall mean, so counting
//! crossings of the mean missed a tenth of them (f0 0.1055 against a spectral peak at 0.1195).
//!
//! Every statistic is also taken over up to [`BATCHES`] consecutive runs of whole periods of the
//! window ([`batches`]): their scatter is the sampling error of a window of this length, which for
//! a chaotic wake can exceed the tolerance a reference is checked to.

use realfft::RealFftPlanner;
use serde::Serialize;

#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct Analysis {
    /// From zero crossings; `None` if fewer than two whole periods (steady flow).
    pub strouhal: Option<f64>,
    /// From the spectral peak.
    pub strouhal_spectral: Option<f64>,
    pub mean_cd: f64,
    pub mean_cl: f64,
    pub cl_amplitude: f64,
    pub cl_rms: f64,
    pub cd_amplitude: f64,
    /// Whole periods used.
    pub periods: usize,
    /// Time window the means are taken over `[t0, t1]`.
    pub window: [f64; 2],
    /// The lift spectrum's substantial peaks (at least a quarter of the tallest): `[frequency,
    /// height relative to the tallest]`, tallest first, at most [`MAX_PEAKS`].
    pub lift_peaks: Vec<[f64; 2]>,
    /// The window cut into consecutive runs of whole periods, each analysed alone (see
    /// [`batches`]); empty when the window holds too few periods.
    pub batches: Vec<Analysis>,
}

/// Batches the averaging window is cut into, at most.
pub const BATCHES: usize = 4;

/// Whole periods a batch needs at least.
pub const MIN_BATCH_PERIODS: usize = 3;

/// The lift spectrum over the window: `(frequencies, amplitudes)`.
pub fn spectrum(t: &[f64], signal: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = signal.len();
    if n < 8 {
        return (vec![], vec![]);
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    let mean = signal.iter().sum::<f64>() / n as f64;
    let padded = (4 * n).next_power_of_two();
    let mut input = vec![0.0f64; padded];
    for (j, v) in signal.iter().enumerate() {
        let w = 0.5 * (1.0 - (2.0 * std::f64::consts::PI * j as f64 / (n - 1) as f64).cos());
        input[j] = (v - mean) * w;
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(padded);
    let mut out = fft.make_output_vec();
    // Lengths match the plan by construction.
    if fft.process(&mut input, &mut out).is_err() {
        return (vec![], vec![]);
    }
    let freqs = (0..out.len()).map(|k| k as f64 / (padded as f64 * dt)).collect();
    // Hann window has coherent gain 1/2.
    let amps = out.iter().map(|c| 4.0 * c.norm() / n as f64).collect();
    (freqs, amps)
}

/// Frequency of the peak at bin `k`, refined by a parabola through the log-magnitudes.
fn refined_peak(freqs: &[f64], amps: &[f64], k: usize) -> f64 {
    let (a, b, c) = (amps[k - 1].max(1e-300).ln(), amps[k].max(1e-300).ln(), amps[k + 1].max(1e-300).ln());
    let den = a - 2.0 * b + c;
    let shift = if den.abs() > 0.0 { 0.5 * (a - c) / den } else { 0.0 };
    let df = freqs[1] - freqs[0];
    freqs[k] + shift.clamp(-0.5, 0.5) * df
}

/// Local maxima of at least a quarter of the tallest: `(refined frequency, amplitude)`, tallest
/// first.
fn substantial_peaks(freqs: &[f64], amps: &[f64]) -> Vec<(f64, f64)> {
    if amps.len() < 3 {
        return vec![];
    }
    let Some(top) = (1..amps.len() - 1).max_by(|&a, &b| amps[a].total_cmp(&amps[b])) else {
        return vec![];
    };
    let mut peaks: Vec<(f64, f64)> = (1..amps.len() - 1)
        .filter(|&k| amps[k] >= 0.25 * amps[top] && amps[k] >= amps[k - 1] && amps[k] >= amps[k + 1])
        .map(|k| (refined_peak(freqs, amps, k), amps[k]))
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
    peaks
}

/// The most peaks a report lists.
pub const MAX_PEAKS: usize = 8;

/// Whether `f` is a whole multiple of `base` within 3 %.
fn multiple_of(f: f64, base: f64) -> bool {
    let m = (f / base).round();
    m >= 1.0 && (m * base - f).abs() <= 0.03 * f
}

/// The lift spectrum's substantial peaks, `[frequency, height / tallest height]`, tallest first
/// (at most [`MAX_PEAKS`]): what a reader needs to tell a limit cycle (the fundamental and its
/// harmonics) from a broadband, chaotic wake (peaks at unrelated frequencies) without re-running
/// the case.
fn lift_peaks(peaks: &[(f64, f64)]) -> Vec<[f64; 2]> {
    let top = peaks.first().map_or(1.0, |p| p.1);
    peaks.iter().take(MAX_PEAKS).map(|&(f, a)| [f, a / top]).collect()
}

/// Whether every listed peak is a harmonic (a whole multiple, within 3 %) of `fundamental`: a
/// periodic lift. A broadband one has peaks between the harmonics.
pub fn is_harmonic_series(peaks: &[[f64; 2]], fundamental: f64) -> bool {
    fundamental > 0.0 && peaks.iter().all(|p| multiple_of(p[0], fundamental))
}

/// The fundamental frequency of the spectrum (see the module doc): the lowest local maximum of at
/// least a quarter of the tallest peak whose 2nd to 6th multiple lies within 3 % of the tallest
/// and of which every such substantial peak is a multiple (within 3 %), else the tallest. The
/// second condition keeps a broadband (chaotic) lift from being read as periodic: the square
/// cylinder at Re 1000 with its lattice velocity halved has its tallest peak at 0.102 and
/// substantial ones at 0.052 and 0.075; 0.052 is half of 0.102 but 0.075 is no multiple of it,
/// and taking 0.052 smoothed the crossings away (no Strouhal number at all).
fn spectral_fundamental(peaks: &[(f64, f64)]) -> Option<f64> {
    let f_top = peaks.first()?.0;
    let mut lower: Vec<f64> = peaks.iter().map(|p| p.0).filter(|&f| f < f_top).collect();
    lower.sort_by(f64::total_cmp);
    let fundamental = lower
        .into_iter()
        .find(|&f| (2..=6).any(|m| (m as f64 * f - f_top).abs() <= 0.03 * f_top) && peaks.iter().all(|p| multiple_of(p.0, f)));
    Some(fundamental.unwrap_or(f_top))
}

/// Centred moving average over `2 half + 1` samples (shorter at the ends).
fn moving_average(v: &[f64], half: usize) -> Vec<f64> {
    if half == 0 {
        return v.to_vec();
    }
    let n = v.len();
    let mut prefix = vec![0.0f64; n + 1];
    for (j, x) in v.iter().enumerate() {
        prefix[j + 1] = prefix[j] + x;
    }
    (0..n)
        .map(|j| {
            let lo = j.saturating_sub(half);
            let hi = (j + half + 1).min(n);
            (prefix[hi] - prefix[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// A lift whose standard deviation over the window is below this (in coefficient units) is a
/// steady flow's: its wiggles are round-off and start-up acoustics, not shedding, so no
/// frequency, spectral peaks or periods are read from it and the means cover the whole window.
/// The pinball's steady symmetric state at Re 30 has a total-lift standard deviation of 2e-6
/// (`pinball_re30_steady`, with its drag still ringing by 0.2); the smallest shedding lift among
/// the committed reports, the pinball's total at Re 150 (its three lifts partly cancel), 0.046.
pub const STEADY_LIFT_STD: f64 = 1e-4;

/// Analyses the samples with `t >= t_start`.
pub fn analyse(t: &[f64], cd: &[f64], cl: &[f64], t_start: f64) -> Analysis {
    let first = t.iter().position(|&v| v >= t_start).unwrap_or(t.len());
    let (t, cd, cl) = (&t[first..], &cd[first..], &cl[first..]);
    let n = t.len();
    if n < 2 {
        return Analysis::default();
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let m_cl = mean(cl);
    let std = (cl.iter().map(|v| (v - m_cl).powi(2)).sum::<f64>() / n as f64).sqrt();
    let steady = std < STEADY_LIFT_STD;
    let hyst = 0.1 * std;
    let (freqs, amps) = spectrum(t, cl);
    // The spectrum's substantial peaks, found once: they give both the fundamental and the list.
    let peaks = if steady { vec![] } else { substantial_peaks(&freqs, &amps) };
    let strouhal_spectral = spectral_fundamental(&peaks);
    let peaks = lift_peaks(&peaks);
    // Crossings are found on the lift low-passed by centred moving averages over a half and a
    // third of the fundamental period (see the module doc), so that harmonics and high-frequency
    // noise cannot add crossings; means and amplitudes use the raw signal.
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    let half_width = |fraction: f64| strouhal_spectral.map_or(0, |f| ((0.5 * fraction / (f * dt)).round() as usize).min(n / 4));
    let (h1, h2, h3) = (half_width(1.0), half_width(1.0 / 2.0), half_width(1.0 / 3.0));
    let smooth = moving_average(&moving_average(cl, h2), h3);
    // The slow drift the cycles ride on (the overall mean when no period is known).
    let level = if h1 > 0 { moving_average(cl, h1) } else { vec![m_cl; n] };
    // Near the ends the averages are one-sided and would shift the crossings: skip those samples.
    let edge = h1.max(h2 + h3);
    // Upward crossings (time, sample index after the crossing).
    let mut crossings: Vec<(f64, usize)> = Vec::new();
    let mut armed = false;
    for j in (edge + 1)..n.saturating_sub(edge) {
        let (a, b) = (smooth[j - 1] - level[j - 1], smooth[j] - level[j]);
        if a < -hyst {
            armed = true;
        }
        if armed && a < 0.0 && b >= 0.0 {
            let tc = t[j - 1] + (t[j] - t[j - 1]) * (-a) / (b - a);
            crossings.push((tc, j));
            armed = false;
        }
    }
    if crossings.len() >= 3 && !steady {
        Analysis {
            strouhal_spectral,
            lift_peaks: peaks,
            batches: batches(cd, cl, &crossings),
            ..over_periods(cd, cl, &crossings)
        }
    } else {
        let (lo, hi) = cl
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let (dlo, dhi) = cd
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        Analysis {
            strouhal: None,
            strouhal_spectral: None,
            mean_cd: mean(cd),
            mean_cl: m_cl,
            cl_amplitude: 0.5 * (hi - lo),
            cl_rms: std,
            cd_amplitude: 0.5 * (dhi - dlo),
            periods: 0,
            window: [t[0], t[n - 1]],
            lift_peaks: peaks,
            batches: vec![],
        }
    }
}

/// Frequency (periods over their duration), means, lift rms and amplitudes (half the range per
/// period, averaged) over the whole periods between the first and the last of `crossings`
/// (upward crossings as `(time, index of the sample after it)`, at least two).
fn over_periods(cd: &[f64], cl: &[f64], crossings: &[(f64, usize)]) -> Analysis {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let periods = crossings.len() - 1;
    let (t0, j0) = crossings[0];
    let (t1, j1) = crossings[periods];
    let cd_w = &cd[j0..j1];
    let cl_w = &cl[j0..j1];
    let m_cl_w = mean(cl_w);
    let half_range = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        0.5 * (hi - lo)
    };
    let (mut amp_l, mut amp_d) = (0.0, 0.0);
    for p in crossings.windows(2) {
        let (a, b) = (p[0].1, p[1].1);
        amp_l += half_range(&cl[a..b]);
        amp_d += half_range(&cd[a..b]);
    }
    Analysis {
        strouhal: Some(1.0 / ((t1 - t0) / periods as f64)),
        strouhal_spectral: None,
        mean_cd: mean(cd_w),
        mean_cl: m_cl_w,
        cl_amplitude: amp_l / periods as f64,
        cl_rms: (cl_w.iter().map(|v| (v - m_cl_w).powi(2)).sum::<f64>() / cl_w.len() as f64).sqrt(),
        cd_amplitude: amp_d / periods as f64,
        periods,
        window: [t0, t1],
        lift_peaks: vec![],
        batches: vec![],
    }
}

/// Batch means (Law & Carson, Oper. Res. 27, 1979; Flyvbjerg & Petersen, J. Chem. Phys. 91,
/// 1989): the window's whole periods cut into [`BATCHES`] consecutive runs of at least
/// [`MIN_BATCH_PERIODS`] (fewer runs if the window is short, none below two), each analysed alone.
/// Their scatter measures how far a window of this length pins a chaotic wake's statistics down:
/// for runs longer than the correlation time, the standard error of the whole window's value is
/// the runs' standard deviation over `sqrt(runs)`. A limit cycle's runs agree to round-off.
fn batches(cd: &[f64], cl: &[f64], crossings: &[(f64, usize)]) -> Vec<Analysis> {
    let periods = crossings.len().saturating_sub(1);
    let k = (periods / MIN_BATCH_PERIODS).min(BATCHES);
    if k < 2 {
        return vec![];
    }
    (0..k)
        .map(|b| over_periods(cd, cl, &crossings[b * periods / k..=(b + 1) * periods / k]))
        .collect()
}

/// Standard error of the mean of `values` from their sample standard deviation: `s / sqrt(n)`;
/// `None` below two values.
pub fn standard_error(values: &[f64]) -> Option<f64> {
    let n = values.len();
    if n < 2 {
        return None;
    }
    let m = values.iter().sum::<f64>() / n as f64;
    let var = values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1) as f64;
    Some((var / n as f64).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_frequency_mean_and_amplitude_of_a_synthetic_signal() {
        let dt = 0.01;
        let st = 0.1957;
        let t: Vec<f64> = (0..20_000).map(|j| j as f64 * dt).collect();
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 0.05 + 0.66 * (2.0 * std::f64::consts::PI * st * t + 0.3).sin())
            .collect();
        let cd: Vec<f64> = t
            .iter()
            .map(|t| 1.35 + 0.02 * (4.0 * std::f64::consts::PI * st * t).sin())
            .collect();
        let a = analyse(&t, &cd, &cl, 20.0);
        assert!((a.strouhal.unwrap() - st).abs() < 1e-4, "{:?}", a.strouhal);
        assert!((a.strouhal_spectral.unwrap() - st).abs() < 2e-3, "{:?}", a.strouhal_spectral);
        assert!((a.mean_cd - 1.35).abs() < 1e-3);
        assert!((a.mean_cl - 0.05).abs() < 1e-3);
        assert!((a.cl_amplitude - 0.66).abs() < 1e-3);
        assert!((a.cl_rms - 0.66 / 2f64.sqrt()).abs() < 2e-3);
        assert!(a.periods >= 30);
    }

    /// Batch means: a limit cycle's four batches agree (standard error at round-off); a lift that
    /// sheds at St 0.10 for the first half of the window and 0.12 for the second gives batches
    /// from 0.10 to 0.12 and about the standard error of 0.10, 0.10, 0.12, 0.12 (`std / 2 =
    /// 0.0058`); a window
    /// of five periods is too short to batch.
    #[test]
    fn batches_measure_the_scatter_of_the_window() {
        use std::f64::consts::PI;
        let dt = 0.01;
        let t: Vec<f64> = (0..20_000).map(|j| j as f64 * dt).collect();
        let cd = vec![1.4; t.len()];
        let cl: Vec<f64> = t.iter().map(|t| (2.0 * PI * 0.1957 * t).sin()).collect();
        let a = analyse(&t, &cd, &cl, 20.0);
        assert_eq!(a.batches.len(), BATCHES);
        let st: Vec<f64> = a.batches.iter().map(|b| b.strouhal.unwrap()).collect();
        assert!(st.iter().all(|s| (s - 0.1957).abs() < 1e-4), "{st:?}");
        assert!(standard_error(&st).unwrap() < 1e-5);
        // The batches partition the window into whole periods.
        assert_eq!(a.batches.iter().map(|b| b.periods).sum::<usize>(), a.periods);
        assert_eq!(a.batches[0].window[0], a.window[0]);
        assert_eq!(a.batches[BATCHES - 1].window[1], a.window[1]);
        // Phase-continuous switch from 0.10 to 0.12 at t = 200 (20 periods of each).
        let phase = |t: f64| if t < 200.0 { 0.10 * t } else { 20.0 + 0.12 * (t - 200.0) };
        let t: Vec<f64> = (0..36_667).map(|j| j as f64 * dt).collect();
        let cd = vec![1.4; t.len()];
        let cl: Vec<f64> = t.iter().map(|&t| (2.0 * PI * phase(t)).sin()).collect();
        let a = analyse(&t, &cd, &cl, 0.0);
        let st: Vec<f64> = a.batches.iter().map(|b| b.strouhal.unwrap()).collect();
        assert_eq!(st.len(), 4, "{st:?}");
        // The middle split falls within a period of the switch: the outer batches are pure.
        assert!((st[0] - 0.10).abs() < 1e-3 && (st[3] - 0.12).abs() < 1e-3, "{st:?}");
        assert!(st.windows(2).all(|w| w[1] >= w[0] - 1e-9), "{st:?}");
        let se = standard_error(&st).unwrap();
        assert!((0.0045..0.0065).contains(&se), "{se} from {st:?}");
        // Five periods: one batch of at least three would be all there is.
        let t: Vec<f64> = (0..5_200).map(|j| j as f64 * dt).collect();
        let cl: Vec<f64> = t.iter().map(|t| (2.0 * PI * 0.1 * t).sin()).collect();
        let a = analyse(&t, &cd[..t.len()], &cl, 0.0);
        assert!(a.periods >= 3 && a.periods < 2 * MIN_BATCH_PERIODS, "{}", a.periods);
        assert!(a.batches.is_empty());
        assert_eq!(standard_error(&[1.0]), None);
    }

    #[test]
    fn high_frequency_noise_does_not_add_crossings() {
        let dt = 0.002;
        let st = 0.17;
        let t: Vec<f64> = (0..50_000).map(|j| j as f64 * dt).collect();
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 0.33 * (2.0 * std::f64::consts::PI * st * t).sin() + 0.1 * (2.0 * std::f64::consts::PI * 2.3 * t).sin())
            .collect();
        let cd = vec![1.3; t.len()];
        let a = analyse(&t, &cd, &cl, 10.0);
        assert!((a.strouhal.unwrap() - st).abs() < 1e-3, "{:?}", a.strouhal);
    }

    /// The pinball's total lift at Re 100: a fundamental at 0.0905 below its 2nd and above-it 3rd
    /// harmonic (amplitudes as measured: 0.0044, 0.0032, 0.0058).
    #[test]
    fn a_dominant_harmonic_does_not_multiply_the_frequency() {
        let dt = 0.0025;
        let st = 0.0905;
        let t: Vec<f64> = (0..120_000).map(|j| j as f64 * dt).collect();
        let w = 2.0 * std::f64::consts::PI * st;
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 0.03 + 0.0044 * (w * t).sin() + 0.0032 * (2.0 * w * t + 0.7).sin() + 0.0058 * (3.0 * w * t + 1.9).sin())
            .collect();
        let cd = vec![2.97; t.len()];
        let a = analyse(&t, &cd, &cl, 10.0);
        assert!((a.strouhal.unwrap() - st).abs() < 1e-3, "{:?}", a.strouhal);
        assert!((a.strouhal_spectral.unwrap() - st).abs() < 2e-3, "{:?}", a.strouhal_spectral);
        assert!((a.mean_cl - 0.03).abs() < 1e-4, "{}", a.mean_cl);
        // The third harmonic is the tallest peak, and the three make a harmonic series.
        assert_eq!(a.lift_peaks.len(), 3, "{:?}", a.lift_peaks);
        assert!((a.lift_peaks[0][0] - 3.0 * st).abs() < 3e-3, "{:?}", a.lift_peaks);
        assert!(is_harmonic_series(&a.lift_peaks, a.strouhal_spectral.unwrap()));
    }

    /// Two unrelated tones: the taller one is the frequency, whichever is lower.
    #[test]
    fn an_unrelated_lower_tone_is_not_taken_for_the_fundamental() {
        let dt = 0.005;
        let t: Vec<f64> = (0..60_000).map(|j| j as f64 * dt).collect();
        let tau = 2.0 * std::f64::consts::PI;
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 0.5 * (tau * 0.2 * t).sin() + 0.2 * (tau * 0.077 * t).sin())
            .collect();
        let cd = vec![1.0; t.len()];
        let a = analyse(&t, &cd, &cl, 5.0);
        assert!((a.strouhal_spectral.unwrap() - 0.2).abs() < 2e-3, "{:?}", a.strouhal_spectral);
    }

    /// Cycles riding on a slow drift larger than themselves (a chaotic wake's lift): every cycle
    /// is counted, where crossings of the overall mean would skip those lifted above it.
    #[test]
    fn a_slow_drift_does_not_hide_cycles() {
        let dt = 0.01;
        let st = 0.1195;
        let t: Vec<f64> = (0..60_000).map(|j| j as f64 * dt).collect();
        let tau = 2.0 * std::f64::consts::PI;
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 0.05 * (tau * st * t).sin() + 0.035 * (tau * 0.006 * t + 0.4).sin())
            .collect();
        let cd = vec![2.7; t.len()];
        let a = analyse(&t, &cd, &cl, 10.0);
        assert!((a.strouhal.unwrap() - st).abs() < 1e-3, "{:?}", a.strouhal);
        assert!(a.periods >= 65, "{} periods in {:?}", a.periods, a.window);
    }

    /// A broadband lift like the square cylinder's at Re 1000 (its measured spectrum's peaks:
    /// 0.102 tallest, 0.075, 0.052, 0.14, 0.195): 0.052 is half the tallest, but the other
    /// peaks are no multiples of it, so the tallest is the frequency and the crossings count it.
    #[test]
    fn a_subharmonic_of_a_broadband_lift_is_not_taken_for_the_fundamental() {
        let dt = 0.01;
        let t: Vec<f64> = (0..18_000).map(|j| j as f64 * dt).collect();
        let tau = 2.0 * std::f64::consts::PI;
        let tones = [
            (0.102, 0.92, 0.0),
            (0.075, 0.83, 1.1),
            (0.052, 0.57, 2.3),
            (0.14, 0.72, 0.4),
            (0.195, 0.55, 1.7),
        ];
        let cl: Vec<f64> = t
            .iter()
            .map(|t| tones.iter().map(|(f, a, p)| a * (tau * f * t + p).sin()).sum())
            .collect();
        let cd = vec![2.4; t.len()];
        let a = analyse(&t, &cd, &cl, 60.0);
        assert!((a.strouhal_spectral.unwrap() - 0.102).abs() < 3e-3, "{:?}", a.strouhal_spectral);
        assert!(a.strouhal.is_some() && a.periods >= 5, "{a:?}");
        // The five tones are listed, tallest first, and are no harmonic series.
        let listed: Vec<f64> = a.lift_peaks.iter().map(|p| p[0]).collect();
        assert_eq!(listed.len(), 5, "{:?}", a.lift_peaks);
        for (p, f) in listed.iter().zip([0.102, 0.075, 0.14, 0.052, 0.195]) {
            assert!((p - f).abs() < 3e-3, "{listed:?}");
        }
        assert_eq!(a.lift_peaks[0][1], 1.0);
        assert!(!is_harmonic_series(&a.lift_peaks, a.strouhal_spectral.unwrap()));
    }

    #[test]
    fn steady_signal_has_no_strouhal_number() {
        let t: Vec<f64> = (0..1000).map(|j| j as f64 * 0.01).collect();
        let cd = vec![2.0; 1000];
        let cl = vec![0.0; 1000];
        let a = analyse(&t, &cd, &cl, 1.0);
        assert_eq!(a.strouhal, None);
        assert!((a.mean_cd - 2.0).abs() < 1e-12);
    }

    /// A steady flow's lift is not exactly zero: round-off and the start's pressure waves leave
    /// wiggles of order 1e-6 on it (pinball_re30_steady: standard deviation 2e-6, with a
    /// broadband spectrum whose crossings the old analysis counted as 5 periods at St 0.30, and
    /// a 'broadband lift' note). Such a lift gives no frequency, no peaks, no batches, and the
    /// means cover the whole window, ringing drag and all.
    #[test]
    fn a_steady_lift_with_round_off_wiggles_has_no_periods() {
        let dt = 0.01;
        let t: Vec<f64> = (0..10_000).map(|j| j as f64 * dt).collect();
        let tau = 2.0 * std::f64::consts::PI;
        let cl: Vec<f64> = t
            .iter()
            .map(|t| 3e-6 * ((tau * 0.47 * t).sin() + (tau * 1.09 * t + 1.0).sin() + (tau * 0.06 * t).sin()))
            .collect();
        let cd: Vec<f64> = t.iter().map(|t| 4.68 + 0.2 * (tau * 0.8 * t).sin()).collect();
        let a = analyse(&t, &cd, &cl, 20.0);
        assert_eq!((a.strouhal, a.strouhal_spectral, a.periods), (None, None, 0));
        assert!(a.lift_peaks.is_empty() && a.batches.is_empty());
        assert_eq!(a.window, [20.0, t[t.len() - 1]]);
        assert!((a.mean_cd - 4.68).abs() < 1e-3, "{}", a.mean_cd);
        // The same wiggles at shedding size are a signal again.
        let big: Vec<f64> = cl.iter().map(|v| v * 1e4).collect();
        assert!(analyse(&t, &cd, &big, 20.0).strouhal.is_some());
    }
}
