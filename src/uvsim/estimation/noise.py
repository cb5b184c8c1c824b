"""Measurement-noise levels per channel, judged at each sensor's native rate.

A logged channel can reach uvsim in three forms:

* **native**: every non-empty cell is a measurement (a sensor slower than the log
  leaves NaN between its samples);
* **held**: a slow sensor logged on a fast grid by repeating its last value
  (sample-and-hold), so most first differences are exactly 0;
* **interpolated**: a slow sensor resampled linearly onto the fast grid, so the
  signal is piecewise linear and most second differences are exactly 0.

Treating held or interpolated cells as measurements makes the noise look tiny
(issue 14: a 10 Hz pressure interpolated to 100 Hz gave 6e-6 m) and counts one
measurement many times.  :func:`sample_kind` detects the form and returns the rows
that carry real measurements (the *native samples*: the first row of each held
value, the knots of an interpolation); calibration and diagnosis use only those rows
as measurements and estimate the noise on them.

The noise estimate (:func:`noise_sigma`) is the median absolute deviation of the
fourth differences of the native samples,
``d4 = x[i-2] - 4 x[i-1] + 6 x[i] - 4 x[i+1] + x[i+2]``:
for white noise ``var(d4) = 70 sigma^2`` (1 + 16 + 36 + 16 + 1), while a motion that
is locally a cubic polynomial cancels exactly, so even a 10 Hz sensor on a moving
vehicle gives the noise rather than the motion (second differences, ``var = 6
sigma^2``, keep the curvature ``a dt^2``: 1 mm at 0.1 m/s^2 and 10 Hz).
``sigma = 1.4826 MAD(d4) / sqrt(70)`` (1.4826 makes the MAD a consistent estimator
of a normal standard deviation; Rousseeuw & Croux 1993).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Share of exactly repeated (held) or exactly collinear (interpolated) consecutive
#: samples above which a channel is taken as held / interpolated.  White sensor noise
#: never repeats a float64 value, and a real motion is never exactly linear over three
#: samples, so even 0.3 is far above what native data shows (0 for noisy channels);
#: a 2x-upsampled channel has 0.5, a 10x one 0.9.
DETECT_SHARE = 0.3
#: Relative tolerance for "exactly collinear" second differences (float rounding of a
#: linear interpolation written to CSV with ~15 digits).
COLLINEAR_RTOL = 1e-9
#: Floor of an estimated noise level in the channel's unit: below the 1e-6 rounding of
#: logs written by uvsim, so it only matters for noise-free data.
NOISE_FLOOR = 1e-6
D4_VARIANCE = 70.0
MAD_TO_SIGMA = 1.4826


@dataclass
class SampleKind:
    """How a channel was logged.

    Attributes
    ----------
    kind : "native" | "held" | "interpolated" | "empty".
    native : (n,) bool, the rows that carry a measurement.
    native_interval_s : median time between native samples, s (NaN if < 2).
    log_interval_s : median time between rows of the log, s.
    """

    kind: str
    native: np.ndarray
    native_interval_s: float
    log_interval_s: float

    @property
    def upsampling(self) -> float:
        """Log rows per native sample (1 for native data)."""
        if not np.isfinite(self.native_interval_s) or self.log_interval_s <= 0:
            return 1.0
        return max(1.0, self.native_interval_s / self.log_interval_s)

    def describe(self, name: str) -> str:
        if self.kind in ("native", "empty"):
            return f"{name}: {self.kind}"
        rate, log_rate = 1.0 / self.native_interval_s, 1.0 / self.log_interval_s
        # irregular native samples whose median interval is the log's: the rate says nothing
        at = ("between irregular samples" if abs(rate - log_rate) < 0.05 * log_rate else f"at {rate:.3g} Hz")
        return (f"{name}: {self.kind} {at} in a {log_rate:.3g} Hz log; {int(self.native.sum())} of "
                f"{self.native.size} rows used as measurements")


def sample_kind(t: np.ndarray, x: np.ndarray) -> SampleKind:
    """Detect whether channel ``x`` (n,) logged at times ``t`` (n,) is native, held or
    interpolated (module docstring) and which rows are its native samples."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    ok = np.isfinite(x)
    dt_log = float(np.median(np.diff(t))) if t.size > 1 else float("nan")
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return SampleKind("empty", ok, float("nan"), dt_log)
    native = ok.copy()
    kind = "native"
    if idx.size >= 4:
        v = x[idx]
        d1 = np.diff(v)
        scale = max(float(np.max(np.abs(v))), 1e-300)
        held = d1 == 0.0
        if held.mean() > DETECT_SHARE:
            kind = "held"
            keep = np.r_[True, ~held]          # the first row of every held value
            native = np.zeros_like(ok)
            native[idx[keep]] = True
        else:
            d2 = np.diff(v, 2)
            lin = np.abs(d2) <= COLLINEAR_RTOL * scale
            if lin.mean() > DETECT_SHARE:
                kind = "interpolated"
                knots = np.r_[True, ~lin, True]  # the ends and every kink
                native = np.zeros_like(ok)
                native[idx[knots]] = True
    nt = t[native]
    dt_nat = float(np.median(np.diff(nt))) if nt.size > 1 else float("nan")
    return SampleKind(kind, native, dt_nat, dt_log)


def noise_sigma(x: np.ndarray, native: np.ndarray | None = None) -> float:
    """1-sigma white-noise level of channel ``x`` from the fourth differences of its
    native samples (module docstring); NaN with fewer than 8 native samples."""
    x = np.asarray(x, float)
    sel = np.isfinite(x) if native is None else (np.asarray(native, bool) & np.isfinite(x))
    v = x[sel]
    if v.size < 8:
        return float("nan")
    d4 = v[:-4] - 4 * v[1:-3] + 6 * v[2:-2] - 4 * v[3:-1] + v[4:]
    return max(float(MAD_TO_SIGMA * np.median(np.abs(d4 - np.median(d4))) / np.sqrt(D4_VARIANCE)), NOISE_FLOOR)

