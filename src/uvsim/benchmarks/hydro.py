"""Benchmark of the hydrodynamic table lookup (cost per call, as used 4x per RK4 step per component)."""
from __future__ import annotations

import time

import numpy as np

DESCRIPTIONS = {
    "hydro_lookup_us": "HydroTable.lookup, one scalar (alpha, Re) call on the REMUS 100 table "
                       "(21 Re x 361 alpha), microseconds per call",
    "hydro_lookup_batch_us": "HydroTable.lookup on a batch of 1000 (alpha, Re) pairs, microseconds "
                             "per pair",
    "hydro_build_table_ms": "build + makima-smooth the REMUS 100 multifidelity table (21 x 361), ms",
}


def run(quick: bool = False) -> dict:
    from uvsim.hydro.assembly import build_body_table

    t0 = time.perf_counter()
    table = build_body_table("remus100")
    build_ms = (time.perf_counter() - t0) * 1e3
    rng = np.random.default_rng(0)
    n = 2000 if quick else 20000
    alpha = rng.uniform(-np.pi, np.pi, n)
    re = 10.0 ** rng.uniform(5.0, 7.0, n)
    al, rl = alpha.tolist(), re.tolist()
    for a, r in zip(al[:100], rl[:100]):  # warm-up
        table.lookup(a, r)
    t0 = time.perf_counter()
    for a, r in zip(al, rl):
        table.lookup(a, r)
    scalar_us = (time.perf_counter() - t0) / n * 1e6
    reps = 20 if quick else 200
    a_b, r_b = alpha[:1000], re[:1000]
    table.lookup(a_b, r_b)
    t0 = time.perf_counter()
    for _ in range(reps):
        table.lookup(a_b, r_b)
    batch_us = (time.perf_counter() - t0) / (reps * 1000) * 1e6
    return {"hydro_lookup_us": scalar_us, "hydro_lookup_batch_us": batch_us, "hydro_build_table_ms": build_ms}
