"""Calibration of vehicle models against logged runs (issue 5, issue 7).

* :class:`Calibrator` - seed 000's DEAP genetic algorithm (Table 3 parameter
  groups, Table 4 settings) with batched, optionally distributed evaluation,
  checkpoints, a least-squares refinement, uncertainty and identifiability.
* :func:`simulate_dataset`, :func:`residuals`, :func:`prepare_runs` - batched
  simulation of logged runs (shared with diagnosis).
* :mod:`uvsim.calibration.estimators` - seed 002's least-squares, recursive
  least-squares, steady-state and sinusoidal-test estimators.
"""
from uvsim.calibration.batching import RunBatch, as_batch, prepare_runs, residuals, simulate_dataset, simulate_rows  # noqa: F401
from uvsim.calibration.calibrator import Calibrator  # noqa: F401
from uvsim.calibration.params import DOF_PARAMETERS, EFFECTIVE_INERTIA  # noqa: F401
