"""Core simulator speed: single-trajectory RK4 steps/s and batched vehicle-steps/s."""
from __future__ import annotations

import os
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

#: (single-trajectory samples, batch trajectories, batch samples) of the full and quick runs.
SIZES = {False: (3001, 2880, 701), True: (601, 480, 201)}


def describe(quick: bool = False) -> dict:
    """Descriptions of the figures, with the problem sizes of this mode."""
    n_single, n, n_t = SIZES[quick]
    batch = ("GA-sized batch (60 parameter sets x 8 runs x 6 DOFs = 2880 trajectories" if not quick
             else f"QUICK batch ({n} trajectories")
    return {
        "single_rk4_steps_per_s": f"single-trajectory RK4 steps per second (BlueROV2 Heavy, PWM inputs, 50 Hz, "
                                  f"{n_single - 1} steps)",
        "batched_vehicle_steps_per_s": f"batched RK4 vehicle-steps per second, {batch}, {(n_t - 1) * 0.02:g} s at "
                                       "50 Hz), split over all cores",
        "batched_vehicle_steps_per_s_1core": "the same batch on one core",
    }


DESCRIPTIONS = describe(False)


def _inputs(n: int, n_t: int, seed: int = 0):
    from uvsim.synthetic import tank_test_pwm, BLUEROV2_HEAVY_PATTERNS

    rng = np.random.default_rng(seed)
    t = np.arange(n_t) * 0.02
    dofs = list(BLUEROV2_HEAVY_PATTERNS)
    U = np.stack([tank_test_pwm(dofs[i % 6], 40 + 80 * rng.random(), t, sign=1 if i % 2 else -1) for i in range(n)])
    return t, U


def _batch(args):
    n, n_t, seed = args
    import uvsim

    t, U = _inputs(n, n_t, seed)
    rng = np.random.default_rng(seed)
    # one parameter set per trajectory, as in a GA generation (+-20 % around Table 5)
    veh = uvsim.load_vehicle("bluerov2_heavy")
    p = veh.parameters()
    ov = {k: p[k] * rng.uniform(0.8, 1.2, n) for k in ("I_xx", "I_yy", "I_zz", "X_udot", "Y_vdot", "Z_wdot",
                                                          "K_pdot", "M_qdot", "N_rdot", "X_u", "Y_v", "Z_w",
                                                          "X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")}
    t0 = time.perf_counter()
    uvsim.simulate_batch(veh, t, U, input_kind="pwm", overrides=ov)
    return time.perf_counter() - t0


def single_rk4(n_t: int = 3001) -> float:
    import uvsim

    veh = uvsim.load_vehicle("bluerov2_heavy")
    t, U = _inputs(1, n_t)
    uvsim.simulate(veh, t[:50], U[0, :50], input_kind="pwm")  # warm-up
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        uvsim.simulate(veh, t, U[0], input_kind="pwm")
        best = min(best, time.perf_counter() - t0)
    return (n_t - 1) / best


def batched(n: int = 2880, n_t: int = 701, workers: int | None = None) -> tuple[float, float]:
    workers = workers or os.cpu_count() or 1
    _batch((64, 20, 0))  # warm-up
    one = _batch((n, n_t, 1))
    rate_1 = n * (n_t - 1) / one
    if workers == 1:
        return rate_1, rate_1
    chunks = [(n // workers + (i < n % workers), n_t, 1 + i) for i in range(workers)]
    with ProcessPoolExecutor(workers) as ex:
        list(ex.map(_batch, [(8, 10, 0)] * workers))  # start the workers
        t0 = time.perf_counter()
        list(ex.map(_batch, chunks))
        wall = time.perf_counter() - t0
    return n * (n_t - 1) / wall, rate_1


def run(quick: bool = False) -> dict:
    n_single, n, n_t = SIZES[quick]
    single = single_rk4(n_single)
    multi, one = batched(n, n_t)
    return {"single_rk4_steps_per_s": single, "batched_vehicle_steps_per_s": multi,
            "batched_vehicle_steps_per_s_1core": one}
