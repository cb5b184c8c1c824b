"""Shared set-up of the body (hull) methods: reference quantities and result container."""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from uvsim.constants import NU_WATER
from uvsim.errors import HydroError
from uvsim.hydro import crossflow
from uvsim.hydro.friction import FRICTION_LINES
from uvsim.hydro.geometry import HullGeometry


class Coefficients(NamedTuple):
    """Force/moment coefficients, all arrays of the shape of ``alpha``.

    ``CL`` lift (perpendicular to the flow, positive for positive alpha at small alpha),
    ``CD`` drag (along the flow, >= 0), ``CM`` pitching moment about ``x_m`` (nose-up positive,
    reference ``A_ref * L_ref``), ``CN`` normal force (body -z for positive alpha), ``CA`` axial
    force (positive aft, i.e. along body -x).  ``CL = CN cos a - CA sin a``,
    ``CD = CN sin a + CA cos a``.
    """

    CL: np.ndarray
    CD: np.ndarray
    CM: np.ndarray
    CN: np.ndarray
    CA: np.ndarray


def wrap_angle(alpha) -> np.ndarray:
    """Angles (rad) mapped to [-pi, pi) (periodic; not a clip)."""
    a = np.asarray(alpha, dtype=float)
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def normal_axial_to_lift_drag(alpha, cn, ca):
    """``(CL, CD)`` from normal and axial coefficients at angle of attack ``alpha`` (rad)."""
    c, s = np.cos(alpha), np.sin(alpha)
    return cn * c - ca * s, cn * s + ca * c


@dataclass(frozen=True)
class BodyModel:
    """A hull plus the modelling choices of the body methods.

    Parameters
    ----------
    hull : HullGeometry
    ref_area : float, optional
        Reference area ``A`` of all coefficients, m^2.  Default: hull frontal area ``pi d^2/4``.
    ref_length : float, optional
        Reference length for ``CM`` and the length Reynolds number, m.  Default: hull length.
    x_m : float, optional
        Moment reference station from the nose, m.  Default: volume centroid (centre of buoyancy).
    cdn_model : {"subcritical", "reynolds"}
        Cross-flow drag model, see :mod:`uvsim.hydro.crossflow`.  Default ``"subcritical"``:
        Jorgensen's method (seed 003 eqs. 7-11) uses the subcritical ``c_dn``, and the
        ``"reynolds"`` curve's drag crisis makes the cross-flow force fall as the speed rises
        (negative damping in a simulator; docs/hydro.md).
    friction_line : {"schoenherr", "ittc57"}
        Turbulent flat-plate line for ``C_f`` (:mod:`uvsim.hydro.friction`).
    munk : float, optional
        ``k2 - k1``; default from the equivalent prolate spheroid (:func:`crossflow.munk_factor`).
    eta : float, optional
        Cross-flow proportionality factor; default Jorgensen Fig. 4 at the hull's l/d.
    munk_moment : bool
        Include the potential-flow Munk couple in ``CM`` (default, as printed in seed 003):
        the ``(k2 - k1) V`` part of eqs. 9/11 and the ``V`` part of eq. 19.  ``False`` keeps
        only the moment of the potential normal force on the base (the ``A_b (L - x_m)``
        part) and the viscous cross-flow moment: for a simulator whose added-mass
        Coriolis term ``C_A(nu_r) nu_r`` already produces the Munk moment
        ``(Z_wdot - X_udot) u w`` (docs/sam.md, "One Munk moment").
    nu : float
        Kinematic viscosity, m^2/s, used only to convert speeds to Reynolds numbers.
    """

    hull: HullGeometry
    ref_area: float | None = None
    ref_length: float | None = None
    x_m: float | None = None
    cdn_model: str = "subcritical"
    friction_line: str = "schoenherr"
    munk: float | None = None
    eta: float | None = None
    nu: float = NU_WATER
    munk_moment: bool = True

    def __post_init__(self):
        if self.cdn_model not in crossflow.CDN_MODELS:
            raise HydroError(f"BodyModel: cdn_model {self.cdn_model!r} not in {crossflow.CDN_MODELS}")
        if not isinstance(self.munk_moment, bool):
            raise HydroError(f"BodyModel: munk_moment must be True or False, got {self.munk_moment!r}")
        if self.friction_line not in FRICTION_LINES:
            raise HydroError(f"BodyModel: friction_line {self.friction_line!r} not in {FRICTION_LINES}")
        for key in ("ref_area", "ref_length", "nu"):
            val = getattr(self, key)
            if val is not None and not (np.isfinite(val) and val > 0):
                raise HydroError(f"BodyModel: {key} must be > 0, got {val!r}")

    @property
    def A(self) -> float:
        return float(self.ref_area) if self.ref_area is not None else self.hull.frontal_area

    @property
    def L(self) -> float:
        return float(self.ref_length) if self.ref_length is not None else self.hull.length

    @property
    def xm(self) -> float:
        return float(self.x_m) if self.x_m is not None else self.hull.volume_centroid

    @property
    def k(self) -> float:
        """Munk factor ``k2 - k1``."""
        return float(self.munk) if self.munk is not None else crossflow.munk_factor(self.hull.fineness_ratio)

    @property
    def eta_value(self) -> float:
        return float(self.eta) if self.eta is not None else crossflow.eta(self.hull.fineness_ratio)

    def crossflow_re(self, alpha, re) -> np.ndarray:
        """Cross-flow Reynolds number ``Re_n = Re_L (d / L_ref) |sin alpha|``."""
        return np.asarray(re, float) * (self.hull.diameter / self.L) * np.abs(np.sin(alpha))

    def cdn(self, alpha, re) -> np.ndarray:
        """Cross-flow drag coefficient at each alpha for length Reynolds number ``re``.

        For ``alpha`` where ``sin(alpha) = 0`` the cross-flow term vanishes anyway; there the
        value is taken at ``Re_n`` of 1 degree to stay finite.
        """
        a = np.asarray(alpha, float)
        s = np.maximum(np.abs(np.sin(a)), np.sin(np.radians(1.0)))
        re_n = np.asarray(re, float) * (self.hull.diameter / self.L) * s
        return np.broadcast_to(crossflow.cdn(re_n, self.cdn_model), np.broadcast_shapes(a.shape, np.shape(re)))

    def re_from_speed(self, speed: float) -> float:
        return float(speed) * self.L / self.nu


def total_incidence(u, v, w):
    """Total incidence angle and cross-flow plane angle of a body of revolution.

    Parameters
    ----------
    u, v, w : array_like
        Body-frame velocity of the component relative to the water, m/s (x fwd, y stbd, z down).

    Returns
    -------
    alpha_t : ndarray
        ``atan2(sqrt(v^2 + w^2), u)`` in [0, pi], rad; the angle to look the body table up with
        (axial symmetry: beta is handled by the same table).
    phi : ndarray
        ``atan2(v, w)``, rad: direction of the cross-flow velocity in the body y-z plane
        (0: cross flow along +z, i.e. positive alpha; pi/2: along +y, i.e. positive beta).
        A positive ``CN`` from the table acts against the cross flow, along
        ``-(0, sin phi, cos phi)``.
    """
    u, v, w = (np.asarray(x, float) for x in (u, v, w))
    return np.arctan2(np.hypot(v, w), u), np.arctan2(v, w)


def reynolds(speed, length: float, nu: float = NU_WATER):
    """``Re = |speed| length / nu`` (-)."""
    return np.abs(np.asarray(speed, float)) * float(length) / float(nu)
