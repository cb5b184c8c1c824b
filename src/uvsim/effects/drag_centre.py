"""``drag_centre``: the translational damping acts at a centre of pressure off the origin.

Seed 003 eq. (25) derives the cross-coupling damping derivatives of a body from a force
acting at a centre of pressure ``r_cp`` away from the body origin: the moment is
``r_cp x F``, e.g. ``K_vv = -z_cp Y_vv``, ``M_ww = -x_cp Z_ww``, ``N_vv = x_cp Y_vv``.  An
open-frame ROV's drag centre is where its frame, floats and thrusters are, not at its
CG; seed 000 (sec. 6) names such couplings among its remaining errors.  This effect
takes the vehicle's own *translational* damping (the ``diagonal`` model's
``X_u, Y_v, Z_w, X_uu, Y_vv, Z_ww``, whatever values a calibration gave them) and moves
its point of action to ``r_cp = [x, y, z]`` (m, body)::

    f_D = [X_u u_r + X_uu |u_r| u_r,  Y_v v_r + Y_vv |v_r| v_r,  Z_w w_r + Z_ww |w_r| w_r]
    tau = [0;  r_cp x f_D]

(the force itself is already in the damping model).  Three parameters describe every
coupling derivative of seed 003 eq. (25) that translational drag can produce, with the
signs and ratios the geometry imposes; :mod:`uvsim.effects.coupled_damping` holds
arbitrary named derivatives instead.
"""
from __future__ import annotations

import numpy as np

from uvsim.effects.base import Effect, Field
from uvsim.errors import SimulationError
from uvsim.forces import register
from uvsim.rigid_body import cross

_LIN = ("X_u", "Y_v", "Z_w")
_QUAD = ("X_uu", "Y_vv", "Z_ww")


@register("drag_centre")
class DragCentre(Effect):
    """Translational damping acting at ``drag_centre_x/y/z`` (m, body) (module docstring)."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    FIELDS = (
        Field("x", "m", -2.0, 2.0, 0.0, "the body x position of the centre of the translational drag"),
        Field("y", "m", -2.0, 2.0, 0.0, "the body y position of the centre of the translational drag"),
        Field("z", "m", -2.0, 2.0, 0.0, "the body z position of the centre of the translational drag"),
    )

    def prepare(self, params, n):
        missing = [k for k in _LIN + _QUAD if k not in params]
        if missing:
            raise SimulationError(f"effects (drag_centre): the vehicle's damping model has no {missing} "
                                  "(it needs the diagonal translational damping coefficients)")
        r = np.stack([self.p(params, k, n) for k in ("x", "y", "z")], -1)
        DL = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in _LIN], -1)
        DQ = np.stack([np.broadcast_to(np.asarray(params[k], float), (n,)) for k in _QUAD], -1)
        return r, DL, DQ

    def forces(self, ctx, prep):
        r, DL, DQ = prep
        v = ctx.nu_r[:, :3]
        f = (DL + DQ * np.abs(v)) * v
        return np.concatenate([np.zeros_like(f), cross(np.broadcast_to(r, f.shape), f)], axis=1)
