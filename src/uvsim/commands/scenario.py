"""``uvsim scenario generate|snr``: randomized datasets from the independent truth model.

    uvsim scenario generate --profile diagnose --seed 3 --out DIR [--n-effects 1] [--effects tether,ballast]
                            [--input-kind pwm] [--spec truth.yaml]
    uvsim scenario snr --profile diagnose --effect tether [--seeds 20] [--magnitude low|high|VALUE]
    uvsim scenario halving --profile issue10_timing --seed 0
"""
from __future__ import annotations

import json

from uvsim.commands.checks import add_progress_arguments, command_progress


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "scenario", help="generate randomized datasets with a known truth (docs/scenarios.md)",
        description="Randomized LOG_FORMAT datasets from a truth model written apart from the simulator, "
                    "with truth.yaml (docs/scenarios.md).")
    sub = p.add_subparsers(dest="scenario_command", metavar="ACTION")
    sub.required = True
    g = sub.add_parser("generate", help="write one dataset (manifest, runs, model vehicle, truth.yaml)")
    g.add_argument("--profile", default="diagnose", help="diagnose, issue10_timing or realsensor")
    g.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    g.add_argument("--out", required=True, help="output directory")
    g.add_argument("--n-effects", type=int, help="number of effects")
    g.add_argument("--effects", help="comma-separated effect types (e.g. tether,ballast)")
    g.add_argument("--input-kind", help="force, thrust or pwm")
    g.add_argument("--spec", help="regenerate from a spec or truth file (YAML) instead of drawing one")
    add_progress_arguments(g)
    g.set_defaults(func=run_generate)
    s = sub.add_parser("snr", help="effect_snr of one effect over drawn scenarios (detectability)")
    s.add_argument("--profile", default="diagnose", help="diagnose, issue10_timing or realsensor")
    s.add_argument("--effect", required=True, help="effect type")
    s.add_argument("--seeds", type=int, default=20, help="number of scenarios (seeds 0..N-1)")
    s.add_argument("--magnitude", default="low", help="low, high or a value in the effect's unit")
    s.add_argument("--variant", help="force one variant")
    s.add_argument("--json", action="store_true", help="print every scenario's result as JSON")
    add_progress_arguments(s)
    s.set_defaults(func=run_snr)
    h = sub.add_parser("halving", help="integration error of a scenario by step halving")
    h.add_argument("--profile", default="issue10_timing", help="diagnose, issue10_timing or realsensor")
    h.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    h.add_argument("--max-step", type=float, help="RK4 step bound to check, s (default the spec's, 0.002)")
    add_progress_arguments(h)
    h.set_defaults(func=run_halving)




def run_generate(args) -> int:
    from pathlib import Path

    import yaml

    from uvsim.files import safe_load
    from uvsim.scenarios import ScenarioError, ScenarioSpec, generate, load_truth, sample_scenario

    if args.spec:
        try:
            doc = safe_load(Path(args.spec).read_text())
        except (OSError, yaml.YAMLError) as exc:
            raise ScenarioError(f"{args.spec}: cannot read the spec ({exc})") from None
        spec = ScenarioSpec.from_dict(doc.get("spec", doc) if isinstance(doc, dict) else doc)
    else:
        over = {}
        if args.n_effects is not None:
            over["n_effects"] = args.n_effects
        if args.effects:
            over["effects"] = [e.strip() for e in args.effects.split(",") if e.strip()]
        if args.input_kind:
            over["input_kind"] = args.input_kind
        spec = sample_scenario(args.seed, args.profile, **over)
    out = generate(spec, args.out, progress=command_progress("scenario generate", args))
    truth = load_truth(out)
    print(f"{out}: {len(spec.runs)} runs, {spec.input_kind} inputs at {spec.rate_hz:g} Hz, vehicle "
          f"{spec.vehicle['model_name']}.yaml")
    for e in truth["effects"]:
        print(f"  effect {e['type']} ({e['variant']}), magnitude {e['magnitude']:.4g} [{e['magnitude_meaning']}], "
              f"effect_snr {e['effect_snr']:.3g}")
    if not truth["effects"]:
        print("  no effect")
    return 0


def run_snr(args) -> int:
    from uvsim.scenarios.studies import snr_study, summarize

    try:
        mag = float(args.magnitude)
    except ValueError:
        mag = args.magnitude
    res = snr_study(args.profile, args.effect, range(args.seeds), magnitude=mag, variant=args.variant,
                    progress=command_progress("scenario snr", args))
    summary = summarize(res)
    if args.json:
        print(json.dumps({"summary": summary, "scenarios": res}, indent=2))
    else:
        print(f"{args.effect} at magnitude {res[0]['magnitude']:g} ({args.profile}, {summary['n']} scenarios): "
              f"effect_snr median {summary['median']:.3g}, 10th percentile {summary['p10']:.3g}, "
              f"min {summary['min']:.3g}; detectable in {100 * summary['fraction_detectable']:.0f} %")
    return 0


def run_halving(args) -> int:
    from uvsim.scenarios import sample_scenario
    from uvsim.scenarios.studies import step_halving

    r = step_halving(sample_scenario(args.seed, args.profile), args.max_step,
                     progress=command_progress("scenario halving", args))
    print(f"{args.profile} seed {args.seed}, {r['runs']} runs, RK4 step {1000 * r['max_step_s']:g} ms vs half of it: "
          f"max difference position {r['position_m']:.2e} m, attitude {r['attitude_rad']:.2e} rad, "
          f"velocity {r['velocity']:.2e}")
    return 0
