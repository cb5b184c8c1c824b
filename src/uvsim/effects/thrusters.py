"""Thruster effects: ``thruster_lag`` (first-order actuator dynamics),
``thrust_asymmetry`` (reverse thrust weaker than forward) and ``thrust_scale`` (the
whole thrust curve scaled).

All three act on what the actuators deliver, so they are bound to the vehicle's
thruster allocation ``B`` (6 x n, :mod:`uvsim.forces.actuators`) when a
:class:`uvsim.model.Model` is built (``bind``).  With per-thruster inputs
(``thrust`` or ``pwm``) ``f_c`` is each unit's thrust as the actuators deliver it:
the curve at the input (and the supply voltage), times the unit's gain and reverse
ratio (``thruster_gain_i``, ``thruster_reverse_i``;
:meth:`uvsim.forces.actuators.Actuators.delivered`), through the allocation with the
units' positions (``thruster_x_i`` ...); with generalized-force inputs (``force``)
they act on each component of ``tau_c`` after the same factors.  So a weak unit's lag
lags its weak thrust, as on the vehicle (gain, then lag); before 2026-11-27 the
effects took the curve's thrust without the unit factors, and a weak thruster with
a lag was off by ``(gain - 1) B (f_c - f)`` during every transient (benchmark pair
118: 10 mm depth and 0.033 rad/s yaw rate RMS against the independent generator's
truth, now 1e-8; tests/test_effects.py).  The effects themselves add up: a lag does
not lag what ``thrust_asymmetry`` or ``thrust_scale`` add.

``thruster_lag`` (seed 002 sec. 6: "the difference in the response is due to the
thrusters dynamics that are not included in the simulation"; seed 000 sec. 6:
differences "particularly in the transient response").  Each thruster's thrust
follows its command with a first-order lag of time constant ``T`` (s), the usual
motor + propeller-inflow model (Fossen 2021 sec. 6.7; Yoerger et al. 1990 give a
more detailed, nonlinear model)::

    T f_dot = f_c - f,            tau_act = B f

The effect holds ``f`` as internal states (one per thruster; six for force
inputs) and contributes ``B (f - f_c)``, so with the ``actuators`` term (which
contributes ``B f_c``) the total is ``B f``.  Initial state: ``start: steady``
(default, ``f = f_c`` at the first sample, no artificial transient at the start
of a log) or ``start: zero`` (thrusters off before the log starts).  RK4 needs
``T`` above about ``dt / 2.8`` to stay stable; a smaller ``T`` is no lag at all at
the log's sample rate.

``thrust_asymmetry`` (seed 002 sec. 5 remarks on propeller interaction; the
T200's reverse branch gives roughly 80 % of the forward thrust at the same PWM
offset: 4.71 N vs 5.88 N at 1500 -+ 100 us in the shipped 16 V curve,
``data/thrusters/t200_16v.csv``; a curve measured in a bollard test need not hold
on the vehicle, where the reversed wake hits the frame).  Negative (reverse) thrusts are
scaled by ``ratio``::

    f_eff = f_c            if f_c >= 0
    f_eff = ratio * f_c    if f_c < 0
    contribution = B (f_eff - f_c) = (ratio - 1) B min(f_c, 0)

A ``ratio`` below 1 means reverse thrust is weaker than the thrust curve (or the
force inputs) claim.  The residual it leaves is "sign-dependent on the input".

``thrust_scale``: every thruster delivers ``scale`` times its curve, both ways::

    contribution = (scale - 1) B f_c

the first-order difference between the vehicle's curve and the one its thrusters
follow on the day: another supply voltage (at a given PWM the T200's thrust grows
roughly with the square of the voltage: rpm ~ V x duty, thrust ~ rpm^2, Blue Robotics
T200 data at 10-20 V, ``data/external`` SOURCE notes), another propeller or ESC.
Diagnosis fits it as part of "the base model is off" (``base_model:thrust_scale``),
before any thruster fault is judged.
"""
from __future__ import annotations

import copy

import numpy as np

from uvsim.bilinear import matvec
from uvsim.forces.actuators import repeat_rows
from uvsim.effects.base import Effect, Field
from uvsim.errors import SimulationError, VehicleError
from uvsim.forces import register


class _ActuatorEffect(Effect):
    """An effect bound to the vehicle's actuators (see module docstring)."""
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    _act = None
    _index = None

    def bind(self, vehicle, index):
        new = copy.copy(self)
        new._act = vehicle.actuators
        new._index = index
        return new

    def _command_prep(self, params, n):
        if self._act is None:
            raise SimulationError(f"effects ({self.kind}): not bound to a vehicle; use it inside a uvsim Model")
        # the actuators' own preparation: curves, each unit's gain, reverse ratio and position,
        # the fitted supply voltage (what Actuators.delivered applies)
        return {"act": self._act.prepare(params, n), "u": None, "fc": None}

    def commanded(self, ctx, cache):
        """Thrusts ``f_c`` (n, n_thr) the units deliver, or forces ``tau_c`` (n, 6), before this
        effect (:meth:`uvsim.forces.actuators.Actuators.delivered`); cached per input array."""
        if cache["u"] is ctx.u and cache.get("v") is ctx.voltage:
            return cache["fc"]
        fc = self._act.delivered(ctx.u, ctx.input_kind, cache["act"], ctx.voltage)
        cache["u"], cache["v"], cache["fc"] = ctx.u, ctx.voltage, fc
        return fc

    def _extra(self, fc, prep, repeat: int):
        """This effect's change of the delivered thrusts ``fc`` (m, k) (rows repeated ``repeat``
        times per prepared row); effects without states only."""
        raise NotImplementedError

    def held_along(self, U, kind, prep, V=None, rows=None):
        """Generalized force (n, m, 6) over inputs ``U`` (n, m, k) (ForceTerm.kernel_part)."""
        n, m, k = U.shape
        fc = self._act.delivered(U.reshape(n * m, k), kind, prep["act"], None if V is None else V.reshape(n * m),
                                 repeat=m)
        return self.to_tau(kind, self._extra(fc, prep, m), prep, m).reshape(n, m, 6)

    def to_tau(self, kind, f, prep, repeat: int = 1):
        """Generalized force of per-thruster forces ``f`` (or ``f`` itself for ``kind`` "force"),
        through the allocation with the units' (possibly fitted) positions; each prepared row
        stands for ``repeat`` rows of ``f``."""
        if kind == "force":
            return f
        return matvec(repeat_rows(prep["act"]["B"], repeat, 2), f)


@register("thruster_lag")
class ThrusterLag(_ActuatorEffect):
    """First-order thruster dynamics ``T f_dot = f_c - f`` (see module docstring)."""

    FIELDS = (
        Field("time_constant", "s", 0.0, 10.0, None, "the thruster time constant", lo_open=True),
    )
    OPTIONS = {"start": "steady"}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if self.options["start"] not in ("steady", "zero"):
            raise VehicleError(
                f"effects (thruster_lag).start = {self.options['start']!r}: expected 'steady' or 'zero'")

    @property
    def n_states(self):
        n_thr = 0 if self._act is None else self._act.n_thrusters
        return max(6, n_thr)

    def state_names(self):
        return [f"thrust_lag_{i + 1}" for i in range(self.n_states)]

    def prepare(self, params, n):
        prep = self._command_prep(params, n)
        prep["T"] = self.p(params, "time_constant", n)[:, None]
        return prep

    def _width(self, ctx):
        return 6 if ctx.input_kind == "force" else self._act.n_thrusters

    def forces(self, ctx, prep):
        fc = self.commanded(ctx, prep)
        f = ctx.states[self._index][:, : fc.shape[1]]
        return self.to_tau(ctx.input_kind, f - fc, prep)

    def state_derivative(self, ctx, prep, x):
        fc = self.commanded(ctx, prep)
        k = fc.shape[1]
        out = np.zeros_like(x)
        out[:, :k] = (fc - x[:, :k]) / prep["T"]
        return out

    def states_along(self, prep, T, U, input_kind, V=None, x0=None):
        """Exact lag states for zero-order-held commands: ``f_{i+1} = a f_i + (1 - a) f_c,i``
        with ``a = exp(-(t_{i+1} - t_i) / T)`` (the lag depends on the inputs only)."""
        n, L = T.shape
        k = U.shape[2]
        flat_v = None if V is None or input_kind == "force" else V.reshape(-1)
        fc = self._act.delivered(U.reshape(n * L, k), input_kind, prep["act"], flat_v, repeat=L).reshape(n, L, -1)
        width = fc.shape[2]
        out = np.zeros((n, L, self.n_states))
        x = np.array(x0[:, :width], float, copy=True)
        out[:, 0, :width] = x
        a = np.exp(-np.diff(T, axis=1) / prep["T"])  # (n, L - 1)
        for i in range(L - 1):
            x = a[:, i:i + 1] * x + (1.0 - a[:, i:i + 1]) * fc[:, i]
            out[:, i + 1, :width] = x
        return out

    def initial_state(self, prep, n, u0, input_kind):
        x = np.zeros((n, self.n_states))
        if self.options["start"] == "steady" and u0 is not None and np.shape(u0)[-1]:
            u0 = np.broadcast_to(np.asarray(u0, float), (n, np.shape(u0)[-1]))
            fc = self._act.delivered(u0, input_kind, prep["act"])
            x[:, : fc.shape[1]] = fc
        return x


@register("thrust_asymmetry")
class ThrustAsymmetry(_ActuatorEffect):
    """Reverse thrust scaled by ``ratio`` (see module docstring)."""

    FIELDS = (
        Field("ratio", "-", 0.0, 2.0, None, "the ratio of actual to modelled reverse thrust", lo_open=True),
    )

    def prepare(self, params, n):
        prep = self._command_prep(params, n)
        prep["ratio"] = self.p(params, "ratio", n)[:, None]
        return prep

    def kernel_part(self, prep):
        return ("held",)

    def _extra(self, fc, prep, repeat):
        return (repeat_rows(prep["ratio"], repeat, 0) - 1.0) * np.minimum(fc, 0.0)

    def forces(self, ctx, prep):
        fc = self.commanded(ctx, prep)
        return self.to_tau(ctx.input_kind, self._extra(fc, prep, 1), prep)


@register("thrust_scale")
class ThrustScale(_ActuatorEffect):
    """Every thruster's curve scaled by ``scale`` (see module docstring)."""

    FIELDS = (
        Field("scale", "-", 0.0, 3.0, None, "the ratio of actual to modelled thrust", lo_open=True),
    )

    def prepare(self, params, n):
        prep = self._command_prep(params, n)
        prep["scale"] = self.p(params, "scale", n)[:, None]
        return prep

    def kernel_part(self, prep):
        return ("held",)

    def _extra(self, fc, prep, repeat):
        return (repeat_rows(prep["scale"], repeat, 0) - 1.0) * fc

    def forces(self, ctx, prep):
        fc = self.commanded(ctx, prep)
        return self.to_tau(ctx.input_kind, self._extra(fc, prep, 1), prep)
