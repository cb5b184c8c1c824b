"""The compiled RK4's driver: :func:`uvsim.simulate._rk4_steps`'s contract on the compiled kernel.

The run is cut into chunks of :func:`chunk_length` sample intervals (a multiple of the 16-interval
blow-up check, so the checks fall where the numpy path makes them): per chunk the held
forces are computed by the terms' own numpy code (the thrust curves once per distinct input
history of the whole run), the kernel advances every row, and a blow-up is raised or
progress reported between chunks.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import SimulationError
from uvsim.forces.actuators import distinct_histories

#: Rows x sample intervals per call of the kernel: the held forces of a chunk stay in cache
#: (measured: 960 rows of PWM inputs ran at 1.2 M vehicle-steps/s in chunks of 16 intervals and
#: 0.5 M in chunks of 64), and one trajectory is not cut into thousands of calls.
CHUNK_CELLS = 16384


def chunk_length(n: int) -> int:
    """Sample intervals per kernel call for ``n`` rows: a multiple of 16 (the blow-up check's
    period), at least 16."""
    return max(16, (CHUNK_CELLS // max(n, 1)) // 16 * 16)


def blowup_message(row: int, t: float, speed_max: float) -> str:
    return (f"integration blew up in trajectory {row} by t = {t:.3f} s (non-finite state or speed above "
            f"{speed_max:g}); check the parameters, the inputs or use a smaller step (substeps)")


def rk4_compiled(advance, plan, model, T, U, y0, substeps, on_blowup, progress, V, accel, speed_max):
    """States (n, n_t, 13) as :func:`uvsim.simulate._rk4_steps` returns them.

    With one BLAS thread (:func:`uvsim.blas.single_thread`) for the numpy around the kernel (the
    input histories' fingerprint, the held forces' small products): the kernel is one thread,
    and a second BLAS thread only spins or waits for a core, which made the batched benchmark
    slower on two processes (four threads on two cores) than on one."""
    from uvsim.blas import single_thread

    with single_thread():
        return _rk4_chunks(advance, plan, model, T, U, y0, substeps, on_blowup, progress, V, accel, speed_max)


def _rk4_chunks(advance, plan, model, T, U, y0, substeps, on_blowup, progress, V, accel, speed_max):
    """:func:`rk4_compiled`'s work, chunk by chunk."""
    n, n_t = T.shape
    Y = np.empty((n, n_t, 13))
    Y[:, 0] = y0
    y = np.array(y0, dtype=float, order="C")
    first_bad = np.full(n, -1, dtype=np.int64)
    want_acc = accel is not None
    T = np.ascontiguousarray(T, dtype=float)
    # the thrust curves once per distinct input history (a fit's parameter sets share their runs)
    rows = distinct_histories(U, V) if plan.held and model.input_kind != "force" and n > 1 else None
    no_acc = np.empty((1, 1, 6))
    chunk = chunk_length(n)
    for c0 in range(0, n_t - 1, chunk):
        c1 = min(c0 + chunk, n_t - 1)
        tau = plan.held_forces(U[:, c0:c1], model.input_kind, None if V is None else V[:, c0:c1], rows)
        advance(y, T, tau, plan.TH, substeps, plan.parts, Y, accel if want_acc else no_acc, want_acc, c0, speed_max,
                first_bad)
        if on_blowup == "raise" and (first_bad >= 0).any():
            g = first_bad[first_bad >= 0].min()
            j = int(np.flatnonzero(first_bad == g)[0])
            raise SimulationError(blowup_message(j, T[j, g + 1], speed_max))
        if progress is not None:
            progress.update(c1 - c0)
    if want_acc:
        t_end = T[0, -1] if bool(np.all(T == T[:1])) else T[:, -1]
        accel[:, -1] = model.rhs(t_end, y, U[:, -1], None if V is None else V[:, -1])[:, 7:13]
    return Y
