"""``current``: a constant, irrotational water current in NED.

Equation (seed 000 eq. 1-2, assumption 5; Fossen 2021 eq. 10.1-10.2).  The
hydrodynamic forces (added mass, damping) act on the velocity relative to the
water, ``nu_r = nu - nu_c`` with ``nu_c = [R^T v_c; 0]``, and for a current
constant in NED ``nu_c_dot = [-omega x R^T v_c; 0]``::

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta) = tau

How it plugs in.  The core model (:class:`uvsim.model.Model`) already implements
this relative-velocity form for the named parameters ``current_n``,
``current_e``, ``current_d`` (m/s, NED).  This effect *owns* those parameters:
its :meth:`parameters` returns them, and because :meth:`Vehicle.parameters`
applies effect parameters after the ``environment.current_ned`` values, the
effect's values are the ones the model uses (they replace, not add to, the
environment current).  Its own :meth:`forces` is therefore zero: the whole
effect acts through ``nu_r`` in every damping and added-mass term, which is
exactly the physics above (a separate force term could only approximate it by
linearizing the damping).  Fitting the effect means fitting ``current_n/e/d``.

Seed 003 (sec. I and VI) names currents near the dock as a disturbance for the
SAM AUV; in a tank, a pump or a seiche gives a slow, nearly uniform current.
"""
from __future__ import annotations

import numpy as np

from uvsim.effects.base import Effect, Field
from uvsim.forces import register

#: 5 m/s: far above tank, harbour or dock currents (tidal streams rarely exceed
#: 3 m/s) and above the top speed of the vehicles modelled here.
MAX_CURRENT = 5.0


@register("current")
class Current(Effect):
    """Constant NED water current ``v_c = [current_n, current_e, current_d]`` (m/s)."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    FIELDS = (
        Field("n", "m/s", -MAX_CURRENT, MAX_CURRENT, 0.0, "the north component of the water current"),
        Field("e", "m/s", -MAX_CURRENT, MAX_CURRENT, 0.0, "the east component of the water current"),
        Field("d", "m/s", -MAX_CURRENT, MAX_CURRENT, 0.0, "the down component of the water current"),
    )

    def kernel_part(self, prep):
        return ("none",)  # the model's current_n/e/d, which the compiled kernel has too

    def forces(self, ctx, prep):
        # acts through nu_r in the model's damping and added-mass terms (see module docstring)
        return np.zeros((ctx.nu.shape[0], 6))
