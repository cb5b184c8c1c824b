"""Issue 47 (part): what a new user tried in the first hour that the commands accepted,
fixed in silence or answered with a traceback; each is now refused in one line naming what is
wrong and what to do (exit 2), before any work."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

import uvsim
from contract_data import SHIPPED_DATASET, shipped_vehicle_text, write_tiny_dataset
from uvsim.cli import main
from uvsim.errors import CalibrationError, LogFormatError, SimulationError, VehicleError
from uvsim.logs import read_dataset

TLOG = Path(uvsim.__file__).parent / "data" / "external" / "ardusub-log-tools-samples" / "small.tlog"
RUN = SHIPPED_DATASET / "heave_01.csv"


def _one_line_error(capsys, *needles):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in err, err
    return err


# ----------------------------------------------------------------------------- files
def test_a_key_twice_in_a_vehicle_file_or_manifest_is_refused(tmp_path):
    text = shipped_vehicle_text()
    veh = tmp_path / "veh.yaml"
    veh.write_text(text + "\nname: another\n")  # YAML would keep the second 'name'
    with pytest.raises(VehicleError, match=r"duplicate key 'name' \(first at line \d+\)"):
        uvsim.load_vehicle(veh)
    ds = write_tiny_dataset(tmp_path / "ds")
    m = ds / "manifest.yaml"
    m.write_text(m.read_text() + "vehicle: bluerov2_heavy_initial\n")
    with pytest.raises(LogFormatError, match="duplicate key 'vehicle'"):
        read_dataset(ds)
    # the same text without the repeat loads
    veh.write_text(text)
    assert uvsim.load_vehicle(veh).name


def test_load_vehicle_of_none_names_what_it_expects():
    with pytest.raises(VehicleError, match="expected a built-in vehicle name, a vehicle file's path or a Vehicle, "
                                           "got NoneType"):
        uvsim.load_vehicle(None)


def test_a_thruster_direction_that_is_not_a_unit_vector_is_refused_not_normalised(tmp_path):
    text = shipped_vehicle_text()
    d = yaml.safe_load(text)
    units = d["thrusters"]["units"]
    bad = dict(units[0], direction=[2.0 * x for x in units[0]["direction"]])
    d["thrusters"]["units"] = [bad] + units[1:]
    with pytest.raises(VehicleError, match=r"thrusters.units\[0\].direction: .* has length 2; expected a unit vector"):
        uvsim.vehicle.vehicle_from_dict(d, source="veh.yaml")
    # written to 4 digits (0.7071) it is a unit vector within the tolerance
    d["thrusters"]["units"] = [dict(units[0], direction=[0.7071, 0.7071, 0.0])] + units[1:]
    uvsim.vehicle.vehicle_from_dict(d, source="veh.yaml")


# ----------------------------------------------------------------------------- simulate
@pytest.mark.parametrize("how", ["same", "dot", "symlink", "other_dir"])
def test_simulate_never_overwrites_its_input_run(tmp_path, monkeypatch, capsys, how):
    work = tmp_path / "w"
    work.mkdir()
    run = work / "R.csv"
    run.write_bytes(RUN.read_bytes())
    monkeypatch.chdir(work)
    out = {"same": "R.csv", "dot": "./R.csv", "other_dir": "../w/R.csv"}.get(how)
    if how == "symlink":
        (work / "link.csv").symlink_to(run)
        out = "link.csv"
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", "R.csv", "--out", out]) == 2
    _one_line_error(capsys, "is the input file --run", "choose another name")
    assert run.read_bytes() == RUN.read_bytes()


def test_a_current_faster_than_any_water_current_is_refused(tmp_path, capsys):
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(RUN), "--current", "30,0,0",
                 "--out", str(tmp_path / "s.csv")]) == 2
    _one_line_error(capsys, "30 m/s is faster than any current", "(at most 5 m/s)")
    assert not (tmp_path / "s.csv").exists()
    d = yaml.safe_load(shipped_vehicle_text())
    d.setdefault("environment", {})["current_ned"] = [0.0, 12.0, 0.0]
    with pytest.raises(VehicleError, match="environment.current_ned .* 12 m/s is faster"):
        uvsim.vehicle.vehicle_from_dict(d, source="veh.yaml")
    # a real current passes
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(RUN), "--current", "0.5,0.2,0",
                 "--out", str(tmp_path / "s.csv")]) == 0


@pytest.mark.parametrize("method, hint", [("bogus", ""), ("rk45", "did you mean 'RK45'?")])
def test_an_unknown_integration_method_is_named_without_scipy_internals(tmp_path, capsys, method, hint):
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(RUN), "--method", method,
                 "--out", str(tmp_path / "s.csv")]) == 2
    err = _one_line_error(capsys, f"method {method!r}: unknown", hint, "RK45, RK23, DOP853, Radau, BDF, LSODA")
    assert "<class" not in err


def test_a_closed_pipe_ends_the_command_quietly():
    """``uvsim vehicle show X | head``: the reader leaves; no "Broken pipe" error, exit 141."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(uvsim.__file__).parents[1]),
                                                        os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen([sys.executable, "-m", "uvsim.cli", "vehicle", "show", "bluerov2_heavy"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # the reader is gone before the first write
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141
    assert "Broken pipe" not in err and "Traceback" not in err and "Exception ignored" not in err, err


# ----------------------------------------------------------------------------- maneuver
@pytest.mark.parametrize("extra, needle", [
    (["--dt", "5"], "longer than the fastest actuator time constant (Propulsion.tv, 0.05 s)"),
    (["--duration", "1e7"], "5e+08 samples"),
    (["--dt", "nan"], "need 0 < dt < duration"),
])
def test_maneuver_steps_and_sizes_it_cannot_integrate_are_refused_before_allocating(tmp_path, capsys, extra,
                                                                                     needle):
    assert main(["maneuver", "tight_loop", "--out", str(tmp_path / "m.csv"), *extra]) == 2
    _one_line_error(capsys, needle)
    assert not (tmp_path / "m.csv").exists()


def test_the_limits_come_from_the_vehicle_s_servos():
    from uvsim.maneuvers import load_sam, run_maneuver
    from uvsim.sam.subsystems import servo_time_constants

    taus = servo_time_constants(load_sam("multifidelity"))
    assert taus and min(taus.values()) == pytest.approx(0.05)
    with pytest.raises(SimulationError, match="fastest actuator time constant"):
        run_maneuver("helix", dt=0.051)


# ----------------------------------------------------------------------------- import
def test_a_surface_pressure_in_hpa_is_refused_with_the_pa_value(tmp_path, capsys):
    out = tmp_path / "dive"
    assert main(["import", "ardusub", str(TLOG), "--out", str(out), "--surface-pressure", "1013.25"]) == 2
    _one_line_error(capsys, "surface pressure 1013.25 Pa", "it looks like hPa (mbar): give 101325 Pa")
    assert not out.exists()
    assert main(["import", "ardusub", str(TLOG), "--out", str(out), "--surface-pressure", "101325",
                 "--adapt-vehicle"]) == 0


# ----------------------------------------------------------------------------- fits
def test_a_misspelt_signal_is_refused_before_the_ga_with_the_name_meant(tmp_path, capsys, monkeypatch):
    import uvsim.calibration.stages as stages

    def no_ga(*a, **k):
        raise AssertionError("the GA ran before the settings were checked")

    monkeypatch.setattr(stages, "run_ga", no_ga)
    ds = write_tiny_dataset(tmp_path / "ds")
    assert main(["calibrate", "--data", str(ds), "--weights", "positon=1", "--out", str(tmp_path / "f.yaml")]) == 2
    _one_line_error(capsys, "weights: unknown signal 'positon' (did you mean 'position'?)")
    assert main(["calibrate", "--data", str(ds), "--noise", "dpeth=0.01", "--out", str(tmp_path / "f.yaml")]) == 2
    _one_line_error(capsys, "noise: unknown signal 'dpeth' (did you mean 'depth'?)")


@pytest.mark.parametrize("option", ["--max-iter", "--top", "--workers", "--max-effects"])
def test_diagnose_refuses_counts_below_one(tmp_path, capsys, option):
    ds = write_tiny_dataset(tmp_path / "ds")
    assert main(["diagnose", "--data", str(ds), option, "0", "--quiet"]) == 2
    name = option[2:].replace("-", "_")
    _one_line_error(capsys, f"{name} must be a positive integer (1 or more), got 0")


@pytest.mark.parametrize("setting", [{"population": 4.5}, {"generations": 2.0}, {"workers": 1.5}, {"seed": True}])
def test_calibrator_settings_are_not_truncated(tmp_path, setting):
    from uvsim.calibration import Calibrator

    ds = write_tiny_dataset(tmp_path / "ds")
    name, value = next(iter(setting.items()))
    with pytest.raises(CalibrationError, match=f"{name} {value!r}: expected a whole number"):
        Calibrator(**setting).fit(ds)


# ----------------------------------------------------------------------------- what is printed
def test_compare_on_a_handful_of_samples_says_it_says_little(tmp_path, capsys):
    run = tmp_path / "three.csv"
    run.write_text("".join(RUN.read_text().splitlines(keepends=True)[:4]))
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(run), "--compare",
                 "--plot", str(tmp_path / "c.png")]) == 0
    text = capsys.readouterr()
    assert "Fit %" in text.out and "warning: only 3 samples" in text.err


def test_rmse_lines_are_printed_to_four_digits_with_units():
    from uvsim.commands.calibration_output import _rmse_text

    text = _rmse_text({"depth_m": 0.007502347860412031, "rates_radps": 0.003885595124409449,
                       "position_m": float("nan")})
    assert text == "depth 0.007502 m, rates 0.003886 rad/s, position not finite"


def test_an_inline_curve_is_named_not_printed():
    from uvsim.calibration.supply_voltage import not_applicable

    d = yaml.safe_load(shipped_vehicle_text())
    d["thrusters"]["curve"] = {"pwm": [1100.0 + 10 * i for i in range(81)],
                               "thrust": [0.05 * (i - 40) for i in range(81)]}
    why = not_applicable(uvsim.vehicle.vehicle_from_dict(d, source="veh.yaml"))
    assert "an inline table (pwm, thrust; 81 points)" in why and "1100.0" not in why


@pytest.mark.parametrize("command, option, default", [
    (["calibrate"], "--population", "60"), (["diagnose"], "--top", "3"), (["simulate"], "--substeps", "1"),
    (["maneuver"], "--dataset", "multifidelity"), (["import", "ardusub"], "--imu", "0"),
])
def test_help_shows_the_defaults(capsys, command, option, default):
    with pytest.raises(SystemExit) as e:
        main([*command, "--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    block = out[out.index("\n  " + option) + 1:]
    block = " ".join(block[:block.find("\n  -", 1) if "\n  -" in block[1:] else len(block)].split())
    assert f"default: {default})" in block or f"default {default}" in block, block


def test_help_shows_no_default_for_a_flag(capsys):
    """``--no-progress`` is a flag: "(default: True)" beside it reads as "off by default"."""
    from uvsim.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name, parser in sub.choices.items():
        text = parser.format_help()
        assert "(default: True)" not in text and "(default: False)" not in text, name


@pytest.mark.parametrize("sep, name", [(";", "semicolon"), ("\t", "tab")])
def test_a_csv_with_another_separator_is_named_as_such(tmp_path, capsys, sep, name):
    run = tmp_path / "R.csv"
    run.write_text("".join(line.replace(",", sep) for line in RUN.read_text().splitlines(keepends=True)[:50]))
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(run), "--out", str(tmp_path / "s.csv")]) == 2
    _one_line_error(capsys, f"the file is {name}-separated ({sep!r}); expected comma-separated columns")


def test_positions_in_millimetres_are_refused_naming_the_point():
    d = yaml.safe_load(shipped_vehicle_text())
    units = d["thrusters"]["units"]
    mm = dict(units[2], position=[1000.0 * x for x in units[2]["position"]])
    d2 = {**d, "thrusters": {**d["thrusters"], "units": units[:2] + [mm] + units[3:]}}
    with pytest.raises(VehicleError, match=r"thrusters.units\[2\] \(.*\).position .* m from the body origin, more "
                                           r"than 10 x the vehicle's length scale"):
        uvsim.vehicle.vehicle_from_dict(d2, source="veh.yaml")
    d3 = {**d, "rigid_body": {**d["rigid_body"], "r_b": [0.0, 0.0, -20.0]}}
    with pytest.raises(VehicleError, match=r"rigid_body.r_b \[0.0, 0.0, -20.0\] is 20 m .* expected metres"):
        uvsim.vehicle.vehicle_from_dict(d3, source="veh.yaml")


def test_the_ga_plot_s_best_so_far_never_rises(tmp_path, monkeypatch):
    """The sway logbook of the shipped data: generation best 156.2 -> 238.8 (no elitism); the
    solid curve is the best so far, each generation's best is drawn beside it, labelled."""
    import uvsim.plotting.calibration as pc

    figs = []
    monkeypatch.setattr(pc, "_save", lambda fig, path: figs.append(fig) or Path(path))
    lb = [{"gen": g, "min": m, "avg": 2 * m} for g, m in enumerate([300.0, 156.2, 238.8, 150.0, 170.0])]
    pc.plot_convergence({"sway": lb}, tmp_path / "ga.png")
    ax = figs[0].axes[0]
    solid = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-"][0]
    y = np.asarray(solid.get_ydata())
    assert np.all(np.diff(y) <= 0) and y[-1] == 150.0 and solid.get_label() == "sway best so far"
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"][0]
    assert list(dashed.get_ydata()) == [r["min"] for r in lb]
    assert "best so far" in ax.get_title() and "each generation's best" in ax.get_title()


# ----------------------------------------------------------------------------- centre of buoyancy
def test_a_centre_of_buoyancy_below_the_centre_of_gravity_is_refused(tmp_path, capsys):
    """Before: r_b [0, 0, +0.024] (a sign slip) loaded and the vehicle capsized in simulation."""
    d = yaml.safe_load(shipped_vehicle_text())
    d["rigid_body"]["r_b"] = [0.0, 0.0, 0.024]
    veh = tmp_path / "veh.yaml"
    veh.write_text(yaml.safe_dump(d))
    assert main(["simulate", "--vehicle", str(veh), "--run", str(RUN), "--out", str(tmp_path / "s.csv")]) == 2
    _one_line_error(capsys, "veh.yaml", "rigid_body.r_b", "below the centre of gravity", "z is positive down")
    assert not (tmp_path / "s.csv").exists()


def test_a_fit_keeps_the_centre_of_buoyancy_above_the_centre_of_gravity(tmp_path):
    from uvsim.calibration import Calibrator
    from uvsim.fitting.parameters import cb_not_below_cg, default_bounds

    lo, hi = cb_not_below_cg("z_b", default_bounds("z_b", -0.024, 0.5), {"z_g": 0.0}, {"z_b"})
    assert lo == pytest.approx(-0.074) and hi == 0.0                    # the default range stops at z_g
    assert cb_not_below_cg("z_b", (-0.1, 0.1), {"z_g": 0.0}, {"z_b", "z_g"}) == (-0.1, 0.1)   # both move
    data = write_tiny_dataset(tmp_path / "ds")
    with pytest.raises(CalibrationError, match=r"bounds for z_b \(-0.05, 0.05\) reach below the centre of gravity"):
        Calibrator(free="z_b", bounds={"z_b": (-0.05, 0.05)}, population=4, generations=1).fit(data)


def test_compare_never_writes_beside_the_shipped_run(tmp_path, monkeypatch, capsys):
    """Before: ``simulate --run <shipped run> --compare`` wrote its figure into the installed package."""
    monkeypatch.chdir(tmp_path)
    beside = RUN.with_name(RUN.stem + "_compare.png")
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(RUN), "--compare"]) == 0
    assert (tmp_path / "heave_01_compare.png").is_file() and not beside.exists()
    assert "plot -> heave_01_compare.png" in capsys.readouterr().out


def test_a_voltage_column_the_vehicle_cannot_use_is_said(tmp_path, capsys):
    """Before: a run's voltage with a curve that does not depend on it (t200_16v) was read and
    ignored in silence."""
    from contract_data import shipped_run

    df = shipped_run("heave_01.csv", 4.0)
    df["voltage"] = 15.2
    run = tmp_path / "R.csv"
    df.to_csv(run, index=False)
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(run), "--out", str(tmp_path / "s.csv")]) == 0
    err = capsys.readouterr().err
    assert "the voltage column of R is not used" in err and "voltage_table" in err
