"""The vehicle file's ``thrusters`` section: read, checked and written back.

:func:`thruster_arguments` turns a section with ``units`` (each thruster's position,
direction, curve, gain and reverse ratio) or a ``configuration_matrix`` into the arguments
of :class:`uvsim.forces.actuators.Actuators` (the allocation matrix of
:func:`allocation_matrix`, the thrust curves, the names and the per-unit and per-DOF
factors), refusing what no vehicle means; :func:`force_factors` reads the per-DOF factors of
a vehicle driven by generalized forces.  :func:`section_with_values` writes fitted actuator
parameters back into a copy of the section, in the file's own form (a unit that pushes the
wrong way is written with its direction reversed).  :func:`uvsim.forces.actuators.build_actuators`
builds the term from the section with these.
"""
from __future__ import annotations

import copy

import numpy as np

from uvsim.errors import VehicleError
from uvsim.schema import check_keys


def allocation_matrix(positions, directions) -> np.ndarray:
    """``B`` (6, n) from positions (n, 3) and directions (n, 3) (normalized here)."""
    P = np.asarray(positions, float)
    D = np.asarray(directions, float)
    D = D / np.linalg.norm(D, axis=1, keepdims=True)
    return np.vstack([D.T, np.cross(P, D).T])


DOF_LETTERS = "XYZKMN"
#: A thruster direction's length may differ from 1 by this much (directions written to 4
#: digits, e.g. 0.7071); beyond it the file is refused rather than normalised in silence, since
#: the export writes the file's direction as given.
DIRECTION_NORM_TOL = 1e-3
#: Accepted range of a gain or reverse ratio in a vehicle file: 0 (a dead unit, or no reverse
#: thrust) to 2 (a thruster delivering more than twice its measured curve is a unit error, not
#: a calibration). A unit that pushes the wrong way is written with its direction reversed.
FACTOR_RANGE = (0.0, 2.0)


def _factor(val, where: str) -> float:
    try:
        v = float(val)
    except (TypeError, ValueError):
        raise VehicleError(f"{where}: expected a number, got {val!r}") from None
    lo, hi = FACTOR_RANGE
    if not (np.isfinite(v) and lo <= v <= hi):
        raise VehicleError(f"{where} = {val!r}: expected a factor in [{lo:g}, {hi:g}] (1 = as the thrust curve, 0 = "
                           "no thrust; a unit that pushes the wrong way: reverse its direction)")
    return v


def _per_dof(spec, where: str) -> np.ndarray:
    out = np.ones(6)
    if spec is None:
        return out
    if not isinstance(spec, dict):
        raise VehicleError(f"{where}: expected a mapping of DOF letters X, Y, Z, K, M, N to factors")
    for k, v in spec.items():
        if k not in DOF_LETTERS or len(k) != 1:
            raise VehicleError(f"{where}.{k}: unknown degree of freedom; expected one of X, Y, Z, K, M, N")
        out[DOF_LETTERS.index(k)] = _factor(v, f"{where}.{k}")
    return out


#: Keys of a vehicle file's ``thrusters`` section (without ``type``) and of each unit.
THRUSTERS_KEYS = ("curve", "units", "configuration_matrix", "names", "gains", "reverse_ratios", "force_gain",
                  "force_reverse_ratio")
UNIT_KEYS = ("name", "position", "direction", "curve", "gain", "reverse_ratio")


def force_factors(spec: dict, where: str) -> tuple[np.ndarray, np.ndarray]:
    """The per-DOF factors ``(force_gain, force_reverse)`` (6,) of a ``thrusters`` section
    (``force_gain`` and ``force_reverse_ratio``, each DOF 1 unless given)."""
    return (_per_dof(spec.get("force_gain"), f"{where}: thrusters.force_gain"),
            _per_dof(spec.get("force_reverse_ratio"), f"{where}: thrusters.force_reverse_ratio"))


def thruster_arguments(spec, where: str) -> dict:
    """The :class:`~uvsim.forces.actuators.Actuators` keyword arguments (``matrix``,
    ``curves``, ``names``, ``positions``, ``directions``, ``gains``, ``reverse``,
    ``force_gain``, ``force_reverse``) of a ``thrusters`` section with ``units`` or a
    ``configuration_matrix``, checked (a :class:`~uvsim.errors.VehicleError` naming the field
    for what no vehicle means)."""
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
        P, D, names, curves, gains, rev = [], [], [], [], [], []
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
            if abs(np.linalg.norm(d) - 1.0) > DIRECTION_NORM_TOL:
                hint = "" if np.linalg.norm(d) < 1e-9 else f": write {np.round(d / np.linalg.norm(d), 4).tolist()}"
                raise VehicleError(f"{where}: {field}.direction: {list(map(float, d))} has length "
                                   f"{np.linalg.norm(d):.4g}; expected a unit vector (length 1 within "
                                   f"{DIRECTION_NORM_TOL:g}){hint}")
            P.append(unit["position"])
            D.append(d)
            names.append(str(unit.get("name", f"T{i + 1}")))
            curves.append(curve_for(unit.get("curve", default_curve), f"{field}.curve"))
            gains.append(_factor(unit.get("gain", 1.0), f"{where}: {field}.gain"))
            rev.append(_factor(unit.get("reverse_ratio", 1.0), f"{where}: {field}.reverse_ratio"))
        B = allocation_matrix(P, D)
        positions = np.asarray(P, float)
        directions = np.asarray(D, float)
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
        positions = directions = None
        gains = [_factor(g, f"{where}: thrusters.gains[{i}]") for i, g in enumerate(spec.get("gains", [1.0] * n))]
        rev = [_factor(g, f"{where}: thrusters.reverse_ratios[{i}]")
               for i, g in enumerate(spec.get("reverse_ratios", [1.0] * n))]
        if len(gains) != n or len(rev) != n:
            raise VehicleError(f"{where}: thrusters.gains / reverse_ratios: expected {n} values each")
    else:
        raise VehicleError(f"{where}: thrusters: expected 'units' or 'configuration_matrix'")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:  # every message, input column and report names a thruster by its name
        raise VehicleError(f"{where}: thrusters: name(s) {twice} given to more than one thruster; expected one name "
                           "per thruster")
    if np.linalg.matrix_rank(B) == 0:
        raise VehicleError(f"{where}: thrusters: allocation matrix is zero")
    if all(c is None for c in curves):
        curves = None
    elif any(c is None for c in curves):
        raise VehicleError(f"{where}: thrusters: either every thruster has a curve or none does")
    force_gain, force_reverse = force_factors(spec, where)
    return {"matrix": B, "curves": curves, "names": names, "positions": positions, "directions": directions,
            "gains": gains, "reverse": rev, "force_gain": force_gain, "force_reverse": force_reverse}


def section_with_values(spec, values: dict, n: int, gains, reverse) -> dict:
    """A copy of the ``thrusters`` section ``spec`` (not a mapping: an empty one) with the
    actuator parameters ``values`` (names of :meth:`uvsim.forces.actuators.Actuators.parameters`)
    written in the section's own form: into its ``units``, a negative ``thruster_gain_i`` (a
    unit pushing the wrong way) as the gain's size with the direction reversed; without units
    into ``gains`` / ``reverse_ratios`` lists for the ``n`` thrusters (the others' values from
    ``gains`` / ``reverse``; a reversed unit's matrix column negated); per-DOF factors into
    ``force_gain`` / ``force_reverse_ratio``; ``supply_voltage`` as the voltage-dependent
    curves' ``nominal_voltage``."""
    spec = copy.deepcopy(spec) if isinstance(spec, dict) else {}
    units = spec.get("units")
    for i in range(n):
        if units is None:
            continue
        u = units[i]
        if f"thruster_gain_{i + 1}" in values:
            g = values[f"thruster_gain_{i + 1}"]
            if g < 0:  # pushes the wrong way (diagnosis' reversed unit): the same thrust, direction reversed
                u["direction"] = [-float(x) for x in u["direction"]]
            u["gain"] = abs(g)
        if f"thruster_reverse_{i + 1}" in values:
            u["reverse_ratio"] = values[f"thruster_reverse_{i + 1}"]
        for a, c in enumerate("xyz"):
            key = f"thruster_{c}_{i + 1}"
            if key in values:
                pos = [float(x) for x in u["position"]]
                pos[a] = values[key]
                u["position"] = pos
    for tag, field in (("gain", "force_gain"), ("reverse", "force_reverse_ratio")):
        for c in DOF_LETTERS:
            key = f"force_{tag}_{c}"
            if key in values:
                spec.setdefault(field, {})[c] = values[key]
    if "supply_voltage" in values:  # every voltage-dependent curve is read at the fitted supply
        for d in [spec] + list(units or []):
            if isinstance(d.get("curve"), dict) and "voltage_table" in d["curve"]:
                d["curve"] = {**d["curve"], "nominal_voltage": values["supply_voltage"]}
    if units is None and any(k.startswith("thruster_") for k in values):
        # a configuration matrix without units: keep gains / ratios in lists
        g = [values.get(f"thruster_gain_{i + 1}", float(gains[i])) for i in range(n)]
        r = [values.get(f"thruster_reverse_{i + 1}", float(reverse[i])) for i in range(n)]
        if any(x < 0 for x in g) and "configuration_matrix" in spec:  # a reversed unit: its column negated
            B = np.asarray(spec["configuration_matrix"], float) * np.where(np.asarray(g) < 0, -1.0, 1.0)
            spec["configuration_matrix"] = B.tolist()
        spec["gains"], spec["reverse_ratios"] = [abs(x) for x in g], r
    return spec
