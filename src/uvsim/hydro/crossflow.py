"""Cross-flow drag data shared by the Jorgensen and DATCOM body methods.

- ``eta(l/d)``: ratio of the cross-flow drag of a finite cylinder to that of an infinite one,
  Jorgensen (1977) NASA TR R-474 Fig. 4 (solid circular-cylinder curve, Re_n = 88,000), from the
  third-party WebPlotDigitizer points in ``data/external/jorgensen-digitized`` (see its SOURCE.md).
- ``c_dn``: cross-flow drag coefficient of an infinite circular cylinder.  Two models:

  ``"subcritical"`` (default)
      Jorgensen (1977) Fig. 1 at cross-flow Mach number -> 0: the mean of the digitized points
      with ``M_n < 0.3`` (about 1.20).  Water flow is incompressible, so only this end of the
      figure applies.  No Reynolds-number dependence.  This is the ``c_dn`` of Jorgensen's
      method (seed 003 eqs. 7-11), and with it every force of a table grows with speed.
  ``"reynolds"``
      Smooth circular cylinder drag versus cross-flow Reynolds number ``Re_n = V sin(alpha) d / nu``
      including the drag crisis (about 1.2 subcritical, dropping near Re_n ~ 3e5 to about 0.3 and
      recovering towards 0.6-0.7 supercritical), using P. D. Sharpe's published curve fit
      (github.com/peterdsharpe/CylinderDragFits, data from Panton, "Incompressible Flow", 4th ed.,
      Wiley).  The fit formula was re-implemented here from its README; constants below.
      Jorgensen's digitized Fig. 1 omits Stack's critical dip (SOURCE.md).  AUV hulls fly in
      that range (Re_n = 1e4..1e6), but the dip makes the cross-flow force *fall* as the speed
      rises (for the SAM hull at 90 deg: 331 N at 2.0 m/s, 241 N at 2.5 m/s), i.e. negative
      damping in a simulator, and a real hull's roughness and free-stream turbulence make the
      crisis shallower and earlier than the smooth-cylinder curve; so it is an option for
      sensitivity studies, not the default (docs/hydro.md).

Both data files are read once and cached.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from uvsim.errors import HydroError

_DATA = Path(__file__).resolve().parent.parent / "data" / "external" / "jorgensen-digitized"

CDN_MODELS = ("subcritical", "reynolds")


@lru_cache(maxsize=1)
def _eta_table() -> tuple[np.ndarray, np.ndarray]:
    data = np.genfromtxt(_DATA / "eta_vs_fineness_ratio.csv", delimiter=",", skip_header=1)
    order = np.argsort(data[:, 0])
    return data[order, 0], data[order, 1]


@lru_cache(maxsize=1)
def subcritical_cdn() -> float:
    """Jorgensen (1977) Fig. 1 c_dn at M_n -> 0: mean of digitized points with M_n < 0.3 (-)."""
    data = np.genfromtxt(_DATA / "crossflow_cd_vs_crossflow_mach.csv", delimiter=",")
    return float(np.mean(data[data[:, 0] < 0.3, 1]))


def eta(fineness_ratio: float) -> float:
    """Cross-flow drag proportionality factor eta(l/d) (Jorgensen 1977 Fig. 4).

    Linear interpolation of the digitized curve (l/d from 1.46 to 39.2).  Outside that range
    a :class:`HydroError` is raised rather than extrapolating.
    """
    x, y = _eta_table()
    f = float(fineness_ratio)
    if not (x[0] <= f <= x[-1]):
        raise HydroError(f"fineness ratio l/d = {f:.3g} is outside the digitized eta range "
                         f"[{x[0]:.3g}, {x[-1]:.3g}] of Jorgensen (1977) Fig. 4")
    return float(np.interp(f, x, y))


# Sharpe's cylinder drag fit constants (CylinderDragFits README, "The Model", x = log10(Re)).
_CSIGC = 5.5766722118597247
_CSIGH = 23.7460859935990563
_CSUB0 = -0.6989492360435040
_CSUB1 = 1.0465189382830078
_CSUB2 = 0.7044228755898569
_CSUB3 = 0.0846501115443938
_CSUP0 = -0.0823564417206403
_CSUPC = 6.8020230357616764
_CSUPH = 9.9999999999999787
_CSUPSCL = -0.4570690347113859


def cylinder_cd_reynolds(re_n) -> np.ndarray:
    """Drag coefficient of a smooth circular cylinder versus Reynolds number (Sharpe fit).

    Parameters
    ----------
    re_n : array_like
        Reynolds number based on diameter and the velocity normal to the axis (-), > 0.
    """
    re = np.asarray(re_n, dtype=float)
    x = np.log10(np.maximum(re, 1.0))  # Re_n < 1 only at rest; the fit is for Re >= 0.1
    sub = np.log10(10.0 ** (_CSUB0 * x + _CSUB1) + _CSUB2 + _CSUB3 * x)
    # log(exp(h (c - x)) + 1) written overflow-safe with logaddexp
    sup = _CSUP0 + _CSUPSCL / _CSUPH * np.logaddexp(_CSUPH * (_CSUPC - x), 0.0)
    w = 0.5 * (1.0 + np.tanh(0.5 * _CSIGH * (x - _CSIGC)))  # = 1/(1+exp(-h(x-c)))
    return 10.0 ** (sub * (1.0 - w) + sup * w)


def cdn(re_n=None, model: str = "subcritical") -> np.ndarray:
    """Cross-flow drag coefficient c_dn of an infinite circular cylinder.

    Parameters
    ----------
    re_n : array_like or None
        Cross-flow Reynolds number ``V |sin alpha| d / nu``; required for ``model="reynolds"``.
    model : {"subcritical", "reynolds"}
        See the module docstring.
    """
    if model == "subcritical":
        return np.full(np.shape(re_n) if re_n is not None else (), subcritical_cdn())
    if model == "reynolds":
        if re_n is None:
            raise HydroError("c_dn model 'reynolds' needs the cross-flow Reynolds number re_n")
        return cylinder_cd_reynolds(re_n)
    raise HydroError(f"unknown c_dn model {model!r}; expected one of {CDN_MODELS}")


def munk_factor(fineness_ratio: float) -> float:
    """Apparent-mass factor ``k2 - k1`` of the prolate spheroid with the same fineness ratio.

    Lamb's coefficients (H. Lamb, Hydrodynamics, 6th ed., 1932, sec. 373): with eccentricity
    ``e = sqrt(1 - (d/l)^2)``, ``alpha0 = 2 (1 - e^2)/e^3 (atanh(e) - e)``,
    ``beta0 = 1/e^2 - (1 - e^2)/e^3 atanh(e)``, ``k1 = alpha0/(2 - alpha0)``,
    ``k2 = beta0/(2 - beta0)``.  This is the curve of DATCOM Fig. 4.2.1.1-20a; it tends to 1 at
    high fineness ratio as seed 003 notes below eq. 12.
    """
    f = float(fineness_ratio)
    if f <= 1.0:
        raise HydroError(f"Munk factor needs a fineness ratio l/d > 1, got {f:.3g}")
    e = np.sqrt(1.0 - 1.0 / f ** 2)
    ath = np.arctanh(e)
    alpha0 = 2.0 * (1.0 - e ** 2) / e ** 3 * (ath - e)
    beta0 = 1.0 / e ** 2 - (1.0 - e ** 2) / e ** 3 * ath
    return float(beta0 / (2.0 - beta0) - alpha0 / (2.0 - alpha0))
