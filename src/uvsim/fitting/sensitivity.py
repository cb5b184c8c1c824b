"""When the free simulation of a run cannot compare two models.

A model whose free simulation amplifies the uncertainty of its initial state (a
directionally unstable ROV: the Munk moment ``(Y_vdot - X_udot) u v`` above what the yaw
damping holds, Fossen 2021 eq. 6.47) cannot be judged by the error of a free simulation
of a whole run: the error is then set by how far the estimated start is from the true
one, not by the model.  On the calibration benchmark's seed 35 (issue 21) uvsim with the
generator's *true* coefficients, simulated from the start estimated from the log, spun
up in yaw to 1 rad/s on a straight surge run (r Fit % -25516) while the wrong but stable
starting model stayed near 0 (r Fit % -910), and the never-worse check refused a fit 100
times closer to the truth.  Simulation is not a meaningful comparison for unstable
models (Ljung 1999, sec. 16.4-16.6).  Windowed (k-step) prediction was tried instead and
does not rescue such a run: with an e-folding time of 0.7 s, node errors of the size of
a gyro bias grow within 1-3 s windows, and the true coefficients still predicted p 74 %
worse than the stable start over 1 s windows.

:func:`initial_state_growth` simulates a model again from its estimated start with every
initial velocity and rate moved by :data:`PERTURBATION` (the "measured" node prior of
:mod:`uvsim.fitting.nodes`), once each way; when the difference from the nominal
simulation has *grown* over the second half of the run (:data:`GROWTH`) the model is
unstable there and the run's free simulation is set by its start.  The never-worse check
(:func:`uvsim.calibration.report.never_worse`) then leaves that run's attitude, rate,
velocity and acceleration channels out for both models (position and depth, aligned at
the start, are still compared: they integrate the motion rather than amplify it) and
says so.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from uvsim.blas import single_thread
from uvsim.fitting.fitter import group_by_input
from uvsim.fitting.nodes import PRIOR_SIGMA
from uvsim.fitting.parameters import ParameterSpace
from uvsim.fitting.windows import whole_runs
from uvsim.simulate import INITIAL_WINDOW_S, initial_state_from_run

#: Initial velocity / rate perturbation (u, v, w m/s; p, q, r rad/s): the prior sd of a
#: measured node velocity (uvsim.fitting.nodes.PRIOR_SIGMA["measured"]).
PERTURBATION = PRIOR_SIGMA["measured"][6:]
#: Signs of the perturbation per component (u, v, w, p, q, r): fixed and mixed, so that no
#: mode is missed for symmetry; each is applied both ways.
SIGNS = np.array([1.0, -1.0, 1.0, -1.0, 1.0, 1.0])
#: A free simulation is set by its start when the perturbation has grown by more than this
#: factor (largest velocity component, in units of its perturbation) over the second half
#: of the run: a stable model damps it (an ROV's velocity time constants are 1-10 s).
GROWTH = 2.0
#: Signal groups left out of the comparison of such a run (module docstring).
AFFECTED_GROUPS = ("attitude", "rates", "velocity", "acceleration")


def initial_state_growth(vehicle, runs: Sequence, meas: Sequence, evaluations: Sequence[dict], *,
                         initial_velocity: str = "zero", overrides=None) -> dict:
    """Per run name: ``{"unstable": bool, "growth": float, "channels": [...]}`` for
    ``vehicle`` (module docstring): ``growth`` the largest velocity difference over the
    run's second half between a perturbed and the nominal free simulation, in units of the
    perturbation (inf when only a perturbed simulation diverged; NaN, and not unstable,
    when the nominal one did: a diverged model is judged, not excused); ``channels`` the
    run's logged channels of :data:`AFFECTED_GROUPS` (what a comparison should leave out
    when ``unstable``).  ``evaluations``: the runs' free
    simulations (entries with ``states`` (n, n_y), e.g. from
    :func:`uvsim.calibration.report.evaluate_runs`), same order as ``runs``; ``overrides``:
    named parameter values the evaluations were simulated with."""
    runs = list(runs)
    out = {}
    space = ParameterSpace([], vehicle.parameters(), dict(overrides or {}))
    for idx in group_by_input(runs):
        group = [runs[i] for i in idx]
        nu0 = np.array([initial_state_from_run(r, initial_velocity=initial_velocity, window_s=INITIAL_WINDOW_S,
                                               sensors=meas[i].sensors)[2] for r, i in zip(group, idx)])
        # both signs in one batched simulation (the group twice): half the numpy calls
        sensors = [meas[i].sensors for i in idx]
        with single_thread():
            Y, _, _ = whole_runs(vehicle, group + group, sensors + sensors, space, np.zeros(0),
                                 initial_velocity=initial_velocity,
                                 nu0=np.concatenate([nu0 + SIGNS * PERTURBATION, nu0 - SIGNS * PERTURBATION]))
        moved = [Y[:len(group), ..., 7:13], Y[len(group):, ..., 7:13]]
        for j, i in enumerate(idx):
            n = runs[i].t.size
            nominal = np.asarray(evaluations[i]["states"], float)[:n, 7:13]
            with np.errstate(all="ignore"):
                d = np.stack([np.abs(mv[j, :n] - nominal) / PERTURBATION for mv in moved])[:, n // 2:]
            if not np.isfinite(nominal).all():
                # the model's own simulation diverged: that is an error to be judged, not a start
                # to be excused (block_costs gives it a huge one)
                growth = float("nan")
            elif not np.isfinite(d).all():  # only a perturbed simulation diverged
                growth = float("inf")
            else:
                growth = float(d.max())
            m = meas[i]
            chans = [c for g in AFFECTED_GROUPS if g in m.groups for j2, c in enumerate(m.groups[g].channels)
                     if m.used(g)[:, j2].any()]
            out[runs[i].name] = {"unstable": bool(growth > GROWTH), "growth": growth, "channels": chans}
    return out
