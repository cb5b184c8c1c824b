"""Benchmark: the docs' real-log command and ``uvsim diagnose`` on a dataset the size of a 2-run,
100 Hz real log (issue 46's figures).

The dataset comes from the independent scenario generator (:mod:`uvsim.scenarios`, profile
``realsensor``): 2 training and 2 validation runs of 35 s, an IMU at 100 Hz, roll and pitch from an
attitude filter, the depth of a pressure sensor at 10 Hz, PWM inputs; the truth's hydrodynamics
perturbed by up to 30 % (:data:`SCENARIO`).  It stands in for the issue's real log, which is not
ours to ship.  Figures, each the command run in this process with 2 workers, as a user types it:

* ``real_log_command_s``: ``uvsim calibrate --data D --free "z_b,thruster_gain_*,thruster_reverse_*"
  --latency auto --supply-voltage auto --trade-off explore --workers 2`` (docs/calibration.md, "Real
  logs"), wall seconds of the whole command;
* ``real_log_joint_stage_s``: its joint fit's first stage (``refinement.stages[0].seconds`` of the
  report), issue 46's "joint stage";
* ``real_log_diagnose_s``: ``uvsim diagnose --data D --workers 2``, wall seconds.

``quick=True``: runs of 10 s.  Not in a plain ``uvsim bench`` (half a minute);
``uvsim bench --only real-log``.
"""
from __future__ import annotations

import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

#: The dataset: ``sample_scenario(seed, profile="realsensor", **rest)``.
SCENARIO = dict(seed=100, n_runs=2, n_validation=2, duration=35.0, rate_hz=100.0, perturbation=0.3)
QUICK = dict(duration=10.0)
WORKERS = 2
#: The docs' real-log command (docs/calibration.md, "Real logs"), without the data and output paths.
COMMAND = ["--free", "z_b,thruster_gain_*,thruster_reverse_*", "--latency", "auto", "--supply-voltage", "auto",
           "--trade-off", "explore", "--workers", str(WORKERS), "--no-progress"]
DEFAULT = False


def describe(quick: bool = False) -> dict:
    size = "2 + 2 runs of 10 s (QUICK)" if quick else "2 + 2 runs of 35 s"
    return {
        "real_log_command_s": f"the docs' real-log calibrate command on a realsensor dataset ({size}, IMU at 100 Hz, "
                              f"PWM), {WORKERS} workers, wall seconds",
        "real_log_joint_stage_s": "its joint fit's first stage (refinement.stages[0].seconds), seconds",
        "real_log_diagnose_s": f"uvsim diagnose on the same dataset, {WORKERS} workers, wall seconds",
    }


DESCRIPTIONS = describe(False)


def make_dataset(out_dir, *, quick: bool = False) -> Path:
    """Generate the dataset into ``out_dir``; returns its directory."""
    from uvsim.scenarios import generate, sample_scenario

    kw = dict(SCENARIO)
    seed = kw.pop("seed")
    if quick:
        kw.update(QUICK)
    return Path(generate(sample_scenario(seed, profile="realsensor", **kw), Path(out_dir)))


def _command(argv: list, report: Path) -> float:
    """Wall seconds of ``uvsim argv`` run in this process (its printed output discarded); a command
    that wrote no ``report`` (its ``--json``: an error, not a verdict) raises."""
    from uvsim.cli import main
    from uvsim.errors import UvsimError

    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = main([*argv, "--json", str(report)])
    if not report.exists():
        raise UvsimError(f"bench real-log: uvsim {argv[0]} exited {code} without a report")
    return time.perf_counter() - t0


def run(quick: bool = False) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        data = make_dataset(tmp / "real_log", quick=quick)
        out = {"real_log_command_s": _command(["calibrate", "--data", str(data), *COMMAND, "--out",
                                               str(tmp / "fitted.yaml")], tmp / "calibrate.json")}
        rep = json.loads((tmp / "calibrate.json").read_text())
        out["real_log_joint_stage_s"] = float(rep["refinement"]["stages"][0]["seconds"])
        out["real_log_diagnose_s"] = _command(["diagnose", "--data", str(data), "--workers", str(WORKERS),
                                               "--no-progress"], tmp / "diagnose.json")
    return out
