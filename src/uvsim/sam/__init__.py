"""The SAM hydrobatic AUV (seed 003, Bhat, Stenius & Miao 2021, sec. II-B and V).

Modules:

* :mod:`uvsim.sam.buildup` - the component build-up damping term ``component_buildup``
  (per-component lookup tables from :mod:`uvsim.hydro`, seed 003 eqs. 23-26);
* :mod:`uvsim.sam.subsystems` - actuator subsystems with internal states, limits and
  rates: command inputs, counter-rotating propellers with thrust vectoring, variable
  buoyancy system, LCG moving mass, TCG revolving masses;
* :mod:`uvsim.sam.vehicle` - :func:`load_sam` (the ``sam`` vehicle with a chosen hull
  data set) and the command vector layout :data:`SAM_INPUTS`.

See docs/sam.md.
"""
from __future__ import annotations

__all__ = ["load_sam", "SAM_INPUTS", "DATASETS"]


def __getattr__(name):  # lazy, so that registering the force terms does not import the vehicle loader
    if name in __all__:
        from uvsim.sam import vehicle

        return getattr(vehicle, name)
    raise AttributeError(name)
