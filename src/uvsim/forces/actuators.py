"""Actuators: thrusters with position and direction -> allocation (configuration) matrix.

For thruster ``i`` at body position ``r_i`` with unit thrust direction ``d_i`` the
column of the allocation matrix is ``[d_i; r_i x d_i]`` (Fossen 2021 eq. 11.6), so
``tau = B f`` for thrusts ``f`` (N).  A vehicle may instead give the matrix itself
(seed 002 eq. 9).  Inputs can be generalized forces (used as ``tau``), per-thruster
thrust (N) or per-thruster ESC PWM (us, mapped by each thruster's curve).
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import SimulationError, VehicleError
from uvsim.forces import register
from uvsim.forces.base import ForceTerm
from uvsim.schema import check_keys


def allocation_matrix(positions, directions) -> np.ndarray:
    """``B`` (6, n) from positions (n, 3) and directions (n, 3) (normalized here)."""
    P = np.asarray(positions, float)
    D = np.asarray(directions, float)
    D = D / np.linalg.norm(D, axis=1, keepdims=True)
    return np.vstack([D.T, np.cross(P, D).T])


@register("actuators")
class Actuators(ForceTerm):
    """Maps the run's inputs to ``tau``.

    Parameters
    ----------
    matrix : (6, n) allocation matrix.
    curves : list of n thrust curves (objects with ``thrust(pwm)``) or None.
    names : thruster names.
    """

    def __init__(self, matrix=None, curves=None, names=None, specs=None):
        self.matrix = None if matrix is None else np.asarray(matrix, float)
        self.curves = curves
        self.names = names
        self.specs = specs  # vehicle-file form, kept for to_dict

    @property
    def n_thrusters(self) -> int:
        return 0 if self.matrix is None else self.matrix.shape[1]

    def prepare(self, params, n):
        groups = []
        if self.curves:
            # group thrusters sharing a curve object so PWM mapping is one call per curve
            seen = {}
            for i, c in enumerate(self.curves):
                seen.setdefault(id(c), (c, []))[1].append(i)
            groups = [(c, np.array(idx)) for c, idx in seen.values()]
        # inputs are held over a sample interval, so the four RK4 stages see the same
        # array object: map PWM -> thrust once per interval (cache keyed on identity)
        return {"groups": groups, "u": None, "f": None}

    def thrusts(self, u, kind, groups):
        if kind == "thrust":
            return u
        if kind == "pwm":
            if not groups:
                raise SimulationError("inputs are PWM but the vehicle's thrusters have no thrust curves")
            f = np.empty_like(u)
            for curve, idx in groups:
                try:
                    f[:, idx] = curve.thrust(u[:, idx])
                except SimulationError as exc:
                    raise SimulationError(self._pwm_error(u, curve, idx, exc)) from None
            return f
        raise SimulationError(f"unknown input kind {kind!r}")

    def _pwm_error(self, u, curve, idx, exc) -> str:
        """Name the input column and thruster of a PWM outside ``curve``'s range."""
        sub = u[:, idx]
        bad = ~((sub >= curve.pwm_min) & (sub <= curve.pwm_max))
        if not bad.any():
            return str(exc)
        row, j = np.unravel_index(int(np.argmax(bad)), sub.shape)
        col = int(idx[j])
        name = self.names[col] if self.names else f"T{col + 1}"
        return (f"input column pwm_{col + 1} (thruster {name}): PWM {sub[row, j]:g} us is outside the range "
                f"{curve.pwm_min:g}..{curve.pwm_max:g} us of thrust curve {curve.name!r} (trajectory {row} of the "
                "batch); commands are never clipped. For a logged run, uvsim.plausibility.check_run names its file "
                "and row")

    def forces(self, ctx, prep):
        kind = ctx.input_kind
        u = ctx.u
        if kind == "force":
            return u
        if self.matrix is None:
            raise SimulationError(f"inputs are per-thruster {kind} but the vehicle defines no thrusters")
        if prep["u"] is u:
            return prep["f"]
        tau = self.thrusts(u, kind, prep["groups"]) @ self.matrix.T
        prep["u"], prep["f"] = u, tau
        return tau

    def check_inputs(self, kind: str, k: int, where: str = "inputs") -> None:
        if kind == "force":
            if k != 6:
                raise SimulationError(f"{where}: generalized-force inputs need 6 columns (X, Y, Z, K, M, N), got {k}")
            return
        if self.matrix is None:
            raise SimulationError(f"{where}: per-thruster {kind} inputs but the vehicle defines no thrusters")
        if k != self.n_thrusters:
            raise SimulationError(
                f"{where}: {k} {kind} columns but the vehicle has {self.n_thrusters} thrusters"
            )

    def to_dict(self):
        return {"type": "actuators"}


#: Keys of a vehicle file's ``thrusters`` section (without ``type``) and of each unit.
THRUSTERS_KEYS = ("curve", "units", "configuration_matrix", "names")
UNIT_KEYS = ("name", "position", "direction", "curve")


def build_actuators(spec, where: str) -> Actuators:
    """Build :class:`Actuators` from a vehicle file's ``thrusters`` section.

    Accepted forms::

        thrusters:
          curve: t200_16v              # default curve for every unit (optional)
          units:
            - {name: T1, position: [x, y, z], direction: [dx, dy, dz], curve: t200_16v}
        # or
        thrusters:
          configuration_matrix: [[...n...], ... 6 rows]
          names: [T1, ...]
          curve: t200_16v
    """
    if spec is None:
        return Actuators()
    if isinstance(spec, dict) and "type" in spec:
        # a registered Actuators subclass (e.g. SAM's command inputs, uvsim.sam.subsystems)
        from uvsim.forces import make_term

        term = make_term(spec, context=f"{where}: thrusters")
        if not isinstance(term, Actuators):
            raise VehicleError(f"{where}: thrusters.type {spec['type']!r} is not an actuator term")
        return term
    if not isinstance(spec, dict):
        raise VehicleError(f"{where}: thrusters: expected a mapping with 'units' or 'configuration_matrix'")
    check_keys(spec, THRUSTERS_KEYS, f"{where}: thrusters", error=VehicleError)
    default_curve = spec.get("curve")
    curve_cache: dict = {}

    def curve_for(c, field):
        if c is None:
            return None
        key = repr(c)
        if key not in curve_cache:
            from uvsim.thrusters import load_thrust_curve

            try:
                curve_cache[key] = load_thrust_curve(c)
            except VehicleError as exc:
                raise VehicleError(f"{where}: {field}: {exc}") from None
        return curve_cache[key]

    if "units" in spec:
        units = spec["units"]
        if not isinstance(units, list) or not units:
            raise VehicleError(f"{where}: thrusters.units: expected a non-empty list")
        P, D, names, curves = [], [], [], []
        for i, unit in enumerate(units):
            field = f"thrusters.units[{i}]"
            if not isinstance(unit, dict):
                raise VehicleError(f"{where}: {field}: expected a mapping {{name, position: [x, y, z], "
                                   f"direction: [dx, dy, dz]}}, got {unit!r}")
            check_keys(unit, UNIT_KEYS, f"{where}: {field}", error=VehicleError)
            for key in ("position", "direction"):
                val = unit.get(key)
                try:
                    arr = np.asarray(val, dtype=float) if val is not None else None
                except (TypeError, ValueError):
                    arr = None
                if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
                    raise VehicleError(f"{where}: {field}.{key}: expected 3 finite numbers, got {val!r}")
            d = np.asarray(unit["direction"], float)
            if np.linalg.norm(d) < 1e-9:
                raise VehicleError(f"{where}: {field}.direction: must not be the zero vector")
            P.append(unit["position"])
            D.append(d)
            names.append(str(unit.get("name", f"T{i + 1}")))
            curves.append(curve_for(unit.get("curve", default_curve), f"{field}.curve"))
        B = allocation_matrix(P, D)
    elif "configuration_matrix" in spec:
        try:
            B = np.asarray(spec["configuration_matrix"], dtype=float)
        except (TypeError, ValueError):
            B = np.zeros(0)
        if B.ndim != 2 or B.shape[0] != 6 or not np.all(np.isfinite(B)):
            raise VehicleError(f"{where}: thrusters.configuration_matrix: expected 6 rows of finite numbers")
        n = B.shape[1]
        names = [str(s) for s in spec.get("names", [f"T{i + 1}" for i in range(n)])]
        if len(names) != n:
            raise VehicleError(f"{where}: thrusters.names: {len(names)} names for {n} matrix columns")
        curves = [curve_for(default_curve, "thrusters.curve")] * n
    else:
        raise VehicleError(f"{where}: thrusters: expected 'units' or 'configuration_matrix'")
    if np.linalg.matrix_rank(B) == 0:
        raise VehicleError(f"{where}: thrusters: allocation matrix is zero")
    if all(c is None for c in curves):
        curves = None
    elif any(c is None for c in curves):
        raise VehicleError(f"{where}: thrusters: either every thruster has a curve or none does")
    return Actuators(B, curves, names, spec)
