"""DATCOM body-of-revolution methods (seed 003 eqs. 12-19, Table I; USAF DATCOM sec. 4.2),
with Jorgensen's method beyond the low-angle ranges.

Conversions: DATCOM writes eqs. 12 and 17 with reference area ``V^(2/3)`` and eqs. 14-16 with
the maximum frontal area ``S_B``; everything here is converted to ``body.A``.

Interpretation notes (see docs/hydro.md):

- eq. 17, first term: the printed ``(2A / V^(2/3)) 2 alpha^2`` with ``A`` = wetted area gives a
  drag ~30 times Jorgensen's at 15 deg for REMUS.  We use DATCOM's potential term
  ``2 alpha^2 A_b / V^(2/3)`` (base area, the drag counterpart of the slender-body normal force
  ``2 alpha A_b``).  The viscous term ``eta c_dn A_p alpha^3 / V^(2/3)`` is as printed.
- eq. 19 ``2 (x_m/l + V/(A l) - 1) alpha`` is DATCOM's slender-body moment referred to the base
  area ``A = A_b``; written for any reference area it is ``2 alpha (V - A_b (l - x_m)) / (A_ref l)``.
- eq. 18 uses ``C_f + C_Db``; we read ``C_f`` there as ``C_Df`` of eq. 15 so that
  ``C_A(0) = C_D0`` of eq. 14 (otherwise DATCOM's own zero-lift drag would be discarded at 15 deg).
"""
from __future__ import annotations

import numpy as np

from uvsim.hydro.body import BodyModel, Coefficients, wrap_angle
from uvsim.hydro.friction import skin_friction
from uvsim.hydro.jorgensen import jorgensen

#: Upper limits of the DATCOM low-angle methods, rad (seed 003 Table I).
LIFT_LIMIT = np.radians(12.0)
DRAG_LIMIT = np.radians(15.0)
MOMENT_LIMIT = np.radians(12.0)


def zero_lift_drag(body: BodyModel, re: float) -> dict:
    """Zero-lift drag ``C_D0 = C_Df + C_Db`` (eqs. 14-16), referred to ``body.A``.

    Returns a dict with ``cf`` (flat-plate line), ``cdf``, ``cdb`` and ``cd0`` (the last three on
    ``body.A``).  Eq. 15: ``C_Df = C_f [1 + 60/(l/d)^3 + 0.0025 (l/d)] S_S/S_B``;
    eq. 16: ``C_Db = 0.029 (d_b/d)^3 / sqrt(C_Df)`` (both on the frontal area ``S_B``).
    """
    h = body.hull
    cf = float(skin_friction(re, body.friction_line))
    f = h.fineness_ratio
    cdf = cf * (1.0 + 60.0 / f ** 3 + 0.0025 * f) * h.wetted_area / h.frontal_area
    cdb = 0.029 * (h.base_diameter / h.diameter) ** 3 / np.sqrt(cdf)
    scale = h.frontal_area / body.A
    return {"cf": cf, "cdf": cdf * scale, "cdb": cdb * scale, "cd0": (cdf + cdb) * scale}


def hopkins_lift(body: BodyModel, alpha, re: float) -> np.ndarray:
    """Eq. 12 (Hopkins 1951): ``C_L = (k2-k1) 2 a S_0 / V^(2/3) + 2 a|a| / V^(2/3) int_x0^l eta r c_dc dx``,
    returned on ``body.A``; ``alpha`` in rad (valid to 12 deg)."""
    h = body.hull
    a = np.asarray(alpha, float)
    mask = h.x >= h.x0
    xs, rs = h.x[mask], h.r[mask]
    # c_dc at each alpha (cross-flow Re depends on alpha), constant along the body
    cdc = body.cdn(a, re)
    integral = body.eta_value * float(np.sum(0.5 * (rs[1:] + rs[:-1]) * np.diff(xs)))
    v23 = h.volume ** (2.0 / 3.0)
    cl = (body.k * 2.0 * a * h.s0 + 2.0 * a * np.abs(a) * integral * cdc) / v23
    return cl * v23 / body.A


def low_alpha_drag(body: BodyModel, alpha, re: float) -> np.ndarray:
    """Eqs. 13 + 17: ``C_D = C_D0 + 2 a^2 A_b / V^(2/3) + eta c_dn A_p |a|^3 / V^(2/3)`` on ``body.A``."""
    h = body.hull
    a = np.asarray(alpha, float)
    v23 = h.volume ** (2.0 / 3.0)
    cda = (2.0 * a ** 2 * h.base_area + body.eta_value * body.cdn(a, re) * h.planform_area * np.abs(a) ** 3) / v23
    return zero_lift_drag(body, re)["cd0"] + cda * v23 / body.A


def slender_moment(body: BodyModel, alpha) -> np.ndarray:
    """Eq. 19 on ``body.A``: ``C_M = 2 a (V - A_b (l - x_m)) / (A_ref l)``; without the Munk
    couple ``2 a V / (A_ref l)`` when ``body.munk_moment`` is False."""
    h = body.hull
    vol = h.volume if body.munk_moment else 0.0
    return 2.0 * np.asarray(alpha, float) * (vol - h.base_area * (body.L - body.xm)) / (body.A * body.L)


def datcom(body: BodyModel, alpha, re: float) -> Coefficients:
    """DATCOM full-envelope coefficients per seed 003 Table I at ``alpha`` (rad, any shape).

    ``C_L``: eq. 12 for |alpha| <= 12 deg, Jorgensen beyond; ``C_D``: eqs. 13-17 for
    |alpha| <= 15 deg, Jorgensen beyond with ``C_A(0) = C_A(180) = C_D0`` (eq. 18);
    ``C_M``: eq. 19 for |alpha| <= 12 deg, Jorgensen beyond.  ``CN``/``CA`` are Jorgensen's
    beyond the limits and re-derived from ``CL``/``CD`` inside them.
    """
    a = wrap_angle(alpha)
    cd0 = zero_lift_drag(body, re)["cd0"]
    jor = jorgensen(body, a, re, ca0=cd0, ca180=cd0)
    aa = np.abs(a)
    cl = np.where(aa <= LIFT_LIMIT, hopkins_lift(body, a, re), jor.CL)
    cd = np.where(aa <= DRAG_LIMIT, low_alpha_drag(body, a, re), jor.CD)
    cm = np.where(aa <= MOMENT_LIMIT, slender_moment(body, a), jor.CM)
    c, s = np.cos(a), np.sin(a)
    cn = cl * c + cd * s
    ca = -cl * s + cd * c
    return Coefficients(cl, cd, cm, cn, ca)
