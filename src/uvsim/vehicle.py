"""Vehicles are data: YAML files with every number's source beside it.

``load_vehicle("bluerov2_heavy")`` reads ``src/uvsim/vehicles/bluerov2_heavy.yaml``;
``load_vehicle("path/to/file.yaml")`` reads any file.  Loading validates the file
against the declarative schema of :mod:`uvsim.vehicle_schema` (``src/uvsim/vehicle_schema.py``:
every section's fields, finite numbers, positive mass and inertia, the physical rules,
positive-definite ``M = M_RB + M_A``; the plug-in sections by their builders: known
thruster curves and term types) and every error names the file and field.  This module
builds the :class:`Vehicle` from the validated sections; the table of fields is in
docs/model.md ("Vehicle file fields").

File layout (see ``src/uvsim/vehicles/bluerov2_heavy.yaml`` for a commented example)::

    name: ...
    environment: {g: 9.81, rho: 1000.0, current_ned: [0, 0, 0]}
    rigid_body:
      mass: 13.17                  # kg
      buoyancy: 132.537            # N
      r_g: [0, 0, 0]               # m, body frame
      r_b: [0, 0, -0.024]          # m
      inertia: {I_xx: .., I_yy: .., I_zz: .., I_xy: 0, I_xz: 0, I_yz: 0}   # tensor I_b = [[Ixx,-Ixy,-Ixz],...]
    added_mass: {X_udot: .., ..., N_rdot: ..}  # positive magnitudes: M_A = diag(...)
                                               # (optional `matrix:` full symmetric 6x6, positive convention)
    damping: {type: diagonal, linear: {X_u: ..}, quadratic: {X_uu: ..}}       # paper sign
    thrusters: {curve: t200_16v, units: [...]}
    effects: [{type: tether, ...}]              # optional extra force terms

Named parameters (used by calibration and overrides): ``m, B, x_g, y_g, z_g, x_b,
y_b, z_b, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz, X_udot ... N_rdot, current_n,
current_e, current_d`` plus those of the damping model and effects.
"""
from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import yaml

from uvsim.constants import G
from uvsim.errors import VehicleError
from uvsim.files import load_yaml
from uvsim.forces import ForceTerm, make_term
from uvsim.forces.actuators import Actuators, build_actuators
from uvsim.rigid_body import inertia_tensor, rigid_body_mass_matrix
from uvsim.schema import did_you_mean
from uvsim.vehicle_schema import (  # noqa: F401  (limits re-exported for the modules importing them here)
    ADDED_MASS_NAMES, ENVIRONMENT, IMU_BIAS_SPECS, INERTIA_NAMES, MAX_LATENCY, MAX_SENSOR_OFFSET, RIGID_BODY,
    SENSOR, SENSOR_NAMES, VEHICLE, added_mass_matrix, check_latency, validate_built_vehicle, validate_vehicle_dict)

RIGID_NAMES = ("m", "B", "x_g", "y_g", "z_g", "x_b", "y_b", "z_b") + INERTIA_NAMES
CURRENT_NAMES = ("current_n", "current_e", "current_d")
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
#: The keys a vehicle file's sections accept (:mod:`uvsim.vehicle_schema`, in the order the messages list
#: them); free-form metadata goes under ``meta`` (docs/contracts.md).
VEHICLE_KEYS = tuple(VEHICLE.fields)
ENVIRONMENT_KEYS = tuple(ENVIRONMENT.fields)
RIGID_BODY_KEYS = tuple(RIGID_BODY.fields)
SENSOR_KEYS = tuple(SENSOR.fields)


@dataclass
class Vehicle:
    """A vehicle definition (parameters only; no state, no integrator)."""

    name: str
    mass: float
    buoyancy: float
    r_g: np.ndarray
    r_b: np.ndarray
    inertia: dict[str, float]
    added_mass_matrix: np.ndarray
    damping: ForceTerm
    actuators: Actuators
    effects: list[ForceTerm] = field(default_factory=list)
    g: float = G
    rho: float = 1000.0
    current_ned: np.ndarray = field(default_factory=lambda: np.zeros(3))
    #: sensor name -> position (3,) on the body, m (``sensors:`` section, :data:`SENSOR_NAMES`)
    sensors: dict = field(default_factory=dict)
    #: parameter name -> 1-sigma uncertainty of the file's value, in the parameter's units
    #: (``uncertainty:`` section): the prior width of a calibration (:mod:`uvsim.fitting.priors`)
    uncertainty: dict = field(default_factory=dict)
    #: the IMU gyro's in-run bias, 1-sigma per axis, rad/s (``sensors.imu.gyro_bias_sd``): the prior
    #: of the gyro bias a fit estimates per run; None: :data:`uvsim.fitting.objective.GYRO_BIAS_SIGMA`
    gyro_bias_sd: float | None = None
    #: the IMU accelerometer's offset, 1-sigma per axis, m/s^2 (``sensors.imu.acc_bias_sd``): the
    #: prior of the offset a fit estimates per run; None: :data:`uvsim.fitting.objective.ACC_BIAS_SIGMA`
    acc_bias_sd: float | None = None
    #: how late every logged sensor reads relative to the logged inputs, s (``sensors.latency``;
    #: docs/model.md, "Sensor latency"): a prediction applies each input this much later than its
    #: time stamp (:mod:`uvsim.latency`)
    sensor_latency: float = 0.0
    #: declared 1-sigma noise levels, channel or group -> level in the channel's unit
    #: (``sensors.noise``; docs/model.md, "Sensor noise"): used instead of the level estimated from
    #: a log (:func:`uvsim.signals.noise_level`)
    sensor_noise: dict = field(default_factory=dict)
    description: str = ""
    source: str = "<memory>"
    raw: dict = field(default_factory=dict, repr=False)

    # -- derived quantities ---------------------------------------------------
    @property
    def weight(self) -> float:
        return self.mass * self.g

    @property
    def inertia_matrix(self) -> np.ndarray:
        i = self.inertia
        return inertia_tensor(i["I_xx"], i["I_yy"], i["I_zz"], i.get("I_xy", 0.0), i.get("I_xz", 0.0), i.get("I_yz", 0.0))

    @property
    def M_RB(self) -> np.ndarray:
        return rigid_body_mass_matrix(self.mass, self.inertia_matrix, self.r_g)

    @property
    def M_A(self) -> np.ndarray:
        return self.added_mass_matrix.copy()

    @property
    def M(self) -> np.ndarray:
        return self.M_RB + self.M_A

    @property
    def n_thrusters(self) -> int:
        return self.actuators.n_thrusters

    @property
    def terms(self) -> list[ForceTerm]:
        from uvsim.forces.restoring import Restoring

        return [Restoring(), self.damping, self.actuators, *self.effects]

    def parameters(self) -> dict[str, float]:
        """All named scalar parameters and their values."""
        p = {"m": self.mass, "B": self.buoyancy}
        p.update(dict(zip(("x_g", "y_g", "z_g"), map(float, self.r_g))))
        p.update(dict(zip(("x_b", "y_b", "z_b"), map(float, self.r_b))))
        for k in INERTIA_NAMES:
            p[k] = float(self.inertia.get(k, 0.0))
        for i, k in enumerate(ADDED_MASS_NAMES):
            p[k] = float(self.added_mass_matrix[i, i])
        p.update(dict(zip(CURRENT_NAMES, map(float, self.current_ned))))
        p.update(self.actuators.parameters())
        for term in [self.damping, *self.effects]:
            p.update(term.parameters())
        return p

    def with_parameters(self, values: Mapping[str, float], *, name: str | None = None) -> "Vehicle":
        """A new vehicle with some named parameters replaced (validated)."""
        known = self.parameters()
        unknown = set(values) - set(known)
        if unknown:
            raise VehicleError(f"{self.source}: unknown parameter(s) {sorted(unknown)}")
        d = self.to_dict()
        v = {k: float(x) for k, x in values.items()}
        rb = d["rigid_body"]
        if "m" in v:
            rb["mass"] = v["m"]
        if "B" in v:
            rb["buoyancy"] = v["B"]
        for i, k in enumerate(("x_g", "y_g", "z_g")):
            if k in v:
                rb["r_g"][i] = v[k]
        for i, k in enumerate(("x_b", "y_b", "z_b")):
            if k in v:
                rb["r_b"][i] = v[k]
        for k in INERTIA_NAMES:
            if k in v:
                rb["inertia"][k] = v[k]
        am = np.asarray(d["added_mass"]["matrix"], float)
        for i, k in enumerate(ADDED_MASS_NAMES):
            if k in v:
                am[i, i] = v[k]
        d["added_mass"]["matrix"] = am.tolist()
        cur = d["environment"]["current_ned"]
        for i, k in enumerate(CURRENT_NAMES):
            if k in v:
                cur[i] = v[k]
        damping = self.damping.with_parameters(v) if set(v) & set(self.damping.parameters()) else self.damping
        effects = [e.with_parameters(v) if set(v) & set(e.parameters()) else e for e in self.effects]
        d["damping"] = damping.to_dict()
        d["effects"] = [e.to_dict() for e in effects]
        actuators = self.actuators
        if set(v) & set(actuators.parameters()):
            actuators = actuators.with_parameters(v)
            d["thrusters"] = actuators.specs
        if name:
            d["name"] = name
        return vehicle_from_dict(d, source=self.source, actuators=actuators)

    def with_latency(self, latency: float) -> "Vehicle":
        """A copy whose sensors read ``latency`` s late (``sensors.latency``, :mod:`uvsim.latency`)."""
        new = copy.copy(self)
        new.sensor_latency = check_latency(latency, f"{self.source}: sensors.latency")
        return new

    def with_effects(self, effects: list) -> "Vehicle":
        """A copy with extra force terms appended (dicts or ``ForceTerm`` objects)."""
        new = copy.copy(self)
        new.effects = [*self.effects, *[make_term(e) for e in effects]]
        return new

    def to_dict(self) -> dict:
        """Vehicle-file dictionary (numbers only; comments with sources live in the
        shipped YAML files, and :func:`save_vehicle` writes provenance notes)."""
        d = {
            "name": self.name,
            "description": self.description,
            "environment": {"g": self.g, "rho": self.rho, "current_ned": [float(x) for x in self.current_ned]},
            "rigid_body": {
                "mass": float(self.mass),
                "buoyancy": float(self.buoyancy),
                "r_g": [float(x) for x in self.r_g],
                "r_b": [float(x) for x in self.r_b],
                "inertia": {k: float(self.inertia.get(k, 0.0)) for k in INERTIA_NAMES},
            },
            "added_mass": {"matrix": self.added_mass_matrix.tolist()},
            "damping": self.damping.to_dict(),
            "effects": [e.to_dict() for e in self.effects],
        }
        if self.sensors:
            d["sensors"] = {k: {"position": [float(x) for x in p]} for k, p in self.sensors.items()}
        for key in IMU_BIAS_SPECS:
            if getattr(self, key) is not None:
                d.setdefault("sensors", {}).setdefault("imu", {})[key] = float(getattr(self, key))
        if self.sensor_latency:
            d.setdefault("sensors", {})["latency"] = float(self.sensor_latency)
        if self.sensor_noise:
            d.setdefault("sensors", {})["noise"] = {k: float(x) for k, x in self.sensor_noise.items()}
        if self.uncertainty:
            d["uncertainty"] = {k: float(x) for k, x in self.uncertainty.items()}
        if self.raw.get("thrusters") is not None:
            d["thrusters"] = copy.deepcopy(self.raw["thrusters"])
        if self.raw.get("sources"):
            d["sources"] = copy.deepcopy(self.raw["sources"])
        return d

    def summary(self) -> dict:
        """The numbers ``uvsim vehicle show --json`` prints."""
        DL, DQ = damping_diagonals(self.damping)
        return {
            "name": self.name,
            "source": self.source,
            "mass": self.mass,
            "weight": self.weight,
            "buoyancy": self.buoyancy,
            "r_g": [float(x) for x in self.r_g],
            "r_b": [float(x) for x in self.r_b],
            "inertia": self.inertia_matrix.tolist(),
            "added_mass": self.added_mass_matrix.tolist(),
            "linear_damping": DL,
            "quadratic_damping": DQ,
            "n_thrusters": self.n_thrusters,
            "effects": [e.kind for e in self.effects],
            "sensor_latency_s": float(self.sensor_latency),
        }


#: Sign rules of the rigid-body and added-mass parameters (the loader's, for overrides):
#: name -> (strictly positive?, what the vehicle file calls it).
_SIGN_RULES = {"m": (True, "rigid_body.mass (kg)"), "B": (False, "rigid_body.buoyancy (N)"),
               **{k: (True, f"rigid_body.inertia.{k} (kg m^2)") for k in INERTIA_NAMES[:3]},
               **{k: (False, f"added_mass.{k} (a positive magnitude)") for k in ADDED_MASS_NAMES}}


def check_parameter_values(values: Mapping[str, Any], terms=()) -> None:
    """Apply the vehicle-file rules to named parameter values given as overrides.

    Parameters
    ----------
    values : name -> float or array (one entry per parameter set).
    terms : the force terms whose parameters may be among ``values``
        (:meth:`uvsim.forces.base.ForceTerm.check_values`).

    Raises
    ------
    VehicleError
        Naming the parameter, the value (and parameter set) and the rule, e.g. a
        positive damping coefficient or a negative added mass.
    """
    from uvsim.forces.base import first_violation

    for k, v in values.items():
        if k in _SIGN_RULES:
            strict, field_name = _SIGN_RULES[k]
            a = np.asarray(v, float)
            bad = first_violation(a, a > 0 if strict else a >= 0, k)
            if bad:
                raise VehicleError(f"parameter {bad}: expected a {'positive' if strict else 'non-negative'} "
                                   f"value, as for {field_name} in a vehicle file")
    for term in terms:
        term.check_values(values)


def damping_diagonals(term):
    from uvsim.forces.damping import LINEAR_NAMES, QUADRATIC_NAMES

    p = term.parameters()
    if all(k in p for k in LINEAR_NAMES):
        return [p[k] for k in LINEAR_NAMES], [p[k] for k in QUADRATIC_NAMES]
    if hasattr(term, "DL"):
        return np.diag(term.DL).tolist(), np.diag(term.DQ).tolist()
    return None, None


# ----------------------------------------------------------------------------- loading
def builtin_vehicles() -> list[str]:
    """Names of the vehicle files shipped in ``uvsim/vehicles``."""
    root = resources.files("uvsim") / "vehicles"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".yaml"))


def vehicle_path(name_or_path: str | Path) -> Path:
    """Resolve a built-in vehicle name or a file path."""
    p = Path(name_or_path)
    if p.suffix in (".yaml", ".yml") or p.exists():
        if not p.exists():
            raise VehicleError(f"vehicle file {p} does not exist")
        return p
    cand = Path(str(resources.files("uvsim") / "vehicles" / f"{name_or_path}.yaml"))
    if not cand.exists():
        raise VehicleError(
            f"unknown vehicle {str(name_or_path)!r}{did_you_mean(name_or_path, builtin_vehicles())}: not a "
            f"file and not a built-in (built-ins: {', '.join(builtin_vehicles())})"
        )
    return cand


def load_vehicle(name_or_path: "str | Path | Vehicle") -> Vehicle:
    """Load and validate a vehicle by built-in name or file path."""
    if isinstance(name_or_path, Vehicle):
        return name_or_path
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise VehicleError(f"load_vehicle: expected a built-in vehicle name, a vehicle file's path or a Vehicle, "
                           f"got {type(name_or_path).__name__} {name_or_path!r}")
    path = vehicle_path(name_or_path)
    d = load_yaml(path, error=VehicleError, what="vehicle file (YAML)")
    if not isinstance(d, dict):
        raise VehicleError(f"{path}: expected a mapping at the top level")
    return vehicle_from_dict(d, source=str(path))


def vehicle_from_dict(d: dict, *, source: str = "<dict>", actuators: Actuators | None = None) -> Vehicle:
    """Build and validate a :class:`Vehicle` from a vehicle-file dictionary.

    Parameters
    ----------
    d : the vehicle file as read (layout and rules: :mod:`uvsim.vehicle_schema`).
    source : the file's name, named by every error.
    actuators : use these instead of building the ``thrusters`` section.

    Raises
    ------
    VehicleError
        Naming ``source``, the section and field, and what was expected.
    """
    f = source
    s = validate_vehicle_dict(d, f)
    env, rb, sensors = s["environment"], s["rigid_body"], s["sensors"]
    damping = make_term(s["damping"], context=f"{f}: damping")
    effects = [make_term(e, context=f"{f}: effects[{i}]") for i, e in enumerate(s["effects"])]
    if actuators is None:
        actuators = build_actuators(s.get("thrusters"), f)
    imu = sensors.get("imu", {})
    v = Vehicle(
        name=s["name"],
        mass=rb["mass"],
        buoyancy=rb["buoyancy"],
        r_g=rb["r_g"],
        r_b=rb["r_b"],
        inertia={k: rb["inertia"][k] for k in INERTIA_NAMES},
        added_mass_matrix=added_mass_matrix(s["added_mass"]),
        damping=damping,
        actuators=actuators,
        effects=effects,
        g=env["g"],
        rho=env["rho"],
        current_ned=env["current_ned"],
        sensors={k: e["position"] for k, e in sensors.items() if k in SENSOR_NAMES and "position" in e},
        gyro_bias_sd=imu.get("gyro_bias_sd"),
        acc_bias_sd=imu.get("acc_bias_sd"),
        sensor_latency=sensors["latency"],
        sensor_noise=dict(sensors.get("noise") or {}),
        description=s["description"],
        source=source,
        raw=d,
    )
    v.uncertainty = validate_built_vehicle(d, f, v)["uncertainty"]  # also checks M = M_RB + M_A
    return v


class _VehicleDumper(yaml.SafeDumper):
    """Block-style mappings (one parameter per line, so a comment can sit beside it) and
    flow-style lists of numbers (vectors, matrix rows)."""


def _represent_list(dumper, data):
    flow = all(not isinstance(x, (dict, list)) for x in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


_VehicleDumper.add_representer(list, _represent_list)


def save_vehicle(vehicle: Vehicle, path: str | Path, *, header: str = "", annotations: Mapping[str, str] | None = None) -> Path:
    """Write ``vehicle`` as YAML.  ``annotations`` maps a parameter name to a comment
    placed beside it (e.g. its previous value and uncertainty after a fit)."""
    path = Path(path)
    text = yaml.dump(vehicle.to_dict(), Dumper=_VehicleDumper, sort_keys=False, width=120)
    if annotations:
        lines = []
        for line in text.splitlines():
            key = line.strip().split(":", 1)[0]
            if key in annotations and ":" in line:
                line = f"{line}  # {annotations[key]}"
            lines.append(line)
        text = "\n".join(lines) + "\n"
    if header:
        text = "".join(f"# {h}\n" for h in header.splitlines()) + text
    path.write_text(text)
    return path
