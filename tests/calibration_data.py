"""Small synthetic datasets for the calibration tests (imported by tests/test_calibration_*.py).

Generated with the simulator (uvsim.synthetic) from bluerov2_heavy = seed 000 Table 5
("truth") plus Gaussian sensor noise; calibration starts from bluerov2_heavy_initial
(Table 2).  Kept small (4 training runs per DOF, 10 s at 25 Hz) so the fast suite stays fast.
"""
from __future__ import annotations

import functools

from uvsim.fitting.evaluate import open_loop, pooled
from uvsim.synthetic import generate_runs

SMALL = dict(runs_per_dof=4, validation_per_dof=1, duration=10.0, rate=25.0)


@functools.lru_cache(maxsize=None)
def tank_runs(dofs=("surge", "sway", "heave", "roll", "pitch", "yaw"), seed=1, signals=None):
    """(runs, truth) of a small tank dataset; ``signals`` as for generate_runs (tuple or
    tuple of (dof, tuple) pairs)."""
    sig = dict(signals) if signals and isinstance(signals[0], tuple) else signals
    return generate_runs("bluerov2_heavy", dofs=list(dofs), seed=seed, signals=sig, **SMALL)


def truth_rmse(runs, split="validation", vehicle="bluerov2_heavy"):
    """Pooled group RMSEs the true model reaches on ``runs`` of ``split`` (its free simulation as
    every report sees it, :func:`uvsim.fitting.evaluate.open_loop`): the noise floor."""
    return pooled(open_loop(vehicle, [r for r in runs if r.split == split]))
