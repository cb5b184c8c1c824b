"""``tether``: pull and drag of an umbilical cable attached to the vehicle.

Seed 000 (sec. 5 and 6) names the umbilical among the unmodelled effects of the
tethered BlueROV2 ("disturbances introduced by the tether"); seed 002 lists
"tether dynamics not considered" among its assumptions.  This is the simplest
physical model with the right signatures (a quasi-static cable, no cable
dynamics; see Eidsvik & Schjolberg 2016, seed 000 ref. 16, for beam models).

Geometry.  The cable leaves the vehicle at the attachment point ``r_a`` (m,
body) and runs straight to an anchor ``p_0`` (m, NED; the spool, the tank edge
or the surface float).  With the attachment point in NED ``p_a = p + R r_a``::

    d = p_0 - p_a,   L = |d|,   e = d / L          (unit vector towards the anchor)

Pull.  A constant tension ``T_0`` (spool / float pull) plus an elastic part when
the cable is stretched beyond its slack length ``L_s`` (stiffness ``k``)::

    F_pull = (T_0 + k max(0, L - L_s)) e                                   (NED)

so the pull grows with the distance from the anchor (the "growing with distance
from the start" signature).

Drag.  The part of the attachment-point velocity relative to the water that is
normal to the cable, ``v_n = v_a - (v_a . e) e`` with ``v_a = R (nu_r1 + omega x
r_a)``, drags a cable of diameter ``D`` and length ``l``.  The normal speed grows
linearly from 0 at the anchor to ``|v_n|`` at the vehicle, so the cable's total
cross-flow drag (quadratic drag, Morison form) is ``1/3`` of a cable moving
uniformly; all of it is carried by the vehicle (an upper bound)::

    F_drag = -1/2 rho C_d D (l / 3) |v_n| v_n                             (NED)

Lumped drag (``lumped_drag`` = ``c_l``, N s^2/m^2): a slack cable's bight is dragged
whichever way the attachment moves, so its drag is also modelled lumped at the
attachment, against the whole attachment velocity (quadratic point drag, the form of
Fossen 2021 eq. 6.61 for one point)::

    F_lumped = -c_l |v_a| v_a                                            (NED)

Horizontal pull (``horizontal: true``): a cable lying on the tank floor or trailing
at the surface pulls only horizontally: ``d`` and ``L`` use the horizontal (north,
east) components only, so ``e`` is horizontal and ``anchor_d`` plays no part.

Generalized force on the vehicle (body frame)::

    f = R^T (F_pull + F_drag),     tau = [f;  r_a x f]

Defaults: ``C_d = 1.2`` (circular cylinder in cross-flow at subcritical Re,
Hoerner 1965 "Fluid-Dynamic Drag" ch. 3), ``D = 0.0076`` m (the BlueROV2's Blue
Robotics Fathom ROV tether R2: "diameter of 7.6 mm", docs.bluerobotics.com/fathom-r2),
``rho = 1000`` kg/m^3 (fresh-water tank).
"""
from __future__ import annotations

import numpy as np

from uvsim.effects.base import Effect, Field
from uvsim.forces import register
from uvsim.rigid_body import cross


@register("tether")
class Tether(Effect):
    """Umbilical pull (tension + stiffness beyond slack), cross-flow drag and lumped drag."""
    position_axes = (0, 1, 2)  # the line from the anchor (ForceTerm.position_axes)

    FIELDS = (
        Field("attach_x", "m", -5.0, 5.0, 0.0, "the body x position of the tether attachment"),
        Field("attach_y", "m", -5.0, 5.0, 0.0, "the body y position of the tether attachment"),
        Field("attach_z", "m", -5.0, 5.0, 0.0, "the body z position of the tether attachment"),
        Field("anchor_n", "m", -1000.0, 1000.0, 0.0, "the NED north position of the tether anchor"),
        Field("anchor_e", "m", -1000.0, 1000.0, 0.0, "the NED east position of the tether anchor"),
        Field("anchor_d", "m", -1000.0, 1000.0, 0.0, "the NED down position of the tether anchor"),
        Field("tension", "N", 0.0, 1000.0, 0.0, "the constant tether pull"),
        Field("stiffness", "N/m", 0.0, 1.0e4, 0.0, "the tether pull per metre beyond the slack length"),
        Field("slack_length", "m", 0.0, 1.0e4, 0.0, "the distance to the anchor at which the tether becomes taut"),
        Field("cd", "-", 0.0, 3.0, 1.2, "the cross-flow drag coefficient of the cable"),
        Field("diameter", "m", 0.0, 0.2, 0.0076, "the cable diameter"),
        Field("length", "m", 0.0, 1.0e4, 0.0, "the wetted cable length"),
        Field("rho", "kg/m^3", 900.0, 1100.0, 1000.0, "the water density"),
        Field("lumped_drag", "N s^2/m^2", 0.0, 1.0e3, 0.0,
              "the quadratic drag of the cable lumped at the attachment, against its velocity in every direction"),
    )

    OPTIONS = {"horizontal": False}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        h = self.options["horizontal"]
        if not isinstance(h, bool):
            from uvsim.errors import VehicleError

            raise VehicleError(f"effects (tether).horizontal: expected true or false, got {h!r}")

    def prepare(self, params, n):
        g = {f.key: self.p(params, f.key, n) for f in self.FIELDS}
        r_a = np.stack([g["attach_x"], g["attach_y"], g["attach_z"]], -1)
        p0 = np.stack([g["anchor_n"], g["anchor_e"], g["anchor_d"]], -1)
        if self.options["horizontal"]:
            p0 = p0[:, :2]  # the pull direction uses the north and east components only
        c_drag = 0.5 * g["rho"] * g["cd"] * g["diameter"] * g["length"] / 3.0
        attached = bool(np.any(r_a))
        return (r_a, p0, g["tension"], g["stiffness"], g["slack_length"], c_drag, bool(np.any(c_drag)), attached,
                g["lumped_drag"], bool(np.any(g["lumped_drag"])))

    def kernel_part(self, prep):
        r_a, p0, T0, k, Ls, c_drag, _, _, c_l, _ = prep
        n = r_a.shape[0]
        horizontal = p0.shape[1] == 2
        anchor = np.concatenate([p0, np.zeros((n, 1))], 1) if horizontal else p0
        return ("tether", np.column_stack([np.broadcast_to(r_a, (n, 3)), anchor, np.full(n, float(horizontal)),
                                           T0, k, Ls, c_drag, c_l]))

    def forces(self, ctx, prep):
        # evaluated in the body frame (one rotation instead of three; the tether is evaluated
        # at every RK4 stage of every diagnosis fit, docs/performance.md):
        #   3-D:        d_b = R^T (p_0 - p) - r_a,  e_b = d_b / L
        #   horizontal: d = (p_0 - p - R r_a) north/east only (NED),  e_b = R^T e
        r_a, p0, T0, k, Ls, c_drag, has_drag, attached, c_l, has_lumped = prep
        R = ctx.R
        if p0.shape[1] == 3:
            dn = p0 - ctx.pos
            d = R[:, 0, :] * dn[:, :1] + R[:, 1, :] * dn[:, 1:2] + R[:, 2, :] * dn[:, 2:3]
            if attached:
                d = d - r_a
            L = np.sqrt((d * d).sum(1))
            e = d / np.maximum(L, 1e-9)[:, None]
        else:
            d = p0 - ctx.pos[:, :2]
            if attached:
                d = d - (R[:, :2, 0] * r_a[:, 0:1] + R[:, :2, 1] * r_a[:, 1:2] + R[:, :2, 2] * r_a[:, 2:3])
            L = np.sqrt((d * d).sum(1))
            en = d / np.maximum(L, 1e-9)[:, None]
            e = R[:, 0, :] * en[:, :1] + R[:, 1, :] * en[:, 1:2]
        f = (T0 + k * np.maximum(0.0, L - Ls))[:, None] * e
        if has_drag or has_lumped:
            v = ctx.nu_r[:, :3]
            if attached:
                v = v + cross(ctx.nu_r[:, 3:], r_a)
            if has_drag:
                v_n = v - (v * e).sum(1)[:, None] * e
                f = f - (c_drag * np.sqrt((v_n * v_n).sum(1)))[:, None] * v_n
            if has_lumped:
                f = f - (c_l * np.sqrt((v * v).sum(1)))[:, None] * v
        tau = np.empty((f.shape[0], 6))
        tau[:, :3] = f
        if attached:
            tau[:, 3:] = cross(r_a, f)
        else:
            tau[:, 3:] = 0.0
        return tau
