"""Benchmark: calibration of multi-DOF runs logged by realistic sensors (issue 14).

The dataset comes from the independent scenario generator (:mod:`uvsim.scenarios`,
profile ``realsensor``; its truth model is written apart from uvsim's simulator):
telegraph PWM runs exciting several DOFs at once (``dof: mixed``), an IMU at 100-200 Hz
(gyro with a bias per run, accelerometer with a bias per run), roll and pitch from an
attitude filter with a first-order lag and noise (no yaw), the depth of a pressure
sensor 0.15 m aft at 10 Hz (interpolated onto the log grid), no position; the truth
moves the centre of buoyancy (z_b) and has one weak thruster, and its added mass,
damping and inertia are the nominal ones perturbed by up to +-10 %.  The model vehicle
file beside the manifest has the nominal values and the sensor positions.

One command calibrates it: ``uvsim calibrate --data DIR --free z_b,thruster_gain_K``
(``K`` the weak thruster, known to the user as the logs' authors knew theirs; freeing
every gain leaves a scale that no data without a force reference can fix, which the
identifiability report shows).  Reported: errors against ``truth.yaml`` of the
identifiable quantities, validation Fit % per channel, the noise estimate of the
interpolated depth against its truth, wall seconds serial and with 2 workers (and
whether both give the same result).  Not in the default ``uvsim bench`` set (minutes);
``uvsim bench --only calibrate-realsensor``.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

#: The scenario: seed and overrides of ``uvsim.scenarios.sample_scenario`` (profile realsensor).
SCENARIO = dict(seed=1, effects=["weak_thruster"], perturb_z_b=True, depth_mode="interpolated")
QUICK = dict(n_runs=5, n_validation=1, duration=10.0)
DEFAULT = False  # not run by a plain `uvsim bench`

DESCRIPTIONS = {
    "realsensor_serial_s": "calibrate the realsensor scenario (mixed runs, IMU + lagged roll/pitch + 10 Hz stern depth), "
                           "one process, wall seconds",
    "realsensor_workers2_s": "the same with --workers 2, wall seconds",
    "realsensor_workers_identical": "1 if --workers 2 gave exactly the serial result, else 0",
    "realsensor_worst_identifiable_error_pct": "largest |error| of z_b, the weak gain, the effective inertias, the "
                                               "quadratic and rotational linear damping, %",
}


def _scenarios():
    try:
        from uvsim import scenarios
    except ImportError as exc:
        from uvsim.errors import UvsimError

        raise UvsimError("the realsensor benchmark needs the scenario generator uvsim.scenarios") from exc
    return scenarios


def make_dataset(out_dir, *, quick: bool = False) -> Path:
    """Generate the benchmark dataset into ``out_dir``; returns its directory."""
    sc = _scenarios()
    kw = dict(SCENARIO)
    seed = kw.pop("seed")
    if quick:
        kw.update(QUICK)
    return Path(sc.generate(sc.sample_scenario(seed, profile="realsensor", **kw), out_dir))


def weak_thruster(truth: dict) -> tuple[str, float] | None:
    """(parameter name, true gain) of the truth's weak thruster, if any."""
    for e in truth.get("effects", []):
        if e["type"] == "weak_thruster":
            return f"thruster_gain_{int(e['thruster'])}", float(e["gain"])
    return None


def truth_errors(cal, truth: dict) -> dict:
    """Errors of a fitted :class:`uvsim.calibration.Calibrator` against a scenario's
    ``truth.yaml`` (dict): percent for parameters, rad/s for gyro biases, m/s^2 for
    accelerometer offsets."""
    from uvsim.calibration.params import EFFECTIVE_INERTIA, LINEAR_DAMPING, QUADRATIC_DAMPING

    p = cal.vehicle_.parameters()
    t = dict(truth["coefficients"]["truth"])
    t["m"] = truth["vehicle"]["rigid_body"]["mass"]
    out = {"z_b": 100 * (p["z_b"] / truth["buoyancy"]["z_b_truth"] - 1)}
    weak = weak_thruster(truth)
    if weak is not None:
        out[weak[0]] = 100 * (p[weak[0]] / weak[1] - 1)
    for d, (a, b) in EFFECTIVE_INERTIA.items():
        out[f"{a}+{b}"] = 100 * ((p[a] + p[b]) / (t[a] + t[b]) - 1)
    for k in list(QUADRATIC_DAMPING.values()) + list(LINEAR_DAMPING.values()):
        out[k] = 100 * (p[k] / t[k] - 1)
    for key, unit in (("gyro_bias", "radps"), ("acc_bias", "mps2")):
        err, true = [], []
        for r in truth["runs"]:
            name = r["file"].rsplit(".", 1)[0]
            if name in cal.report_.get(key, {}):
                err.append(np.subtract(cal.report_[key][name], r[key]))
                true.append(r[key])
        if err:
            out[f"{key}_rms_error_{unit}"] = float(np.sqrt(np.mean(np.square(err))))
            out[f"{key}_rms_error_pct_of_rms_bias"] = float(100 * np.sqrt(np.mean(np.square(err)))
                                                            / np.sqrt(np.mean(np.square(true))))
    lag = cal.report_["attitude_lag"]["tau"]
    out["attitude_lag"] = 100 * (lag / truth["sensors"]["euler"]["time_constant"] - 1)
    return out


IDENTIFIABLE = ("z_b", "X_udot+", "Y_vdot+", "Z_wdot+", "K_pdot", "M_qdot", "N_rdot", "X_uu", "Y_vv", "Z_ww",
                "K_pp", "M_qq", "N_rr", "K_p", "M_q", "N_r", "thruster_gain_")


def worst_identifiable(errors: dict) -> float:
    """Largest |error| % over the quantities the data identify (:data:`IDENTIFIABLE`;
    the translational linear damping is not: at these speeds its force is ~1 % of the
    quadratic one)."""
    keys = [k for k in errors if any(k.startswith(p) or p in k for p in IDENTIFIABLE)]
    return float(max(abs(errors[k]) for k in keys))


def calibrate(data, truth: dict, *, workers: int = 1, **kw):
    """Calibrate ``data`` with z_b and the weak thruster's gain free; returns the Calibrator."""
    from uvsim.calibration import Calibrator

    weak = weak_thruster(truth)
    free = "z_b" + (f",{weak[0]}" if weak else "")
    return Calibrator(free=free, workers=workers, **kw).fit(data)


def run(quick: bool = False, workers: int = 2, out_dir=None) -> dict:
    from uvsim.files import safe_load

    with tempfile.TemporaryDirectory() as tmp:
        d = make_dataset(Path(out_dir or tmp) / "realsensor", quick=quick)
        truth = safe_load((d / "truth.yaml").read_text())
        t0 = time.perf_counter()
        serial = calibrate(d, truth)
        t1 = time.perf_counter()
        par = calibrate(d, truth, workers=workers)
        t2 = time.perf_counter()
    errors = truth_errors(serial, truth)
    rep = serial.report_
    depth_sigma = [m["depth"]["sigma"] for m in rep["noise"].values() if "depth" in m]
    out = {"realsensor_serial_s": t1 - t0, "realsensor_workers2_s": t2 - t1,
           "realsensor_workers_identical": float(serial.params_ == par.params_),
           "realsensor_worst_identifiable_error_pct": worst_identifiable(errors),
           "realsensor_depth_noise_ratio": float(np.median(depth_sigma) / truth["sensors"]["depth"]["sigma"])}
    # (the sensor biases' errors carry their own units in their names: not "error_pct_")
    out.update({(f"realsensor_{k}" if k.startswith(("gyro_bias", "acc_bias")) else f"realsensor_error_pct_{k}"): v
                for k, v in errors.items()})
    out.update({f"realsensor_validation_fit_pct_{c}": v for c, v in rep["validation_fit_percent"].items()})
    return out
