"""Thrusters' curves as a vehicle file gives them, and one curve per thruster.

:func:`load_thrust_curve` builds a curve from the forms a vehicle YAML uses (a shipped
table name, ``{"table": name}``, an inline ``{"pwm": [...], "thrust": [...]}`` table, a
CSV file, ``{"type": "linear", ...}`` or a battery-aware ``{"voltage_table": ...}``);
:class:`ThrustCurveSet` applies one curve per thruster to ``(..., n_thrusters)`` arrays
with one call per distinct curve.

The curves themselves (PWM command -> thrust) live in :mod:`uvsim.thrust_curves` (fixed
curves and the shipped tables), :mod:`uvsim.voltage_curves` (battery-aware) and
:mod:`uvsim.thrust_curve_base` (the :class:`ThrustCurve` interface).  The public names of
:mod:`uvsim.thrust_curves` are re-exported here, where vehicle code and user scripts import
them (``from uvsim.thrusters import TabulatedThrustCurve`` keeps working).  Imports run one
way: thrusters -> voltage_curves -> thrust_curves -> thrust_curve_base.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from uvsim.errors import SimulationError, VehicleError
from uvsim.schema import did_you_mean
from uvsim.thrust_curves import (  # noqa: F401  (re-exported, see the module docstring)
    DATA_DIR,
    DEFAULT_CURVE,
    KGF_TO_N,
    LinearThrustCurve,
    TabulatedThrustCurve,
    available_tables,
    shipped_curve,
)
from uvsim.thrust_curve_base import ThrustCurve
from uvsim.voltage_curves import load_voltage_curve


# ------------------------------------------------------------------ per-thruster set
class ThrustCurveSet:
    """One curve per thruster, applied to ``(..., n_thrusters)`` arrays.

    Thrusters sharing an equal curve are evaluated in a single vectorized call, so the
    common case (all eight BlueROV2 thrusters on ``t200_16v``) costs one ``np.interp``.

    Parameters
    ----------
    curves : sequence of ThrustCurve, length n_thrusters
    """

    def __init__(self, curves: Sequence[ThrustCurve]):
        self.curves = tuple(curves)
        if not self.curves:
            raise VehicleError("a thrust curve set needs at least one thruster curve")
        groups: dict[ThrustCurve, list[int]] = {}
        for j, c in enumerate(self.curves):
            if not isinstance(c, ThrustCurve):
                raise VehicleError(f"thruster {j}: expected a ThrustCurve, got {type(c).__name__}")
            groups.setdefault(c, []).append(j)
        self._groups = [(c, np.array(cols)) for c, cols in groups.items()]

    def __len__(self) -> int:
        return len(self.curves)

    def thrust(self, pwm: np.ndarray) -> np.ndarray:
        """``(..., n_thrusters)`` PWM (us) -> thrust (N), column j through curve j."""
        return self._apply(pwm, "thrust")

    def pwm(self, thrust: np.ndarray) -> np.ndarray:
        """``(..., n_thrusters)`` thrust (N) -> PWM (us), inverse of :meth:`thrust`."""
        return self._apply(thrust, "pwm")

    def _apply(self, x, method):
        x = np.asarray(x, dtype=float)
        if x.ndim == 0 or x.shape[-1] != len(self.curves):
            raise SimulationError(
                f"expected an array with last axis of length {len(self.curves)} (one per thruster), "
                f"got shape {x.shape}"
            )
        if len(self._groups) == 1:
            return getattr(self._groups[0][0], method)(x)
        out = np.empty_like(x)
        for curve, cols in self._groups:
            out[..., cols] = getattr(curve, method)(x[..., cols])
        return out


# --------------------------------------------------------------------------- loading
def load_thrust_curve(spec, *, field: str = "curve", base_dir=None) -> ThrustCurve:
    """Build a thrust curve from a vehicle-file specification.

    Parameters
    ----------
    spec : str, mapping or ThrustCurve
        ``"t200_16v"`` (a shipped table); ``{"table": "t200_16v"}``;
        ``{"csv": "my_curve.csv"}`` (columns pwm_us, thrust_N; relative to ``base_dir``);
        ``{"pwm": [...], "thrust": [...], "deadband": [lo, hi]}`` (inline table, us and N);
        ``{"type": "linear", "forward_gain": .., "reverse_gain": .., ...}``;
        ``{"voltage_table": "t200", "nominal_voltage": 16.0}`` (battery-aware,
        :mod:`uvsim.voltage_curves`).  Table mappings may add ``deadband`` and ``neutral``.  A ThrustCurve is returned as is.
    field : str
        YAML location named in error messages, e.g. ``"thrusters[3].curve"``.
    base_dir : path, optional
        Directory that relative ``csv`` paths are resolved against (the vehicle file's).

    Raises
    ------
    VehicleError
        Unknown table name, unknown keys, missing fields or an invalid table.
    """
    if isinstance(spec, ThrustCurve):
        return spec
    if isinstance(spec, str):
        return shipped_curve(spec, field=field)
    if isinstance(spec, Mapping):
        if "voltage_table" in spec:
            return load_voltage_curve(spec, field=field)
        kind = spec.get("type", "table")
        if kind == "linear":
            return LinearThrustCurve.from_mapping(spec, field=field)
        if kind == "table":
            return TabulatedThrustCurve.from_mapping(spec, field=field, base_dir=base_dir)
        raise VehicleError(f"{field}.type: unknown thrust curve type {kind!r}{did_you_mean(kind, ('table', 'linear'))}; "
                           "expected 'table' or 'linear'")
    raise VehicleError(
        f"{field}: expected a shipped curve name (one of {available_tables()}) or a mapping, "
        f"got {type(spec).__name__}"
    )


__all__ = [
    "DATA_DIR", "DEFAULT_CURVE", "KGF_TO_N", "LinearThrustCurve", "TabulatedThrustCurve", "ThrustCurve",
    "ThrustCurveSet", "available_tables", "load_thrust_curve", "shipped_curve",
]
