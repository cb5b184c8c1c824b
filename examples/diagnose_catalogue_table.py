"""Recovered parameters and validation RMSE before/after for every catalogue effect.

Runs the cases of tests/test_diagnosis.py (three magnitudes per effect, a clean
dataset and an effect outside the catalogue) and prints the markdown table that
docs/diagnose.md shows.  About 1-2 minutes.

    python examples/diagnose_catalogue_table.py
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_diagnosis import CASES, WaveForce, make_data  # noqa: E402

from uvsim.diagnosis import diagnose  # noqa: E402
from uvsim.synthetic import generate_dataset  # noqa: E402


def fmt_params(report, truth=None):
    out = []
    for k, d in report["parameters"].items():
        t = f" (truth {truth[k][0]:g})" if truth and k in truth else ""
        out.append(f"{k} = {d['value']:.4g}{t}")
    return "; ".join(out) or "-"


def row(label, report, truth=None, secs=0.0):
    b, a = report["rmse_before"], report["rmse_after"]
    return (f"| {label} | {report['effect']} ({report['confidence']}) | {fmt_params(report, truth)} | "
            f"{1000 * b['position_m']:.1f} / {1000 * a['position_m']:.1f} | "
            f"{1000 * b['attitude_rad']:.1f} / {1000 * a['attitude_rad']:.1f} | {secs:.1f} |")


def main() -> int:
    print("| truth in the data | diagnosed | fitted parameters | position RMSE before / after (mm) | "
          "attitude RMSE before / after (mrad) | time (s) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, cases in CASES.items():
            for k, (spec, truth) in enumerate(cases):
                t0 = time.time()
                rep = diagnose(make_data(Path(tmp) / f"{name}{k}", spec), "bluerov2_heavy").report
                label = ", ".join(f"{kk} {v:g}" for kk, v in spec.items() if kk != "type")
                print(row(f"{name}: {label}", rep, truth, time.time() - t0), flush=True)
        for floor, damping in ((1.2, -400.0), (0.8, -150.0)):
            spec = {"type": "bottom_effect", "floor_d": floor, "damping": damping, "decay_length": 0.25}
            t0 = time.time()
            ds = generate_dataset("bluerov2_heavy", Path(tmp) / f"floor{floor}", dofs=("surge", "heave", "pitch"),
                                  runs_per_dof=4, validation_per_dof=2, duration=10.0, rate=10.0,
                                  signals=("position", "mocap_attitude"), seed=1, effects=[spec],
                                  levels={"heave": [60, 90, 120, 150, 75, 105]})
            rep = diagnose(ds, "bluerov2_heavy").report
            truth = {"bottom_effect_floor_d": (floor, 0), "bottom_effect_damping": (damping, 0)}
            print(row(f"bottom_effect: floor_d {floor:g}, damping {damping:g} (surge/heave/pitch runs)", rep, truth,
                      time.time() - t0), flush=True)
        t0 = time.time()
        rep = diagnose(make_data(Path(tmp) / "clean", None, seed=3), "bluerov2_heavy").report
        print(row("clean (no effect)", rep, None, time.time() - t0), flush=True)
        for amp in (1.0, 2.5):
            t0 = time.time()
            rep = diagnose(make_data(Path(tmp) / f"wave{amp}", WaveForce(amp, 4.0), seed=4), "bluerov2_heavy").report
            print(row(f"not in the catalogue: oscillating NED force, {amp:g} N, 4 s", rep, None, time.time() - t0),
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
