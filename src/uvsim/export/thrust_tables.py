"""The thrust curve a model used, as the PWM -> thrust table a target can hold, and its check.

Neither target evaluates uvsim's curves itself:

* gz-sim's ``Thruster`` system takes a thrust command in newtons and only clamps it to
  ``[min_thrust_cmd, max_thrust_cmd]`` (gz-sim ``src/systems/thruster/Thruster.cc:517-526``,
  commit 93bbf3ed1bd2); its only curve is ``T = rho C_t D^4 w|w|`` for propeller speed
  commands (lines 562-599), which no linear PWM -> speed map turns into a T200 curve with
  its dead band and unequal branches.  So the export writes the thrust commands' table
  into the plugin block (``<uvsim_pwm_to_thrust>``, ignored by gz-sim) for the bridge that
  turns ESC PWM into thrust commands, and the replay reads it from there.
* UUV Simulator's ``LinearInterp`` conversion interpolates a table linearly and holds its
  end values outside it (``ThrusterConversionFcn.cc:268-297``, commit bfb40cb15368): the
  same table goes into ``<inputValues>``/``<outputValues>``.

:func:`curve_knots` gives the knots at which uvsim's piecewise-linear curves bend, so that
linear interpolation between them reproduces the curve exactly (at its nominal voltage);
:func:`thrust_table_check` measures it.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import VehicleError


def curve_knots(curve) -> tuple[np.ndarray, np.ndarray]:
    """PWM knots (us) and thrust (N) of ``curve`` at its nominal voltage.

    * tabulated curve: its table plus the dead-band edges (the curve interpolates to 0 there,
      :class:`uvsim.thrust_curves.TabulatedThrustCurve`);
    * linear curve: ``pwm_min``, the dead band's edges, ``pwm_max``;
    * battery-aware curve: its PWM grid with the nominal voltage's sheet (bilinear, so
      linear in PWM between grid points at a fixed voltage).
    Any other curve is refused (a table could only approximate it)."""
    from uvsim.thrust_curves import LinearThrustCurve, TabulatedThrustCurve
    from uvsim.voltage_curves import VoltageThrustCurve

    if isinstance(curve, TabulatedThrustCurve):
        pwm = np.union1d(np.asarray(curve.table_pwm, float), np.asarray(curve.deadband, float))
    elif isinstance(curve, LinearThrustCurve):
        pwm = np.unique([curve.pwm_min, *curve.deadband, curve.pwm_max])
    elif isinstance(curve, VoltageThrustCurve):
        pwm = np.asarray(curve.table_pwm, float)
    else:
        raise VehicleError(f"thrust curve {getattr(curve, 'name', curve)!r} ({type(curve).__name__}) has no "
                           "piecewise-linear form to export as a table")
    return pwm, np.asarray(curve.thrust(pwm), float)


def thrust_table_check(curve, pwm, thrust, *, step: float = 1.0) -> dict:
    """Compare a target's table (``pwm``, ``thrust``, interpolated linearly and held at its
    ends, as both targets do) with uvsim's ``curve`` at every ``step`` us over the curve's
    range and at the knots.

    Returns ``{"max_error_N", "at_pwm"}`` at the nominal voltage and, for a battery-aware
    curve, ``{"voltage_error_N", "at_voltage"}``: the largest difference between the
    nominal table and the curve at the other measured voltages (what a target without a
    voltage input misses unless its bridge applies the voltage)."""
    p = np.union1d(np.arange(curve.pwm_min, curve.pwm_max + 0.5 * step, step), np.asarray(pwm, float))
    p = p[(p >= curve.pwm_min) & (p <= curve.pwm_max)]
    table = np.interp(p, np.asarray(pwm, float), np.asarray(thrust, float))
    err = np.abs(table - curve.thrust(p))
    i = int(np.argmax(err))
    out = {"max_error_N": float(err[i]), "at_pwm": float(p[i])}
    if getattr(curve, "voltage_dependent", False):
        worst, at = 0.0, float(curve.nominal_voltage)
        for v in curve.voltages:
            e = float(np.max(np.abs(curve.thrust(p, np.full(p.shape, v)) - table)))
            if e > worst:
                worst, at = e, float(v)
        out.update(voltage_error_N=worst, at_voltage=at)
    return out


def thrust_range(curve) -> tuple[float, float]:
    """Smallest and largest thrust (N) of ``curve`` over its PWM range and, for a
    battery-aware curve, all its measured voltages (the clamp a target must not undercut)."""
    p = np.arange(curve.pwm_min, curve.pwm_max + 0.5, 1.0)
    if getattr(curve, "voltage_dependent", False):
        T = np.concatenate([curve.thrust(p, np.full(p.shape, v)) for v in curve.voltages])
    else:
        T = curve.thrust(p)
    return float(min(T.min(), curve.max_reverse)), float(max(T.max(), curve.max_forward))


def table_warnings(vehicle, target: str) -> list[str]:
    """Warnings for thrust curves a target's table does not reproduce exactly (module docstring)."""
    out = []
    curves = vehicle.actuators.curves or []
    for name, curve in zip(vehicle.actuators.names, curves):
        pwm, thrust = curve_knots(curve)
        chk = thrust_table_check(curve, pwm, thrust)
        if chk["max_error_N"] > 1e-9:
            out.append(f"{name}: the {target} thrust table differs from uvsim's curve by up to "
                       f"{chk['max_error_N']:.3g} N (at {chk['at_pwm']:g} us)")
        if chk.get("voltage_error_N", 0.0) > 1e-9:
            out.append(f"{name}: curve {curve.name!r} depends on the battery voltage; the {target} table is its "
                       f"{curve.nominal_voltage:g} V sheet, {chk['voltage_error_N']:.3g} N away from the "
                       f"{chk['at_voltage']:g} V sheet"
                       + (": the PWM bridge must apply the run's voltage (uvsim export --to json has every sheet)"
                          if target == "gz-sim" else ": UUV Simulator's LinearInterp has no voltage input"))
    return out


def file_thrust_check(vehicle, parsed: dict, target: str) -> list[dict]:
    """Each exported thruster's table, read back from the file (``parsed``), against the
    vehicle's curve (:func:`thrust_table_check`), and whether the target's clamp keeps the
    curve's whole range: ``[{"name", "max_error_N", "at_pwm", "clamp_ok", ...}]``."""
    curves = vehicle.actuators.curves or []
    out = []
    for name, curve, th in zip(vehicle.actuators.names, curves, parsed.get("thrusters", [])):
        if "pwm" not in th:
            continue
        chk = thrust_table_check(curve, th["pwm"], th["thrust"])
        lo, hi = thrust_range(curve)
        if target == "gz-sim":
            clamp = (th.get("min", -np.inf), th.get("max", np.inf))
        else:
            clamp = th["limits"]
            chk["clamp_ok_pwm"] = bool(th["clamp"][0] <= curve.pwm_min and th["clamp"][1] >= curve.pwm_max)
        chk.update(name=name, clamp_ok=bool(clamp[0] <= lo + 1e-12 and clamp[1] >= hi - 1e-12))
        out.append(chk)
    return out


def describe_thrust_check(rows: list[dict], curves) -> str:
    """One line for the CLI: the largest table error and any clamp that cuts the curve."""
    if not rows:
        return "thrust tables: none in the file (no thrusters with a PWM curve)"
    worst = max(rows, key=lambda r: r["max_error_N"])
    c = curves[0]
    text = (f"thrust tables: {len(rows)} thrusters, largest difference from uvsim's curves {worst['max_error_N']:.3g} N "
            f"({worst['name']} at {worst['at_pwm']:g} us; every 1 us over {c.pwm_min:g}..{c.pwm_max:g} us)")
    bad = [r["name"] for r in rows if not r["clamp_ok"] or not r.get("clamp_ok_pwm", True)]
    if bad:
        text += f"; the target's clamp cuts the curve of {', '.join(bad)}"
    volt = [r for r in rows if r.get("voltage_error_N", 0.0) > 1e-9]
    if volt:
        v = max(volt, key=lambda r: r["voltage_error_N"])
        text += (f"; the nominal table is {v['voltage_error_N']:.3g} N from the {v['at_voltage']:g} V sheet "
                 "(battery-aware curve)")
    return text
