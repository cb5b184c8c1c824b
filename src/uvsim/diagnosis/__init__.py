"""Close the loop: residuals -> signatures -> catalogue effects -> refit -> before/after.

``diagnose(data, vehicle)`` (:mod:`uvsim.diagnosis.core`) answers which effect of
the catalogue (:mod:`uvsim.effects`) a model lacks, fits its parameters and
reports the validation error before and after; ``uvsim diagnose`` is its command
line.  Building blocks: :mod:`~uvsim.diagnosis.residuals` (output and
inverse-dynamics force residuals), :mod:`~uvsim.diagnosis.signatures` (residual
shape tests), :mod:`~uvsim.diagnosis.candidates` (what is fitted per effect),
:mod:`~uvsim.diagnosis.fit` (least squares and the BIC score).
"""
from __future__ import annotations

from uvsim.diagnosis.core import Diagnosis, diagnose, save_fixed_vehicle  # noqa: F401
from uvsim.diagnosis.residuals import force_residual, noise_levels, output_residuals  # noqa: F401
from uvsim.diagnosis.signatures import evidence  # noqa: F401
