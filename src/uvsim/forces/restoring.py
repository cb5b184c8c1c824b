"""Restoring forces g(eta) for any attitude (Fossen 2021 eq. 4.6).

The weight ``W`` acts at the centre of gravity ``r_g`` and the buoyancy ``B`` at the
centre of buoyancy ``r_b``, both along NED +z / -z.  In the body frame the NED
down axis is ``k = R^T e_3`` (the third row of ``R``), so

    f_g = W k,   f_b = -B k,
    -g(eta) = [f_g + f_b;  r_g x f_g + r_b x f_b].

Seed 000 eq. (10) is the special case r_g = 0, r_b = [0, 0, z_b].
"""
from __future__ import annotations

import numpy as np

from uvsim.forces import register
from uvsim.forces.base import ForceTerm
from uvsim.rigid_body import cross, skew


@register("restoring")
class Restoring(ForceTerm):
    """Weight and buoyancy.  Reads ``B``, ``x_b``, ``y_b``, ``z_b`` from the model
    parameters and the current weight / centre of gravity from the context (they may
    change with mass-changing actuators)."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    def prepare(self, params, n):
        if all(np.ndim(params[k]) == 0 for k in ("B", "x_b", "y_b", "z_b", "m", "x_g", "y_g", "z_g")):
            B, r_b, G = self._prepare(params, 1)  # one parameter set for every row: shared G
            return np.broadcast_to(B, (n,)), np.broadcast_to(r_b, (n, 3)), G
        return self._prepare(params, n)

    def _prepare(self, params, n):
        B = np.broadcast_to(np.asarray(params["B"], float), (n,))
        r_b = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in ("x_b", "y_b", "z_b")], -1)
        m = np.broadcast_to(np.asarray(params["m"], float), (n,))
        r_g = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in ("x_g", "y_g", "z_g")], -1)
        W = m * params["g"]
        # -g(eta) is linear in k:  tau_g = k @ G  with G = [(W - B) I, S(W r_g - B r_b)^T]  (n, 3, 6)
        h = W[:, None] * r_g - B[:, None] * r_b
        G = np.zeros((n, 3, 6))
        G[:, [0, 1, 2], [0, 1, 2]] = (W - B)[:, None]
        G[:, :, 3:] = np.swapaxes(skew(h), 1, 2)
        shared = bool(np.all(G == G[:1]))
        return B, r_b, (G[0] if shared else G)

    def kernel_part(self, prep):
        return ("restoring", prep[2])

    def forces(self, ctx, prep):
        B, r_b, G = prep
        k = ctx.R[:, 2, :]  # NED down axis in body coordinates, (n, 3)
        if not ctx.mass_changed:
            return k @ G if G.ndim == 2 else (k[:, None, :] @ G)[:, 0]
        W = ctx.weight
        f = (W - B)[:, None] * k
        m = cross(W[:, None] * ctx.r_g - B[:, None] * r_b, k)
        return np.concatenate([f, m], axis=1)


def restoring_vector(R, W, B, r_g, r_b):
    """``g(eta)`` (the left-hand-side vector, Fossen sign) for arrays ``R`` (..., 3, 3)."""
    R = np.asarray(R, float)
    k = R[..., 2, :]
    W = np.asarray(W, float)[..., None]
    B = np.asarray(B, float)[..., None]
    f = (W - B) * k
    m = cross(W * np.asarray(r_g, float) - B * np.asarray(r_b, float), k)
    return -np.concatenate([f, m], axis=-1)
