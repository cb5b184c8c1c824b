"""Damping models (plug-ins).

``diagonal``: the open-frame ROV model of seed 000 eq. (7)-(9),

    tau_D = D_L nu_r + D_Q |nu_r| nu_r        (element-wise, diagonal matrices)

with the coefficients kept in the *paper sign*: ``X_u``, ``X_uu`` (= X_{u|u|}) ... are
negative for a damped vehicle (seed 000 Table 2), so the returned force opposes the
motion.  In Fossen's form ``D(nu_r) = -diag(X_u, ...) - diag(X_uu, ...) |nu_r|`` is
positive.  ``coupled``: a full 6x6 linear and quadratic matrix (seed 003 eq. 26 style),
``tau_D = D_L nu_r + D_Q (|nu_r| * nu_r)`` with ``D_L``, ``D_Q`` in paper sign.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import VehicleError
from uvsim.forces import register
from uvsim.forces.base import ForceTerm, first_violation
from uvsim.schema import check_keys, finite_number

LINEAR_NAMES = ("X_u", "Y_v", "Z_w", "K_p", "M_q", "N_r")
QUADRATIC_NAMES = ("X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")


def _coeffs(values, names, field):
    if isinstance(values, (list, tuple)):
        if len(values) != 6:
            raise VehicleError(f"damping.{field}: expected 6 values ({', '.join(names)}), got {len(values)}")
        values = dict(zip(names, values))
    if not isinstance(values, dict):
        raise VehicleError(f"damping.{field}: expected a mapping {names[0]}..{names[-1]} or a list of 6 numbers")
    check_keys(values, names, f"damping.{field}", error=VehicleError)
    out = {}
    for name in names:
        v = finite_number(values.get(name, 0.0), f"damping.{field}.{name}", error=VehicleError, bool_ok=False)
        if v > 0:
            raise VehicleError(
                f"damping.{field}.{name} = {v}: damping coefficients are given in the paper sign "
                "(negative for a damped vehicle, e.g. X_u = -0.161 kg/s in seed 000 Table 2); a positive "
                "value would feed energy into the motion"
            )
        out[name] = v
    return out


@register("diagonal")
class DiagonalDamping(ForceTerm):
    """Diagonal linear + quadratic damping (seed 000 eq. 7-9), paper sign."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    def __init__(self, linear=None, quadratic=None):
        self.linear = _coeffs(linear or {}, LINEAR_NAMES, "linear")
        self.quadratic = _coeffs(quadratic or {}, QUADRATIC_NAMES, "quadratic")

    def parameters(self):
        return {**self.linear, **self.quadratic}

    def check_values(self, values):
        for k, v in values.items():
            if k in self.linear or k in self.quadratic:
                bad = first_violation(v, np.asarray(v, float) <= 0, k)
                if bad:
                    raise VehicleError(
                        f"parameter {bad}: damping coefficients are in the paper sign (negative for a damped "
                        "vehicle, as in the vehicle file's damping section); a positive value would feed "
                        "energy into the motion")

    def prepare(self, params, n):
        DL = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in LINEAR_NAMES], -1)
        DQ = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in QUADRATIC_NAMES], -1)
        return DL, DQ

    def kernel_part(self, prep):
        return ("diagonal", *prep)

    def forces(self, ctx, prep):
        DL, DQ = prep
        nr = ctx.nu_r
        return (DL + DQ * np.abs(nr)) * nr

    def to_dict(self):
        return {"type": "diagonal", "linear": dict(self.linear), "quadratic": dict(self.quadratic)}


@register("coupled")
class CoupledDamping(ForceTerm):
    """Full 6x6 linear and quadratic damping matrices (paper sign, row = force DOF,
    column = velocity DOF).  Named parameters ``D_L[i,j]`` / ``D_Q[i,j]`` for the
    non-zero entries, so a calibration can fit selected off-diagonal terms."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    def __init__(self, linear=None, quadratic=None):
        self.DL = self._matrix(linear, "linear")
        self.DQ = self._matrix(quadratic, "quadratic")

    @staticmethod
    def _matrix(values, field):
        if values is None:
            return np.zeros((6, 6))
        A = np.asarray(values, dtype=float)
        if A.shape == (6,):
            A = np.diag(A)
        if A.shape != (6, 6) or not np.all(np.isfinite(A)):
            raise VehicleError(f"damping.{field}: expected a finite 6x6 matrix (paper sign)")
        return A

    def parameters(self):
        out = {}
        for tag, A in (("D_L", self.DL), ("D_Q", self.DQ)):
            for i, j in zip(*np.nonzero(A)):
                out[f"{tag}[{i},{j}]"] = float(A[i, j])
        return out

    def prepare(self, params, n):
        mats = []
        for tag, A in (("D_L", self.DL), ("D_Q", self.DQ)):
            M = np.broadcast_to(A, (n, 6, 6)).copy()
            for i in range(6):
                for j in range(6):
                    key = f"{tag}[{i},{j}]"
                    if key in params:
                        M[:, i, j] = params[key]
            mats.append(M)
        return mats

    def kernel_part(self, prep):
        return ("coupled", *prep)

    def forces(self, ctx, prep):
        DL, DQ = prep
        nr = ctx.nu_r
        return np.einsum("nij,nj->ni", DL, nr) + np.einsum("nij,nj->ni", DQ, np.abs(nr) * nr)

    def to_dict(self):
        return {"type": "coupled", "linear": self.DL.tolist(), "quadratic": self.DQ.tolist()}

    def with_parameters(self, values):
        DL, DQ = self.DL.copy(), self.DQ.copy()
        for key, val in values.items():
            for tag, A in (("D_L", DL), ("D_Q", DQ)):
                if key.startswith(tag + "["):
                    i, j = (int(x) for x in key[len(tag) + 1:-1].split(","))
                    A[i, j] = float(val)
        return CoupledDamping(DL, DQ)
