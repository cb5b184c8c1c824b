"""``uvsim bench [--json] [--quick] [--only AREA,...]``: speed figures (docs/performance.md).

``uvsim bench calibrate-structural --scenarios N [--free LIST] [--latency auto|S|none] [--compare-no-prior]``: calibration on data that
differ from the model in structure (:mod:`uvsim.benchmarks.calibration_structural`, docs/calibration.md).

``uvsim bench diagnose --scenarios N --seed S [--two-effects M] [--results FILE]``: the
diagnosis on randomized scenarios from the independent truth model
(:mod:`uvsim.benchmarks.scenarios`, docs/diagnose.md).

``uvsim bench diagnose-field --scenarios N --seed S [--workers W] [--only CASES]``: the diagnosis
on field-like logs of an ArduSub-flown BlueROV2 Heavy (:mod:`uvsim.benchmarks.field_logs`,
docs/diagnose.md "Field logs")."""
from __future__ import annotations

import json
import os
import platform

from uvsim.commands.checks import add_progress_arguments, command_progress


def register(sub) -> None:
    from uvsim.benchmarks.calibration_structural import REAL_LOG_FREE, REAL_LOG_LATENCY, REAL_LOG_SUPPLY
    from uvsim.fit_settings import LOSSES

    p = sub.add_parser("bench", help="measure simulator / calibration speed; 'bench diagnose': scenario benchmark")
    p.add_argument("suite", nargs="?",
                   choices=["diagnose", "diagnose-structural", "diagnose-field", "calibrate-structural"],
                   default=None,
                   help="'diagnose': diagnose randomized scenarios; 'diagnose-structural': scenarios whose data "
                        "differ from the model in structure, N per class; 'diagnose-field': N field-like logs of an "
                        "ArduSub-flown BlueROV2 Heavy, one case after another; 'calibrate-structural': calibrate N such "
                        "datasets and compare with the start model (default: the speed figures)")
    p.add_argument("--loss", choices=LOSSES, default="linear",
                   help="(calibrate-structural) the calibration's --loss")
    p.add_argument("--supply-voltage", nargs="?", const="free", default=None, choices=("free", "auto", "none"),
                   help="(calibrate-structural, diagnose-structural) '--supply-voltage' alone: start model on the "
                        "T200 voltage family at its file's 16 V, calibration frees supply_voltage beside --free's "
                        "parameters, diagnosis has it as a base-model candidate; 'auto' (calibrate-structural's "
                        f"default {REAL_LOG_SUPPLY!r}, the real-log command): the calibration's --supply-voltage auto; "
                        "'none': neither (calibrate-structural: the releases before; diagnose-structural's default)")
    p.add_argument("--free", default=REAL_LOG_FREE,
                   help=f"(calibrate-structural) the calibration's --free (default {REAL_LOG_FREE!r}, the real-log "
                        "command of docs/calibration.md; 'z_b': the releases before, no actuator parameter)")
    p.add_argument("--latency", default=REAL_LOG_LATENCY, metavar="auto|SECONDS|none",
                   help=f"(calibrate-structural) the calibration's --latency (default {REAL_LOG_LATENCY!r}, the "
                        "real-log command; 'none': no --latency, the releases before)")
    p.add_argument("--trade-off", default="explore", choices=("explore", "none"),
                   help="(calibrate-structural) the calibration's --trade-off (default 'explore', the real-log "
                        "command; 'none': without it, the releases before)")
    p.add_argument("--compare-no-prior", action="store_true",
                   help="(calibrate-structural) calibrate each dataset also without the priors (--no-prior)")
    p.add_argument("--scenarios", type=int, default=20,
                   help="(scenario suites) scenarios: single-effect or clean ones (diagnose), per class "
                        "(diagnose-structural), datasets (calibrate-structural)")
    p.add_argument("--two-effects", type=int, default=0, help="(diagnose) two-effect scenarios")
    p.add_argument("--seed", type=int, default=0, help="(scenario suites) first scenario seed")
    p.add_argument("--workers", type=int, default=1, help="(scenario suites) processes per diagnosis or calibration")
    p.add_argument("--results", default=None,
                   help="(scenario suites) JSON-lines file of finished scenarios; an interrupted "
                        "benchmark resumes from it")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quick", action="store_true", help="smaller problems (a smoke test, not the recorded figures)")
    p.add_argument("--only", default=None, help="comma-separated areas (core, hydro, sam, calibration, diagnosis; "
                                                 "calibrate-realsensor and real-log run only when named); diagnose-structural: "
                                                 "classes; diagnose-field: cases (clean, dead, reversed, ...)")
    add_progress_arguments(p)
    p.set_defaults(func=_run)



def _run(args) -> int:
    from uvsim.benchmarks import available
    from uvsim.errors import UvsimError

    if args.suite == "diagnose":
        return _diagnose(args)
    if args.suite == "diagnose-structural":
        return _structural(args)
    if args.suite == "calibrate-structural":
        return _calibrate_structural(args)
    if args.suite == "diagnose-field":
        return _field(args)
    mods = available()
    if args.only:
        want = [a.strip() for a in args.only.split(",") if a.strip()]
        unknown = [a for a in want if a not in mods]
        if unknown:
            raise UvsimError(f"--only: unknown area(s) {unknown}; available: {', '.join(mods)}")
        mods = {a: mods[a] for a in want}
    else:
        mods = {a: m for a, m in mods.items() if getattr(m, "DEFAULT", True)}
    results: dict = {}
    desc: dict = {}
    progress = command_progress("bench", args)
    for area, mod in mods.items():
        with progress.stage(f"[{area}] speed figures" + (" (--quick)" if args.quick else "")):
            results.update(mod.run(quick=args.quick))
        describe = getattr(mod, "describe", None)  # labels with this mode's problem sizes
        desc.update(describe(args.quick) if describe else getattr(mod, "DESCRIPTIONS", {}))
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    print(_machine_line())
    for k, v in results.items():
        print(f"  {k:34s} {v:14,.1f}   {desc.get(k, '')}")
    return 0


def _machine_line() -> str:
    """The machine, and the RK4 kernel the figures were measured with (uvsim.kernels)."""
    from uvsim.kernels import describe

    return (f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
            f"{platform.python_version()}; RK4 kernel: {describe()}")


def _suite(args, run) -> dict | None:
    """Run a scenario benchmark (``run(say, stages)``: a line per finished case, each case a stage of
    :mod:`uvsim.progress`) with ``--results`` checked; print its JSON and return None with ``--json``,
    else print the machine line and return its output."""
    from uvsim.commands.checks import check_outputs
    from uvsim.errors import UvsimError
    from uvsim.schema import check_workers, whole_number

    # scenario seeds are numpy seeds (non-negative); refused here, not by numpy after the first scenario
    whole_number(args.seed, "--seed", minimum=0, error=UvsimError)
    check_workers(args.workers, "--workers", error=UvsimError)
    check_outputs({"--results": args.results})
    out = run(None if args.json else (lambda m: print(m, flush=True)), command_progress("bench", args))
    if args.json:
        print(json.dumps(out, indent=2, default=float))
        return None
    print(_machine_line())
    return out


def _diagnose(args) -> int:
    from uvsim.benchmarks.scenarios import run_benchmark

    out = _suite(args, lambda say, stages: run_benchmark(args.scenarios, args.seed, two_effects=args.two_effects,
                                                 workers=args.workers, results=args.results, progress=say, stages=stages))
    if out is None:
        return 0
    s = out["summary"]
    print(f"scenarios: {s['scenarios']} (seed {args.seed}); single-effect or clean: "
          f"{s['single_or_clean']['correct']}/{s['single_or_clean']['n']} named correctly"
          + (f" ({100 * s['single_or_clean']['correct_rate']:.0f} %)" if s['single_or_clean']['n'] else ""))
    if s["two_effects"]["n"]:
        print(f"two effects: both named in {s['two_effects']['both_named']}/{s['two_effects']['n']} "
              f"({100 * s['two_effects']['both_named_rate']:.0f} %)")
    if s["false_positive_rate_clean"] is not None:
        print(f"false positives on clean data: {100 * s['false_positive_rate_clean']:.0f} % "
              f"of {s['clean_scenarios']}")
    if s["halved_share_of_correct_detections"] is not None:
        print(f"validation RMSE at least halved in {100 * s['halved_share_of_correct_detections']:.0f} % of "
              f"{s['correct_detections']} correct detections")
    print("detection rate per effect: " + ", ".join(f"{e} {d['found']}/{d['of']}" for e, d in s["detection_rate"].items()))
    sec = s["seconds_per_dataset"]
    print(f"seconds per dataset: mean {sec['mean']:.1f}, median {sec['median']:.1f}, max {sec['max']:.1f}")
    w = s.get("worst_group_change")
    print("largest open-loop worsening of a logged group by a chosen candidate: "
          + ("none chosen" if w is None else f"{100 * w:+.1f} %")
          + f"; scenarios with a group worsened by > 10 %: {s.get('accepted_worsening_a_group_over_10pct', 0)}")
    print("confusion (true -> named: count):")
    for c in s["confusion"]:
        print(f"  {c['true']:32s} -> {c['named']:32s} {c['count']}")
    return 0


def _diagnosis_supply(args) -> bool:
    """``--supply-voltage`` for diagnose-structural: a base-model candidate, not "auto"."""
    from uvsim.errors import UvsimError

    if args.supply_voltage == "auto":
        raise UvsimError("--supply-voltage auto is a calibration setting (calibrate-structural); "
                         "diagnose-structural takes --supply-voltage alone")
    return args.supply_voltage == "free"


def _structural(args) -> int:
    from uvsim.benchmarks.structural import CLASSES, run_benchmark

    classes = [c.strip() for c in args.only.split(",") if c.strip()] if args.only else list(CLASSES)
    out = _suite(args, lambda say, stages: run_benchmark(args.scenarios, args.seed, classes=classes, workers=args.workers,
                                                 supply=_diagnosis_supply(args), results=args.results,
                                                 progress=say, stages=stages))
    if out is None:
        return 0
    s = out["summary"]
    for cls, d in s["classes"].items():
        print(f"{cls:18s} right {d['correct']}/{d['n']} ({100 * d['rate']:.0f} %); clean {d['clean']}, false positives "
              f"{d['false_positives_clean']}; named anything {d['named_anything']}; base model off "
              f"{d['base_model_answers']}; seconds mean {d['seconds_mean']:.1f}, max {d['seconds_max']:.1f}")
    w = s["worst_group_change_of_an_accepted_candidate"]
    print("largest open-loop worsening of a logged group by an accepted candidate: "
          + ("none accepted" if w is None else f"{100 * w:+.1f} %")
          + f"; accepted candidates worsening a group by > 10 %: {s['accepted_candidates_worsening_a_group_over_10pct']}")
    return 0


def _field(args) -> int:
    from uvsim.benchmarks.field_logs import run_benchmark

    cases = [c.strip() for c in args.only.split(",") if c.strip()] if args.only else None
    out = _suite(args, lambda say, stages: run_benchmark(args.scenarios, args.seed, cases=cases, workers=args.workers,
                                                 results=args.results, progress=say, stages=stages))
    if out is None:
        return 0
    s = out["summary"]

    def frac(a, b):
        return f"{a}/{b}" + (f" ({100 * a / b:.0f} %)" if b else "")

    print(f"cases: {s['cases']} (seed {args.seed}); diagnosed {frac(s['diagnosed'], s['cases'])}")
    print(f"single effects: right set named {frac(s['single_named'], s['single_effects'])}; named with validation "
          f"fixed {frac(s['single_named_and_fixed'], s['single_effects'])}; dead named dead "
          f"{frac(s['dead_named_dead'], s['dead'])}; reversed named reversed "
          f"{frac(s['reversed_named_reversed'], s['reversed'])}")
    print(f"clean logs: {s['clean']}, with false effects {s['clean_with_false_effects']} "
          f"({s['false_effects_on_clean']} effects); outside the catalogue: not explained "
          f"{frac(s['outside_not_explained'], s['outside'])}")
    print("per case: " + ", ".join(f"{c} {d['right']}/{d['n']}" for c, d in s["per_case"].items()))
    print(f"seconds per case: mean {s['seconds_mean']:.0f}, max {s['seconds_max']:.0f}")
    return 0


def _calibrate_structural(args) -> int:
    from uvsim.benchmarks.calibration_structural import REAL_LOG_SUPPLY, WORSE_POINTS, run_benchmark

    supply = {None: REAL_LOG_SUPPLY, "free": True, "auto": "auto", "none": False}[args.supply_voltage]

    out = _suite(args, lambda say, stages: run_benchmark(args.scenarios, args.seed, compare_no_prior=args.compare_no_prior,
                                                 loss=args.loss, supply=supply,
                                                 free=args.free,
                                                 latency=None if args.latency == "none" else args.latency,
                                                 trade_off=None if args.trade_off == "none" else args.trade_off,
                                                 workers=args.workers, results=args.results,
                                                 progress=say, stages=stages))
    if out is None:
        return 0
    for mode, d in out["summary"].items():
        print(f"{mode}: {d['n']} fits ({d['errors']} refused before a result); verdict better {d['better']}/{d['n']} "
              f"({100 * d['better_rate']:.0f} %), trade-off {d['trade-off']}, worse {d['worse']}; better but a channel "
              f"more than {WORSE_POINTS:g} Fit % point lower (within the noise) "
              f"{d['better_but_a_channel_loses_points']}; median pooled error change "
              f"{100 * (d['median_pooled_rmse_change'] or 0):+.0f} %; fits with a parameter on a bound "
              f"{d['fits_with_a_bound_hit']}; seeds compared over a shorter horizon (a diverged simulation) "
              f"{d['seeds_compared_over_a_shorter_horizon']}; seconds median {d['seconds_median']:.1f}, "
              f"max {d['seconds_max']:.1f}")
        print(f"  against the generator's noise-free truth: closer or as close in every state channel "
              f"{d['closer_to_truth_everywhere']}/{d['n']}; farther in some channel {d['farther_from_truth']}, of which "
              f"not better {d['farther_not_better']}; not better though closer everywhere "
              f"{d['not_better_though_closer_to_truth']}")
        for name, what in (("truth", "the truth as a vehicle file states it"),
                           ("truth_coefficients", "the start model with the truth's coefficients")):
            if d[f"{name}_n"]:
                print(f"  judged like a fit, {what} ({d[f'{name}_n']} seeds): better {d[f'{name}_better']}; fits not "
                      f"better where it is not better either {d[f'fits_not_better_whose_{name}_is_not_better_either']}")
        print("  median validation Fit % gain per channel (points): "
              + ", ".join(f"{c} {g:+.1f}" for c, g in d["median_gain_points"].items()))
    return 0
