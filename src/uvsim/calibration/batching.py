"""Simulate many logged runs (times many parameter sets) in one batched call.

:class:`RunBatch` holds a list of :class:`uvsim.logs.Run` padded to a common
length: shorter runs repeat their last time stamp (zero-length RK4 steps, see
:func:`uvsim.simulate_batch`) and their last input.  Each run's initial state is
built from what it measured (partial initial state, issue 7):

* position: each logged axis smoothed over the first :data:`INITIAL_WINDOW_S`
  seconds (quadratic fit evaluated at the first sample), 0 for axes not logged
  (they are not compared either);
* attitude: the same for the (unwrapped) Euler angles, level when none is logged;
* velocities / rates: the first logged sample where present; where absent,
  ``initial_velocity="zero"`` (default, seed 000: runs start at rest),
  ``"differentiate"`` (a Savitzky-Golay derivative of the smoothed logged
  positions / attitude at the start, :func:`uvsim.estimation.derivatives`) or a
  value given per run (e.g. estimated with the parameters by the refinement).

:func:`simulate_dataset` and :func:`simulate_rows` are the entry points used by
calibration (the GA) and diagnosis.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from uvsim.errors import CalibrationError, SimulationError
from uvsim.initial_state import INITIAL_WINDOW_S, initial_state_from_run
from uvsim.simulate import simulate_batch
from uvsim.vehicle import load_vehicle

@dataclass
class RunBatch:
    """Runs padded to one length, ready for :func:`uvsim.simulate_batch`.

    Attributes
    ----------
    runs : the runs, in order.
    t : (R, L) times, s (padded by repeating the last time).
    inputs : (R, L, k) inputs (padded by repeating the last row).
    lengths : (R,) true number of samples of each run.
    input_kind : shared input kind ("force", "thrust" or "pwm").
    pos0, q0, nu0 : (R, 3), (R, 4), (R, 6) initial states.
    nu0_known : (R, 6) bool, which initial velocity components were logged.
    measured : per run, its measured signals (:func:`signals_from_run`).
    voltage : (R, L) battery voltages (V, held; padded like the inputs; NaN for runs
        that logged none, i.e. nominal voltage), or None when no run logged one.
    """

    runs: list
    t: np.ndarray
    inputs: np.ndarray
    lengths: np.ndarray
    input_kind: str
    pos0: np.ndarray
    q0: np.ndarray
    nu0: np.ndarray
    nu0_known: np.ndarray
    measured: list = field(repr=False)
    voltage: np.ndarray | None = None

    @property
    def n_runs(self) -> int:
        return len(self.runs)

    @property
    def names(self) -> list[str]:
        return [r.name for r in self.runs]

    def subset(self, index: Sequence[int]) -> "RunBatch":
        """The batch of runs ``index`` (padding kept as is)."""
        idx = np.asarray(index, int)
        return RunBatch([self.runs[i] for i in idx], self.t[idx], self.inputs[idx], self.lengths[idx],
                        self.input_kind, self.pos0[idx], self.q0[idx], self.nu0[idx], self.nu0_known[idx],
                        [self.measured[i] for i in idx], None if self.voltage is None else self.voltage[idx])


def signals_from_run(run) -> dict[str, np.ndarray]:
    """A run's logged signals by kind of state: "position" (n, 3), "quaternion" (n, 4),
    "velocity" (n, 3), "rates" (n, 3), for the groups it logged (NaN for absent axes and
    missing samples).  Plumbing for the batch's start states, not a measure: runs are compared
    through :mod:`uvsim.measurements` and :mod:`uvsim.metrics`."""
    out: dict[str, np.ndarray] = {}
    groups = run.signals()
    if "position" in groups:
        out["position"] = run.position
    if "attitude" in groups:
        out["quaternion"] = run.quaternion
    vel = run.velocity
    if "velocity" in groups:
        out["velocity"] = vel[:, :3]
    if "rates" in groups:
        out["rates"] = vel[:, 3:]
    return out


def signals_from_states(y: np.ndarray) -> dict[str, np.ndarray]:
    """Simulated states ``y`` (..., n, n_y) as the signals of :func:`signals_from_run`
    (columns as in :mod:`uvsim.model`: position 0:3, quaternion 3:7, nu 7:13)."""
    y = np.asarray(y)
    return {"position": y[..., 0:3], "quaternion": y[..., 3:7], "velocity": y[..., 7:10], "rates": y[..., 10:13]}


def initial_state(run, *, initial_velocity: str = "zero", window_s: float = INITIAL_WINDOW_S, sensors=None):
    """(pos0 (3,), q0 (4,), nu0 (6,), nu0_known (6,) bool) of one run, with the start
    smoothed over :data:`INITIAL_WINDOW_S` (:func:`uvsim.initial_state.initial_state_from_run`;
    ``sensors``: sensor positions, for the depth of a pressure sensor)."""
    try:
        return initial_state_from_run(run, initial_velocity=initial_velocity, window_s=window_s, sensors=sensors)
    except SimulationError as exc:
        raise CalibrationError(str(exc)) from None


def prepare_runs(runs: Sequence, *, initial_velocity: str = "zero", sensors=None) -> RunBatch:
    """Pad ``runs`` (:class:`uvsim.logs.Run`) into a :class:`RunBatch` (``sensors``: the
    vehicle's sensor positions, used for the initial depth of a pressure sensor).

    All runs must share one input kind and input count (they are simulated in
    one call); raises :class:`CalibrationError` otherwise or for an empty list."""
    runs = list(runs)
    if not runs:
        raise CalibrationError("no runs to simulate (empty list; check the dataset's dof/split selection)")
    kinds = {(r.input_kind, r.inputs.shape[1]) for r in runs}
    if len(kinds) > 1:
        detail = ", ".join(f"{r.name}: {r.input_kind} x{r.inputs.shape[1]}" for r in runs)
        raise CalibrationError(f"runs mix input kinds/counts and cannot share one batch ({detail})")
    kind = runs[0].input_kind
    lengths = np.array([len(r.t) for r in runs])
    L = int(lengths.max())
    k = runs[0].inputs.shape[1]
    T = np.empty((len(runs), L))
    U = np.empty((len(runs), L, k))
    V = np.full((len(runs), L), np.nan) if any(r.voltage is not None for r in runs) else None
    P0, Q0, N0, K0 = [], [], [], []
    for i, r in enumerate(runs):
        n = lengths[i]
        T[i, :n] = r.t
        T[i, n:] = r.t[-1]
        U[i, :n] = r.inputs
        U[i, n:] = r.inputs[-1]
        if V is not None and r.voltage is not None:
            V[i, :n] = r.voltage
            V[i, n:] = r.voltage[-1]
        p, q, nu, kn = initial_state(r, initial_velocity=initial_velocity, sensors=sensors)
        P0.append(p), Q0.append(q), N0.append(nu), K0.append(kn)
    return RunBatch(runs, T, U, lengths, kind, np.array(P0), np.array(Q0), np.array(N0), np.array(K0),
                    [signals_from_run(r) for r in runs], V)


def simulate_rows(vehicle, batch: RunBatch, run_index: np.ndarray, overrides: Mapping[str, np.ndarray] | None = None,
                  nu0: np.ndarray | None = None, model=None, acceleration: bool = False):
    """Simulate rows: row ``j`` is run ``run_index[j]`` with parameter values
    ``overrides[name][j]``.

    Parameters
    ----------
    vehicle : Vehicle (or name/file).
    batch : the runs.
    run_index : (N,) int, which run each row simulates.
    overrides : name -> float or (N,) array.
    nu0 : optional (N, 6) initial velocities replacing the batch's.
    acceleration : also return the accelerations ``nu_dot`` (N, L, 6) (accelerometer models).

    Returns
    -------
    y : (N, L, n_y) states (NaN rows for diverged simulations); only the first
    ``batch.lengths[run_index[j]]`` samples of row j are meaningful; ``(y, nu_dot)``
    with ``acceleration=True``.
    """
    idx = np.asarray(run_index, int)
    res = simulate_batch(vehicle, batch.t[idx], batch.inputs[idx], input_kind=batch.input_kind,
                         pos0=batch.pos0[idx], q0=batch.q0[idx],
                         nu0=batch.nu0[idx] if nu0 is None else nu0,
                         overrides=overrides, on_blowup="nan", model=model, return_acceleration=acceleration,
                         voltage=None if batch.voltage is None else batch.voltage[idx])
    return (res.y, res.nu_dot) if acceleration else res.y


def _with_effects(vehicle, effects):
    veh = load_vehicle(vehicle)
    return veh.with_effects(list(effects)) if effects else veh


def simulate_dataset(vehicle, runs, overrides: Mapping[str, float] | None = None, effects=None, *,
                     initial_velocity: str = "zero") -> list[dict[str, np.ndarray]]:
    """Simulate every run of ``runs`` (a list of Runs, a Dataset or a RunBatch)
    with one parameter set, in one batched call.

    Parameters
    ----------
    vehicle : Vehicle, built-in name or file.
    runs : list of :class:`uvsim.logs.Run`, a :class:`uvsim.logs.Dataset` or a :class:`RunBatch`.
    overrides : named parameter values (floats) replacing the vehicle's.
    effects : extra force terms (dicts or ForceTerm objects) added to the vehicle.

    Returns
    -------
    list, one per run, of predicted signals (:func:`signals_from_states`)
    cut to the run's length, plus ``"states"`` (n, n_y) and ``"t"`` (n,).
    """
    batch = as_batch(runs, initial_velocity=initial_velocity)
    veh = _with_effects(vehicle, effects)
    y = simulate_rows(veh, batch, np.arange(batch.n_runs), overrides)
    out = []
    for i in range(batch.n_runs):
        n = batch.lengths[i]
        d = signals_from_states(y[i, :n])
        d["states"] = y[i, :n]
        d["t"] = batch.t[i, :n]
        out.append(d)
    return out


def as_batch(runs, *, initial_velocity: str = "zero") -> RunBatch:
    """A :class:`RunBatch` from a RunBatch, a Dataset (all runs) or a list of Runs."""
    if isinstance(runs, RunBatch):
        return runs
    if hasattr(runs, "runs") and not isinstance(runs, (list, tuple)):
        runs = runs.runs
    return prepare_runs(runs, initial_velocity=initial_velocity)
