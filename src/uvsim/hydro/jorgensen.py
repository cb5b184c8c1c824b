"""Jorgensen's method for slender bodies over the full 0..180 deg envelope (seed 003 eqs. 7-11;
L. H. Jorgensen, NASA TR R-474, 1977), mirrored to -180..0 by symmetry.
"""
from __future__ import annotations

import numpy as np

from uvsim.hydro.body import BodyModel, Coefficients, normal_axial_to_lift_drag, wrap_angle
from uvsim.hydro.friction import skin_friction


def default_axial_drag(body: BodyModel, re: float) -> float:
    """Jorgensen-only form drag ``C_A(alpha=0)``: turbulent flat-plate friction on the wetted area.

    ``C_A0 = C_f(Re) S_wet / A_ref`` (no form factor, no base drag).  Jorgensen's method takes
    ``C_A0`` as an input (measured in TR R-474); seed 003 does not say what it used for its
    Jorgensen column.  DATCOM's refined value (eq. 14-16, 18) is :func:`uvsim.hydro.datcom.zero_lift_drag`.
    """
    return float(skin_friction(re, body.friction_line) * body.hull.wetted_area / body.A)


def jorgensen(body: BodyModel, alpha, re: float, ca0: float | None = None,
              ca180: float | None = None) -> Coefficients:
    """Jorgensen coefficients at angles ``alpha`` (rad, any shape, wrapped to [-pi, pi)).

    Parameters
    ----------
    body : BodyModel
    alpha : array_like
        Angle of attack, rad.
    re : float
        Length Reynolds number ``V L_ref / nu`` (sets ``C_f`` and the cross-flow ``Re_n``).
    ca0 : float, optional
        Axial force coefficient at 0 deg (> 0, drag).  Default :func:`default_axial_drag`.
    ca180 : float, optional
        Magnitude of the axial force coefficient at 180 deg.  Default ``ca0`` (seed 003 eq. 18
        uses equal magnitudes).  In our sign convention ``CA(180 deg) = -ca180``; seed 003 eq. 18
        writes the same with the axial force positive forward.

    Returns
    -------
    Coefficients
        Arrays of the shape of ``alpha``; ``CM`` about ``body.xm`` (without the Munk couple
        ``k V`` when ``body.munk_moment`` is False).
    """
    a = wrap_angle(alpha)
    if ca0 is None:
        ca0 = default_axial_drag(body, re)
    if ca180 is None:
        ca180 = ca0
    h = body.hull
    A, L, xm, k = body.A, body.L, body.xm, body.k
    aa = np.abs(a)
    sign = np.where(a < 0, -1.0, 1.0)
    back = aa > 0.5 * np.pi
    ap = np.where(back, np.pi - aa, aa)  # alpha' of eq. 7
    eta_cdn = body.eta_value * body.cdn(aa, re)
    pot = np.sin(2 * ap) * np.cos(0.5 * ap)
    visc = eta_cdn * (h.planform_area / A) * np.sin(ap) ** 2
    cn = k * (h.base_area / A) * pot + visc  # eq. 7
    ca = np.where(back, -ca180, ca0) * np.cos(ap) ** 2  # eqs. 8, 10
    # eqs. 9, 11: k (V - A_b (L - x_m)) / (A L): the Munk couple (k V) and the moment of the
    # potential normal force on the base (-k A_b (L - x_m)); the couple is optional (BodyModel.munk_moment)
    vol = h.volume if body.munk_moment else 0.0
    munk_m = k * (vol - h.base_area * (L - xm)) / (A * L) * pot
    cm = np.where(back, -munk_m, munk_m) + visc * (xm - h.planform_centroid) / L  # eqs. 9, 11
    cn, cm = sign * cn, sign * cm  # C_N, C_M odd; C_A even
    cl, cd = normal_axial_to_lift_drag(a, cn, ca)
    return Coefficients(cl, cd, cm, cn, ca)
