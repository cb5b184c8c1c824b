"""Randomized scenarios from an independent truth model (issues 10 and 14).

``sample_scenario(seed, profile=..., **overrides) -> ScenarioSpec`` draws every random choice of
a dataset; ``generate(spec, out_dir)`` simulates it with a truth model written apart from
the project's simulator and writes a LOG_FORMAT dataset, the model vehicle file handed to
the user and ``truth.yaml``.  See docs/scenarios.md.

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
