"""Vehicles are data: YAML files with every number's source beside it.

``load_vehicle("bluerov2_heavy")`` reads ``src/uvsim/vehicles/bluerov2_heavy.yaml``;
``load_vehicle("path/to/file.yaml")`` reads any file.  Loading validates the file
(finite numbers, positive mass and inertia, positive-definite ``M = M_RB + M_A``,
known thruster curves and term types) and every error names the file and field.

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
from uvsim.rigid_body import rigid_body_mass_matrix
from uvsim.schema import check_keys, did_you_mean, require_mapping, unknown_key_message

ADDED_MASS_NAMES = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")
INERTIA_NAMES = ("I_xx", "I_yy", "I_zz", "I_xy", "I_xz", "I_yz")
RIGID_NAMES = ("m", "B", "x_g", "y_g", "z_g", "x_b", "y_b", "z_b") + INERTIA_NAMES
CURRENT_NAMES = ("current_n", "current_e", "current_d")
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")

#: Keys a vehicle file may have at the top level; free-form metadata goes under ``meta``
#: (docs/contracts.md).  The plug-in sections (``damping``, ``thrusters`` with a ``type``,
#: each ``effects`` entry) are checked by their plug-in classes.
VEHICLE_KEYS = ("name", "description", "sources", "meta", "environment", "rigid_body", "added_mass",
                "damping", "thrusters", "effects", "sensors", "uncertainty")
ENVIRONMENT_KEYS = ("g", "rho", "current_ned")
RIGID_BODY_KEYS = ("mass", "buoyancy", "r_g", "r_b", "inertia")
SENSOR_KEYS = ("position", "source", "gyro_bias_sd", "acc_bias_sd")
#: the IMU's bias specs: key -> (unit, largest plausible value (exclusive), what it is)
IMU_BIAS_SPECS = {"gyro_bias_sd": ("rad/s", 1.0, "a MEMS gyro's in-run bias (0.001-0.05 rad/s)"),
                  "acc_bias_sd": ("m/s^2", 2.0, "a MEMS accelerometer's offset (0.01-0.8 m/s^2)")}


def inertia_tensor(Ixx, Iyy, Izz, Ixy=0.0, Ixz=0.0, Iyz=0.0) -> np.ndarray:
    """Inertia tensor about the body origin with Fossen's product-of-inertia signs
    (Fossen 2021 eq. 3.34), broadcasting over array arguments -> (..., 3, 3)."""
    arrs = np.broadcast_arrays(*[np.asarray(a, float) for a in (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)])
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = arrs
    Ixy, Ixz, Iyz = Ixy + 0.0, Ixz + 0.0, Iyz + 0.0
    row0 = np.stack([Ixx, 0.0 - Ixy, 0.0 - Ixz], -1)
    row1 = np.stack([0.0 - Ixy, Iyy, 0.0 - Iyz], -1)
    row2 = np.stack([0.0 - Ixz, 0.0 - Iyz, Izz], -1)
    return np.stack([row0, row1, row2], -2)


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
    path = vehicle_path(name_or_path)
    d = load_yaml(path, error=VehicleError, what="vehicle file (YAML)")
    if not isinstance(d, dict):
        raise VehicleError(f"{path}: expected a mapping at the top level")
    return vehicle_from_dict(d, source=str(path))


def _num(d: Mapping, key: str, where: str, *, positive=False, nonneg=False, default: Any = None) -> float:
    if key not in d or d[key] is None:
        if default is not None:
            return float(default)
        raise VehicleError(f"{where}.{key}: missing (expected a number)")
    if isinstance(d[key], bool):
        raise VehicleError(f"{where}.{key}: expected a number, got {d[key]!r}")
    try:
        v = float(d[key])
    except (TypeError, ValueError):
        raise VehicleError(f"{where}.{key}: expected a number, got {d[key]!r}") from None
    if not np.isfinite(v):
        raise VehicleError(f"{where}.{key}: expected a finite number, got {v}")
    if positive and v <= 0:
        raise VehicleError(f"{where}.{key}: expected a positive number, got {v}")
    if nonneg and v < 0:
        raise VehicleError(f"{where}.{key}: expected a non-negative number, got {v}")
    return v


def _vec3(d: Mapping, key: str, where: str, default=None) -> np.ndarray:
    val = d.get(key, default)
    try:
        a = np.asarray(val, dtype=float)
    except (TypeError, ValueError):
        raise VehicleError(f"{where}.{key}: expected 3 numbers, got {val!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise VehicleError(f"{where}.{key}: expected 3 finite numbers, got {val!r}")
    return a


#: Sensors whose position on the body enters a measurement model (docs/log_format.md):
#: ``imu`` (the accelerometer: specific force at that point), ``pressure`` (the ``depth``
#: column is the depth of that point), ``dvl`` (``u, v, w`` are the velocity of that point).
SENSOR_NAMES = ("imu", "pressure", "dvl")
#: Largest sensor offset from the body origin accepted, m (a sensor is on the vehicle).
MAX_SENSOR_OFFSET = 10.0


#: Largest ``sensors.latency`` accepted, s: an autopilot's sensor and telemetry path is tens of
#: milliseconds (ArduSub logs); half a second is a clock error, not a latency.
MAX_LATENCY = 0.5


def check_latency(value, where: str) -> float:
    """A sensor latency in s, validated (0 <= latency <= :data:`MAX_LATENCY`)."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise VehicleError(f"{where}: expected a latency in s (a number), got {value!r}") from None
    if not (np.isfinite(x) and 0.0 <= x <= MAX_LATENCY):
        raise VehicleError(f"{where} = {value!r}: expected 0 <= latency <= {MAX_LATENCY:g} s "
                           "(how late the sensors read relative to the logged inputs)")
    return x


def _sensors(spec, f: str) -> tuple[dict, dict, float]:
    """``sensors:`` section -> ({name: position (3,)}, the imu's bias specs {key of
    :data:`IMU_BIAS_SPECS`: value}, ``latency`` (s, 0 when not given)); validated."""
    if spec is None:
        return {}, {}, 0.0
    if not isinstance(spec, dict):
        raise VehicleError(f"{f}: sensors: expected a mapping such as {{pressure: {{position: [x, y, z]}}}}")
    out, bias_sd = {}, {}
    latency = check_latency(spec["latency"], f"{f}: sensors.latency") if "latency" in spec else 0.0
    for name, val in spec.items():
        if name == "latency":
            continue
        if name not in SENSOR_NAMES:
            raise VehicleError(unknown_key_message(f"{f}: sensors", name, SENSOR_NAMES + ("latency",), noun="sensor"))
        if not isinstance(val, dict):
            raise VehicleError(f"{f}: sensors.{name}: expected a mapping {{position: [x, y, z]}} "
                               "(m, body frame; optional source)")
        check_keys(val, SENSOR_KEYS, f"{f}: sensors.{name}", error=VehicleError)
        for key, (unit, top, what) in IMU_BIAS_SPECS.items():
            if key in val and name != "imu":
                raise VehicleError(f"{f}: sensors.{name}.{key}: only the imu has a gyro and an accelerometer")
            if val.get(key) is not None:
                bias_sd[key] = _num(val, key, f"{f}: sensors.imu", positive=True)
                if bias_sd[key] >= top:
                    raise VehicleError(f"{f}: sensors.imu.{key} = {bias_sd[key]:g}: expected {unit}, {what}")
        if name == "imu" and "position" not in val and any(k in val for k in IMU_BIAS_SPECS):
            continue  # the IMU's bias specs alone (the accelerometer's position not given)
        if "position" not in val:
            raise VehicleError(f"{f}: sensors.{name}.position: missing (expected [x, y, z], m, body frame)")
        pos = _vec3(val, "position", f"{f}: sensors.{name}")
        if np.linalg.norm(pos) > MAX_SENSOR_OFFSET:
            raise VehicleError(f"{f}: sensors.{name}.position {pos.tolist()} is more than {MAX_SENSOR_OFFSET:g} m "
                               "from the body origin (expected metres, body frame)")
        out[name] = pos
    return out, bias_sd, latency


def vehicle_from_dict(d: dict, *, source: str = "<dict>", actuators: Actuators | None = None) -> Vehicle:
    """Build and validate a :class:`Vehicle` from a vehicle-file dictionary."""
    f = source
    check_keys(d, VEHICLE_KEYS, f, error=VehicleError, hint=" (free-form metadata goes under 'meta:')")
    for key in ("rigid_body", "added_mass", "damping"):
        if not isinstance(d.get(key), dict):
            raise VehicleError(f"{f}: '{key}' section missing or not a mapping")
    env = require_mapping(d.get("environment"), f"{f}: environment", error=VehicleError,
                          example="{g: 9.81, rho: 1000.0, current_ned: [0, 0, 0]}")
    check_keys(env, ENVIRONMENT_KEYS, f"{f}: environment", error=VehicleError)
    g = _num(env, "g", f"{f}: environment", positive=True, default=G)
    rho = _num(env, "rho", f"{f}: environment", positive=True, default=1000.0)
    current = _vec3(env, "current_ned", f"{f}: environment", default=[0.0, 0.0, 0.0])

    rb = d["rigid_body"]
    w = f"{f}: rigid_body"
    check_keys(rb, RIGID_BODY_KEYS, w, error=VehicleError)
    mass = _num(rb, "mass", w, positive=True)
    buoyancy = _num(rb, "buoyancy", w, nonneg=True)
    if not 0.2 < buoyancy / (mass * g) < 5.0 and buoyancy > 0:
        raise VehicleError(
            f"{w}.buoyancy = {buoyancy} N is {buoyancy / (mass * g):.2f} times the weight m g = {mass * g:.1f} N; "
            "expected a value near the weight for an underwater vehicle (check units: buoyancy is a force in N)"
        )
    r_g = _vec3(rb, "r_g", w, default=[0, 0, 0])
    r_b = _vec3(rb, "r_b", w, default=[0, 0, 0])
    inertia_d = rb.get("inertia")
    if not isinstance(inertia_d, dict):
        raise VehicleError(f"{w}.inertia: expected a mapping I_xx, I_yy, I_zz (and optional I_xy, I_xz, I_yz)")
    check_keys(inertia_d, INERTIA_NAMES, f"{w}.inertia", error=VehicleError)
    inertia = {}
    for k in INERTIA_NAMES:
        inertia[k] = _num(inertia_d, k, f"{w}.inertia", positive=k in INERTIA_NAMES[:3], default=None if k in INERTIA_NAMES[:3] else 0.0)
    I = inertia_tensor(*(inertia[k] for k in INERTIA_NAMES))
    ev = np.linalg.eigvalsh(I)
    if ev.min() <= 0:
        raise VehicleError(f"{w}.inertia: the inertia tensor is not positive definite (eigenvalues {ev})")
    Ixx, Iyy, Izz = ev  # principal moments must satisfy the triangle inequality
    if Ixx + Iyy < Izz * (1 - 1e-9):
        raise VehicleError(f"{w}.inertia: principal moments {ev} violate the triangle inequality (non-physical body)")

    am = d["added_mass"]
    w = f"{f}: added_mass"
    check_keys(am, (*ADDED_MASS_NAMES, "matrix", "convention"), w, error=VehicleError)
    if "matrix" in am:
        try:
            MA = np.asarray(am["matrix"], dtype=float)
        except (TypeError, ValueError):
            raise VehicleError(f"{w}.matrix: expected a finite 6x6 matrix of numbers") from None
        if MA.shape != (6, 6) or not np.all(np.isfinite(MA)):
            raise VehicleError(f"{w}.matrix: expected a finite 6x6 matrix")
        if not np.allclose(MA, MA.T, atol=1e-9 * max(1.0, np.abs(MA).max())):
            raise VehicleError(f"{w}.matrix: must be symmetric (an ideal-fluid added-mass matrix is)")
    else:
        MA = np.zeros((6, 6))
    for i, k in enumerate(ADDED_MASS_NAMES):
        if k in am:
            MA[i, i] = _num(am, k, w, nonneg=True)
    if np.any(np.diag(MA) < 0):
        raise VehicleError(
            f"{w}: diagonal added mass must be given as positive magnitudes (M_A = -diag(X_udot, ...) in SNAME sign)"
        )

    sensors, bias_sd, latency = _sensors(d.get("sensors"), f)
    damping = make_term(d["damping"], context=f"{f}: damping")
    effects_spec = d.get("effects") or []
    if not isinstance(effects_spec, list):
        raise VehicleError(f"{f}: effects: expected a list")
    effects = [make_term(e, context=f"{f}: effects[{i}]") for i, e in enumerate(effects_spec)]
    if actuators is None:
        actuators = build_actuators(d.get("thrusters"), f)

    v = Vehicle(
        name=str(d.get("name", Path(source).stem)),
        mass=mass,
        buoyancy=buoyancy,
        r_g=r_g,
        r_b=r_b,
        inertia=inertia,
        added_mass_matrix=MA,
        damping=damping,
        actuators=actuators,
        effects=effects,
        g=g,
        rho=rho,
        current_ned=current,
        sensors=sensors,
        gyro_bias_sd=bias_sd.get("gyro_bias_sd"),
        acc_bias_sd=bias_sd.get("acc_bias_sd"),
        sensor_latency=latency,
        description=str(d.get("description", "")),
        source=source,
        raw=d,
    )
    v.uncertainty = _uncertainty(d.get("uncertainty"), f, v.parameters())
    M = v.M
    ev = np.linalg.eigvalsh(0.5 * (M + M.T))
    if ev.min() <= 0:
        raise VehicleError(f"{f}: M = M_RB + M_A is not positive definite (eigenvalues {np.round(ev, 6)})")
    return v


def _uncertainty(spec, f: str, params: Mapping[str, float]) -> dict:
    """The ``uncertainty:`` section: {parameter name: positive 1-sigma in its units}."""
    if spec is None:
        return {}
    require_mapping(spec, f"{f}: uncertainty", error=VehicleError, example="uncertainty: {X_u: 2.0, N_rdot: 0.05}")
    check_keys(spec, list(params), f"{f}: uncertainty", error=VehicleError,
               hint=" (a parameter name of this vehicle: uvsim.load_vehicle(...).parameters())")
    out = {}
    for k, x in spec.items():
        out[k] = _num(spec, k, f"{f}: uncertainty", positive=True)
    return out


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
