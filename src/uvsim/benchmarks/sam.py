"""Benchmark of the SAM model: the accelerating turn of seed 003 Table V in real time.

The accelerating turn (rpm ramp 0 -> 1525 in 30 s, 7 deg yaw vector; uvsim.maneuvers) is
simulated with the full model - component build-up damping from the multifidelity lookup
tables (hull + two NACA 0015 nozzle sections), propulsion/thrust-vectoring dynamics and the
mass-changing trim subsystems - with fixed-step RK4 on one trajectory.  Reported:
simulated seconds per wall second (higher is faster; seed 003 Table V reports a
simulation-time/real-time ratio of 1.2, i.e. a factor 0.83 in these units).
"""
from __future__ import annotations

import time

import numpy as np

DESCRIPTIONS = {
    "sam_realtime_factor": "SAM accelerating turn (30 s, full lookup-table model, RK4 dt = 0.05 s), simulated "
                           "seconds per wall second",
    "sam_realtime_factor_dt10ms": "same at RK4 dt = 0.01 s (the step of the public pure-Python SAM model), "
                                  "simulated seconds per wall second",
    "sam_dt50ms_position_error_m": "largest position difference of the dt = 0.05 s run from a dt = 0.005 s "
                                   "reference over the 30 s accelerating turn, m",
}

BENCH_DT = 0.05


def _timed(dt: float, veh, repeats: int):
    from uvsim.maneuvers import MANEUVERS
    from uvsim.sam.model import make_model
    from uvsim.simulate import simulate

    m = MANEUVERS["accelerating_turn"]
    t = np.arange(0.0, m.duration + 0.5 * dt, dt)
    u = m.commands(t)
    best = np.inf
    res = None
    for _ in range(repeats):
        model = make_model(veh)
        t0 = time.perf_counter()
        res = simulate(veh, t, u, input_kind="thrust", model=model)
        best = min(best, time.perf_counter() - t0)
    return t, res, float(t[-1] / best)


def run(quick: bool = False) -> dict:
    from uvsim.sam.vehicle import load_sam

    veh = load_sam("multifidelity")
    reps = 1 if quick else 3
    t, res, rt = _timed(BENCH_DT, veh, reps)
    _, _, rt10 = _timed(0.01, veh, 1)
    out = {"sam_realtime_factor": rt, "sam_realtime_factor_dt10ms": rt10}
    if not quick:
        tr, ref, _ = _timed(0.005, veh, 1)
        P = res.position
        Pr = np.stack([np.interp(t, tr, ref.position[:, k]) for k in range(3)], 1)
        out["sam_dt50ms_position_error_m"] = float(np.abs(P - Pr).max())
    return out
