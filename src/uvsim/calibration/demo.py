"""The calibration step of ``uvsim demo`` and the Table-5-style comparison.

``run(out_dir, dataset)`` calibrates the six DOFs of the shipped synthetic tank
dataset from ``bluerov2_heavy_initial`` (seed 000 Table 2) with a *reduced* GA
(:data:`DEMO_SETTINGS`, so that ``make demo`` stays well under two minutes) plus
the joint prediction-error fit, and prints seed 000 Table 5's columns (initial,
fitted, difference %) next to the truth that generated the data.
``examples/paper_workflow.py`` runs the same with the paper's full GA setting.
"""
from __future__ import annotations

import json
from pathlib import Path

from uvsim.calibration.params import DOF_PARAMETERS, EFFECTIVE_INERTIA

#: Reduced GA for the demo (paper: population 60, 30 generations).
DEMO_SETTINGS = dict(population=20, generations=8, seed=0, workers=2, max_iter=15)


def table5_rows(cal, truth: dict | None = None) -> list[dict]:
    """Rows of seed 000 Table 5 (parameter, initial, fitted, difference % = fitted vs
    initial) plus truth, error % (fitted vs truth) and 1-sigma where known."""
    rep = cal.report_
    rows = []
    order = [k for d in ("roll", "pitch", "yaw") for k in DOF_PARAMETERS[d][:1]]
    order += [DOF_PARAMETERS[d][0] for d in ("surge", "sway", "heave")] + [DOF_PARAMETERS[d][1] for d in
                                                                            ("roll", "pitch", "yaw")]
    order += [DOF_PARAMETERS[d][-2] for d in DOF_PARAMETERS] + [DOF_PARAMETERS[d][-1] for d in DOF_PARAMETERS]
    for k in order:
        if k not in rep["parameters"]:
            continue
        ini, fit = rep["initial_parameters"][k], rep["parameters"][k]
        row = {"parameter": k, "initial": ini, "fitted": fit, "difference_percent": 100 * (fit - ini) / ini,
               "sigma": rep["uncertainty"].get(k)}
        if truth and k in truth:
            row["truth"] = truth[k]
            row["error_percent"] = 100 * (fit - truth[k]) / truth[k]
        rows.append(row)
    return rows


def format_table5(cal, truth: dict | None = None) -> str:
    """Text table of :func:`table5_rows` plus the identifiable effective inertias."""
    lines = [f"{'parameter':10s} {'initial':>10s} {'fitted':>10s} {'diff %':>8s} {'1-sigma':>9s}"
             + (f" {'truth':>10s} {'error %':>8s}" if truth else "")]
    from uvsim.commands.checks import bound_hits

    rep = cal.report_
    at_bound = list(bound_hits(rep))
    for r in table5_rows(cal, truth):
        sig = "   (sum)" if r["sigma"] is None else f"{r['sigma']:9.3g}"
        line = f"{r['parameter']:10s} {r['initial']:10.4g} {r['fitted']:10.4g} {r['difference_percent']:8.2f} {sig:>9s}"
        if truth:
            line += f" {r['truth']:10.4g} {r['error_percent']:8.2f}"
        if r["parameter"] in at_bound:
            line += "  ON A BOUND"
        lines.append(line)
    if at_bound:
        lines.append(f"{', '.join(at_bound)}: ended on a search bound (+-{100 * rep['settings']['margin']:g} % of the "
                     "initial value); the fit would have gone further and the 1-sigma does not hold there.")
    lines.append("")
    lines.append("identifiable effective inertia (rigid body + added):")
    for d in rep["dofs"]:
        a, b = EFFECTIVE_INERTIA[d]
        v = rep["effective_inertia"][d]
        s = rep["effective_inertia_uncertainty"].get(d)
        line = f"  {d:6s} {a} + {b:7s} = {v:9.4f}" + (f" +- {s:.3g}" if s else "")
        if truth:
            tv = truth[a] + truth[b]
            line += f"   truth {tv:9.4f}   error {100 * (v - tv) / tv:6.2f} %"
        lines.append(line)
    return "\n".join(lines)


def run(out_dir, dataset, settings: dict | None = None) -> str:
    """Calibrate ``dataset`` (the shipped tank data), print the verdict and write
    calibration_report.json, the plots and (unless the verdict is worse) fitted.yaml into
    ``out_dir``.  Returns the verdict's status (:mod:`uvsim.fitting.verdict`).  ``settings``:
    the Calibrator's, over :data:`DEMO_SETTINGS` (``progress``: its stages and the plots',
    :mod:`uvsim.progress`)."""
    from uvsim.calibration import Calibrator
    from uvsim.commands.calibration_output import jsonable, print_verdict, record_outcome, save_fitted_vehicle
    from uvsim.progress import as_progress

    s = {**DEMO_SETTINGS, **(settings or {})}
    out = Path(out_dir)
    print(f"calibration (seed 000 GA + joint fit) of {len(dataset.runs)} runs from bluerov2_heavy_initial "
          f"(Table 2): REDUCED GA for the demo, population {s['population']} x {s['generations']} generations "
          f"(the paper: 60 x 30; run examples/paper_workflow.py for that), {s.get('workers', 1)} workers ...")
    cal = Calibrator(**s).fit(dataset, "bluerov2_heavy_initial")
    rep = cal.report_
    truth = (dataset.meta.get("truth") or {}).get("parameters")
    print(f"{rep['evaluations']} GA evaluations in {rep['ga_seconds']:.1f} s, joint fit {rep['refine_seconds']:.1f} s")
    print(format_table5(cal, truth))
    status, why, keep = record_outcome(cal, dataset)
    print_verdict(rep, status, why)
    if keep:
        save_fitted_vehicle(cal, out / "fitted.yaml")
    (out / "calibration_report.json").write_text(json.dumps(jsonable(rep), indent=2))
    from uvsim.plotting.calibration import plot_calibration

    with as_progress(s.get("progress")).stage(f"plots into {out / 'calibration_plots'}"):
        plot_calibration(cal, dataset, out / "calibration_plots", run_plots="validation")
    print(f"calibration outputs: {(str(out / 'fitted.yaml') + ', ') if keep else ''}"
          f"{out / 'calibration_report.json'}, {out / 'calibration_plots'}/")
    return status
