"""The joint stage of a calibration: one windowed prediction-error fit of every training
run (:func:`uvsim.fitting.fit`), with an excitation screen, a checkpoint and a progress bar.

:func:`run_joint` frees ``keep`` (always) plus the ``screen`` candidates that the data
excite (:func:`uvsim.calibration.selection.excitation` at the start values), then fits
them together with every run's window-start states and gyro biases (the nuisance).

Checkpoint (:class:`JointCheckpoint`): one file holding the screen's outcome and the
fit's state, written atomically after the screen, after every accepted
Levenberg-Marquardt step and after every continuation stage; a fit resumed from it
continues where it stopped (finished stages and iterations are not redone) and gives
the result of an uninterrupted fit.
"""
from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from uvsim.calibration.selection import EXCITATION_REL_SIGMA, excitation, information
from uvsim.checkpoint import Checkpoint
from uvsim.errors import CalibrationError
from uvsim.fitting import fit, make_space
from uvsim.fitting.fitter import build_problems
from uvsim.progress import as_progress

log = logging.getLogger("uvsim")
#: What a resumed calibration must keep equal (for the mismatch message).
MUST_MATCH = ("--data, --vehicle, --dof, --free/--fix/--bounds, --weights, --noise, --horizons, --continuity "
              "and the GA settings")


def joint_checkpoint_path(path) -> Path:
    """The joint stage's checkpoint file beside a calibration checkpoint ``path``."""
    return Path(f"{path}.joint")


class JointCheckpoint:
    """Checkpoint file of the joint stage (module docstring), on the shared
    :class:`uvsim.checkpoint.Checkpoint` (atomic writes, problem fingerprint, "resuming
    from ..."): one envelope holding the screen's outcome and the fit's state.

    Parameters
    ----------
    path : file written after every step (None: no saving).
    key : fingerprint of the problem (vehicle, runs, settings); a saved state of another
        problem is refused.
    resume : file to continue from (None: start afresh).
    """

    def __init__(self, path, key: str, resume=None):
        self._out = None if path is None else Checkpoint(path, kind="joint", key=key, what="the joint stage",
                                                         must_match=MUST_MATCH)
        self._doc = {"screen": None, "fit": None}
        if resume is not None and Path(resume).is_file():
            doc = Checkpoint(resume, kind="joint", key=key, what="the joint stage", must_match=MUST_MATCH).load()
            self._doc = {"screen": doc.get("screen"), "fit": doc.get("fit")}

    @property
    def screen(self):
        return self._doc["screen"]

    def save_screen(self, screen: dict) -> None:
        self._doc["screen"] = screen
        self._write("screen done")

    # the protocol of uvsim.fitting.fit(checkpoint=...)
    def load(self):
        return self._doc["fit"]

    def save(self, state, *, progress: str = "") -> None:
        self._doc["fit"] = state
        self._write(progress)

    def _write(self, progress: str) -> None:
        if self._out is not None:
            self._out.save(dict(self._doc), progress=progress)


def run_joint(vehicle, runs, meas, params, *, keep, screen, bounds, horizons, max_iter: int, gyro_bias: bool,
              attitude_bias: bool = False, acc_bias: bool = False, initial_velocity: str = "zero", workers: int = 1,
              checkpoint: JointCheckpoint | None = None,
              progress=False, prior_mean=None, prior_sd=None, loss: str = "linear",
              continuity=(1.0,), ftol: float = 1e-6, stage_meas=None, label: str = "joint fit"):
    """Screen and fit (module docstring).

    Parameters
    ----------
    vehicle : the model at the start values (GA results applied).
    runs, meas : training runs and their measurement models.
    params : ``vehicle.parameters()``.
    keep : names freed whatever the screen says; screen : candidates freed if excited.
    bounds : {name: (low, high)} for every name of ``keep`` and ``screen``.
    horizons, max_iter, gyro_bias, attitude_bias, acc_bias, initial_velocity, workers : see
        :func:`uvsim.fitting.fit`.
    prior_mean, prior_sd : {name: value} (every parameter) and {name: sd} (some): the prior
        of :func:`uvsim.fitting.fit` (None: no prior).
    loss : "linear" or "huber" (:func:`uvsim.fitting.fit`).
    continuity : continuity factors of the last horizon's stages (:func:`uvsim.fitting.fit`).
    ftol : relative cost decrease below which a stage stops (:func:`uvsim.fitting.fit`).
    stage_meas : the measurement models of each stage (:func:`uvsim.fitting.fit`).
    progress, label : the screen and the fit as stages named after ``label``
        (:func:`uvsim.progress.as_progress`: True a tqdm bar of the iterations).

    Returns
    -------
    (FitResult or None when nothing is free, screen report {"relative_sigma": {name:
    value}, "not_excited": [names], "threshold": EXCITATION_REL_SIGMA})
    """
    progress = as_progress(progress)
    keep, screen = list(keep), [k for k in screen if k not in keep]
    report = {"relative_sigma": {}, "not_excited": [], "threshold": EXCITATION_REL_SIGMA}
    if screen:
        saved = checkpoint.screen if checkpoint is not None else None
        if saved is None:
            with progress.stage(f"excitation screen of {len(keep + screen)} parameters on {len(runs)} runs"):
                space = make_space(params, keep + screen, bounds=bounds)
                probs, _ = build_problems(vehicle, runs, meas, space, horizons[0], space.z0, gyro_bias=gyro_bias,
                                          attitude_bias=attitude_bias, acc_bias=acc_bias,
                                          initial_velocity=initial_velocity, loss=loss)
                rel = excitation(space, information(probs, space.z0, workers))
            saved = {"relative_sigma": {k: rel[k] for k in screen},
                     "not_excited": [k for k in screen if not rel[k] <= EXCITATION_REL_SIGMA]}
            if checkpoint is not None:
                checkpoint.save_screen(saved)
        report.update(saved)
    names = [k for k in params if k in keep or (k in screen and k not in report["not_excited"])]
    if not names:
        return None, report
    space = make_space(params, names, bounds=bounds)
    n_stages = len(horizons) - 1 + len(continuity)
    name = (f"{label} of {len(names)} parameters on {len(runs)} runs ({n_stages} stage(s) of at most {max_iter} "
            "iterations)")
    with progress.stage(name, total=max_iter * n_stages, unit="it", short=label.split(" (")[0]) as bar:

        def on_it(stage, it, cost):
            bar.set(stage * max_iter + it, stage=f"{stage + 1}/{n_stages}", cost=f"{cost:.5g}")

        res = fit(vehicle, runs, space, meas=meas, horizons=horizons, max_iter=max_iter, gyro_bias=gyro_bias,
                  attitude_bias=attitude_bias, acc_bias=acc_bias, initial_velocity=initial_velocity, workers=workers,
                  checkpoint=checkpoint, on_iteration=on_it,
                  progress=lambda msg: log.debug(msg), prior_mean=prior_mean, prior_sd=prior_sd,
                  loss=loss, continuity=continuity, ftol=ftol, stage_meas=stage_meas)
        bar.set(max_iter * n_stages)
        bar.summary = f"{sum(int(s.get('iterations', 0)) for s in res.stages)} iterations"
    if not np.all(np.isfinite(res.z)):
        raise CalibrationError("the joint fit diverged (non-finite parameters)")
    return res, report
