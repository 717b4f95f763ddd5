#!/usr/bin/env python3
"""Strouhal number of a lift history by several standard estimators, side by side.

A study tool for broadband wakes (benchmarks/validation/STUDIES.md, "What the Strouhal number of
this lift is"). On a limit cycle every estimator gives the same frequency. On a broadband lift
they differ by more than a validation tolerance. `hgym validate` reports one of them: the cycles
of the tallest spectral peak, counted on the lift low-passed around that peak
(src/validate/analysis.rs). This script prints the others for the same `forces.csv`:

- crossings: upward zero crossings of the raw lift minus its mean, re-armed only after the lift has
  gone below -h * std (h = 0 and 0.3); frequency = (crossings - 1) / (last - first);
- Welch: the power spectral density averaged over Hann windows of `--segment` D/U with half overlap
  (Welch 1967); its tallest peak, its median frequency (half the power either side) and its
  power-weighted mean frequency, in the band 0.02-0.5.

Usage (the project venv has numpy: make setup):
    ~/.cache/hgym-venv/bin/python scripts/strouhal_estimators.py results/validation/square_re1000/forces.csv 60
Times and frequencies are in the case's convective units (D/U and U/D).
"""

import argparse
import sys

import numpy as np


def crossings_frequency(t, x, hysteresis):
    """Upward zero crossings of `x` (zero mean); armed again only below -hysteresis * std."""
    level = hysteresis * x.std()
    armed, times = False, []
    for j in range(1, len(x)):
        if x[j - 1] < -level:
            armed = True
        if armed and x[j - 1] < 0.0 <= x[j]:
            times.append(t[j - 1] + (t[j] - t[j - 1]) * (-x[j - 1]) / (x[j] - x[j - 1]))
            armed = False
    if len(times) < 2:
        return float("nan")
    return (len(times) - 1) / (times[-1] - times[0])


def welch(t, x, segment):
    """Frequencies and Welch-averaged power of `x` over Hann windows of `segment` time units."""
    dt = t[1] - t[0]
    n = min(int(round(segment / dt)), len(x))
    step = max(n // 2, 1)
    power, count = None, 0
    for start in range(0, len(x) - n + 1, step):
        p = np.abs(np.fft.rfft(x[start : start + n] * np.hanning(n))) ** 2
        power = p if power is None else power + p
        count += 1
    return np.fft.rfftfreq(n, dt), power / count


def estimators(t, lift, segment=100.0, band=(0.02, 0.5)):
    x = lift - lift.mean()
    freqs, power = welch(t, x, segment)
    inside = (freqs > band[0]) & (freqs < band[1])
    f, p = freqs[inside], power[inside]
    cumulative = np.cumsum(p)
    return {
        "crossings, no hysteresis": crossings_frequency(t, x, 0.0),
        "crossings, hysteresis 0.3 std": crossings_frequency(t, x, 0.3),
        "Welch tallest peak": f[np.argmax(p)],
        "Welch median frequency": f[np.searchsorted(cumulative, 0.5 * cumulative[-1])],
        "Welch mean frequency": float((f * p).sum() / p.sum()),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("forces", help="a forces.csv written by hgym validate (columns t, c_d, c_l, ...)")
    parser.add_argument("t_start", type=float, help="first time to use (after the spin-up), in D/U")
    parser.add_argument("--column", default="c_l", help="signal column (default c_l)")
    parser.add_argument("--segment", type=float, default=100.0, help="Welch window length in D/U (default 100)")
    args = parser.parse_args()
    data = np.genfromtxt(args.forces, delimiter=",", names=True)
    if args.column not in data.dtype.names:
        sys.exit(f"no column {args.column!r} in {args.forces}: it has {', '.join(data.dtype.names)}")
    keep = data["t"] >= args.t_start
    t, lift = data["t"][keep], data[args.column][keep]
    if len(t) < 16 or t[-1] - t[0] < args.segment:
        sys.exit(f"only {t[-1] - t[0] if len(t) else 0:.1f} time units after t = {args.t_start}: "
                 f"need at least one Welch window of {args.segment} (see --segment)")
    for name, value in estimators(t, lift, args.segment).items():
        print(f"{name:32s} {value:.4f}")


if __name__ == "__main__":
    main()
