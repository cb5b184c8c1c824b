"""``ballast``: an extra weight (or buoyancy) acting at a point of the body.

Equation (Fossen 2021 eq. 4.6 applied to one point load).  A net vertical load
``w`` (N; positive = heavier, e.g. a lead weight or a flooded compartment;
negative = extra buoyancy, e.g. trapped air or added foam) acts at ``r_p =
[x, y, z]`` (m, body frame) along the NED down axis, which is ``k = R^T e_3`` in
body coordinates::

    f = w k,        tau = [f;  r_p x f]

So the force is constant in NED (always vertical) and the moment depends on the
attitude.  Seed 000 (Table 2, sec. 4.1) measures the BlueROV2's weight, buoyancy and
CG/CB; a mis-trimmed vehicle (wrong B - W or CB offset) shows exactly this residual.

The piece's own mass ``m_p`` (``mass``, kg; default 0: a massless load) is inertia
only: it joins the rigid body as a point mass at ``r_p`` (Fossen 2021 eq. 3.44 with
``m + m_p``, the CG moved to ``(m r_g + m_p r_p) / (m + m_p)`` and ``I_o + m_p (|r_p|^2
I - r_p r_p^T)``, the parallel-axis theorem), so also ``C_RB``; its weight is already in
``w`` (``w = m_p g - rho V_p g``).  A 10 g foam block is < 0.1 % of a 13 kg BlueROV2, yet
on a run whose heading is held by nothing, its ``m_p y_p u_dot`` yaw moment
(~5e-4 N m) decides which way the vehicle turns (docs/diagnose.md, seed 38).  Added
mass of the piece is neglected.
"""
from __future__ import annotations

import numpy as np

from uvsim.effects.base import Effect, Field
from uvsim.forces import register
from uvsim.rigid_body import cross, skew


@register("ballast")
class Ballast(Effect):
    """Point load ``ballast_weight`` (N, + down) at ``ballast_x/y/z`` (m, body)."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    FIELDS = (
        Field("weight", "N", -1000.0, 1000.0, None, "the extra weight (+) or buoyancy (-) of the point load"),
        Field("x", "m", -5.0, 5.0, 0.0, "the body x position of the point load"),
        Field("y", "m", -5.0, 5.0, 0.0, "the body y position of the point load"),
        Field("z", "m", -5.0, 5.0, 0.0, "the body z position of the point load"),
        Field("mass", "kg", 0.0, 100.0, 0.0, "the mass of the piece itself (inertia only; its weight is in weight)"),
    )

    def fixed_mass_properties(self, params, n):
        m_p = self.p(params, "mass", n)
        if not np.any(m_p):
            return None
        r = np.stack([self.p(params, k, n) for k in ("x", "y", "z")], -1)
        # parallel-axis theorem: a point mass at r_p about the body origin
        dI = m_p[:, None, None] * (np.einsum("ni,ni->n", r, r)[:, None, None] * np.eye(3) - r[:, :, None] * r[:, None, :])
        return m_p.copy(), m_p[:, None] * r, dI

    def prepare(self, params, n):
        w = self.p(params, "weight", n)
        r = np.stack([self.p(params, k, n) for k in ("x", "y", "z")], -1)
        return w, r

    def kernel_part(self, prep):
        # [w k; r x w k] = k G with G = [w I, S(w r)^T] (as the restoring term's)
        w, r = prep
        G = np.zeros((w.size, 3, 6))
        G[:, [0, 1, 2], [0, 1, 2]] = w[:, None]
        G[:, :, 3:] = np.swapaxes(skew(w[:, None] * np.broadcast_to(r, (w.size, 3))), 1, 2)
        return ("restoring", G)

    def forces(self, ctx, prep):
        w, r = prep
        k = ctx.R[:, 2, :]  # NED down axis in body coordinates
        f = w[:, None] * k
        return np.concatenate([f, cross(np.broadcast_to(r, f.shape), f)], axis=1)
