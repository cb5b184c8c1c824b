"""Benchmark: ``uvsim diagnose`` wall time (issue 6).

* ``diagnose_small_s``: a synthetic dataset with a tether the model lacks, 6 DOFs x
  (2 training + 1 validation) runs of 10 s at 10 Hz (the size of the test cases),
  every catalogue candidate fitted (one process).
* ``diagnose_tank_s``: the shipped tank dataset (``data/datasets/bluerov2_tank``: 48
  training + 12 validation runs of 14 s at 50 Hz) with ``bluerov2_heavy``; skipped
  with ``quick=True``.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

DESCRIPTIONS = {
    "diagnose_small_s": "diagnose a 18-run synthetic dataset (10 s at 10 Hz, a tether the model lacks), all "
                        "candidates, wall seconds",
    "diagnose_tank_s": "diagnose the shipped tank dataset (60 runs of 14 s at 50 Hz) with bluerov2_heavy, wall seconds",
}


def run(quick: bool = False) -> dict:
    from uvsim.diagnosis import diagnose
    from uvsim.synthetic import generate_dataset

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        ds = generate_dataset("bluerov2_heavy", Path(tmp) / "d", runs_per_dof=2, validation_per_dof=1, duration=10.0,
                              rate=10.0, signals=("position", "mocap_attitude"), seed=1,
                              effects=[{"type": "tether", "anchor_n": -4.0, "anchor_e": 1.0, "anchor_d": -1.0,
                                        "stiffness": 0.3}])
        t0 = time.perf_counter()
        diagnose(ds, "bluerov2_heavy")
        out["diagnose_small_s"] = time.perf_counter() - t0
    if not quick:
        import uvsim

        path = Path(uvsim.__file__).parent / "data" / "datasets" / "bluerov2_tank"
        t0 = time.perf_counter()
        diagnose(path, "bluerov2_heavy")
        out["diagnose_tank_s"] = time.perf_counter() - t0
    return out
