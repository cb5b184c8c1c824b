"""Thrust curves: one ESC's PWM command (microseconds) -> thrust (N), and back.

A *thrust curve* is a small picklable strategy object with two vectorized methods:

- ``thrust(pwm)``: any-shaped PWM array (us) -> thrust array (N), same shape;
- ``pwm(thrust)``: the inverse, used by tests and data generators; 0 N maps to the
  neutral command (middle of the deadband).

This module holds the fixed curve classes and the shipped tables (the value checks of a
specification: :mod:`uvsim.curve_checks`).  The interface they implement,
:class:`ThrustCurve` (range checks, inverse, equality), is in :mod:`uvsim.thrust_curve_base`
and re-exported here; no other uvsim curve module is imported: the battery-aware curve
builds on this one (:mod:`uvsim.voltage_curves`), and :mod:`uvsim.thrusters` turns vehicle-file
specifications into curves (:func:`uvsim.thrusters.load_thrust_curve`) and applies one
per thruster (:class:`uvsim.thrusters.ThrustCurveSet`).

Two kinds ship:

- :class:`TabulatedThrustCurve`: a measured PWM -> thrust table interpolated piecewise
  linearly (``np.interp``, which preserves the table's monotonicity), with an explicit
  deadband ``[lo, hi]`` where the thrust is exactly 0, a reverse branch (``pwm < lo``,
  thrust <= 0) and a forward branch (``pwm > hi``, thrust >= 0).  The shipped default
  for the BlueROV2 is ``t200_16v``: Blue Robotics' published T200 bollard-thrust data at
  16 V (T200-Public-Performance-Data-10-20V-September-2019), see
  ``src/uvsim/data/thrusters/SOURCE.md`` and ``docs/thrusters.md``.
- :class:`LinearThrustCurve`: separate forward/reverse gains (N/us) outside a deadband.

PWM outside a curve's range, non-finite PWM, or a thrust beyond what the curve can
produce raise :class:`uvsim.errors.SimulationError` naming the value and the valid range;
nothing is clipped.  Malformed tables or specs raise :class:`uvsim.errors.VehicleError`
naming the file or field.
"""
from __future__ import annotations

import functools
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from uvsim.constants import PWM_RANGE_US
from uvsim.curve_checks import as_1d, check_curve_keys, finite_number, number_pair, readonly_array
from uvsim.errors import VehicleError
from uvsim.schema import did_you_mean
from uvsim.thrust_curve_base import ThrustCurve  # noqa: F401 (re-exported: the curves' interface)

#: Directory of the shipped tables (``<name>.csv`` with columns pwm_us, thrust_N).
DATA_DIR = Path(__file__).resolve().parent / "data" / "thrusters"

#: Name of the default curve for BlueROV2-class vehicles (T200 at 16 V, 4S battery).
DEFAULT_CURVE = "t200_16v"

#: Standard gravity used to convert kilogram-force to newtons (exact by definition of
#: the kgf; CGPM 1901).  Only used to document/convert published kgf tables.
KGF_TO_N = 9.80665


# ------------------------------------------------------------------------- tabulated
class TabulatedThrustCurve(ThrustCurve):
    """Measured PWM -> thrust table, interpolated piecewise linearly.

    Parameters
    ----------
    pwm : array_like, shape (n,)
        Commands, us, finite and strictly increasing, n >= 2.
    thrust : array_like, shape (n,)
        Thrust at each command, N, finite and non-decreasing, <= 0 below the deadband,
        >= 0 above it and exactly 0 inside it.
    deadband : (lo, hi), optional
        Closed interval of commands with zero thrust, ``pwm[0] <= lo <= hi <= pwm[-1]``.
        Default: the first and last table commands whose thrust is 0 (for ``t200_16v``
        that is 1472-1528 us).  Between ``lo`` and the last reverse point (and ``hi``
        and the first forward point) thrust is interpolated linearly to 0.
    neutral : float, optional
        Command that :meth:`pwm` returns for 0 N; default the deadband midpoint.
    name : str
        Used in error messages and by :meth:`to_mapping` (a shipped table's name).
    source : str
        Where the numbers came from (file or field), used in validation errors.

    Notes
    -----
    ``np.interp`` is used over the whole (deadband-augmented) table, so one call serves
    any array shape; it returns the tabulated values exactly at the table commands and
    exactly 0 inside the deadband.  When the knots are uniformly spaced (as in the Blue
    Robotics sheets) large arrays use an equivalent search-free formula instead.
    """

    def __init__(self, pwm, thrust, *, deadband=None, neutral=None, name="table", source=None):
        source = source or name
        pwm = as_1d(pwm, f"{source}: pwm")
        thrust = as_1d(thrust, f"{source}: thrust")
        if pwm.size != thrust.size:
            raise VehicleError(
                f"{source}: pwm and thrust must have the same length, got {pwm.size} and {thrust.size}"
            )
        if pwm.size < 2:
            raise VehicleError(f"{source}: a thrust table needs at least 2 points, got {pwm.size}")
        if not np.all(np.diff(pwm) > 0):
            i = int(np.argmax(~(np.diff(pwm) > 0)))
            raise VehicleError(
                f"{source}: pwm must be strictly increasing, but pwm[{i}]={pwm[i]:g} and "
                f"pwm[{i + 1}]={pwm[i + 1]:g}"
            )
        lo_us, hi_us = PWM_RANGE_US
        if pwm[0] < lo_us or pwm[-1] > hi_us:
            bad = pwm[0] if pwm[0] < lo_us else pwm[-1]
            raise VehicleError(
                f"{source}: pwm {bad:g} is outside the ESC command range {lo_us:g}..{hi_us:g} us; expected "
                f"microseconds (a table in ms or in percent is a unit slip: 1.5 ms = 1500 us)"
            )
        if not np.all(np.diff(thrust) >= 0):
            i = int(np.argmax(~(np.diff(thrust) >= 0)))
            raise VehicleError(
                f"{source}: thrust must be non-decreasing in pwm (a monotone curve), but "
                f"thrust={thrust[i]:g} N at {pwm[i]:g} us and {thrust[i + 1]:g} N at {pwm[i + 1]:g} us"
            )

        if deadband is None:
            zero = np.flatnonzero(thrust == 0.0)
            if zero.size == 0:
                raise VehicleError(
                    f"{source}: the table has no zero-thrust entry, so the deadband cannot be "
                    f"inferred; give deadband: [lo, hi] (us)"
                )
            lo, hi = float(pwm[zero[0]]), float(pwm[zero[-1]])
        else:
            lo, hi = number_pair(deadband, f"{source}: deadband")
            if not lo <= hi:
                raise VehicleError(f"{source}: deadband must satisfy lo <= hi, got [{lo:g}, {hi:g}]")
            if lo < pwm[0] or hi > pwm[-1]:
                raise VehicleError(
                    f"{source}: deadband [{lo:g}, {hi:g}] us must lie inside the table's pwm "
                    f"range [{pwm[0]:g}, {pwm[-1]:g}] us"
                )
        inside = (pwm >= lo) & (pwm <= hi)
        if np.any(thrust[inside] != 0.0):
            i = int(np.flatnonzero(inside & (thrust != 0.0))[0])
            raise VehicleError(
                f"{source}: thrust must be 0 inside the deadband [{lo:g}, {hi:g}] us, but is "
                f"{thrust[i]:g} N at {pwm[i]:g} us"
            )
        if np.any(thrust[pwm < lo] > 0.0):
            i = int(np.flatnonzero((pwm < lo) & (thrust > 0.0))[0])
            raise VehicleError(
                f"{source}: thrust must be <= 0 below the deadband (reverse branch, pwm < {lo:g} us), "
                f"but is {thrust[i]:g} N at {pwm[i]:g} us"
            )
        if np.any(thrust[pwm > hi] < 0.0):
            i = int(np.flatnonzero((pwm > hi) & (thrust < 0.0))[0])
            raise VehicleError(
                f"{source}: thrust must be >= 0 above the deadband (forward branch, pwm > {hi:g} us), "
                f"but is {thrust[i]:g} N at {pwm[i]:g} us"
            )
        if neutral is None:
            neutral = 0.5 * (lo + hi)
        neutral = float(neutral)
        if not (np.isfinite(neutral) and lo <= neutral <= hi):
            raise VehicleError(f"{source}: neutral {neutral:g} us must lie in the deadband [{lo:g}, {hi:g}] us")

        # Table as given (for to_mapping / equality) and the interpolation knots: the
        # table points plus (lo, 0) and (hi, 0) where the table has no point there.
        self.table_pwm = readonly_array(pwm)
        self.table_thrust = readonly_array(thrust)
        extra = [v for v in sorted({lo, hi}) if v not in pwm]
        order = np.argsort(np.concatenate([pwm, extra]), kind="stable")
        self._xp = readonly_array(np.concatenate([pwm, extra])[order])
        self._fp = readonly_array(np.concatenate([thrust, np.zeros(len(extra))])[order])
        # Uniformly spaced knots (the Blue Robotics sheets: 4 us steps) allow a
        # search-free evaluation, about twice as fast as np.interp on large arrays.
        step = np.diff(self._xp)
        self._step = float(step[0]) if np.all(step == step[0]) else None
        self.pwm_min, self.pwm_max = float(pwm[0]), float(pwm[-1])
        self.deadband = (lo, hi)
        self.neutral = neutral
        self.name = str(name)
        self._deadband_given = deadband is not None
        self._neutral_given = neutral != 0.5 * (lo + hi)

    # -- evaluation -------------------------------------------------------------------
    def _thrust(self, pwm):
        if self._step is None or pwm.size < 64:
            return np.interp(pwm, self._xp, self._fp)
        # Uniform knots: segment index by division, then the same linear interpolation
        # as np.interp, written so that knots (t = 0, or t = 1 at the last knot) return
        # the table value exactly and zero-thrust segments return exactly 0.  Compiled where
        # numba is (uvsim.kernels.table_lookup: these operations in one pass, to the bit).
        from uvsim.kernels import compiled_uniform_table

        table = compiled_uniform_table()
        if table is not None:
            flat = np.ascontiguousarray(pwm).ravel()
            out = np.empty(flat.size)
            table(flat, float(self._xp[0]), self._step, self._fp, out)
            return out.reshape(pwm.shape)
        u = (pwm - self._xp[0]) / self._step
        i = np.minimum(u.astype(np.intp), self._xp.size - 2)
        t = u - i
        return self._fp[i] * (1.0 - t) + self._fp[i + 1] * t

    def _pwm(self, thrust):
        xp, fp = self._xp, self._fp
        # Forward (T > 0): first knot with fp >= T; the knot before it has fp < T, so the
        # segment rises strictly.  Reverse (T < 0): last knot with fp <= T; the next knot
        # has fp > T.  Both pick the command nearest to neutral on flat stretches.
        i_f = np.clip(np.searchsorted(fp, thrust, side="left"), 1, fp.size - 1)
        i_r = np.clip(np.searchsorted(fp, thrust, side="right"), 1, fp.size - 1)
        i = np.where(thrust > 0, i_f, i_r)
        x0, x1, f0, f1 = xp[i - 1], xp[i], fp[i - 1], fp[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            out = x0 + (thrust - f0) / (f1 - f0) * (x1 - x0)
        return np.where(thrust == 0, self.neutral, out)

    # -- construction -----------------------------------------------------------------
    @classmethod
    def from_csv(cls, path, *, deadband=None, neutral=None, name=None) -> "TabulatedThrustCurve":
        """Read a table from a CSV file with columns ``pwm_us`` and ``thrust_N``.

        Lines starting with ``#`` are comments.  Raises :class:`VehicleError` naming the
        file if it is missing, lacks a column or holds non-numbers.
        """
        import pandas as pd  # local import: pandas is only needed to read files

        path = Path(path)
        try:
            df = pd.read_csv(path, comment="#", skipinitialspace=True)
        except FileNotFoundError:
            raise VehicleError(f"thrust curve file {path} does not exist") from None
        except (ValueError, pd.errors.ParserError) as exc:
            raise VehicleError(f"thrust curve file {path} could not be parsed as CSV: {exc}") from None
        df.columns = [str(c).strip() for c in df.columns]
        missing = [c for c in ("pwm_us", "thrust_N") if c not in df.columns]
        if missing:
            raise VehicleError(
                f"thrust curve file {path}: missing column(s) {missing}; expected columns "
                f"pwm_us, thrust_N (got {list(df.columns)})"
            )
        cols = {}
        for c in ("pwm_us", "thrust_N"):
            vals = pd.to_numeric(df[c], errors="coerce").to_numpy(dtype=float)
            if not np.all(np.isfinite(vals)):
                row = int(np.flatnonzero(~np.isfinite(vals))[0])
                raise VehicleError(
                    f"thrust curve file {path}: column {c} row {row + 1} is {df[c].iloc[row]!r}, "
                    f"expected a finite number"
                )
            cols[c] = vals
        return cls(cols["pwm_us"], cols["thrust_N"], deadband=deadband, neutral=neutral,
                   name=name or path.stem, source=str(path))

    @classmethod
    def from_mapping(cls, d: Mapping[str, Any], *, field: str = "curve",
                     base_dir=None) -> "TabulatedThrustCurve":
        """Build from a YAML mapping.

        Forms: ``{"table": "t200_16v"}`` (a shipped table), ``{"csv": "file.csv"}``
        (relative to ``base_dir``), or ``{"pwm": [...], "thrust": [...]}``; each may add
        ``deadband: [lo, hi]`` and ``neutral``.  ``field`` names the YAML location in
        error messages.
        """
        if not isinstance(d, Mapping):
            raise VehicleError(f"{field}: expected a mapping, got {type(d).__name__}")
        check_curve_keys(d, {"table", "csv", "pwm", "thrust", "deadband", "neutral", "type"}, field)
        forms = [k for k in ("table", "csv", "pwm") if k in d]
        if len(forms) != 1 or ("pwm" in d) != ("thrust" in d):
            raise VehicleError(
                f"{field}: give exactly one of 'table: NAME', 'csv: FILE' or 'pwm: [...]' "
                f"with 'thrust: [...]' (got keys {sorted(d)})"
            )
        deadband = d.get("deadband")
        if deadband is not None:
            deadband = number_pair(deadband, f"{field}.deadband")
        neutral = d.get("neutral")
        if neutral is not None:
            neutral = finite_number(neutral, f"{field}.neutral")
        if "table" in d:
            if deadband is None and neutral is None:
                return shipped_curve(d["table"], field=f"{field}.table")
            return cls.from_csv(_shipped_path(d["table"], f"{field}.table"), deadband=deadband,
                                neutral=neutral, name=str(d["table"]))
        if "csv" in d:
            p = Path(str(d["csv"]))
            if not p.is_absolute() and base_dir is not None:
                p = Path(base_dir) / p
            return cls.from_csv(p, deadband=deadband, neutral=neutral)
        return cls(d["pwm"], d["thrust"], deadband=deadband, neutral=neutral,
                   name="inline", source=field)

    def to_mapping(self) -> dict:
        if self.name in available_tables() and shipped_curve(self.name) == self:
            return {"table": self.name}
        out = {"pwm": self.table_pwm.tolist(), "thrust": self.table_thrust.tolist(),
               "deadband": list(self.deadband)}
        if self._neutral_given:
            out["neutral"] = self.neutral
        return out

    def _key(self):
        return (tuple(self.table_pwm.tolist()), tuple(self.table_thrust.tolist()),
                self.deadband, self.neutral)

    def __repr__(self) -> str:
        return (f"TabulatedThrustCurve(name={self.name!r}, pwm=[{self.pwm_min:g}..{self.pwm_max:g}] us, "
                f"deadband={self.deadband}, thrust=[{self.max_reverse:.3f}, {self.max_forward:.3f}] N)")


# ---------------------------------------------------------------------------- linear
class LinearThrustCurve(ThrustCurve):
    """Piecewise-linear curve with asymmetric gains and a deadband.

    ``thrust = forward_gain * (pwm - hi)`` for ``pwm > hi``,
    ``thrust = reverse_gain * (pwm - lo)`` for ``pwm < lo`` and 0 in ``[lo, hi]``.
    With the default zero-width deadband ``lo = hi = neutral`` this is
    ``gain * (pwm - neutral)``; a wider deadband shifts each branch so the thrust is
    continuous at the deadband edges (no jump).

    Parameters
    ----------
    forward_gain, reverse_gain : float
        Slopes, N/us, > 0 (reverse thrust = -reverse_gain * (lo - pwm)).
    neutral : float
        Command for zero thrust, us (default 1500).
    deadband : (lo, hi), optional
        Default ``(neutral, neutral)``.
    pwm_range : (min, max)
        Valid commands, us (default 1100-1900, the T200/Basic ESC range).
    """

    def __init__(self, forward_gain, reverse_gain, *, neutral=1500.0, deadband=None,
                 pwm_range=(1100.0, 1900.0), name="linear", source=None):
        source = source or name
        self.forward_gain = finite_number(forward_gain, f"{source}: forward_gain")
        self.reverse_gain = finite_number(reverse_gain, f"{source}: reverse_gain")
        for k in ("forward_gain", "reverse_gain"):
            if not getattr(self, k) > 0:
                raise VehicleError(f"{source}: {k} must be > 0 N/us, got {getattr(self, k):g}")
        self.neutral = finite_number(neutral, f"{source}: neutral")
        lo, hi = (self.neutral, self.neutral) if deadband is None else number_pair(deadband, f"{source}: deadband")
        pmin, pmax = number_pair(pwm_range, f"{source}: pwm_range")
        if not (pmin <= lo <= self.neutral <= hi <= pmax):
            raise VehicleError(
                f"{source}: need pwm_range[0] <= deadband lo <= neutral <= deadband hi <= pwm_range[1], "
                f"got pwm_range=[{pmin:g}, {pmax:g}], deadband=[{lo:g}, {hi:g}], neutral={self.neutral:g}"
            )
        self.deadband = (lo, hi)
        self.pwm_min, self.pwm_max = pmin, pmax
        self.name = str(name)

    def _thrust(self, pwm):
        lo, hi = self.deadband
        return (self.forward_gain * np.maximum(pwm - hi, 0.0)
                + self.reverse_gain * np.minimum(pwm - lo, 0.0))

    def _pwm(self, thrust):
        lo, hi = self.deadband
        return np.where(thrust > 0, hi + thrust / self.forward_gain,
                        np.where(thrust < 0, lo + thrust / self.reverse_gain, self.neutral))

    @classmethod
    def from_mapping(cls, d: Mapping[str, Any], *, field: str = "curve") -> "LinearThrustCurve":
        """``{"type": "linear", "forward_gain": .., "reverse_gain": .., "neutral": ..,
        "deadband": [lo, hi], "pwm_range": [min, max]}`` (gains N/us)."""
        check_curve_keys(d, {"type", "forward_gain", "reverse_gain", "neutral", "deadband", "pwm_range"}, field)
        for k in ("forward_gain", "reverse_gain"):
            if k not in d:
                raise VehicleError(f"{field}: linear thrust curve needs '{k}' (N/us)")
        kw = {k: d[k] for k in ("neutral", "deadband", "pwm_range") if k in d}
        return cls(d["forward_gain"], d["reverse_gain"], name="linear", source=field, **kw)

    def to_mapping(self) -> dict:
        return {"type": "linear", "forward_gain": self.forward_gain, "reverse_gain": self.reverse_gain,
                "neutral": self.neutral, "deadband": list(self.deadband),
                "pwm_range": [self.pwm_min, self.pwm_max]}

    def _key(self):
        return (self.forward_gain, self.reverse_gain, self.neutral, self.deadband,
                self.pwm_min, self.pwm_max)

    def __repr__(self) -> str:
        return (f"LinearThrustCurve(forward_gain={self.forward_gain:g}, reverse_gain={self.reverse_gain:g}, "
                f"neutral={self.neutral:g}, deadband={self.deadband}, "
                f"pwm_range=({self.pwm_min:g}, {self.pwm_max:g}))")


# --------------------------------------------------------------------- shipped tables
def available_tables() -> list[str]:
    """Names of the shipped tables (``src/uvsim/data/thrusters/*.csv``)."""
    return sorted(p.stem for p in DATA_DIR.glob("*.csv"))


def _shipped_path(name, field) -> Path:
    names = available_tables()
    if not isinstance(name, str) or name not in names:
        raise VehicleError(f"{field}: unknown thrust curve {name!r}{did_you_mean(name, names)}; shipped tables: {names}")
    return DATA_DIR / f"{name}.csv"


@functools.lru_cache(maxsize=None)
def _cached_shipped(name: str) -> TabulatedThrustCurve:
    return TabulatedThrustCurve.from_csv(DATA_DIR / f"{name}.csv", name=name)


def shipped_curve(name: str, *, field: str = "curve") -> TabulatedThrustCurve:
    """The shipped table ``name`` (e.g. ``"t200_16v"``); one shared, read-only instance."""
    _shipped_path(name, field)
    return _cached_shipped(name)
