"""Which model parameters a fit varies, their bounds, and a physical map.

A :class:`ParameterSpace` turns scaled fit variables ``z`` (one per free parameter,
``value = z * scale`` inside ``[lower, upper]``) into named model parameters for
:class:`uvsim.model.Model` (``overrides``), for a whole batch of parameter sets at
once.  It is shared by calibration and diagnosis.

**Physical by construction.**  Some combinations of in-bounds values are not a
physical body: principal moments of inertia must satisfy the triangle inequalities
(``I_xx <= I_yy + I_zz`` and cyclic), which a fit that moves ``I_xx`` and ``K_pdot``
or several inertias at once can cross (issue 14).  With zero products of inertia these
are the conditions ``Sigma_i >= 0`` on the second moments of the mass distribution,
``Sigma_x = (I_yy + I_zz - I_xx) / 2`` (cyclic), which are linear in the moments.
:func:`physical_moments` moves only the *free* moments into that set with a smooth,
one-sided clamp ``lo + eps softplus((x - lo) / eps)`` (and its mirror at an upper
limit), which equals ``x`` to double precision a few ``eps`` inside the set:

* one free moment, e.g. ``I_xx``: ``|I_yy - I_zz| <= I_xx <= I_yy + I_zz``;
* two free, e.g. ``I_xx, I_yy``: in ``s = I_xx + I_yy``, ``d = I_xx - I_yy`` the
  conditions separate into ``s >= I_zz`` and ``|d| <= I_zz``;
* all three: each ``Sigma_i >= 0``.

Fixed parameters never move.  (With non-zero products of inertia the exact condition
is a positive semidefinite second-moment matrix ``Sigma = 1/2 tr(I) 1 - I``;
:func:`physical_inertia` maps its eigenvalues, which can move the products near the
limit; the diagonal clamp is used when all products are zero.)  ``eps`` is
:data:`INERTIA_EPS` of the mean principal moment.  Added-mass magnitudes are kept
non-negative by their bounds, the mass positive, damping coefficients non-positive
(paper sign) by theirs.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.forces.damping import LINEAR_NAMES, QUADRATIC_NAMES
from uvsim.vehicle import ADDED_MASS_NAMES, INERTIA_NAMES
from uvsim.voltage_curves import measured_voltage_range

#: Relative width of the softplus that keeps the second moments positive.
INERTIA_EPS = 1e-3
#: Parameters whose value must be positive / non-negative / non-positive whatever the bounds say.
POSITIVE = ("m",) + INERTIA_NAMES[:3]
DAMPING_PREFIXES = ("X_", "Y_", "Z_", "K_", "M_", "N_")


def _softplus(x):
    return np.where(x > 30.0, x, np.log1p(np.exp(np.minimum(x, 30.0))))


def physical_inertia(Ixx, Iyy, Izz, Ixy, Ixz, Iyz, eps: float):
    """The nearest-in-the-interior physical inertia (module docstring); arrays (B,)."""
    I = np.empty(np.shape(Ixx) + (3, 3))
    I[..., 0, 0], I[..., 1, 1], I[..., 2, 2] = Ixx, Iyy, Izz
    I[..., 0, 1] = I[..., 1, 0] = -np.asarray(Ixy)
    I[..., 0, 2] = I[..., 2, 0] = -np.asarray(Ixz)
    I[..., 1, 2] = I[..., 2, 1] = -np.asarray(Iyz)
    tr = np.trace(I, axis1=-2, axis2=-1)
    S = 0.5 * tr[..., None, None] * np.eye(3) - I
    lam, V = np.linalg.eigh(S)
    lam = eps * _softplus(lam / eps)
    S = np.einsum("...ij,...j,...kj->...ik", V, lam, V)
    I2 = np.trace(S, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - S
    return I2[..., 0, 0], I2[..., 1, 1], I2[..., 2, 2], -I2[..., 0, 1], -I2[..., 0, 2], -I2[..., 1, 2]


def _clamp_lo(x, lo, eps):
    return lo + eps * _softplus((x - lo) / eps)


def _clamp(x, lo, hi, eps):
    return hi - eps * _softplus((hi - _clamp_lo(x, lo, eps)) / eps)


def physical_moments(I: list, free: list, eps: float) -> list:
    """Principal moments ``[I_xx, I_yy, I_zz]`` (arrays (B,)) with the ``free`` ones
    (bool (3,)) moved smoothly into the triangle-inequality set (module docstring)."""
    I = [np.asarray(a, float) for a in I]
    idx = [i for i in range(3) if free[i]]
    if len(idx) == 1:
        a = idx[0]
        b, c = [i for i in range(3) if i != a]
        out = list(I)
        out[a] = _clamp(I[a], np.abs(I[b] - I[c]) + eps, I[b] + I[c] - eps, eps)
        return out
    if len(idx) == 2:
        a, b = idx
        c = 3 - a - b
        s = _clamp_lo(I[a] + I[b], I[c] + eps, eps)
        d = _clamp(I[a] - I[b], -I[c] + eps, I[c] - eps, eps)
        out = list(I)
        out[a], out[b] = 0.5 * (s + d), 0.5 * (s - d)
        return out
    if len(idx) == 3:
        S = [0.5 * (I[1] + I[2] - I[0]), 0.5 * (I[0] + I[2] - I[1]), 0.5 * (I[0] + I[1] - I[2])]
        S = [_clamp_lo(x, eps, eps) for x in S]
        return [S[1] + S[2], S[0] + S[2], S[0] + S[1]]
    return I


@dataclass
class FreeParameter:
    """One free parameter: model name, start value, bounds and scale (typical size)."""

    name: str
    start: float
    lower: float
    upper: float
    scale: float = 0.0

    def __post_init__(self):
        if not (np.isfinite(self.lower) and np.isfinite(self.upper) and self.lower < self.upper):
            raise CalibrationError(f"bounds for {self.name}: need finite low < high, got ({self.lower}, {self.upper})")
        if not self.lower <= self.start <= self.upper:
            raise CalibrationError(f"bounds for {self.name}: ({self.lower:g}, {self.upper:g}) do not contain the start "
                                   f"value {self.start:g}")
        if not self.scale > 0:
            self.scale = max(abs(self.start), 0.1 * (self.upper - self.lower), 1e-6)


@dataclass
class ParameterSpace:
    """Free parameters of a fit on top of a vehicle's parameters (module docstring).

    Parameters
    ----------
    free : the free parameters.
    base : every named model parameter of the vehicle (``Vehicle.parameters()`` plus any
        effect parameters), used for the parameters that are not free.
    """

    free: list
    base: Mapping[str, float]
    fixed: dict = field(default_factory=dict)

    def __post_init__(self):
        names = [p.name for p in self.free]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise CalibrationError(f"parameter(s) {dup} listed twice")
        unknown = sorted(set(names) - set(self.base))
        if unknown:
            raise CalibrationError(f"unknown parameter(s) {unknown}; known: {sorted(self.base)}")
        self.base = {k: float(v) for k, v in self.base.items()}
        self._inertia = any(n in INERTIA_NAMES for n in names)
        I0 = [self.base.get(k, 0.0) for k in INERTIA_NAMES[:3]]
        self._eps = INERTIA_EPS * float(np.mean(I0)) if all(np.isfinite(I0)) else 1e-6

    # ------------------------------------------------------------------ vectors
    @property
    def names(self) -> list[str]:
        return [p.name for p in self.free]

    @property
    def p(self) -> int:
        return len(self.free)

    @property
    def scale(self) -> np.ndarray:
        return np.array([p.scale for p in self.free], float)

    @property
    def z0(self) -> np.ndarray:
        return np.array([p.start for p in self.free], float) / self.scale

    @property
    def z_lower(self) -> np.ndarray:
        return np.array([p.lower for p in self.free], float) / self.scale

    @property
    def z_upper(self) -> np.ndarray:
        return np.array([p.upper for p in self.free], float) / self.scale

    def to_z(self, values: Mapping[str, float]) -> np.ndarray:
        """Scaled variables of named values (missing names: the start value)."""
        return np.array([values.get(p.name, p.start) for p in self.free], float) / self.scale

    # ------------------------------------------------------------------ mapping
    def _mapped(self, Z: np.ndarray) -> dict[str, np.ndarray]:
        """Free values (B,) by name after the physical map, plus the whole mapped
        inertia tensor (all of INERTIA_NAMES) when an inertia is free."""
        Z = np.atleast_2d(np.asarray(Z, float))
        vals = {p.name: Z[:, i] * p.scale for i, p in enumerate(self.free)}
        if self._inertia:
            arrs = [vals.get(k, np.full(Z.shape[0], self.base.get(k, 0.0))) for k in INERTIA_NAMES]
            if all(np.all(a == 0) for a in arrs[3:]):
                free = [k in vals for k in INERTIA_NAMES[:3]]
                vals.update({k: v for k, v, f in zip(INERTIA_NAMES[:3], physical_moments(arrs[:3], free, self._eps),
                                                    free) if f})
            else:
                vals.update(zip(INERTIA_NAMES, physical_inertia(*arrs, eps=self._eps)))
        return vals

    def values(self, Z: np.ndarray) -> dict[str, np.ndarray]:
        """Free parameter values (B,) per name after the physical map."""
        vals = self._mapped(Z)
        return {p.name: vals[p.name] for p in self.free}

    def overrides(self, Z: np.ndarray, repeat: int = 1) -> dict[str, np.ndarray]:
        """Model overrides: each free parameter (and, when an inertia is free, the
        physically mapped inertia tensor, whose products of inertia may move too near
        the limit) as an array (B * repeat,), every parameter set repeated ``repeat``
        times (one copy per simulated row), plus the ``fixed`` values."""
        Z = np.atleast_2d(np.asarray(Z, float))
        out = {k: np.repeat(np.asarray(v, float), repeat) for k, v in self._mapped(Z).items()}
        for k, v in self.fixed.items():
            out[k] = np.full(Z.shape[0] * repeat, float(v))
        return out

    def as_dict(self, z: np.ndarray) -> dict[str, float]:
        """Named values of one parameter set z (p,)."""
        return {k: float(v[0]) for k, v in self.values(np.asarray(z, float)[None]).items()}

    def at_bounds(self, z: np.ndarray, rtol: float = 1e-6) -> list[str]:
        """Names of the parameters at (within ``rtol`` of the width of) a bound."""
        z = np.asarray(z, float)
        lo, hi = self.z_lower, self.z_upper
        w = hi - lo
        return [p.name for p, zi, a, b, wi in zip(self.free, z, lo, hi, w) if min(zi - a, b - zi) <= rtol * wi]

    def physical_limit(self, z: np.ndarray, rtol: float = 1e-4) -> list[str]:
        """Free inertias moved by the physical map by more than ``rtol`` (they sit at the
        triangle-inequality limit)."""
        if not self._inertia:
            return []
        raw = {p.name: zi * p.scale for p, zi in zip(self.free, np.asarray(z, float))}
        mapped = self.as_dict(z)
        return [k for k in raw if k in INERTIA_NAMES and abs(mapped[k] - raw[k]) > rtol * max(abs(raw[k]), 1e-12)]


#: Absolute half-widths of default search ranges for parameters whose value may be 0
#: (positions in m, currents in m/s), and default ranges of actuator factors.
POSITION_HALF_WIDTH = 0.05
THRUSTER_POSITION_HALF_WIDTH = 0.05
CURRENT_RANGE = (-1.0, 1.0)
#: A thruster's gain: 0 (a dead unit, a physical answer, issue 48) to 1.5 (more than 1.5 times
#: its measured curve points to a wrong curve); a unit pushing the wrong way (mounted or wired
#: reversed) has a negative gain, fitted as a candidate of its own in REVERSED_GAIN_RANGE.
GAIN_RANGE = (0.0, 1.5)
REVERSED_GAIN_RANGE = (-1.5, 0.0)
REVERSE_RANGE = (0.1, 1.5)


def default_bounds(name: str, value: float, margin: float) -> tuple[float, float]:
    """Default search range of parameter ``name`` around ``value``.

    * centre of gravity / buoyancy coordinates (``x_g`` ... ``z_b``) and thruster
      positions: ``value -+ max(0.05 m, margin |value|)``;
    * thruster and generalized-force gains: (0, 1.5), 0 being a dead unit; reverse ratios: (0.1, 1.5)
      (a unit delivering more than 1.5 times its measured curve points to a wrong curve);
    * current components: (-1, 1) m/s;
    * ``supply_voltage``: the voltages the shipped thrust-curve families were measured at
      (10-20 V for the T200, :mod:`uvsim.voltage_curves`);
    * everything else: ``value (1 -+ margin)``, so inertias, masses and added masses stay
      positive and damping coefficients negative (paper sign); a value of 0 has no
      relative range and needs explicit bounds."""
    if name in ("x_g", "y_g", "z_g", "x_b", "y_b", "z_b"):
        h = max(POSITION_HALF_WIDTH, margin * abs(value))
        return value - h, value + h
    if name.startswith("thruster_") and name.split("_")[1] in ("x", "y", "z"):
        h = max(THRUSTER_POSITION_HALF_WIDTH, margin * abs(value))
        return value - h, value + h
    if name.startswith(("thruster_gain_", "force_gain_")):
        return min(GAIN_RANGE[0], value), max(GAIN_RANGE[1], value)
    if name.startswith(("thruster_reverse_", "force_reverse_")):
        return min(REVERSE_RANGE[0], value), max(REVERSE_RANGE[1], value)
    if name in ("current_n", "current_e", "current_d"):
        return min(CURRENT_RANGE[0], value), max(CURRENT_RANGE[1], value)
    if name == "supply_voltage":  # the measured sheets bound it: nothing is extrapolated
        lo, hi = measured_voltage_range()
        return min(lo, value), max(hi, value)
    if value == 0:
        raise CalibrationError(f"parameter {name} is 0 in the vehicle, so a relative margin gives no search range; "
                               f"give its bounds explicitly (--bounds {name}=LOW:HIGH)")
    lo, hi = sorted((value * (1 - margin), value * (1 + margin)))
    return lo, hi


def cb_not_below_cg(name: str, bounds: tuple[float, float], values, free,
                    explicit: bool = False) -> tuple[float, float]:
    """``bounds`` of ``name`` with the physical limit of the centre of buoyancy: ``z_b``
    never goes below the centre of gravity (``z_b <= z_g``, z down; the vehicle file's rule
    :func:`uvsim.vehicle_rules.cb_not_below_cg`), so a fit cannot end in a vehicle that
    capsizes. Applies when ``z_g`` is held (not in ``free``); the default ranges are cut at
    ``z_g``, ``explicit`` bounds (the user's) that reach below it are an error."""
    if name != "z_b" or "z_g" in free:
        return bounds
    lo, hi = bounds
    z_g = float(values["z_g"])
    if lo >= z_g or (explicit and hi > z_g):
        raise CalibrationError(f"bounds for z_b ({lo:g}, {hi:g}) reach below the centre of gravity (z_g = {z_g:g} m, "
                               f"z down), where the vehicle would capsize; give bounds with z_b <= {z_g:g}")
    return lo, min(hi, z_g)


#: How far the joint fit's physical bounds let a mass, moment of inertia, added mass or damping
#: coefficient move from the vehicle file's value: a factor of 10 either way. The sign is the
#: physical limit (a body's diagonal added mass is >= 0, a passive hull's diagonal damping
#: dissipates, a mass is > 0); the factor only keeps the solver's steps finite. A coefficient
#: ten times off the file is a wrong vehicle file, not a calibration (the start models this
#: project calibrates are 20-40 % off: issue 21).
PHYSICAL_FACTOR = 10.0


def physical_bounds(name: str, value: float, margin: float) -> tuple[float, float]:
    """Bounds of parameter ``name`` for a fit whose start model is also its prior
    (:mod:`uvsim.fitting.priors`: the prior, not the bounds, keeps a coefficient near
    the file's value; issue 21 "bounds are physical limits only").

    * diagonal damping (``X_u`` ... ``N_rr``, paper sign <= 0):
      ``(PHYSICAL_FACTOR value, 0)``, so no longer dissipative is the limit;
    * added masses (``X_udot`` ... ``N_rdot``, positive magnitudes): ``(0, PHYSICAL_FACTOR value)``;
    * mass and principal moments of inertia: ``(value / PHYSICAL_FACTOR, PHYSICAL_FACTOR value)``
      (the triangle inequalities are kept by :func:`physical_moments`);
    * everything else: :func:`default_bounds` (positions, gains, currents and the supply
      voltage already have ranges that are not relative to the file's value).

    A value of 0 has no relative range and raises, as in :func:`default_bounds`; a value of
    the wrong sign (which a vehicle file cannot hold) falls back to :func:`default_bounds` too."""
    value = float(value)
    if name in LINEAR_NAMES + QUADRATIC_NAMES and value < 0:
        return PHYSICAL_FACTOR * value, 0.0
    if name in ADDED_MASS_NAMES and value > 0:
        return 0.0, PHYSICAL_FACTOR * value
    if name in POSITIVE and value > 0:
        return value / PHYSICAL_FACTOR, PHYSICAL_FACTOR * value
    return default_bounds(name, value, margin)


def make_space(vehicle_params: Mapping[str, float], names: Sequence[str], *, margin: float = 0.5,
               bounds: Mapping[str, Sequence[float]] | None = None, start: Mapping[str, float] | None = None,
               fixed: Mapping[str, float] | None = None) -> ParameterSpace:
    """A :class:`ParameterSpace` for ``names`` with bounds ``bounds[name]`` or
    :func:`default_bounds` around the vehicle's value, started at ``start[name]`` or
    the vehicle's value (a start outside its bounds is an error, not clipped)."""
    bounds = dict(bounds or {})
    start = dict(start or {})
    free = []
    for k in names:
        if k not in vehicle_params:
            raise CalibrationError(f"unknown parameter {k!r}; known: {', '.join(sorted(vehicle_params))}")
        v = float(vehicle_params[k])
        if k in bounds:
            try:
                lo, hi = (float(bounds[k][0]), float(bounds[k][1]))
            except (TypeError, ValueError, IndexError):
                raise CalibrationError(f"bounds for {k}: expected (low, high), got {bounds[k]!r}") from None
        else:
            lo, hi = default_bounds(k, v, margin)
        s0 = float(start.get(k, v))  # outside the bounds: an error naming both (FreeParameter)
        free.append(FreeParameter(k, s0, lo, hi, max(abs(v), abs(s0), 0.1 * (hi - lo))))
    return ParameterSpace(free, dict(vehicle_params), dict(fixed or {}))
