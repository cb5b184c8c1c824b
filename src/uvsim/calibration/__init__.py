"""Calibration of vehicle models against logged runs (issues 5, 7, 14).

* :class:`Calibrator` - seed 000's DEAP genetic algorithm per DOF (Table 3 parameter
  groups, Table 4 settings; batched, optionally distributed, checkpointed) for runs
  marked with one DOF, then one joint windowed prediction-error fit of every training
  run (marked and mixed, :mod:`uvsim.fitting`) with uncertainty, identifiability and
  free-parameter control (:mod:`uvsim.calibration.selection`); each stage set up from its
  settings in :mod:`uvsim.calibration.stages`.
* :func:`simulate_dataset`, :func:`prepare_runs`, :func:`simulate_rows` - batched
  simulation of logged runs (shared with diagnosis).
* :mod:`uvsim.calibration.estimators` - seed 002's least-squares, recursive
  least-squares, steady-state and sinusoidal-test estimators.
"""
from uvsim.calibration.batching import RunBatch, as_batch, prepare_runs, simulate_dataset, simulate_rows  # noqa: F401
from uvsim.calibration.calibrator import Calibrator  # noqa: F401
from uvsim.calibration.params import DOF_PARAMETERS, EFFECTIVE_INERTIA  # noqa: F401
