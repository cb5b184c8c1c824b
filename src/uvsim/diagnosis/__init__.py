"""Close the loop: residuals -> candidate effects -> refit -> before/after.

``diagnose(data, vehicle)`` (:mod:`uvsim.diagnosis.core`) finds which effects of the
catalogue a model lacks, by forward selection: screen every candidate variant
(:mod:`uvsim.diagnosis.candidates`) by equation error, fit the best through the
simulator (:mod:`uvsim.fitting`), keep one only if it improves the validation runs
significantly (block bootstrap), refit everything chosen, repeat; then report the
error before and after.  ``uvsim diagnose`` is its command line.
"""
from __future__ import annotations

from uvsim.diagnosis.core import Diagnosis, diagnose, save_fixed_vehicle  # noqa: F401
