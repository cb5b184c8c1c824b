"""What a diagnosis reports: the named effects' and the base model's parameters, the message in
words, each fitted candidate's row, and the corrected vehicle file.

:func:`uvsim.diagnosis.diagnose` decides; this module only writes down what was decided
(docs/diagnose.md, "Reading the report").
"""
from __future__ import annotations

from typing import Mapping

from uvsim.diagnosis.candidates import BASE_MODEL, Candidate, search_bound_hits
from uvsim.diagnosis.units import DEAD_GAIN, plain_answer, reported_variant
from uvsim.errors import UvsimError
from uvsim.forces import make_term


def parameter_reports(accepted, values: Mapping[str, float], final, vehicle) -> tuple[list, dict | None]:
    """The report's ``effects`` (one dict per named effect) and ``base_model`` (None when the base
    model was not changed) of the ``accepted`` candidates with their fitted ``values``; ``final``:
    the last fit (its standard deviations and bounds hit), ``vehicle`` the given model."""
    effects_rep, base_rep = [], None
    for c in accepted:
        # on the edge of its search range in the final fit (a base-model coefficient at its bound is;
        # a physical floor is not, candidates.search_bound_hits, nor a unit's gain within DEAD_GAIN of 0
        # from either side: a dead unit, which a reversed unit's range reaches at its upper end)
        hits = [n for n in c.free if final is not None and n in final.at_bounds]
        edge = set(hits if c.effect == BASE_MODEL else search_bound_hits(c, values, hits))
        if c.effect == "thruster_gain":
            edge = {n for n in edge if not abs(values[n]) < DEAD_GAIN}
        params = {n: {"value": values[n], "std": (final.std.get(n) if final else None), "unit": _unit(c, n),
                      "at_bound": n in edge}
                  for n in c.free}
        if c.effect == BASE_MODEL:
            for n in c.free:
                params[n]["before"] = vehicle.parameters().get(n, 1.0)
            if base_rep is None:
                base_rep = {"variant": c.variant, "notes": c.notes, "parameters": params}
            else:  # a thrust scale kept beside a unit, then a hydrodynamic variant (step_choice.unit_beside_base)
                base_rep = {"variant": f"{base_rep['variant']}+{c.variant}", "notes": f"{base_rep['notes']}; {c.notes}",
                            "parameters": {**base_rep["parameters"], **params}}
        else:
            effects_rep.append({"effect": c.effect, "variant": reported_variant(c, values), "fitted_as": c.variant,
                                "notes": c.notes, "parameters": params,
                                "answer": plain_answer(c, values)})
    return effects_rep, base_rep


def retuned_report(sel, values: Mapping[str, float], vehicle, fit) -> dict:
    """The report's ``retuned``: per re-tuned coefficient kept in ``values``, its ``value``, the given
    model's (``before``) and ``at_bound``: on the edge of its search range (the re-tune's margin round
    the given value) in ``fit``, the last fit that freed it. A re-tune on its edge is kept (a
    coefficient far off is not unphysical, :func:`uvsim.diagnosis.candidates.search_bound_hits`), but
    the reader is told: the data push it further, so it is the edge, not an estimate (field logs, clean
    seed 0: four of the six quadratic drags at +50 %, standing in for a drag along the relative velocity
    the diagonal form lacks)."""
    hits = set(fit.at_bounds) if fit is not None else set()
    return {n: {"value": values[n], "before": vehicle.parameters()[n], "at_bound": n in hits}
            for n in sel.retune if n in values}


def every_parameter_on_bound(params: Mapping[str, Mapping]) -> bool:
    """Whether a reported effect's (or base model's) ``parameters`` (``{name: {"at_bound", ...}}``,
    :func:`parameter_reports`) are all on the edge of their search ranges (none: False)."""
    return bool(params) and all(d.get("at_bound") for d in params.values())


def summary_message(accepted, values, base_rep, val_given, val_cur, at_noise_level: float, retune_verdict,
                    asked_retune, backward) -> str:
    """The report's ``message``: what was named (or none) and the validation cost before and after,
    the base model's change, a re-tune not kept and an effect dropped in the backward pass."""
    at_noise = val_cur["per_entry"] <= at_noise_level
    names = [c.effect for c in accepted if c.effect != BASE_MODEL]
    base_msg = ""
    if base_rep is not None:
        edge = every_parameter_on_bound(base_rep["parameters"])
        base_msg = (f"The base model is off: {base_rep['notes']} (base_model:{base_rep['variant']}, "
                    + ", ".join(f"{n} {d['before']:.4g} -> {d['value']:.4g}" for n, d in base_rep["parameters"].items())
                    + ("; on the edge of its search range, so it stands in for something the model lacks rather "
                       "than a value to calibrate). " if edge else
                       "); calibrate it (uvsim calibrate) rather than add an effect. "))
    if names:
        msg = base_msg + (
            f"{' + '.join(plain_answer(c, values) or c.label for c in accepted if c.effect != BASE_MODEL)}: validation cost "
            f"{val_given['per_entry']:.2f} -> {val_cur['per_entry']:.2f} squared noise sigmas per residual. "
            + ("The residual is now at the noise level." if at_noise else
               "Something the catalogue does not explain remains (the cost is above the noise level)."))
    else:
        msg = base_msg + (
            "none: no catalogue effect removes a significant part of the validation cost "
            f"({val_cur['per_entry']:.2f} squared noise sigmas per residual). "
            + ("The model is at the noise level." if at_noise else
               "The cost is above the noise level: an effect outside the catalogue, or base coefficients to "
               "calibrate (uvsim calibrate, or --retune)."))
    if retune_verdict is not None and not retune_verdict["ok"]:
        msg += (f" The re-tune of {', '.join(asked_retune)} alone was not kept (its verdict against the given model: "
                f"{retune_verdict['message']})" + (", only beside the effects named." if names else "."))
    for r in backward:
        if not r["kept"]:
            msg += (f" {r['effect']}:{r['variant']}, chosen first, was dropped: beside the later effect it is "
                    f"not needed ({r['why']}).")
    return msg


def _unit(c: Candidate, name: str) -> str:
    """The unit of parameter ``name`` of candidate ``c`` (its term's, "m" for a thruster position)."""
    if c.spec is None:
        return "m" if name.startswith("thruster_") and name.split("_")[1] in "xyz" else "-"
    try:
        term = make_term(dict(c.spec))
        return term.units().get(name, "") if hasattr(term, "units") else ""
    except UvsimError:
        return ""


def row_report(row, best) -> dict:
    """A fitted candidate's row in a step of the report (``best``: the step's winner, or None)."""
    out = {"effect": row["effect"], "variant": row["variant"], "free": list(row["free"]),
           "accepted": bool(row.get("accepted")), "chosen": row is best, "why": row.get("why", "")}
    if "compare" in row:
        out.update(values=row["values"], std=row["std"], train_cost=row["train_cost"],
                   validation_cost_per_entry=row["val"]["per_entry"], compare=row["compare"],
                   at_bounds=row["at_bounds"])
    if "open_loop_cost" in row:
        out["open_loop_cost"] = row["open_loop_cost"]
    if "replaces" in row:  # fitted because that variant ran to a search bound (Selector.fit_judged)
        out["replaces"] = row["replaces"]
    return out


def save_fixed_vehicle(diag, path):
    """Write the corrected vehicle of ``diag`` (a :class:`uvsim.diagnosis.core.Diagnosis`) to ``path``
    with provenance comments."""
    from uvsim.vehicle import save_vehicle

    rep = diag.report
    ann = {}
    for e in rep["effects"]:
        for k, d in e["parameters"].items():
            std = d.get("std")
            key = k.split("_", 1)[1] if k.startswith(e["effect"] + "_") else k
            ann[key] = f"diagnosed: {d['value']:.6g}" + (f" +- {std:.2g}" if std is not None else "") + f" {d['unit']}"
    header = (f"{diag.vehicle_after.name}: corrected by `uvsim diagnose` on {rep['data']}\n"
              f"effects: {rep['effect']} ({rep['confidence']}); {rep['message']}\n"
              f"validation RMSE before {rep['rmse_before']} after {rep['rmse_after']}")
    return save_vehicle(diag.vehicle_after, path, header=header, annotations=ann)
