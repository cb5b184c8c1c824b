"""Bad inputs, case by case (issue 47, "a user's first hour", part 2): numeric options against
physical ranges, vehicle-file unit slips, log values no sensor gives, and API misuse.

Beyond tests/test_contracts.py, tests/test_fuzz.py and tests/test_first_hour.py: each case is
something the commands or the API accepted (a wrong success), changed without a word (a silent
fix), answered with a traceback, or worked on far too long before failing.  Every case ends in

* ``error``: exit status 2 and, as the last line on stderr, ``uvsim CMD: error: ...`` holding the
  fragments listed (the option, file or field, what was expected and what to do), no traceback;
  for the API a :class:`uvsim.errors.UvsimError` subclass holding them.  Where a case marks
  ``before`` (the work that must not start: the GA, the integration, the replay), that work is
  replaced by a function that fails the test: a refusal comes before the work, not after it;
* ``ok``: exit status 0 (a legitimate value next to a refused one: the limit is not too tight),
  with the listed fragments on stderr (a ``note:`` where the reader did not use something);
* ``same``: exit status 0 and the same output as the unchanged input.

The data are the shipped tank runs and vehicle cut to a few seconds (tests/contract_data.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import yaml

import uvsim
from contract_data import shipped_run, shipped_vehicle_text, write_tiny_dataset
from uvsim.cli import main
from uvsim.errors import CalibrationError, LogFormatError, SimulationError, UvsimError, VehicleError

TLOG = Path(uvsim.__file__).parent / "data" / "external" / "ardusub-log-tools-samples" / "small.tlog"
#: a 4 x 1 GA without the joint stage: every calibrate case is refused before it anyway
CAL = ["--vehicle", "bluerov2_heavy_initial", "--population", "4", "--generations", "1", "--no-refine",
       "--keep-worse", "--no-progress"]
DIAG = ["--only", "current", "--max-iter", "3", "--max-effects", "1", "--quiet"]
U1 = "{name: T1_front_right, position: [0.156, 0.111, 0.085], direction: [0.7071068, -0.7071068, 0.0]}"


# ----------------------------------------------------------------------------- builders
def run_file(tmp: Path, change: Callable | None = None, name="run.csv", seconds=4.0) -> Path:
    df = shipped_run("surge_01.csv", seconds)
    p = tmp / name
    (change(df) if change else df).to_csv(p, index=False)
    return p


def raw_run(tmp: Path, data: bytes, name="run.csv") -> Path:
    p = tmp / name
    p.write_bytes(data)
    return p


def csv_text() -> str:
    return shipped_run("surge_01.csv", 4.0).to_csv(index=False)


def vehicle_file(tmp: Path, *edits) -> Path:
    text = shipped_vehicle_text()
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new, 1)
    p = tmp / "veh.yaml"
    p.write_text(text)
    return p


def sim(run, tmp, *extra):
    return ["simulate", "--vehicle", "bluerov2_heavy", "--run", run, "--out", tmp / "sim.csv", *extra]


def calibrate(tmp, *extra, ds=None):
    return ["calibrate", "--data", ds or write_tiny_dataset(tmp / "ds"), *CAL, "--out", tmp / "out" / "fit.yaml",
            *extra]


def diagnose(tmp, *extra):
    return ["diagnose", "--data", write_tiny_dataset(tmp / "ds"), *DIAG, *extra]


def show(p):
    return ["vehicle", "show", p]


def manifest(tmp, edit: Callable[[dict], dict]) -> Path:
    ds = write_tiny_dataset(tmp / "ds")
    doc = yaml.safe_load((ds / "manifest.yaml").read_text())
    (ds / "manifest.yaml").write_text(yaml.safe_dump(edit(doc), sort_keys=False))
    return ds


def first_run(**entry):
    return lambda d: {**d, "runs": [{**d["runs"][0], **entry}] + d["runs"][1:]}


def assign(**cols):
    return lambda d: d.assign(**{k: (v(d) if callable(v) else v) for k, v in cols.items()})


def curve(pwm, thrust):
    return vehicle_file_edit("  curve: t200_16v", f"  curve: {{pwm: {pwm}, thrust: {thrust}}}")


def vehicle_file_edit(old, new):
    return lambda t: show(vehicle_file(t, (old, new)))


# the work a refusal must come before: replaced by a function that fails the test if called
BEFORE = {
    "ga": ("uvsim.calibration.stages", "run_ga"),
    "rk4": ("uvsim.simulate", "_rk4_steps"),
    "replay": ("uvsim.export.replay._Target", "step"),
    "diagnosis": ("uvsim.diagnosis.core", "Selector"),
}


def forbid(monkeypatch, what: str) -> None:
    import importlib

    mod, attr = BEFORE[what]
    owner = importlib.import_module(mod) if "_Target" not in mod else importlib.import_module(
        mod.rsplit(".", 1)[0])._Target

    def refused_too_late(*a, **k):
        raise AssertionError(f"{what} started before the input was checked")

    monkeypatch.setattr(owner, attr, refused_too_late)


@dataclass
class Case:
    id: str
    argv: Callable[[Path], list]   # tmp -> command line
    expect: str                    # error | ok | same
    frags: tuple = ()              # fragments of the error line (error) or of stderr (ok)
    before: str | None = None      # the work the refusal must precede (BEFORE)
    same_as: Callable | None = field(default=None)  # same: tmp -> command line of the unchanged input


CASES = [
    # --- simulate: numeric options ------------------------------------------------------------------
    Case("simulate-substeps-1e8", lambda t: sim(run_file(t), t, "--substeps", "100000000"), "error",
         ("substeps 100000000", "<= 100", "RK4 steps per sample interval"), "rk4"),
    Case("simulate-substeps-101", lambda t: sim(run_file(t), t, "--substeps", "101"), "error",
         ("substeps 101", "<= 100"), "rk4"),
    Case("simulate-substeps-100-ok", lambda t: sim(run_file(t, seconds=0.5), t, "--substeps", "100"), "ok"),
    Case("simulate-initial-window-negative", lambda t: sim(run_file(t), t, "--initial-window=-1"), "error",
         ("--initial-window -1", "finite number of seconds >= 0"), "rk4"),
    Case("simulate-initial-window-nan", lambda t: sim(run_file(t), t, "--initial-window", "nan"), "error",
         ("--initial-window nan", ">= 0"), "rk4"),
    Case("simulate-initial-window-inf", lambda t: sim(run_file(t), t, "--initial-window", "inf"), "error",
         ("--initial-window inf", ">= 0"), "rk4"),
    Case("simulate-initial-window-longer-than-run", lambda t: sim(run_file(t), t, "--initial-window", "100"),
         "error", ("--initial-window 100 s is longer than the run", "0.5 s"), "rk4"),
    Case("simulate-initial-window-0.5-ok", lambda t: sim(run_file(t), t, "--initial-window", "0.5"), "ok"),
    # --- calibrate / diagnose: settings refused before the GA or the diagnosis ---------------------------
    Case("calibrate-seed-negative", lambda t: calibrate(t, "--seed=-1"), "error", ("seed -1", ">= 0"), "ga"),
    Case("calibrate-max-iter-zero", lambda t: calibrate(t, "--max-iter", "0"), "error", ("max_iter 0", ">= 1"), "ga"),
    Case("calibrate-max-iter-negative", lambda t: calibrate(t, "--max-iter=-5"), "error", ("max_iter -5",), "ga"),
    Case("calibrate-workers-1000", lambda t: calibrate(t, "--workers", "1000"), "error",
         ("workers 1000", "CPUs", "start-up time"), "ga"),
    Case("calibrate-low-speed-exponent-nan", lambda t: calibrate(t, "--low-speed-exponent", "nan"), "error",
         ("low_speed_exponent", "finite number"), "ga"),
    Case("calibrate-low-speed-exponent-inf", lambda t: calibrate(t, "--low-speed-exponent", "inf"), "error",
         ("low_speed_exponent", "finite number"), "ga"),
    Case("calibrate-attitude-lag-1e9", lambda t: calibrate(t, "--attitude-lag", "1e9"), "error",
         ("attitude_lag", "longer than the longest run", "0.01-1 s"), "ga"),
    Case("calibrate-manifest-weight-1e300", lambda t: calibrate(t, ds=manifest(t, first_run(weight=1e300))),
         "error", ("manifest.yaml", "runs[0]", "weight 1e+300", "relative"), "ga"),
    Case("diagnose-workers-1000", lambda t: diagnose(t, "--workers", "1000"), "error",
         ("workers 1000", "CPUs"), "diagnosis"),
    Case("diagnose-attitude-lag-1e9", lambda t: diagnose(t, "--attitude-lag", "1e9"), "error",
         ("attitude_lag", "longer than the longest run"), "diagnosis"),
    # --- hydro, export, bench, import ----------------------------------------------------------------------
    Case("hydro-rho-specific-gravity", lambda t: ["hydro", "remus100", "--speed", "1", "--rho", "1.025"], "error",
         ("--rho", "not a water density", "give 1025 kg/m^3")),
    Case("hydro-rho-negative", lambda t: ["hydro", "remus100", "--speed", "1", "--rho=-1025"], "error",
         ("--rho", "900..1250 kg/m^3")),
    Case("hydro-rho-nan", lambda t: ["hydro", "remus100", "--speed", "1", "--rho", "nan"], "error",
         ("--rho", "not a water density")),
    Case("hydro-rho-sea-water-ok", lambda t: ["hydro", "remus100", "--speed", "1", "--rho", "1025"], "ok"),
    Case("hydro-speed-negative", lambda t: ["hydro", "remus100", "--speed=-1"], "error",
         ("--speed must be a positive speed in m/s", "-1")),
    Case("hydro-table-n-re-1e8", lambda t: ["hydro", "table", "remus100", "--out", t / "h", "--n-re", "100000000"],
         "error", ("--n-re", "at most 1000")),
    Case("hydro-table-re-max-inf", lambda t: ["hydro", "table", "remus100", "--out", t / "h", "--re-max", "inf"],
         "error", ("--re-max", "finite")),
    Case("export-physics-step-1e-9", lambda t: ["export", "bluerov2_heavy", "--to", "gz-sim", "--out", t / "x.sdf",
                                                "--check", "standard", "--physics-step", "1e-9"], "error",
         ("physics_step 1e-09 s", "6e+10 steps", "at most 1e+06", "0.001 s"), "replay"),
    Case("bench-seed-negative", lambda t: ["bench", "diagnose", "--seed=-1", "--results", t / "b.json"], "error",
         ("--seed -1", ">= 0")),
    Case("bench-workers-1000", lambda t: ["bench", "diagnose", "--workers", "1000", "--results", t / "b.json"],
         "error", ("--workers 1000", "CPUs")),
    Case("import-imu-negative", lambda t: ["import", "ardusub", TLOG, "--out", t / "imp", "--imu=-1"], "error",
         ("--imu", "-1", ">= 0")),
    Case("import-water-specific-gravity", lambda t: ["import", "ardusub", TLOG, "--out", t / "imp", "--water",
                                                     "1.025"], "error", ("water density", "give 1025 kg/m^3")),
    # --- vehicle files ------------------------------------------------------------------------------------
    Case("vehicle-rho-g-per-cm3", vehicle_file_edit("  rho: 1000.0 ", "  rho: 1.0 "), "error",
         ("veh.yaml", "environment.rho", "not a water density", "give 1000 kg/m^3")),
    Case("vehicle-rho-g-per-m3", vehicle_file_edit("  rho: 1000.0 ", "  rho: 1000000.0 "), "error",
         ("veh.yaml", "environment.rho", "900..1250 kg/m^3")),
    Case("vehicle-rho-sea-water-ok", vehicle_file_edit("  rho: 1000.0 ", "  rho: 1025.0 "), "ok"),
    Case("vehicle-g-ft-per-s2", vehicle_file_edit("  g: 9.81 ", "  g: 32.17 "), "error",
         ("veh.yaml", "environment.g = 32.17", "ft/s^2")),
    Case("vehicle-g-cm-per-s2", vehicle_file_edit("  g: 9.81 ", "  g: 981 "), "error",
         ("veh.yaml", "environment.g = 981", "m/s^2")),
    Case("vehicle-added-mass-indefinite", vehicle_file_edit(
        "  X_udot: 15.638", "  matrix: [[15.6, 20, 0, 0, 0, 0], [20, 16.4, 0, 0, 0, 0], [0, 0, 16.7, 0, 0, 0], "
                            "[0, 0, 0, 0.157, 0, 0], [0, 0, 0, 0, 0.165, 0], [0, 0, 0, 0, 0, 0.133]]\n  X_udot: 15.638"),
         "error", ("veh.yaml", "added_mass", "M_A is not positive semi-definite", "off-diagonal")),
    Case("vehicle-thruster-name-twice", vehicle_file_edit("T2_front_left", "T1_front_right"), "error",
         ("veh.yaml", "thrusters", "'T1_front_right'", "more than one thruster")),
    Case("vehicle-curve-pwm-in-ms", curve("[1.1, 1.5, 1.9]", "[-40, 0, 50]"), "error",
         ("veh.yaml", "curve", "pwm 1.1", "1000..2000 us", "microseconds")),
    Case("vehicle-curve-pwm-in-percent", curve("[0, 50, 100]", "[-40, 0, 50]"), "error",
         ("veh.yaml", "curve", "pwm 0", "1000..2000 us")),
    Case("vehicle-thruster-without-name-ok", vehicle_file_edit(U1, U1.replace("name: T1_front_right, ", "")), "ok"),
    # --- run files --------------------------------------------------------------------------------------
    Case("run-position-1e30", lambda t: sim(run_file(t, assign(x=lambda d: d.x + 1e30)), t), "error",
         ("run.csv", "column 'x'", "half the Earth's circumference", "local NED position in metres"), "rk4"),
    Case("run-position-utm-northing-ok", lambda t: sim(run_file(t, assign(x=lambda d: d.x + 6.6e6)), t), "ok"),
    Case("run-depth-above-surface", lambda t: sim(run_file(
        t, lambda d: d.drop(columns=["z"]).assign(depth=-d.z - 500.0)), t), "error",
         ("run.csv", "column 'depth'", "above the surface", "negative absolute pressure"), "rk4"),
    Case("run-depth-at-surface-ok", lambda t: sim(run_file(
        t, lambda d: d.drop(columns=["z"]).assign(depth=d.z * 0.0 - 0.05)), t), "ok"),
    Case("run-utf16", lambda t: sim(raw_run(t, csv_text().encode("utf-16")), t), "error",
         ("run.csv", "UTF-16", "save it as UTF-8")),
    Case("run-utf32", lambda t: sim(raw_run(t, csv_text().encode("utf-32")), t), "error",
         ("run.csv", "UTF-32", "save it as UTF-8")),
    Case("run-nul-bytes", lambda t: sim(raw_run(t, b"\x00" * 200), t), "error",
         ("run.csv", "not a text CSV file", "NUL byte")),
    Case("run-utf8-bom-same", lambda t: sim(raw_run(t, b"\xef\xbb\xbf" + csv_text().encode()), t), "same",
         same_as=lambda t: sim(run_file(t, name="plain.csv"), t)),
    Case("run-voltage-millivolts", lambda t: sim(run_file(t, assign(voltage=16000.0)), t), "error",
         ("run.csv", "column 'voltage'", "16000 V", "millivolts"), "rk4"),
    Case("run-voltage-48v-ok", lambda t: sim(run_file(t, assign(voltage=48.0)), t), "ok"),
    Case("run-voltage-empty-column-noted", lambda t: sim(run_file(t, assign(voltage=np.nan)), t), "ok",
         ("note:", "run.csv", "column voltage entirely empty, not used")),
    Case("run-x-empty-column-noted", lambda t: sim(run_file(t, assign(x=np.nan)), t), "ok",
         ("note:", "run.csv", "column x entirely empty, not used")),
    Case("manifest-weight-1e7", lambda t: calibrate(t, ds=manifest(t, first_run(weight=1e7))), "error",
         ("manifest.yaml", "runs[0]", "above 1e+06"), "ga"),
]


def _cli(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_cli(case, tmp_path, capsys, monkeypatch):
    argv = case.argv(tmp_path)
    if case.before:
        forbid(monkeypatch, case.before)
    rc, out, err = _cli(argv, capsys)
    assert "Traceback" not in err, err
    if case.expect == "error":
        assert rc == 2, f"expected a refusal, got rc {rc}; stderr: {err}"
        last = err.strip().splitlines()[-1]
        assert last.startswith(f"uvsim {argv[0]}: error: "), err
        for frag in case.frags:
            assert frag in last, f"{frag!r} not in {last!r}"
        return
    assert rc == 0, err
    for frag in case.frags:
        assert frag in err, f"{frag!r} not in stderr {err!r}"
    if case.expect == "same":
        got = (tmp_path / "sim.csv").read_text()
        assert _cli(case.same_as(tmp_path), capsys)[0] == 0
        assert got == (tmp_path / "sim.csv").read_text()


# ----------------------------------------------------------------------------- API
T = np.arange(0.0, 1.0, 0.02)
PWM = np.full((50, 8), 1500.0)


def _module(name):
    import importlib

    return importlib.import_module(name)


def _sim(**kw):
    return lambda t: uvsim.simulate("bluerov2_heavy", kw.pop("t", T), kw.pop("inputs", PWM), input_kind="pwm", **kw)


def _fit(dataset=None, **settings):
    from uvsim.calibration import Calibrator

    def call(t):
        ds = write_tiny_dataset(t / "ds") if dataset is None else dataset
        return Calibrator(**{"population": 4, "generations": 1, "refine": False, **settings}).fit(
            ds, "bluerov2_heavy_initial")
    return call


API_CASES = {
    # simulate / simulate_batch: a traceback, a silent no-op or a misleading blow-up before
    "simulate-substeps-2.5": (_sim(substeps=2.5), SimulationError, ("substeps 2.5", "whole number")),
    "simulate-substeps-text": (_sim(substeps="2"), SimulationError, ("substeps '2'", "whole number")),
    "simulate-batch-substeps-zero": (lambda t: uvsim.simulate_batch("bluerov2_heavy", T, PWM, input_kind="pwm",
                                                                    substeps=0), SimulationError, ("substeps 0", ">= 1")),
    "simulate-t-text": (_sim(t=["a"] * 50), SimulationError, ("t:", "numbers")),
    "simulate-pos0-two-numbers": (_sim(pos0=[0.0, 0.0]), SimulationError, ("pos0", "3 finite numbers", "(2,)")),
    "simulate-nu0-nan": (_sim(nu0=[np.nan, 0, 0, 0, 0, 0]), SimulationError, ("nu0", "non-finite")),
    "simulate-current-30": (_sim(current=[30.0, 0.0, 0.0]), SimulationError, ("current", "30 m/s is faster")),
    "simulate-override-text": (_sim(overrides={"X_u": "a"}), VehicleError, ("parameter X_u", "'a'")),
    "simulate-rtol-negative": (_sim(method="RK45", rtol=-1.0), SimulationError, ("rtol -1.0", "positive tolerance")),
    "initial-window-nan": (lambda t: _module("uvsim.simulate").initial_state_from_run(
        uvsim.logs.read_run(run_file(t)), window_s=float("nan")), SimulationError, ("initial window nan", ">= 0")),
    "thrust-table-in-ms": (lambda t: _module("uvsim.thrusters").load_thrust_curve(
        {"pwm": [1.1, 1.5, 1.9], "thrust": [-4, 0, 5]}), VehicleError, ("pwm 1.1", "1000..2000 us")),
    # Calibrator: wrong keyword types and ranges, refused before the GA
    "calibrator-dofs-number": (_fit(dofs=123), CalibrationError, ("dofs 123", "names")),
    "calibrator-free-number": (_fit(free=5), CalibrationError, ("free 5", "names")),
    "calibrator-margin-text": (_fit(margin="0.5"), CalibrationError, ("margin", "expected a number", "'0.5'")),
    "calibrator-margin-none": (_fit(margin=None), CalibrationError, ("margin", "expected a number")),
    "calibrator-bounds-list": (_fit(bounds=[1, 2]), CalibrationError, ("bounds", "expected a mapping")),
    "calibrator-weights-list": (_fit(signal_weights=[1]), CalibrationError, ("weights", "expected a mapping")),
    "calibrator-noise-text": (_fit(noise="depth=0.01"), CalibrationError, ("noise", "expected a mapping")),
    "calibrator-dataset-number": (_fit(dataset=5), CalibrationError, ("dataset", "got int 5")),
    "calibrator-mutation-sigma-nan": (_fit(mutation_sigma=float("nan")), CalibrationError,
                                      ("mutation_sigma", "finite")),
    "calibrator-refine-text": (_fit(refine="no"), CalibrationError, ("refine 'no'", "True or False")),
    "calibrator-seed-negative": (_fit(seed=-1), CalibrationError, ("seed -1", ">= 0")),
    "calibrator-workers-million": (_fit(workers=10 ** 6), CalibrationError, ("workers 1000000", "CPUs")),
    "calibrator-max-iter-zero": (_fit(max_iter=0), CalibrationError, ("max_iter 0", ">= 1")),
    "diagnose-workers-million": (lambda t: _module("uvsim.diagnosis.core").diagnose(write_tiny_dataset(t / "ds"), workers=10 ** 6),
                                 CalibrationError, ("workers 1000000", "CPUs")),
    "read-run-voltage-millivolts": (lambda t: uvsim.logs.read_run(run_file(t, assign(voltage=14800.0))),
                                    LogFormatError, ("run.csv", "column 'voltage'", "14800 V")),
}


@pytest.mark.parametrize("name", list(API_CASES))
def test_bad_input_api(name, tmp_path, monkeypatch):
    call, err, frags = API_CASES[name]
    forbid(monkeypatch, "ga")
    with pytest.raises(err) as info:
        call(tmp_path)
    assert isinstance(info.value, UvsimError)
    for frag in frags:
        assert frag in str(info.value), f"{frag!r} not in {info.value}"


def test_case_count():
    """Issue 47 asks for at least 50 new bad-input cases."""
    assert len(CASES) + len(API_CASES) >= 50


def test_shipped_vehicles_pass_the_new_limits():
    """The water densities, gravities, added-mass matrices, thruster names and curves of every
    shipped vehicle are within the limits above (a limit too tight would refuse them)."""
    for name in uvsim.vehicle.builtin_vehicles():
        uvsim.load_vehicle(name)
