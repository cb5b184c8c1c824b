"""Export a vehicle to other simulators (docs/import_export.md).

* ``gz-sim``: SDF with the Hydrodynamics and Thruster systems (:mod:`uvsim.export.gz_sim`);
* ``uuv-simulator``: xacro macros for UUV Simulator's Fossen model and thrusters
  (:mod:`uvsim.export.uuv_simulator`);
* ``json``: the vehicle's numbers in uvsim's own frame and signs, with the thrust
  curves as tables (:func:`vehicle_json`).

The frame conversion is stated once, in :mod:`uvsim.export.frames`.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import damping_matrices

TARGETS = ("gz-sim", "uuv-simulator", "json")


def vehicle_json(vehicle) -> dict:
    """Vehicle numbers in uvsim's conventions (NED/FRD, SNAME, added mass positive,
    damping in the paper sign ``tau_D = D_L nu + D_Q (|nu| * nu)``), thrust curves tabulated."""
    DL, DQ = damping_matrices(vehicle)
    act = vehicle.actuators
    units = (vehicle.raw.get("thrusters") or {}).get("units") or []
    thrusters = []
    for i in range(act.n_thrusters):
        entry = {"name": act.names[i], "allocation_column": act.matrix[:, i].tolist()}
        if i < len(units):
            entry.update(position=[float(x) for x in units[i]["position"]],
                         direction=[float(x) for x in units[i]["direction"]])
        if act.curves:
            c = act.curves[i]
            pwm = np.asarray(getattr(c, "table_pwm", [c.pwm_min, c.pwm_max]), float)
            entry["curve"] = {"name": c.name, "pwm_us": pwm.tolist(), "thrust_N": c.thrust(pwm).tolist()}
            if getattr(c, "voltage_dependent", False):
                entry["curve"].update(nominal_voltage=c.nominal_voltage, voltages=c.voltages.tolist(),
                                      thrust_N_by_voltage=c.table_thrust.tolist())
        thrusters.append(entry)
    return {
        "format": "uvsim vehicle export 1",
        "conventions": "world NED, body FRD (x fwd, y starboard, z down); SNAME; added_mass = M_A (positive); "
                       "damping paper sign: tau_D = linear @ nu + quadratic @ (|nu| * nu); inertia about the body "
                       "origin, tensor entries (off-diagonals = -products of inertia)",
        "name": vehicle.name, "source": vehicle.source,
        "environment": {"g": vehicle.g, "rho": vehicle.rho, "current_ned": [float(x) for x in vehicle.current_ned]},
        "mass": vehicle.mass, "buoyancy": vehicle.buoyancy,
        "r_g": [float(x) for x in vehicle.r_g], "r_b": [float(x) for x in vehicle.r_b],
        "inertia": vehicle.inertia_matrix.tolist(), "added_mass": vehicle.added_mass_matrix.tolist(),
        "damping": {"linear": DL.tolist(), "quadratic": DQ.tolist()},
        "thrusters": thrusters,
        "sensors": {k: [float(x) for x in v] for k, v in vehicle.sensors.items()},
    }


#: Duration of the replay an export to UUV Simulator runs before writing (s of the standard
#: maneuver at a 1 ms physics step; uvsim.export.replay).
UUV_CHECK_S = 15.0


def export_vehicle(vehicle, to: str, out, *, added_mass: str | None = None,
                   force: bool = False) -> tuple[Path, list[str], str]:
    """Render ``vehicle`` for ``to`` (one of :data:`TARGETS`).

    ``added_mass``: gz-sim only, "fluid" (default) or "plugin" (:func:`uvsim.export.gz_sim.gz_sdf`).
    Returns ``(path, warnings, text)``; the caller prints the warnings and writes ``text``."""
    if added_mass is not None and to != "gz-sim":
        raise VehicleError(f"--added-mass is a gz-sim option; {to} takes the added mass in its own model")
    out = Path(out)
    if to == "gz-sim":
        from uvsim.export.gz_sim import gz_sdf

        text, warnings = gz_sdf(vehicle, added_mass=added_mass or "fluid")
    elif to == "uuv-simulator":
        from uvsim.export.uuv_simulator import uuv_xacro

        text, warnings = uuv_xacro(vehicle, force=force)
        if not vehicle.effects:
            from uvsim.export.replay import replay_check, standard_maneuver

            t, U = standard_maneuver(UUV_CHECK_S)
            with np.errstate(all="ignore"):
                res = replay_check(vehicle, t, U, input_kind="force", target="uuv-simulator", physics_step=0.001,
                                   text=text)
            if res.diverged:
                why = (f"UUV Simulator's HMFossen applies the added mass from a low-pass filtered finite-difference "
                       f"acceleration (uuv_gazebo_plugins HydrodynamicModel.cc:102-125, alpha 0.3 at line 400), and "
                       f"uvsim's replay of those equations with this model diverges on the standard maneuver at a "
                       f"1 ms physics step ({res.summary()}); UUV Simulator itself was not run "
                       "(docs/import_export.md)")
                if not force:
                    raise VehicleError(f"{vehicle.source}: not exported to uuv-simulator: {why}. Write it anyway "
                                       "with --force")
                warnings.append(why + "; written anyway (--force)")
    elif to == "json":
        text, warnings = json.dumps(vehicle_json(vehicle), indent=2) + "\n", []
    else:
        raise VehicleError(f"--to {to!r}: expected one of {', '.join(TARGETS)}")
    return out, warnings, text
