"""Seed 000's calibration workflow end to end on the shipped synthetic tank dataset.

Orjales et al. 2025 (seed 000) sec. 3-5: start from the measured/estimated model
(Table 2 = ``bluerov2_heavy_initial``), fit each DOF's inertia, added mass and
damping (Table 3) with the DEAP GA of Table 4 (60 individuals, 30 generations,
tournament 5, two-point crossover 0.5, Gaussian mutation 0.25) to eight runs per
DOF, then validate on held-out runs.  uvsim adds a joint windowed prediction-error fit
of all training runs with uncertainties and an identifiability report.  The dataset was generated from
Table 5 (``bluerov2_heavy``), so the fitted values can be compared with the truth.

Run:  python examples/paper_workflow.py [--workers 2] [--population 60 --generations 30] [--out DIR]
Prints a Table-5-style comparison (initial, fitted, difference %, truth, error %).
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from uvsim.calibration import Calibrator
from uvsim.calibration.demo import format_table5
from uvsim.commands.calibration_output import jsonable, print_verdict, record_outcome, save_fitted_vehicle
from uvsim.fitting.verdict import EXIT_CODES
from uvsim.commands.demo import shipped_dataset_path
from uvsim.logs import read_dataset


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--population", type=int, default=60)
    ap.add_argument("--generations", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="paper_workflow_output")
    ap.add_argument("--plots", action="store_true", help="also write the plots (measured vs simulated, boxplots)")
    args = ap.parse_args()

    ds = read_dataset(shipped_dataset_path())
    truth = ds.meta["truth"]["parameters"]
    print(f"{ds.path.name}: {len(ds.train)} training + {len(ds.validation)} validation runs "
          f"(synthetic; truth = seed 000 Table 5)")
    t0 = time.perf_counter()
    cal = Calibrator(population=args.population, generations=args.generations, seed=args.seed,
                     workers=args.workers, progress=True).fit(ds, "bluerov2_heavy_initial")
    rep = cal.report_
    print(f"\nGA: {rep['evaluations']} evaluations in {rep['ga_seconds']:.1f} s "
          f"({args.population} x {args.generations}, {args.workers} workers); "
          f"joint fit {rep['refine_seconds']:.1f} s; total {time.perf_counter() - t0:.1f} s\n")
    print("Table 5 style (difference % = fitted vs initial as in seed 000; error % = fitted vs truth):")
    print(format_table5(cal, truth))
    a = rep["identifiability"]
    for c in a["effective_inertia"]:
        print(f"  the data determine {c}")
    if a["not_identifiable"]:
        print(f"  the data determine only {', '.join(a['identifiable_combinations'])}")
    print(f"  stopped at a search bound: {a['at_bound'] or 'none'}; "
          f"1-sigma > 25 % of the value: {a['weakly_determined'] or 'none'}")
    for pair, r in a["correlations"].items():
        print(f"  correlated: {pair} ({r:+.3f})")
    print()
    status, why, keep = record_outcome(cal, ds)
    print_verdict(rep, status, why)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if keep:
        save_fitted_vehicle(cal, out / "fitted.yaml")
    (out / "report.json").write_text(json.dumps(jsonable(rep), indent=2))
    if args.plots:
        from uvsim.plotting.calibration import plot_calibration

        plot_calibration(cal, ds, out / "plots")
    print(f"-> {out}/" + ("fitted.yaml, " if keep else "") + "report.json")
    return EXIT_CODES[status]


if __name__ == "__main__":
    raise SystemExit(main())
