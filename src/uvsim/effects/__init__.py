"""The effects catalogue: physical force terms a model may lack.

Each effect is a :class:`uvsim.forces.ForceTerm` registered under its name, so a
vehicle file can switch it on under ``effects:`` and the simulator adds it to the
force sum; its named parameters (``<effect>_<field>``, see each module) can be
calibrated like any other.  ``uvsim diagnose`` (:mod:`uvsim.diagnosis`) fits them
to the residual of a model against logged runs.

=====================  ============================================  ==========================
name                   physics                                       parameters (unit)
=====================  ============================================  ==========================
``current``            constant NED current via ``nu_r = nu - nu_c``   current_n/e/d (m/s)
``tether``             umbilical pull (tension + stiffness beyond      tether_attach_x/y/z (m),
                       slack) and cross-flow cable drag                tether_anchor_n/e/d (m),
                                                                       tether_tension (N),
                                                                       tether_stiffness (N/m), ...
``thruster_lag``       first-order thrust dynamics ``T f' = f_c - f``  thruster_lag_time_constant (s)
``thrust_asymmetry``   reverse thrust scaled by a ratio                thrust_asymmetry_ratio (-)
``thrust_scale``       the whole thrust curve scaled                   thrust_scale_scale (-)
``ballast``            extra weight/buoyancy at a body point, and      ballast_weight (N), ballast_x/y/z (m),
                       the piece's own mass (inertia only)             ballast_mass (kg)
``coupled_damping``    off-diagonal damping derivatives (seed 003      K_vv, M_u, ... (SNAME names)
                       eq. 26)
``drag_centre``        translational damping acting at a centre of     drag_centre_x/y/z (m)
                       pressure off the origin (seed 003 eq. 25)
``bottom_effect``      extra vertical drag near the tank floor         bottom_effect_floor_d (m),
                       (seed 000 sec. 5)                               bottom_effect_damping (kg/m),
                                                                       bottom_effect_decay_length (m)
=====================  ============================================  ==========================
"""
from __future__ import annotations

from uvsim.effects.base import Effect, Field  # noqa: F401
from uvsim.effects.current import Current  # noqa: F401
from uvsim.effects.ballast import Ballast  # noqa: F401
from uvsim.effects.tether import Tether  # noqa: F401
from uvsim.effects.thrusters import ThrusterLag, ThrustAsymmetry, ThrustScale  # noqa: F401
from uvsim.effects.coupled_damping import CoupledDampingEffect  # noqa: F401
from uvsim.effects.drag_centre import DragCentre  # noqa: F401
from uvsim.effects.bottom import BottomEffect  # noqa: F401

#: The catalogue, in the order diagnosis tries it.
CATALOGUE = ("current", "tether", "thruster_lag", "thrust_asymmetry", "thrust_scale", "ballast", "coupled_damping", "drag_centre",
             "bottom_effect")
