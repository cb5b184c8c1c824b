"""A :class:`uvsim.model.Model` that reuses the rebuilt mass matrix while the trim
subsystems are settled.

The core model rebuilds ``M_RB`` and inverts ``M_RB + M_A`` at every integrator stage when
any term changes mass (``Model._mass_update``).  For SAM the mass-changing actuators
(VBS, LCG, TCG) are still most of the time, and their states are then exactly constant
(the servo model has a dead band, :class:`uvsim.sam.subsystems._Servo`), so the result
only changes when one of those states changes.  :class:`SamModel` caches the last result
keyed on the bytes of those states: identical equations, fewer operations.  (Suggested
for the core: the same cache inside ``Model._mass_update``.)
"""
from __future__ import annotations

import numpy as np

from uvsim.model import Model


class SamModel(Model):
    """:class:`Model` with a cached mass update (same arguments as :class:`Model`)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._mass_slices = [self.state_slices[i] for i, t in enumerate(self.terms)
                             if t.changes_mass and i in self.state_slices]
        self._mass_key = None
        self._mass_val = None

    def _mass_update(self, t, y, pos, R, nu, nu_r, u):
        key = b"".join(np.ascontiguousarray(y[:, s]).tobytes() for s in self._mass_slices)
        if key == self._mass_key:
            return self._mass_val
        val = super()._mass_update(t, y, pos, R, nu, nu_r, u)
        self._mass_key, self._mass_val = key, val
        return val


def make_model(vehicle, n: int = 1, overrides=None, **kwargs) -> SamModel:
    """A :class:`SamModel` for SAM commands (``input_kind="thrust"``)."""
    return SamModel(vehicle, overrides, n=n, input_kind="thrust", **kwargs)
