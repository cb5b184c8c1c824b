"""``coupled_damping``: off-diagonal hydrodynamic damping (cross-couplings).

Seed 003 eq. (26) writes the full quadratic damping matrix of an AUV with
cross-coupling derivatives (``X_qq``, ``Y_pp``, ``K_vv``, ``M_uu``, ``N_vv``, ...);
its eq. (25) shows where they come from: a force acting at a centre of pressure
``r_cp`` away from the origin gives a moment (e.g. ``K_vv = -z_cp Y_vv``).  Seed 000
(sec. 6) names "the coupling between different movements" as a cause of its
remaining reality gap, and an open-frame ROV, with its CB and its drag centre
not on the CG, has them.  The diagonal terms belong to the damping model of the
vehicle file; this effect adds selected off-diagonal ones::

    tau_i += sum_j ( L_ij nu_r,j + Q_ij |nu_r,j| nu_r,j ),    i != j

Named by SNAME convention: the force letter (X Y Z K M N) of row ``i``, then the
velocity letter (u v w p q r) of column ``j`` once for a linear term (``K_v``,
``N/(m/s)`` for a moment: N m s/m) and twice for a quadratic one (``K_vv``).
Each named coefficient is the derivative itself (``K_vv = dK / d(|v| v)``), so
it can take either sign; seed 003 eq. (26)'s minus signs are the geometric
signs of eq. (25) and are absorbed in the value.  The same matrices can be given
as a whole with the ``coupled`` damping model (:mod:`uvsim.forces.damping`); this
effect keeps the vehicle's own damping model and adds a few named terms, which is
what a diagnosis fits.
"""
from __future__ import annotations

import re

import numpy as np

from uvsim.effects.base import Effect, Field, check_number
from uvsim.errors import VehicleError
from uvsim.forces import register

FORCE_LETTERS = "XYZKMN"
VEL_LETTERS = "uvwpqr"
_NAME = re.compile(r"^([XYZKMN])_([uvwpqr])(\2)?$")

#: 1e4 (N or N m per (m/s) or per (m/s)^2): two orders of magnitude above the
#: largest diagonal coefficient of the vehicles shipped (seed 000 Table 5: Z_ww = -70 kg/m).
MAX_COEFF = 1.0e4


def parse_name(name: str) -> tuple[int, int, bool]:
    """``"K_vv"`` -> (row 3, column 1, quadratic True)."""
    m = _NAME.match(name)
    if not m:
        raise VehicleError(
            f"effects (coupled_damping).{name}: expected a SNAME derivative name such as K_v (linear) or "
            "K_vv (quadratic): a force letter X Y Z K M N, '_', a velocity letter u v w p q r (twice for quadratic)"
        )
    i, j = FORCE_LETTERS.index(m.group(1)), VEL_LETTERS.index(m.group(2))
    if i == j:
        raise VehicleError(
            f"effects (coupled_damping).{name}: a diagonal term; diagonal damping belongs to the vehicle's "
            "damping model (damping: linear/quadratic), this effect holds off-diagonal couplings only"
        )
    return i, j, m.group(3) is not None


def coefficient_unit(i: int, j: int, quadratic: bool) -> str:
    """Unit of a derivative: force (N) or moment (N m) per velocity (m/s or rad/s), squared if quadratic."""
    base = "N" if i < 3 else "N m"
    vel = "(m/s)" if j < 3 else "(rad/s)"
    return f"{base}/{vel}{'^2' if quadratic else ''}"


def coefficient_name(i: int, j: int, quadratic: bool) -> str:
    v = VEL_LETTERS[j]
    return f"{FORCE_LETTERS[i]}_{v}{v if quadratic else ''}"


@register("coupled_damping")
class CoupledDampingEffect(Effect):
    """Selected off-diagonal damping derivatives (see module docstring).

    Vehicle file::

        effects:
          - {type: coupled_damping, K_vv: -1.2, M_u: 0.3}
    """
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    def __init__(self, **kwargs):
        self.values = {}
        self.options = {}
        self.terms = []  # (i, j, quadratic, name)
        for name, raw in kwargs.items():
            i, j, quad = parse_name(name)
            unit = coefficient_unit(i, j, quad)
            f = Field(name, unit, -MAX_COEFF, MAX_COEFF, None, "a cross-coupling damping derivative")
            self.values[name] = check_number(raw, f, "effects (coupled_damping)")
            self.terms.append((i, j, quad, name))
        if not self.terms:
            raise VehicleError("effects (coupled_damping): no coefficients given (e.g. K_vv: -1.0)")
        self.FIELDS = tuple(Field(n, "", -MAX_COEFF, MAX_COEFF, None, "") for _, _, _, n in self.terms)

    def param_name(self, key: str) -> str:
        return key

    def units(self):
        return {name: coefficient_unit(i, j, quad) for i, j, quad, name in self.terms}

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``(L, Q)`` 6x6 matrices (row = force DOF, column = velocity DOF)."""
        L, Q = np.zeros((6, 6)), np.zeros((6, 6))
        for i, j, quad, name in self.terms:
            (Q if quad else L)[i, j] = self.values[name]
        return L, Q

    def prepare(self, params, n):
        return [(i, j, quad, self.p(params, name, n)) for i, j, quad, name in self.terms]

    def kernel_part(self, prep):
        # the named terms as the full matrices of the compiled kernel's coupled damping
        n = max([np.size(c) for *_, c in prep] or [1])
        DL, DQ = np.zeros((n, 6, 6)), np.zeros((n, 6, 6))
        for i, j, quad, c in prep:
            (DQ if quad else DL)[:, i, j] += c
        return ("coupled", DL, DQ)

    def forces(self, ctx, prep):
        nr = ctx.nu_r
        tau = np.zeros((nr.shape[0], 6))
        for i, j, quad, c in prep:
            x = nr[:, j]
            tau[:, i] += c * (np.abs(x) * x if quad else x)
        return tau
