"""Clean interrupts of `uvsim calibrate --workers 2` (issue 13).

Real processes: the command runs in a subprocess on the first seconds of the shipped tank
runs; the test sends SIGKILL, SIGTERM or SIGINT to it and then looks at the process table
(psutil) for anything still running with the test's temporary directory on its command
line.  The kill-and-resume tests kill the command in the GA or in the refinement (watching
the GA checkpoint) and resume it: the fitted vehicle file and the report's numbers must be
identical to those of an uninterrupted run.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from contract_data import write_tiny_dataset
from uvsim.calibration.ga import load_checkpoint
from uvsim.errors import UvsimError

psutil = pytest.importorskip("psutil")

SRC = str(Path(__file__).resolve().parents[1] / "src")
GA = ["--vehicle", "bluerov2_heavy_initial", "--dof", "surge", "--population", "12", "--seed", "4",
      "--workers", "2", "--no-progress"]


def _default_sigint():
    """In the child before exec: SIGINT to its default disposition, as in a terminal. A test
    run started in the background by a shell without job control (``make test &``, ``nohup``)
    inherits SIGINT ignored, Python then installs no KeyboardInterrupt handler, and the
    command would rightly ignore the test's Ctrl-C."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(tmp: Path, ds: Path, out: Path, *extra) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, "-m", "uvsim.cli", "calibrate", "--data", str(ds), *GA, "--out", str(out),
           "--json", str(out.with_suffix(".json")), *extra]
    return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_sigint)


def _ours(tmp: Path) -> list:
    """Processes whose command line names ``tmp`` (the command and anything it started)."""
    found = []
    for p in psutil.process_iter(["cmdline", "status"]):
        try:
            if p.info["status"] != psutil.STATUS_ZOMBIE and any(str(tmp) in a for a in p.info["cmdline"] or ()):
                found.append(p)
        except (psutil.NoSuchProcess, psutil.AccessDenied):
            pass
    return found


def _generation(ckpt: Path):
    try:
        return load_checkpoint(ckpt)["generation"]
    except UvsimError:
        return None


def _left_behind(tmp: Path, recorded=(), timeout=10.0) -> list:
    """What still runs ``timeout`` s after the command ended: processes naming ``tmp`` on
    their command line, and the ``recorded`` processes (e.g. spawned workers)."""
    def alive():
        rec = [p for p in recorded if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
        return _ours(tmp) + rec
    t0 = time.time()
    while alive() and time.time() - t0 < timeout:
        time.sleep(0.05)
    return alive()


def _wait(pred, timeout=60.0, what=""):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = pred()
        if v:
            return v
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def _finish(proc, tmp, timeout=60.0):
    """Wait for ``proc``; whatever happens, nothing started by the test survives it."""
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:  # e.g. orphaned workers holding the pipes open
        for p in _ours(tmp):
            p.kill()
        proc.kill()
        out, err = proc.communicate()
        raise AssertionError(f"the command did not end within {timeout} s; stderr: {err}")
    return out, err


@pytest.fixture
def tiny(tmp_path):
    return write_tiny_dataset(tmp_path / "ds", seconds=5.0)


@pytest.mark.parametrize("sig", [signal.SIGKILL, pytest.param(signal.SIGTERM, marks=pytest.mark.slow), signal.SIGINT],
                         ids=["SIGKILL", "SIGTERM", "SIGINT"])
def test_workers_die_with_the_parent(sig, tiny, tmp_path):
    out = tmp_path / "run" / "fit.yaml"
    proc = _start(tmp_path, tiny, out, "--generations", "500")
    ckpt = Path(str(out) + ".ckpt")
    _wait(lambda: _generation(ckpt) is not None, what="the first GA generation")
    workers = [p for p in psutil.Process(proc.pid).children(recursive=True)]
    assert len(workers) >= 2, "the GA runs on 2 worker processes"
    err = _signal_and_check(proc, sig, tmp_path, workers)
    if sig != signal.SIGKILL:
        assert f"interrupted ({sig.name})" in err and f"--resume {ckpt}" in err


def _signal_and_check(proc, sig, tmp_path, workers) -> str:
    """Send ``sig`` to the command; it ends as the signal says (killed, or exit 143 / 130 without a
    traceback) and leaves nothing of its own running, ``workers`` included.  Returns its stderr."""
    proc.send_signal(sig)
    _, err = _finish(proc, tmp_path)
    if sig == signal.SIGKILL:
        assert proc.returncode == -signal.SIGKILL
    else:
        assert proc.returncode == (143 if sig == signal.SIGTERM else 130), err
        assert "Traceback" not in err
    left = _left_behind(tmp_path, workers)
    assert not left, f"processes left behind: {[p.cmdline() for p in left]}"
    return err


@pytest.mark.parametrize("sig", [pytest.param(signal.SIGKILL, marks=pytest.mark.slow), signal.SIGTERM,
                                 pytest.param(signal.SIGINT, marks=pytest.mark.slow)],
                         ids=["SIGKILL", "SIGTERM", "SIGINT"])
def test_diagnosis_workers_die_with_the_parent(sig, tmp_path):
    """The worker processes a diagnosis keeps for all its fits (uvsim.fitting.worker_pool)."""
    import uvsim

    data = Path(uvsim.__file__).parent / "data" / "datasets" / "bluerov2_tank_tether"
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = [sys.executable, "-m", "uvsim.cli", "diagnose", "--data", str(data), "--vehicle", "bluerov2_heavy",
           "--workers", "2", "--quiet", "--json", str(tmp_path / "report.json")]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_default_sigint)

    def two_workers():
        kids = [p for p in psutil.Process(proc.pid).children(recursive=True) if p.status() != psutil.STATUS_ZOMBIE]
        return kids if len(kids) >= 2 else None

    workers = _wait(two_workers, what="the diagnosis's 2 worker processes")
    _signal_and_check(proc, sig, tmp_path, workers)
    assert not (tmp_path / "report.json").exists()


def _numbers(out: Path) -> dict:
    rep = json.loads(out.with_suffix(".json").read_text())
    keep = ("parameters", "uncertainty", "ga_parameters", "training_rmse", "validation_rmse", "evaluations",
            "generations_run", "identifiability")
    d = {k: rep[k] for k in keep}
    d["logbook"] = {dof: [{k: v for k, v in rec.items() if k != "wall_s"} for rec in lb]
                    for dof, lb in rep["logbook"].items()}
    return d


GENERATIONS = "12"


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The dataset and an uninterrupted run on it."""
    tmp = tmp_path_factory.mktemp("reference")
    ds = write_tiny_dataset(tmp / "ds", seconds=5.0)
    ref = tmp / "ref" / "fit.yaml"
    p = _start(tmp, ds, ref, "--generations", GENERATIONS)
    _, err = _finish(p, tmp)
    assert p.returncode == 0, err
    return ds, ref


@pytest.mark.slow  # end to end: three calibrate processes, one killed (in-process resume: test_calibration_ga.py)
@pytest.mark.parametrize("phase", ["ga", "refinement"])
def test_kill_and_resume_is_bit_identical(phase, reference, tmp_path):
    tiny, ref = reference
    gens = GENERATIONS
    out = tmp_path / "run" / "fit.yaml"
    ckpt = Path(str(out) + ".ckpt")
    p = _start(tmp_path, tiny, out, "--generations", gens)
    if phase == "ga":
        _wait(lambda: (_generation(ckpt) or 0) >= 2, what="GA generation 2")
    else:
        _wait(lambda: _generation(ckpt) == int(gens), what="the end of the GA")
    p.kill()
    _finish(p, tmp_path)
    done = _generation(ckpt)
    assert not out.exists(), "killed before the end"
    assert (done < int(gens)) if phase == "ga" else (done == int(gens))
    assert not _left_behind(tmp_path)

    p = _start(tmp_path, tiny, out, "--generations", gens, "--resume", str(ckpt))
    _, err = _finish(p, tmp_path)
    assert p.returncode == 0, err
    assert f"resuming from {ckpt}: the GA, generation {done} of {gens} done" in err
    assert out.read_text() == ref.read_text()
    assert _numbers(out) == _numbers(ref)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_dask_local_workers_die_with_the_parent(sig, tiny, tmp_path):
    pytest.importorskip("dask.distributed")
    out = tmp_path / "run" / "fit.yaml"
    proc = _start(tmp_path, tiny, out, "--generations", "500", "--dask", "local")
    _wait(lambda: _generation(Path(str(out) + ".ckpt")) is not None, timeout=120, what="the first GA generation")
    workers = psutil.Process(proc.pid).children(recursive=True)
    assert len(workers) >= 2
    proc.send_signal(sig)
    _finish(proc, tmp_path, timeout=120)
    left = _left_behind(tmp_path, workers, timeout=30)
    assert not left, f"processes left behind: {[p.cmdline() for p in left]}"
