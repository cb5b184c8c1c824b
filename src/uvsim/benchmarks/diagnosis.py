"""Benchmark: ``uvsim diagnose`` wall time (issue 10).

* ``diagnose_timing_s``: issue 10's timing configuration (``uvsim.scenarios`` profile
  ``issue10_timing``: 48 step-then-reverse runs and a spiral, 14 s at 50 Hz, force inputs,
  one undeclared effect), default settings, 2 worker processes; target at most 30 s on
  2 cores.  With ``quick=True`` the same runs cut to 6 s.
* ``diagnose_tank_tether_s``: the shipped tethered tank dataset
  (``data/datasets/bluerov2_tank_tether``, 24 runs of 14 s at 50 Hz) with
  ``bluerov2_heavy``, 2 workers; skipped with ``quick=True``.

The randomized accuracy benchmark is ``uvsim bench diagnose`` (:mod:`uvsim.benchmarks.scenarios`).
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

#: Scenario seed of the timing configuration (its effect is drawn from it).
TIMING_SEED = 0
WORKERS = 2


def describe(quick: bool = False) -> dict:
    dur = 6 if quick else 14
    out = {"diagnose_timing_s": f"diagnose issue 10's timing dataset (49 runs, {dur} s at 50 Hz, force inputs, one "
                                f"effect; scenario seed {TIMING_SEED}), {WORKERS} workers, wall seconds"}
    if not quick:
        out["diagnose_tank_tether_s"] = ("diagnose the shipped tethered tank dataset (24 runs of 14 s at 50 Hz) "
                                         f"with bluerov2_heavy, {WORKERS} workers, wall seconds")
    return out


DESCRIPTIONS = describe(False)


def run(quick: bool = False) -> dict:
    import uvsim
    from uvsim.diagnosis import diagnose
    from uvsim.scenarios import generate, sample_scenario

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        over = {"duration": 6.0} if quick else {}
        data = generate(sample_scenario(TIMING_SEED, profile="issue10_timing", **over), Path(tmp) / "d")
        t0 = time.perf_counter()
        diagnose(data, workers=WORKERS)
        out["diagnose_timing_s"] = time.perf_counter() - t0
    if not quick:
        path = Path(uvsim.__file__).parent / "data" / "datasets" / "bluerov2_tank_tether"
        t0 = time.perf_counter()
        diagnose(path, "bluerov2_heavy", workers=WORKERS)
        out["diagnose_tank_tether_s"] = time.perf_counter() - t0
    return out
