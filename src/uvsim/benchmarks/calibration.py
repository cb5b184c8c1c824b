"""Benchmark: seed 000's whole six-DOF GA calibration (issue 5 "Speed").

6 DOFs x 8 training runs x 60 individuals x 30 generations (Table 4), 14-s runs
at 50 Hz (700 samples), PWM inputs, generated with :mod:`uvsim.synthetic` from
``bluerov2_heavy`` (Table 5) and fitted from ``bluerov2_heavy_initial`` (Table 2),
GA evaluations on 2 local worker processes (``workers=2``).  The figure is the
wall time of the GA (all generations, including the worker start-up); the
joint prediction-error fit after it (not part of the paper's method, 2 workers) is
timed separately and the whole fit as ``calibration_total_s``.  ``quick=True`` runs 5
generations of 20 individuals instead.
"""
from __future__ import annotations

import time

#: (population, generations) of the full (the paper's Table 4) and quick runs.
SIZES = {False: (60, 30), True: (20, 5)}


def describe(quick: bool = False) -> dict:
    """Descriptions of the figures, with the GA size of this mode."""
    pop, gens = SIZES[quick]
    what = "seed 000's six-DOF GA calibration" if not quick else "QUICK six-DOF GA calibration (not the paper's size)"
    return {
        "paper_calibration_s": f"{what} (6 DOFs x 8 runs x {pop} individuals x {gens} generations, "
                               "14-s runs at 50 Hz) on 2 worker processes, wall seconds of the GA",
        "paper_calibration_refine_s": "uvsim's joint windowed prediction-error fit after that GA (2 workers), "
                                      "wall seconds",
        "calibration_total_s": "whole Calibrator.fit of that setup: GA + joint fit + report, wall seconds",
        "paper_calibration_evaluations": "fitness evaluations (individual x DOF) the GA made (unchanged offspring "
                                         "are not re-evaluated), count",
    }


DESCRIPTIONS = describe(False)


def run(quick: bool = False, workers: int = 2) -> dict:
    from uvsim.calibration import Calibrator
    from uvsim.synthetic import generate_runs

    runs, _ = generate_runs("bluerov2_heavy", runs_per_dof=8, validation_per_dof=0, duration=14.0, rate=50.0,
                            seed=0)
    pop, gens = SIZES[quick]
    cal = Calibrator(population=pop, generations=gens, seed=0, workers=workers)
    t0 = time.perf_counter()
    cal.fit(runs, "bluerov2_heavy_initial")
    total = time.perf_counter() - t0
    rep = cal.report_
    return {"paper_calibration_s": float(rep["ga_seconds"]),
            "paper_calibration_refine_s": float(rep["refine_seconds"]),
            "paper_calibration_evaluations": float(rep["evaluations"]),
            "calibration_total_s": float(total)}
