"""Benchmarks behind ``uvsim bench``.

Each area has a module here exposing ``run(quick: bool = False) -> dict`` of
``{json_key: value}`` and ``DESCRIPTIONS = {json_key: "text with unit"}`` (a module
whose problem sizes change with ``--quick`` also has ``describe(quick) -> dict``, so the
labels say what was measured); a module with ``DEFAULT = False`` runs only when named
(``--only``).  Results and the machine they were measured on go in docs/performance.md.
"""
from __future__ import annotations

import importlib

#: area -> module; a module that is missing (feature not installed) is skipped.
MODULES = {
    "core": "uvsim.benchmarks.core",
    "hydro": "uvsim.benchmarks.hydro",
    "sam": "uvsim.benchmarks.sam",
    "calibration": "uvsim.benchmarks.calibration",
    "diagnosis": "uvsim.benchmarks.diagnosis",
    "calibrate-realsensor": "uvsim.benchmarks.realsensor",
    "real-log": "uvsim.benchmarks.real_log",
}


def available() -> dict:
    out = {}
    for area, name in MODULES.items():
        try:
            out[area] = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
    return out
