"""Vehicle data for the truth model, read straight from the shipped data files.

The scenario generator shares *data* with the project (the vehicle YAML file and the
T200 thrust table) but no *code*: this module parses ``vehicles/bluerov2_heavy.yaml``
(seed 000 Table 2 for mass, buoyancy, CG, CB; Table 5 for inertia, added mass and
damping; thruster geometry from von Benzon et al. 2022) and
``data/thrusters/t200_16v.csv`` (Blue Robotics T200 at 16 V) itself.

Conventions (docs/model.md): SI units, body x forward / y starboard / z down; added
mass as positive magnitudes, damping coefficients in the paper sign (negative);
``buoyancy`` is a force in N; a thruster's ``direction`` is the direction of positive
thrust.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import yaml

from uvsim.errors import VehicleError
from uvsim.files import safe_load

PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: The nominal vehicle of every profile (seed 000 Tables 2 and 5).
DEFAULT_VEHICLE_FILE = PACKAGE_DIR / "vehicles" / "bluerov2_heavy.yaml"
#: Blue Robotics T200 bollard thrust at 16 V (data/thrusters/SOURCE.md).
THRUST_TABLES = {"t200_16v": PACKAGE_DIR / "data" / "thrusters" / "t200_16v.csv"}
#: Blue Robotics T200 bollard thrust at 10-20 V (data/thrusters/t200_voltage/SOURCE.md): the
#: curves a truth may follow when its supply voltage is not the vehicle file's.
THRUST_TABLES.update({f"t200_{v}v_measured": PACKAGE_DIR / "data" / "thrusters" / "t200_voltage" / f"t200_{v}v.csv"
                      for v in (10, 12, 14, 16, 18, 20)})

INERTIA_NAMES = ("I_xx", "I_yy", "I_zz")
ADDED_MASS_NAMES = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot")
LINEAR_NAMES = ("X_u", "Y_v", "Z_w", "K_p", "M_q", "N_r")
QUADRATIC_NAMES = ("X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")
#: Coefficients a scenario may perturb (each by its own factor).
PERTURBABLE = INERTIA_NAMES + ADDED_MASS_NAMES + LINEAR_NAMES + QUADRATIC_NAMES


@dataclass(frozen=True)
class ThrustTable:
    """Measured ESC command -> bollard thrust table, interpolated linearly.

    ``thrust(pwm) = np.interp(pwm, pwm_us, thrust_n)``: the tabulated values at the
    table's commands, straight lines between, zero where the table says zero (the
    deadband, 1472-1528 us for the T200 at 16 V).
    """

    name: str
    pwm_us: np.ndarray = field(repr=False)
    thrust_n: np.ndarray = field(repr=False)

    @property
    def pwm_range(self) -> tuple[float, float]:
        return float(self.pwm_us[0]), float(self.pwm_us[-1])

    @property
    def max_forward(self) -> float:
        return float(self.thrust_n[-1])

    @property
    def max_reverse(self) -> float:
        return float(self.thrust_n[0])

    def thrust(self, pwm) -> np.ndarray:
        """Thrust (N) for ESC commands (us), any shape."""
        return np.interp(np.asarray(pwm, dtype=float), self.pwm_us, self.thrust_n)

    def command_for(self, thrust) -> np.ndarray:
        """ESC command (us, rounded to whole microseconds as an ESC receives it) whose
        thrust is closest to ``thrust`` (N); 0 N -> the middle of the deadband.

        Each branch is inverted on its strictly increasing part, taking for a flat stretch
        of the table the command nearest to neutral."""
        f = np.asarray(thrust, dtype=float)
        zero = np.flatnonzero(self.thrust_n == 0.0)
        lo, hi = self.pwm_us[zero[0]], self.pwm_us[zero[-1]]
        fw = self.pwm_us >= hi
        pf, tf = self.pwm_us[fw], self.thrust_n[fw]
        keep = np.r_[True, np.diff(tf) > 0]           # first command reaching each thrust
        rv = self.pwm_us <= lo
        pr, tr = self.pwm_us[rv], self.thrust_n[rv]
        keep_r = np.r_[np.diff(tr) > 0, True]         # last (nearest neutral) command
        out = np.where(f > 0, np.interp(f, tf[keep], pf[keep]),
                       np.where(f < 0, np.interp(f, tr[keep_r], pr[keep_r]), 0.5 * (lo + hi)))
        return np.rint(out)


def load_thrust_table(name: str) -> ThrustTable:
    """Read a shipped thrust table (CSV ``pwm_us, thrust_N``)."""
    if name not in THRUST_TABLES:
        raise VehicleError(f"thrust curve {name!r}: the scenario generator knows {sorted(THRUST_TABLES)}")
    path = THRUST_TABLES[name]
    header = path.read_text().splitlines()[0].split(",")
    a = np.loadtxt(path, delimiter=",", skiprows=1)
    if "thrust_kgf" in header:  # Blue Robotics' measurement sheets: kgf (1 kgf = 9.80665 N by definition)
        return ThrustTable(name, a[:, header.index("pwm_us")].copy(), 9.80665 * a[:, header.index("thrust_kgf")])
    return ThrustTable(name, a[:, 0].copy(), a[:, 1].copy())


@dataclass(frozen=True)
class VehicleData:
    """The physical data of one vehicle (floats and arrays, SI units).

    ``coefficients`` maps the perturbable names (``I_xx`` ... ``N_rr``) to values.
    ``thruster_positions`` / ``thruster_directions`` are (k, 3) arrays (m, body;
    unit vectors of positive thrust).  ``document`` is the parsed YAML file, kept to
    write the user's model file from it.
    """

    name: str
    g: float
    rho: float
    mass: float
    buoyancy: float
    r_g: np.ndarray
    r_b: np.ndarray
    products_of_inertia: tuple[float, float, float]
    coefficients: dict
    thruster_names: tuple
    thruster_positions: np.ndarray
    thruster_directions: np.ndarray
    curve: ThrustTable
    document: dict = field(repr=False)

    @property
    def weight(self) -> float:
        """W = m g, N."""
        return self.mass * self.g

    @property
    def n_thrusters(self) -> int:
        return len(self.thruster_names)

    def inertia_tensor(self) -> np.ndarray:
        """(3, 3) inertia tensor about the body origin, kg m^2 (Fossen 2021 eq. 3.33:
        off-diagonal entries are minus the products of inertia)."""
        c = self.coefficients
        ixy, ixz, iyz = self.products_of_inertia
        return np.array([[c["I_xx"], -ixy, -ixz], [-ixy, c["I_yy"], -iyz], [-ixz, -iyz, c["I_zz"]]])

    def added_mass_matrix(self) -> np.ndarray:
        """(6, 6) positive added-mass matrix ``M_A = -diag{X_udot, ...}`` in SNAME sign
        (seed 000 eq. 4), i.e. ``diag`` of the stored magnitudes."""
        return np.diag([self.coefficients[k] for k in ADDED_MASS_NAMES])

    def linear_damping(self) -> np.ndarray:
        """(6,) ``X_u ... N_r`` in the paper sign (negative)."""
        return np.array([self.coefficients[k] for k in LINEAR_NAMES])

    def quadratic_damping(self) -> np.ndarray:
        """(6,) ``X_uu ... N_rr`` in the paper sign (negative)."""
        return np.array([self.coefficients[k] for k in QUADRATIC_NAMES])

    def allocation(self) -> np.ndarray:
        """(6, k) thruster allocation: column ``i`` is ``[d_i; r_i x d_i]`` (Fossen 2021 eq. 11.6)."""
        d, r = self.thruster_directions, self.thruster_positions
        return np.vstack([d.T, np.cross(r, d).T])

    def with_coefficients(self, values: dict) -> "VehicleData":
        """A copy with some coefficients replaced (unknown names are an error)."""
        bad = sorted(set(values) - set(self.coefficients))
        if bad:
            raise VehicleError(f"{self.name}: unknown coefficient(s) {bad}; expected names from {list(PERTURBABLE)}")
        return replace(self, coefficients={**self.coefficients, **{k: float(v) for k, v in values.items()}})

    def with_rigid_body(self, *, buoyancy: float | None = None, r_b=None) -> "VehicleData":
        kw = {}
        if buoyancy is not None:
            kw["buoyancy"] = float(buoyancy)
        if r_b is not None:
            kw["r_b"] = np.asarray(r_b, dtype=float)
        return replace(self, **kw)


def _number(d: dict, key: str, where: str) -> float:
    if not isinstance(d, dict) or key not in d:
        raise VehicleError(f"{where}: missing {key!r}")
    try:
        v = float(d[key])
    except (TypeError, ValueError):
        raise VehicleError(f"{where}.{key}: expected a number, got {d[key]!r}") from None
    if not np.isfinite(v):
        raise VehicleError(f"{where}.{key}: expected a finite number, got {d[key]!r}")
    return v


def _vector(d: dict, key: str, where: str) -> np.ndarray:
    v = np.asarray(d.get(key, [0.0, 0.0, 0.0]), dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise VehicleError(f"{where}.{key}: expected 3 finite numbers, got {d.get(key)!r}")
    return v


def load_vehicle_data(path: str | Path = DEFAULT_VEHICLE_FILE) -> VehicleData:
    """Parse a vehicle YAML file with diagonal added mass and diagonal damping
    (the form of ``vehicles/bluerov2_heavy.yaml``) and its thruster table."""
    path = Path(path)
    try:
        doc = safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise VehicleError(f"{path}: cannot read the vehicle file ({exc})") from None
    f = path.name
    rb = doc.get("rigid_body", {})
    env = doc.get("environment", {})
    inertia = rb.get("inertia", {})
    am = doc.get("added_mass", {})
    damp = doc.get("damping", {})
    if damp.get("type", "diagonal") != "diagonal":
        raise VehicleError(f"{f}: damping.type {damp.get('type')!r}: the scenario truth model takes diagonal damping")
    coeffs = {k: _number(inertia, k, f"{f}: rigid_body.inertia") for k in INERTIA_NAMES}
    coeffs.update({k: _number(am, k, f"{f}: added_mass") for k in ADDED_MASS_NAMES})
    coeffs.update({k: _number(damp.get("linear", {}), k, f"{f}: damping.linear") for k in LINEAR_NAMES})
    coeffs.update({k: _number(damp.get("quadratic", {}), k, f"{f}: damping.quadratic") for k in QUADRATIC_NAMES})
    thr = doc.get("thrusters", {})
    units = thr.get("units", [])
    if not units:
        raise VehicleError(f"{f}: thrusters.units: the scenario generator needs a thruster list")
    pos = np.array([_vector(u, "position", f"{f}: thrusters.units[{i}]") for i, u in enumerate(units)])
    dirs = np.array([_vector(u, "direction", f"{f}: thrusters.units[{i}]") for i, u in enumerate(units)])
    dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
    return VehicleData(
        name=str(doc.get("name", path.stem)),
        g=float(env.get("g", 9.81)),
        rho=float(env.get("rho", 1000.0)),
        mass=_number(rb, "mass", f"{f}: rigid_body"),
        buoyancy=_number(rb, "buoyancy", f"{f}: rigid_body"),
        r_g=_vector(rb, "r_g", f"{f}: rigid_body"),
        r_b=_vector(rb, "r_b", f"{f}: rigid_body"),
        products_of_inertia=tuple(float(inertia.get(k, 0.0)) for k in ("I_xy", "I_xz", "I_yz")),
        coefficients=coeffs,
        thruster_names=tuple(str(u.get("name", f"T{i + 1}")) for i, u in enumerate(units)),
        thruster_positions=pos,
        thruster_directions=dirs,
        curve=load_thrust_table(str(thr.get("curve", "t200_16v"))),
        document=copy.deepcopy(doc),
    )
