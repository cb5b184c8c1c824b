"""``ballast``: an extra weight (or buoyancy) acting at a point of the body.

Equation (Fossen 2021 eq. 4.6 applied to one point load).  A net vertical load
``w`` (N; positive = heavier, e.g. a lead weight or a flooded compartment;
negative = extra buoyancy, e.g. trapped air or added foam) acts at ``r_p =
[x, y, z]`` (m, body frame) along the NED down axis, which is ``k = R^T e_3`` in
body coordinates::

    f = w k,        tau = [f;  r_p x f]

So the force is constant in NED (always vertical) and the moment depends on the
attitude.  The small change of mass and inertia of the load is neglected (its
weight is what changes the trim; a 100 g weight adds < 1 % to the 13 kg
BlueROV2).  Seed 000 (Table 2, sec. 4.1) measures the BlueROV2's weight,
buoyancy and CG/CB; a mis-trimmed vehicle (wrong B - W or CB offset) shows
exactly this residual.
"""
from __future__ import annotations

import numpy as np

from uvsim.effects.base import Effect, Field
from uvsim.forces import register
from uvsim.rigid_body import cross


@register("ballast")
class Ballast(Effect):
    """Point load ``ballast_weight`` (N, + down) at ``ballast_x/y/z`` (m, body)."""

    FIELDS = (
        Field("weight", "N", -1000.0, 1000.0, None, "the extra weight (+) or buoyancy (-) of the point load"),
        Field("x", "m", -5.0, 5.0, 0.0, "the body x position of the point load"),
        Field("y", "m", -5.0, 5.0, 0.0, "the body y position of the point load"),
        Field("z", "m", -5.0, 5.0, 0.0, "the body z position of the point load"),
    )

    def prepare(self, params, n):
        w = self.p(params, "weight", n)
        r = np.stack([self.p(params, k, n) for k in ("x", "y", "z")], -1)
        return w, r

    def forces(self, ctx, prep):
        w, r = prep
        k = ctx.R[:, 2, :]  # NED down axis in body coordinates
        f = w[:, None] * k
        return np.concatenate([f, cross(np.broadcast_to(r, f.shape), f)], axis=1)
