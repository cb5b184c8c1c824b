"""Randomized scenarios from an independent truth model (issues 10 and 14).

``sample_scenario(seed, profile=..., **overrides) -> ScenarioSpec`` draws every random choice of
a dataset; ``generate(spec, out_dir)`` simulates it with a truth model written apart from
the project's simulator and writes a LOG_FORMAT dataset, the model vehicle file handed to
the user and ``truth.yaml``.  See docs/scenarios.md.

Effects and their magnitude ranges (log-uniform over 10x; ``mocap`` suite for the profiles
``diagnose``/``issue10_timing``, ``imu`` for ``realsensor`` where it differs):

==================  ==========================================  ==================
current             speed, m/s                                  0.01-0.1 (imu 0.1-1.0)
tether              tension T_0 (N) and/or stiffness k (N/m)    0.1-1.0
ballast             net weight of a point load, N               0.1-1.0 (imu 0.3-3.0)
thruster_lag        time constant, s                            0.03-0.3
thrust_asymmetry    reverse-thrust loss 1 - ratio               0.05-0.5
weak_thruster       thrust loss 1 - gain of one thruster        0.07-0.7
coupled_damping     drag-centre offset, m                       0.012-0.12
periodic_force      amplitude, N (uncatalogued; on request)     0.3-3.0
==================  ==========================================  ==================

Structural differences (issue 21, opt-in overrides, off by default): thruster positions off the
vehicle file's (``thruster_position_error``), jittered time stamps (``time_jitter``), late sensors
(``sensor_latency``), runs flown by a pilot (``pilot_inputs``); see spec.py.

Detectability: ``effect_snr`` is the RMS, over all channels and samples of the validation
runs, of the noise-free sensor difference with and without the effect divided by each
channel's noise level; an effect is ``detectable`` when ``effect_snr >= 2``.  Each low end
is a round value at which at least 90 % of drawn scenarios are detectable (``uvsim scenario
snr``; the imu current is the exception, so ``realsensor`` draws it only with a DVL).

Isolation: nothing in this package imports the project's model, simulator, force terms,
effects, vehicle loader, metrics, calibration, diagnosis or synthetic data (a test parses
the sources); it reads the vehicle YAML and the thrust table itself and writes through
``uvsim.logs``.
"""
from __future__ import annotations

from uvsim.scenarios.effects import CATALOGUED, EFFECTS, MAGNITUDE_RANGES, ScenarioError  # noqa: F401
from uvsim.scenarios.generate import DETECTABLE_SNR, generate, load_truth, simulate_spec  # noqa: F401
from uvsim.scenarios.spec import OVERRIDES, PROFILES, ScenarioSpec, sample_scenario  # noqa: F401
from uvsim.scenarios.truth import simulate_truth  # noqa: F401
from uvsim.scenarios.vehicle_data import load_vehicle_data  # noqa: F401
