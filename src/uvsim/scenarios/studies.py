"""Studies of the generator: how visible an effect is, how accurate the integration is.

:func:`snr_study` draws ``n`` scenarios of a profile with one given effect at a fixed
magnitude (default: the low end of its range, :data:`MAGNITUDE_RANGES`), simulates only
their validation runs with and without the effect, and returns each scenario's
``effect_snr`` (:func:`uvsim.scenarios.generate.effect_snr`).  The low ends of the ranges
were chosen with it (docs/scenarios.md, "Detectability"; ``uvsim scenario snr``).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from uvsim.scenarios.effects import MAGNITUDE_RANGES, ScenarioError
from uvsim.scenarios.generate import DETECTABLE_SNR, effect_snr, simulate_spec
from uvsim.scenarios.spec import PROFILE_SUITE, sample_scenario


def snr_study(profile: str, effect: str, seeds, *, magnitude: float | str = "low", variant: str | None = None,
              max_step: float = 0.005, progress=None, **overrides) -> list[dict]:
    """``effect_snr`` of ``effect`` in the scenarios ``seeds`` of ``profile``.

    Parameters
    ----------
    magnitude : "low", "high" (ends of the effect's range) or a number in its unit.
    variant : force one variant (default: drawn per scenario).
    max_step : RK4 step bound, s (5 ms: integration error ~1e-8 m, far below any noise).
    progress : the scenarios as a stage (:func:`uvsim.progress.as_progress`).
    **overrides : passed to :func:`sample_scenario`.

    Returns
    -------
    one dict per seed: ``seed``, ``variant``, ``magnitude``, ``input_kind``, ``effect_snr``,
    ``effect_snr_by_signal``, ``detectable``.
    """
    if profile not in PROFILE_SUITE:
        raise ScenarioError(f"snr_study: profile {profile!r}; expected one of {sorted(PROFILE_SUITE)}")
    if effect not in MAGNITUDE_RANGES["mocap"]:
        raise ScenarioError(f"snr_study: effect {effect!r}; expected one of {sorted(MAGNITUDE_RANGES['mocap'])}")
    lo, hi = MAGNITUDE_RANGES[PROFILE_SUITE[profile]][effect]
    mag = {"low": lo, "high": hi}.get(magnitude, magnitude)
    try:
        mag = float(mag)
    except (TypeError, ValueError):
        raise ScenarioError(f"snr_study: magnitude {magnitude!r}; expected low, high or a number") from None
    eff = {"type": effect, "magnitude": mag}
    if variant is not None:
        eff["variant"] = variant
    from uvsim.progress import as_progress

    seeds = list(seeds)
    out = []
    with as_progress(progress).stage(f"{effect} in {len(seeds)} {profile} scenarios, validation runs with and without "
                                     "it", total=len(seeds), unit="scenario", short=f"snr {effect}") as stage:
        for seed in seeds:
            spec = sample_scenario(int(seed), profile, effects=[eff], **overrides)
            spec = dataclasses.replace(spec, runs=[r for r in spec.runs if r["split"] == "validation"],
                                       max_step=max_step)
            res = simulate_spec(spec)
            s = effect_snr(spec, res)[0]
            out.append({"seed": int(seed), "variant": spec.effects[0]["variant"], "magnitude": mag,
                        "input_kind": spec.input_kind, **s})
            stage.update(1)
    return out


def summarize(results: list[dict]) -> dict:
    """Median, 10th percentile, min and the fraction detectable of a study."""
    snr = np.array([r["effect_snr"] for r in results])
    return {"n": int(snr.size), "median": float(np.median(snr)), "p10": float(np.percentile(snr, 10)),
            "min": float(snr.min()), "fraction_detectable": float(np.mean(snr >= DETECTABLE_SNR))}


def step_halving(spec, max_step: float | None = None, progress=None) -> dict:
    """Integration error of a scenario's truth trajectories by step halving.

    Simulates every run at ``max_step`` (default the spec's) and at half of it and returns
    the largest differences over all runs and samples: ``position_m`` (NED position of the
    body origin), ``attitude_rad`` (angle of the relative rotation) and ``velocity`` (body
    velocity, m/s or rad/s).  RK4's error shrinks 16-fold per halving, so the difference is
    the error of the coarser run to within ~7 %.  ``progress``: the two simulations as stages
    (:func:`uvsim.progress.as_progress`).
    """
    from scipy.spatial.transform import Rotation

    from uvsim.progress import as_progress

    h = float(max_step or spec.max_step)
    sims = []
    for s in (h, h / 2):
        with as_progress(progress).stage(f"truth simulation of {len(spec.runs)} runs at RK4 step {1000 * s:g} ms"):
            sims.append(simulate_spec(dataclasses.replace(spec, max_step=s), with_snr=False)["sim"])
    qa, qb = (s["quat"].reshape(-1, 4)[:, [1, 2, 3, 0]] for s in sims)
    ang = (Rotation.from_quat(qa).inv() * Rotation.from_quat(qb)).magnitude()
    return {"max_step_s": h, "position_m": float(np.abs(sims[0]["pos"] - sims[1]["pos"]).max()),
            "attitude_rad": float(ang.max()), "velocity": float(np.abs(sims[0]["nu"] - sims[1]["nu"]).max()),
            "runs": len(spec.runs)}
