"""Walk through one diagnosis: a BlueROV2 whose model lacks a tether and a current.

1. Read the shipped dataset ``bluerov2_two_effects`` (written by the independent truth
   model of ``uvsim.scenarios``; its ``truth.yaml`` holds what the diagnosis is not told).
2. Diagnose it with the vehicle file beside its manifest (the BlueROV2 Heavy of seed 000
   Table 5, without the two effects): every candidate variant screened by equation error,
   the best fitted through the simulator, accepted only when significant in training and
   confirmed on the validation runs; forward selection adds the second effect.
3. Print each step's candidates, the fitted parameters next to the truth, and the
   before/after validation RMSE; write report.json, the corrected vehicle and the plots.

    python examples/diagnose_walkthrough.py [OUT_DIR] [WORKERS]     (about a minute on 2 cores)
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import yaml

import uvsim
from uvsim.commands.diagnose import format_table
from uvsim.diagnosis import diagnose, save_fixed_vehicle
from uvsim.plotting.diagnosis import plot_diagnosis

DATA = Path(uvsim.__file__).parent / "data" / "datasets" / "bluerov2_two_effects"


def main(out="diagnose_walkthrough_out", workers="2") -> int:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    truth = yaml.safe_load((DATA / "truth.yaml").read_text())
    print(f"dataset: {DATA}")
    print("truth (not given to the diagnosis): "
          + "; ".join(f"{e['type']} ({e['variant']}, magnitude {e['magnitude']:g})" for e in truth["effects"]) + "\n")

    diag = diagnose(DATA, workers=int(workers), progress=lambda m: print(f"  ... {m}"))
    rep = diag.report
    print()
    print(format_table(rep))
    print("\nfitted vs truth:")
    for e in truth["effects"]:
        if e["type"] == "current":
            print(f"  current (m/s, NED):   truth {e['velocity_ned'][:2]}")
        elif e["type"] == "tether":
            print(f"  tether anchor (m, NED): truth {[round(x, 3) for x in e['anchor_ned']]}, tension {e['tension']} N, "
                  f"stiffness {e['stiffness']} N/m beyond {e['slack_length']:.2f} m")
    for e in rep["effects"]:
        vals = ", ".join(f"{k} = {d['value']:.4g}" for k, d in e["parameters"].items())
        print(f"  diagnosed {e['effect']}:{e['variant']}: {vals}")
    (out / "report.json").write_text(json.dumps(rep, indent=2, default=float))
    save_fixed_vehicle(diag, out / "fixed_vehicle.yaml")
    files = plot_diagnosis(diag, out / "plots")
    print(f"\nwrote {out / 'report.json'}, {out / 'fixed_vehicle.yaml'} and {', '.join(map(str, files))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(*sys.argv[1:]))
