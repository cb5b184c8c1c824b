"""Close the loop: residuals -> candidate effects -> refit -> before/after.

``diagnose(data, vehicle)`` (:mod:`uvsim.diagnosis.core`) finds which effects of the
catalogue a model lacks, by forward selection: screen every candidate variant
(:mod:`uvsim.diagnosis.candidates`) by equation error, fit the best through the
simulator (:mod:`uvsim.fitting`), keep one only if it improves the validation runs
significantly (block bootstrap), refit everything chosen, repeat; then report the
error before and after.  ``uvsim diagnose`` is its command line.

Its modules: the catalogue (:mod:`~uvsim.diagnosis.candidates`, the thruster units'
variants in :mod:`~uvsim.diagnosis.units`) and the fits' starts
(:mod:`~uvsim.diagnosis.starts`); the acceptance of one fitted effect
(:mod:`~uvsim.diagnosis.decision`); the runs and the fits through the simulator
(:mod:`~uvsim.diagnosis.simulator_fits`); the equation-error screening (its least squares in
:mod:`~uvsim.diagnosis.regression`) and the forward step (:mod:`~uvsim.diagnosis.selector`);
which candidate a step keeps and whether earlier ones stay (:mod:`~uvsim.diagnosis.step_choice`),
and which form of a faulty thruster unit (:mod:`~uvsim.diagnosis.unit_choice`); the "not
explained" verdict (:mod:`~uvsim.diagnosis.residual`) and the report
(:mod:`~uvsim.diagnosis.summary`).
"""
from __future__ import annotations

from uvsim.lazy_imports import lazy_getattr

#: Imported when first used (PEP 562): the command line reads the catalogue's names
#: (``uvsim.diagnosis.candidates``) without importing the diagnosis itself.
_LAZY = {"Diagnosis": "uvsim.diagnosis.core", "diagnose": "uvsim.diagnosis.core",
         "save_fixed_vehicle": "uvsim.diagnosis.summary"}
__all__ = list(_LAZY)

__getattr__ = lazy_getattr(__name__, _LAZY)
