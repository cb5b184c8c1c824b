"""Wings and control surfaces (seed 003 sec. III-B, Algorithm 2).

- Lifting line (Lanchester-Prandtl, eqs. 20-22) at low angle of attack,
- flat plate beyond stall,
- linear blend between them from 10 to 15 deg (Montgomerie 2004, FOI-R-1305-SE, as used by
  seed 003: "a linear interpolation is performed to reduce discontinuities in the transition
  region"), over -180..180 deg.

All angles in rad.  ``CM`` is about the quarter chord, nose-up positive, reference
``S * c``; the centre of pressure is returned by :func:`center_of_pressure`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uvsim.errors import HydroError
from uvsim.hydro.body import Coefficients, normal_axial_to_lift_drag, wrap_angle
from uvsim.hydro.friction import FRICTION_LINES, skin_friction

#: Normal-force coefficient of a 2-D flat plate broadside to the flow, -
#: (S. F. Hoerner, Fluid-Dynamic Drag, 1965, ch. 3: two-dimensional plate C_D = 1.98).
CD90_2D = 1.98

#: Blending range of seed 003 sec. IV-B / Algorithm 2, rad.
BLEND_START = np.radians(10.0)
BLEND_END = np.radians(15.0)


@dataclass(frozen=True)
class WingModel:
    """Planform and section parameters of a wing/fin/control surface.

    Parameters
    ----------
    aspect_ratio : float
        Effective aspect ratio ``AR``; ``np.inf`` gives 2-D section coefficients.
    oswald : float
        Span efficiency ``e`` of eqs. 20-21 (default 0.9, a common assumption for
        untwisted straight wings; not given in seed 003).
    thickness : float
        Section thickness/chord ``t/c`` (NACA 0015: 0.15).
    cl_alpha : float
        2-D lift slope, 1/rad (thin-airfoil theory ``2 pi``).
    cd90 : float, optional
        Flat-plate normal force coefficient at 90 deg.  Default :data:`CD90_2D` for
        ``AR = inf``, else Viterna & Corrigan (1982) ``1.11 + 0.018 AR`` (capped at 2-D value).
    friction_line : {"schoenherr", "ittc57"}
        Turbulent line for the profile drag (see :func:`profile_drag`).
    """

    aspect_ratio: float = np.inf
    oswald: float = 0.9
    thickness: float = 0.15
    cl_alpha: float = 2.0 * np.pi
    cd90: float | None = None
    friction_line: str = "schoenherr"

    def __post_init__(self):
        if not (self.aspect_ratio > 0):
            raise HydroError(f"WingModel: aspect_ratio must be > 0 (or inf), got {self.aspect_ratio!r}")
        if not (0 < self.oswald <= 1.0):
            raise HydroError(f"WingModel: oswald efficiency must be in (0, 1], got {self.oswald!r}")
        if not (0 <= self.thickness < 1.0):
            raise HydroError(f"WingModel: thickness t/c must be in [0, 1), got {self.thickness!r}")
        if self.friction_line not in FRICTION_LINES:
            raise HydroError(f"WingModel: friction_line {self.friction_line!r} not in {FRICTION_LINES}")

    @property
    def cd90_value(self) -> float:
        if self.cd90 is not None:
            return float(self.cd90)
        if np.isinf(self.aspect_ratio):
            return CD90_2D
        return float(min(1.11 + 0.018 * self.aspect_ratio, CD90_2D))

    @property
    def lift_slope_3d(self) -> float:
        """``a = a0 / (1 + 2/(e AR))`` (eq. 20 with ``C_l = a0 alpha``), 1/rad."""
        if np.isinf(self.aspect_ratio):
            return self.cl_alpha
        return self.cl_alpha / (1.0 + 2.0 / (self.oswald * self.aspect_ratio))


def profile_drag(wing: WingModel, re) -> np.ndarray:
    """Section profile drag ``C_D0 = 2 C_f (1 + 2 t/c + 60 (t/c)^4)`` at chord Reynolds number ``re``
    (Hoerner 1965, Fluid-Dynamic Drag, ch. 6, form factor of streamline sections; fully turbulent)."""
    t = wing.thickness
    return 2.0 * skin_friction(re, wing.friction_line) * (1.0 + 2.0 * t + 60.0 * t ** 4)


def lifting_line(wing: WingModel, alpha, re: float) -> Coefficients:
    """Eqs. 20-22: ``C_L = C_l/(1 + 2/(e AR))`` with ``C_l = cl_alpha * alpha``,
    ``C_D = C_D0 + C_L^2/(pi e AR)``; ``CM`` about c/4 = 0 (symmetric section).
    Meant for |alpha| <= 15 deg; evaluated as given for any angle."""
    a = wrap_angle(alpha)
    cl = wing.lift_slope_3d * a
    cdi = 0.0 if np.isinf(wing.aspect_ratio) else cl ** 2 / (np.pi * wing.oswald * wing.aspect_ratio)
    cd = profile_drag(wing, re) + cdi
    cm = np.zeros_like(a)
    c, s = np.cos(a), np.sin(a)
    return Coefficients(cl, cd, cm, cl * c + cd * s, -cl * s + cd * c)


def flat_plate_cp(alpha) -> np.ndarray:
    """Centre of pressure of the flat plate, chord fraction from the leading edge.

    Assumption: moves linearly from c/4 at 0 deg to c/2 at 90 deg and 3c/4 at 180 deg (the
    quarter chord seen from the trailing edge in reversed flow).
    """
    return 0.25 + 0.25 * np.abs(wrap_angle(alpha)) / (0.5 * np.pi)


def flat_plate(wing: WingModel, alpha, re: float) -> Coefficients:
    """Flat plate: ``C_N = cd90 sin(alpha)``, axial ``C_A = C_D0 cos(alpha)``,
    ``CM_c/4 = -C_N (x_cp - 1/4)``."""
    a = wrap_angle(alpha)
    cn = wing.cd90_value * np.sin(a)
    ca = profile_drag(wing, re) * np.cos(a)
    cl, cd = normal_axial_to_lift_drag(a, cn, ca)
    cm = -cn * (flat_plate_cp(a) - 0.25)
    return Coefficients(cl, cd, cm, cn, ca)


def blend_weight(alpha) -> np.ndarray:
    """Weight of the flat plate: 0 for |alpha| <= 10 deg, 1 for |alpha| >= 15 deg, linear between."""
    aa = np.abs(wrap_angle(alpha))
    return np.clip((aa - BLEND_START) / (BLEND_END - BLEND_START), 0.0, 1.0)


def montgomerie_blend(wing: WingModel, alpha, re: float) -> Coefficients:
    """Full-envelope analytic wing: lifting line, flat plate, linear blend from 10 to 15 deg."""
    a = wrap_angle(alpha)
    w = blend_weight(a)
    ll = lifting_line(wing, a, re)
    fp = flat_plate(wing, a, re)
    return Coefficients(*[(1.0 - w) * x + w * y for x, y in zip(ll, fp)])


def center_of_pressure(cn, cm) -> np.ndarray:
    """Chord fraction of the centre of pressure from the leading edge, ``1/4 - CM/CN``
    (NaN where ``CN = 0``)."""
    cn = np.asarray(cn, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cn != 0, 0.25 - np.asarray(cm, float) / cn, np.nan)
