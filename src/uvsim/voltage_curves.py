"""Battery-aware thrust: a PWM -> thrust curve interpolated in PWM *and* supply voltage.

A thruster's bollard thrust at a fixed ESC command falls with the battery voltage (the
T200 gives 51.4 N at 1900 us and 16 V, 28.7 N at 10 V; ``data/thrusters/t200_voltage``).
:class:`VoltageThrustCurve` holds one measured table per voltage on a common PWM grid
and evaluates ``thrust(pwm, voltage)`` bilinearly: linear in PWM between table points
(as :class:`uvsim.thrust_curves.TabulatedThrustCurve` does) and linear in voltage between
the two bracketing sheets.  Without a voltage (``voltage=None``, or NaN for a row) it
uses :attr:`nominal_voltage`.

Voltages outside the measured range, PWM outside the table, or non-finite PWM raise
:class:`uvsim.errors.SimulationError` naming the value; nothing is extrapolated or
clipped.  Vehicle files name the shipped family as
``curve: {voltage_table: t200, nominal_voltage: 16.0}`` (docs/thrusters.md).
"""
from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

from uvsim.errors import SimulationError, VehicleError
from uvsim.thrust_curve_base import ThrustCurve
from uvsim.thrust_curves import DATA_DIR, KGF_TO_N, TabulatedThrustCurve

#: Shipped voltage families: name -> directory of ``<name>_<V>v.csv`` sheets.
FAMILIES = {"t200": DATA_DIR / "t200_voltage"}


class VoltageThrustCurve(ThrustCurve):
    """PWM (us) x supply voltage (V) -> thrust (N), bilinear in both.

    Parameters
    ----------
    pwm : array_like, shape (k,)
        Common command grid, us, strictly increasing and uniformly spaced.
    voltages : array_like, shape (m,)
        Supply voltages of the sheets, V, strictly increasing, m >= 2.
    thrust : array_like, shape (m, k)
        Thrust at each (voltage, command), N; 0 in each sheet's dead band.
    nominal_voltage : float
        Voltage used when none is given, V (inside the measured range).
    name : str
        Family name (used by :meth:`to_mapping` and in messages).
    """

    voltage_dependent = True

    def __init__(self, pwm, voltages, thrust, *, nominal_voltage, name="voltage_table", source=None):
        source = source or name
        pwm = np.asarray(pwm, float)
        volts = np.asarray(voltages, float)
        T = np.asarray(thrust, float)
        if pwm.ndim != 1 or pwm.size < 2 or not np.all(np.diff(pwm) > 0):
            raise VehicleError(f"{source}: pwm grid must be a strictly increasing list of >= 2 commands")
        step = np.diff(pwm)
        if not np.allclose(step, step[0]):
            raise VehicleError(f"{source}: pwm grid must be uniformly spaced (got steps {np.unique(step)})")
        if volts.ndim != 1 or volts.size < 2 or not np.all(np.diff(volts) > 0):
            raise VehicleError(f"{source}: voltages must be strictly increasing, >= 2 sheets, got {volts.tolist()}")
        if T.shape != (volts.size, pwm.size) or not np.all(np.isfinite(T)):
            raise VehicleError(f"{source}: thrust table must be finite with shape {(volts.size, pwm.size)}, got {T.shape}")
        v0 = float(nominal_voltage)
        if not volts[0] <= v0 <= volts[-1]:
            raise VehicleError(
                f"{source}: nominal_voltage {v0:g} V is outside the measured {volts[0]:g}..{volts[-1]:g} V")
        self.table_pwm = pwm
        self.voltages = volts
        self.table_thrust = T
        self.nominal_voltage = v0
        self._step = float(step[0])
        self.pwm_min, self.pwm_max = float(pwm[0]), float(pwm[-1])
        self.name = str(name)
        nominal = self._sheet(v0)
        zero = np.flatnonzero(nominal == 0.0)
        self.deadband = (float(pwm[zero[0]]), float(pwm[zero[-1]])) if zero.size else (1500.0, 1500.0)
        self.neutral = 0.5 * sum(self.deadband)

    # -- evaluation -------------------------------------------------------------------
    def _sheet(self, v: float) -> np.ndarray:
        j = int(np.clip(np.searchsorted(self.voltages, v, side="right") - 1, 0, self.voltages.size - 2))
        w = (v - self.voltages[j]) / (self.voltages[j + 1] - self.voltages[j])
        return (1.0 - w) * self.table_thrust[j] + w * self.table_thrust[j + 1]

    def thrust(self, pwm, voltage=None) -> np.ndarray:
        """Thrust (N) for commands ``pwm`` (us, any shape) at supply ``voltage`` (V).

        ``voltage`` broadcasts against ``pwm`` (e.g. (n, 1) per row for (n, k) PWM);
        None or NaN entries mean the nominal voltage."""
        pwm = np.asarray(pwm, dtype=float)
        if pwm.size and not (pwm.min() >= self.pwm_min and pwm.max() <= self.pwm_max):
            self._range_error(pwm, self.pwm_min, self.pwm_max, "PWM", "us")
        if voltage is None:
            v = np.full(pwm.shape, self.nominal_voltage)
        else:
            v = np.asarray(voltage, dtype=float)
            v = np.where(np.isnan(v), self.nominal_voltage, v)
            if v.size and not (v.min() >= self.voltages[0] and v.max() <= self.voltages[-1]):
                self._range_error(v, self.voltages[0], self.voltages[-1], "supply voltage", "V")
            v = np.broadcast_to(v, np.broadcast_shapes(v.shape, pwm.shape))
            pwm = np.broadcast_to(pwm, v.shape)
        if pwm.size >= 64:
            # compiled where numba is (uvsim.kernels.table_lookup.voltage_table: these operations
            # in one pass, to the bit)
            from uvsim.kernels import compiled_voltage_table

            table = compiled_voltage_table()
            if table is not None:
                flat = np.ascontiguousarray(pwm, dtype=float).ravel()
                out = np.empty(flat.size)
                table(flat, np.ascontiguousarray(v, dtype=float).ravel(), float(self.table_pwm[0]), self._step,
                      self.voltages, self.table_thrust, out)
                return out.reshape(pwm.shape)
        u = (pwm - self.table_pwm[0]) / self._step
        i = np.minimum(u.astype(np.intp), self.table_pwm.size - 2)
        t = u - i
        j = np.clip(np.searchsorted(self.voltages, v, side="right") - 1, 0, self.voltages.size - 2)
        w = (v - self.voltages[j]) / (self.voltages[j + 1] - self.voltages[j])
        T = self.table_thrust
        lo = T[j, i] * (1.0 - t) + T[j, i + 1] * t
        hi = T[j + 1, i] * (1.0 - t) + T[j + 1, i + 1] * t
        return lo * (1.0 - w) + hi * w

    def _thrust(self, pwm):  # used by max_forward / max_reverse (nominal voltage)
        return self.thrust(pwm)

    def pwm(self, thrust, voltage=None) -> np.ndarray:
        """Inverse at one voltage (default nominal): needs that sheet to be monotone."""
        v = self.nominal_voltage if voltage is None else float(voltage)
        return self.at_voltage(v).pwm(thrust)

    def at_voltage(self, voltage: float) -> TabulatedThrustCurve:
        """The fixed-voltage curve at ``voltage`` V (a :class:`TabulatedThrustCurve`);
        raises VehicleError when the interpolated sheet is not monotone there."""
        v = float(voltage)
        if not self.voltages[0] <= v <= self.voltages[-1]:
            raise SimulationError(f"thrust curve {self.name!r}: voltage {v:g} V outside "
                                  f"{self.voltages[0]:g}..{self.voltages[-1]:g} V")
        return TabulatedThrustCurve(self.table_pwm, self._sheet(v), name=f"{self.name}@{v:g}V",
                                    source=f"thrust curve {self.name!r} at {v:g} V")

    # -- identity -----------------------------------------------------------------------
    def to_mapping(self) -> dict:
        return {"voltage_table": self.name, "nominal_voltage": self.nominal_voltage}

    def _key(self):
        return (self.name, tuple(self.voltages.tolist()), self.table_thrust.tobytes(), self.nominal_voltage)

    def __repr__(self) -> str:
        return (f"VoltageThrustCurve(name={self.name!r}, voltages={self.voltages.tolist()} V, "
                f"nominal={self.nominal_voltage:g} V, pwm=[{self.pwm_min:g}..{self.pwm_max:g}] us)")


@functools.lru_cache(maxsize=None)
def _family_table(name: str):
    import pandas as pd  # local import, as in uvsim.thrust_curves

    root = FAMILIES[name]
    sheets = []
    for path in sorted(root.glob(f"{name}_*v.csv")):
        df = pd.read_csv(path)
        missing = [c for c in ("pwm_us", "voltage_v", "thrust_kgf") if c not in df.columns]
        if missing:
            raise VehicleError(f"thrust table {path}: missing column(s) {missing}")
        volt = np.unique(df["voltage_v"].to_numpy(float))
        if volt.size != 1:
            raise VehicleError(f"thrust table {path}: voltage_v must be one value, got {volt.tolist()}")
        sheets.append((float(volt[0]), df["pwm_us"].to_numpy(float), df["thrust_kgf"].to_numpy(float) * KGF_TO_N))
    sheets.sort(key=lambda s: s[0])
    pwm = sheets[0][1]
    for v, p, _ in sheets:
        if p.shape != pwm.shape or np.any(p != pwm):
            raise VehicleError(f"thrust table {name} at {v:g} V: PWM grid differs from the {sheets[0][0]:g} V sheet")
    return pwm, np.array([s[0] for s in sheets]), np.array([s[2] for s in sheets])


def load_voltage_curve(spec, *, field: str = "curve") -> VoltageThrustCurve:
    """``{"voltage_table": "t200", "nominal_voltage": 16.0}`` -> :class:`VoltageThrustCurve`.

    ``nominal_voltage`` (V) defaults to 16 V, the voltage of the ``t200_16v`` default curve."""
    unknown = sorted(set(spec) - {"voltage_table", "nominal_voltage", "type"})
    if unknown:
        raise VehicleError(f"{field}: unknown key(s) {unknown}; allowed: nominal_voltage, voltage_table")
    name = spec["voltage_table"]
    if name not in FAMILIES:
        raise VehicleError(f"{field}.voltage_table: unknown voltage-dependent table {name!r}; "
                           f"shipped: {sorted(FAMILIES)}")
    nominal = spec.get("nominal_voltage", 16.0)
    try:
        nominal = float(nominal)
    except (TypeError, ValueError):
        raise VehicleError(f"{field}.nominal_voltage: expected a number of volts, got {nominal!r}") from None
    pwm, volts, T = _family_table(name)
    return VoltageThrustCurve(pwm, volts, T, nominal_voltage=nominal, name=name, source=field)


def measured_voltage_range() -> tuple[float, float]:
    """The supply voltages (V) every shipped family was measured between (T200: 10-20 V):
    the physical range of a fitted ``supply_voltage`` (:mod:`uvsim.forces.actuators`)."""
    ranges = [_family_table(name)[1] for name in FAMILIES]
    return max(float(v[0]) for v in ranges), min(float(v[-1]) for v in ranges)


def family_path(name: str) -> Path:
    """Directory holding the sheets of the shipped family ``name``."""
    return FAMILIES[name]
