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
measurement many times.  :func:`sample_kind` detects the form (not from the repeats and
equal steps of a value rounded to a resolution, :data:`ROUNDED_ADJACENT`) and returns the rows
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

**What the estimate cannot see** (issue 48, item 4).  The fourth differences see the noise
that changes from sample to sample.  Two kinds of channel hide their error from them:

* **rounded values**: a channel logged to a resolution ``q`` (0.01 deg, 1 mm) carries a
  rounding error uniform in ``+-q/2``, ``sigma = q / sqrt(12)`` (Bennett 1948; Widrow &
  Kollar 2008, ch. 4), whatever the fourth differences of a smooth signal show.
  :func:`quantum` reads ``q`` from the data (the smallest step between samples, when the
  other steps are whole multiples of it) and :func:`quantisation_sigma` is a floor of every
  channel's level;
* **an estimator's output**: an attitude filter (AHRS, EKF, complementary filter) integrates
  the gyro and corrects slowly, so its angles change from sample to sample by the integrated
  gyro noise only, and their error (a bias, a drift, a lag) varies over seconds, where the
  differences do not look.  On a field log of the generator (:mod:`uvsim.scenarios.field`,
  10 Hz) the estimate of roll, pitch and yaw is about 1e-4 rad while the filter's error
  against the truth is 0.005-0.02 rad in roll / pitch and 0.02-0.12 rad in yaw.  Such a
  channel is recognised by :func:`filter_output`: its visible noise is at most
  :data:`FILTER_GATE` times the gyro's noise integrated over one of its sample intervals
  (``sigma_gyro dt``).  A random walk of the integrated gyro stays below that (its
  fourth-difference estimate is ``sqrt(20 / 70) sigma_gyro sqrt(dt_filter dt)``, at most
  ``0.53 sigma_gyro dt``; 0.2-1.1 times ``sigma_gyro dt`` on the field logs, where the motion
  adds to it), and an angle with noise of its own (motion capture, a noisy AHRS) exceeds it by
  far (0.002 rad against 2 x 6e-5 rad at 50 Hz).  Its level is then at least
  :data:`FILTER_FLOOR`.

A declared level (``sensors.noise`` in the vehicle file, or the ``noise`` option) replaces the
estimate and both floors.
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
#: Share of adjacent events (the rows where a held channel changes, or where an interpolated one
#: kinks) at or above which the repeats or straight stretches of a channel logged to a
#: resolution (:func:`quantum`) come from its rounding, not from a slow sensor.  A sensor held or
#: interpolated onto a log at least twice its rate changes on one row and kinks on one or two
#: adjacent rows per native sample (a share of at most 0.5); a motion rounded to 0.01 deg repeats a
#: value or steps by equal multiples now and then and changes on most rows (0.66-0.99 on the field
#: logs' yaw, which was taken as held or interpolated and lost a third of its rows before).
ROUNDED_ADJACENT = 0.6
#: Floor of an estimated noise level in the channel's unit: below the 1e-6 rounding of
#: logs written by uvsim, so it only matters for noise-free data.
NOISE_FLOOR = 1e-6
D4_VARIANCE = 70.0
MAD_TO_SIGMA = 1.4826
#: Share of a channel's non-zero steps that must be whole multiples of the smallest one (within
#: QUANTUM_RTOL of it) for the channel to count as rounded to that resolution: a continuous
#: signal's steps are multiples of its smallest step about 2 % of the time.
QUANTUM_SHARE = 0.9
QUANTUM_RTOL = 0.01
#: Fewest non-zero steps from which a resolution is read.
QUANTUM_MIN_STEPS = 8
#: An attitude channel whose estimated noise is at most this many times ``sigma_gyro dt`` is an
#: estimator's output (module docstring: a random walk of the integrated gyro gives at most 0.53).
FILTER_GATE = 2.0
#: Lowest noise level (1-sigma, rad) of an attitude estimator's roll, pitch and yaw: the
#: accuracy of a high-performance industrial MEMS AHRS, Movella (Xsens) MTi-300 data sheet (2023),
#: "sensor fusion performance": roll and pitch 0.2 deg RMS, yaw / heading 1 deg RMS (with its
#: magnetometer in an undisturbed field; a compass-less yaw drifts with the gyro bias and is
#: worse).  A floor, not a typical value.
FILTER_FLOOR = {"roll": float(np.radians(0.2)), "pitch": float(np.radians(0.2)), "yaw": float(np.radians(1.0))}


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


def _rounding(events: np.ndarray, v: np.ndarray) -> bool:
    """Whether the repeats or straight stretches of the values ``v`` (whose changes or kinks are
    ``events``, bool) come from rounding to a resolution (:data:`ROUNDED_ADJACENT`)."""
    idx = np.flatnonzero(events)
    return idx.size >= 2 and float(np.mean(np.diff(idx) == 1)) >= ROUNDED_ADJACENT and quantum(v) > 0


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
        if held.mean() > DETECT_SHARE and not _rounding(~held, v):
            kind = "held"
            keep = np.r_[True, ~held]          # the first row of every held value
            native = np.zeros_like(ok)
            native[idx[keep]] = True
        else:
            d2 = np.diff(v, 2)
            lin = np.abs(d2) <= COLLINEAR_RTOL * scale
            if lin.mean() > DETECT_SHARE and not _rounding(~lin, v):
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



def quantum(x: np.ndarray, native: np.ndarray | None = None) -> float:
    """The resolution ``q`` channel ``x`` was logged to: the smallest non-zero step between its
    native samples when at least :data:`QUANTUM_SHARE` of the non-zero steps are whole multiples
    of it; 0 when they are not (a continuous value) or there are fewer than
    :data:`QUANTUM_MIN_STEPS` steps."""
    x = np.asarray(x, float)
    sel = np.isfinite(x) if native is None else (np.asarray(native, bool) & np.isfinite(x))
    v = x[sel]
    if v.size < 2:
        return 0.0
    d = np.abs(np.diff(v))
    d = d[d > 1e-12 * max(float(np.max(np.abs(v))), 1e-300)]  # steps above float rounding
    if d.size < QUANTUM_MIN_STEPS:
        return 0.0
    q = float(d.min())
    k = d / q
    return q if float(np.mean(np.abs(k - np.round(k)) <= QUANTUM_RTOL)) >= QUANTUM_SHARE else 0.0


def quantisation_sigma(q: float) -> float:
    """1-sigma of the rounding to resolution ``q``: ``q / sqrt(12)`` (module docstring)."""
    return float(q) / np.sqrt(12.0)


def filter_output(sigma_angle: float, sigma_gyro: float, interval_s: float) -> bool:
    """Whether an attitude channel whose estimated noise is ``sigma_angle`` (rad), sampled every
    ``interval_s`` s beside a gyro of noise ``sigma_gyro`` (rad/s), is an estimator's output: its
    visible noise is at most :data:`FILTER_GATE` times the gyro's noise integrated over one
    sample interval (module docstring)."""
    return bool(np.isfinite(sigma_angle) and np.isfinite(sigma_gyro) and interval_s > 0
                and sigma_angle <= FILTER_GATE * sigma_gyro * interval_s)


@dataclass
class NoiseLevel:
    """The noise level a channel is measured with, and where it comes from.

    Attributes
    ----------
    sigma : the level, the channel's unit: what every fit, verdict, report and plot divides the
        channel's error by.
    source : "estimated" (fourth differences of the native samples), "floor" (the estimate was
        below what the rounding or an estimator's output allows, module docstring) or "declared"
        (the vehicle file's ``sensors.noise`` or the ``noise`` option).
    basis : what the level rests on, in words.
    estimate : the fourth-difference estimate (NaN with fewer than 8 native samples).
    quantum : the resolution the channel was logged to (0: none found).
    note : what a command tells the user about it (the same for every run; "" for nothing).
    """

    sigma: float
    source: str
    basis: str
    estimate: float = float("nan")
    quantum: float = 0.0
    note: str = ""

    def describe(self) -> dict:
        return {"sigma": float(self.sigma), "source": self.source, "basis": self.basis,
                "estimate": float(self.estimate) if np.isfinite(self.estimate) else None,
                "quantum": float(self.quantum) if self.quantum > 0 else None}
