"""Single-trajectory steps/s of uvsim's RK4 beside PythonVehicleSimulator's forward Euler, in one run.

Issue 46 asks for uvsim's single RK4 at >= 10x the steps/s of PythonVehicleSimulator's Euler
"in the same run". PythonVehicleSimulator (T. I. Fossen, MIT licence,
https://github.com/cybergalactic/PythonVehicleSimulator) is not a dependency: clone it and give
its path::

    git clone https://github.com/cybergalactic/PythonVehicleSimulator /tmp/pvs
    python benchmarks/reference_simulators/pvs_euler_steps.py /tmp/pvs

What is timed, best of 3 each:

* PythonVehicleSimulator: its REMUS 100 (``vehicles/remus100.py``, 6 DOF) with its own step
  inputs, ``vehicle.dynamics`` + ``gnc.attitudeEuler`` per step (the body of ``lib/mainLoop.py``
  without its data logging, whose ``np.vstack`` per step grows quadratically), 0.02 s steps;
* uvsim: ``uvsim.simulate`` of the BlueROV2 Heavy with PWM inputs through the T200 curve, RK4
  (four derivative evaluations per step), 50 Hz, with the compiled kernel and with numpy.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np


def pvs_steps_per_s(root: Path, n: int = 3000) -> float:
    sys.path.insert(0, str(root / "src"))
    from python_vehicle_simulator.lib.gnc import attitudeEuler
    from python_vehicle_simulator.vehicles.remus100 import remus100

    best = np.inf
    for _ in range(3):
        veh = remus100("stepInput")
        eta = np.zeros(6)
        nu, u_actual = veh.nu.copy(), veh.u_actual.copy()
        h = 0.02
        t0 = time.perf_counter()
        for i in range(n):
            u_control = veh.stepInput(i * h)
            nu, u_actual = veh.dynamics(eta, nu, u_actual, u_control, h)
            eta = attitudeEuler(eta, nu, h)
        best = min(best, time.perf_counter() - t0)
    assert np.all(np.isfinite(eta))
    return n / best


def uvsim_steps_per_s(kernel: str, n_t: int = 3001) -> float:
    import uvsim
    from uvsim.benchmarks.core import single_rk4

    with uvsim.kernels.use(kernel):
        return single_rk4(n_t)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1 or not (Path(argv[0]) / "src" / "python_vehicle_simulator").is_dir():
        print(__doc__)
        print("usage: pvs_euler_steps.py PATH_TO_PythonVehicleSimulator")
        return 2
    pvs = pvs_steps_per_s(Path(argv[0]))
    print(f"PythonVehicleSimulator REMUS 100, forward Euler: {pvs:12,.0f} steps/s")
    for kernel in ("numba", "numpy"):
        try:
            rate = uvsim_steps_per_s(kernel)
        except Exception as exc:  # numba not installed: say so, go on
            print(f"uvsim RK4, kernel {kernel}: not run ({exc})")
            continue
        print(f"uvsim RK4, kernel {kernel:5s}:                  {rate:12,.0f} steps/s = {rate / pvs:7.1f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
