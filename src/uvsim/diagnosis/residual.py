"""What the diagnosed model still gets wrong: the "not explained" verdict and where it lies.

A diagnosis names effects from a catalogue; when the validation cost after selection
stays well above the noise level, the honest answer is that the catalogue does not
explain the data (Ljung 1999 sec. 16.6: residual analysis of a model that failed
validation points to what is missing, not to the nearest candidate).  This module turns
the corrected model's open-loop validation residuals (:func:`uvsim.fitting.evaluate.open_loop`)
into

* the share of the noise-normalized squared error in each logged channel, each
  validation run and each third of the runs (start, middle, end), and
* hints of what to check for the channels that dominate (a table written from the
  physics each channel responds to, not fitted to any data).

:func:`verdict` combines them with the validation cost into the report's ``verdict``.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from uvsim.fitting.verdict import HINTS  # noqa: F401  (what to check per channel; re-exported)

#: Validation cost per residual (squared noise sigmas) above which the residual is "not
#: explained": the model's own error is then at least as large as the noise (cost 1 is
#: the noise alone; core.AT_NOISE = 1.5 is "at the noise level").
UNEXPLAINED = 2.0
#: Channels, runs or parts listed as "where it concentrates": those holding at least this
#: share of the error, at most TOP of them.
SHARE = 0.15
TOP = 3

PART_HINTS = {
    "start": "errors concentrated at the start point to the initial state or to thrust already acting when the "
             "log starts (steps from t = 0)",
    "end": "errors growing to the end point to a slowly acting force (current, tether, buoyancy) or a drift",
    "middle": "errors in the middle of the runs point to what the manoeuvres excite most (damping, thrust curve)",
}


def concentration(meas: Sequence, results: Sequence[dict], runs: Sequence | None = None) -> dict:
    """Shares of the open-loop validation error by channel, run and third of the run.

    Parameters
    ----------
    meas : measurement models of the validation runs (:mod:`uvsim.measurements`).
    results : :func:`uvsim.fitting.evaluate.open_loop` of the same runs.
    runs : the runs (for their DOF labels), optional.

    Returns
    -------
    dict with ``by_channel``, ``by_run`` and ``by_part``: lists of ``{"name", "share"}``
    sorted by share (shares of the total noise-normalized sum of squares), and ``total``.
    """
    ch: dict[str, float] = {}
    rn: dict[str, float] = {}
    part = {"start": 0.0, "middle": 0.0, "end": 0.0}
    for k, (m, o) in enumerate(zip(meas, results)):
        res = m.residuals(o["pred"])
        t = np.asarray(m.t, float)
        third = np.minimum((3 * (t - t[0]) / max(t[-1] - t[0], 1e-9)).astype(int), 2)
        label = m.name
        if runs is not None and getattr(runs[k], "dof", None):
            label = f"{m.name} ({runs[k].dof})"
        for g, e in res.items():
            grp = m.groups[g]
            used = m.used(g)
            sig = np.where(grp.logged, grp.sigma, 1.0)
            z2 = np.where(used, np.nan_to_num(e / sig, nan=0.0, posinf=1e6, neginf=-1e6), 0.0) ** 2
            for j, c in enumerate(grp.channels):
                if used[:, j].any():
                    ch[c] = ch.get(c, 0.0) + float(z2[:, j].sum())
            rn[label] = rn.get(label, 0.0) + float(z2.sum())
            for i, name in enumerate(("start", "middle", "end")):
                part[name] += float(z2[third == i].sum())
    total = sum(ch.values())

    def ranked(d):
        return sorted(({"name": k, "share": v / total if total > 0 else 0.0} for k, v in d.items()),
                      key=lambda x: -x["share"])

    return {"by_channel": ranked(ch), "by_run": ranked(rn), "by_part": ranked(part), "total": total}


def verdict(cost_per_entry: float, named: Sequence[str], conc: dict, at_noise: float,
            base_model_off: bool = False) -> dict:
    """The report's ``verdict``: ``status`` is ``"at noise"`` (nothing needed), ``"explained"``
    (named effects bring the residual to the noise level), ``"partly explained"`` (effects
    named, a residual above :data:`UNEXPLAINED` remains), ``"not explained"`` (no effect named
    and a residual above :data:`UNEXPLAINED`) or ``"between"`` (above the noise level, below
    UNEXPLAINED); ``base_model_off`` adds that the base model's re-tune was the answer.
    With a residual, ``where`` lists the channels, runs and part of the runs that hold it
    and ``check`` what to look at."""
    unexplained = cost_per_entry > UNEXPLAINED
    if cost_per_entry <= at_noise:
        status = "explained" if named else "at noise"
    elif unexplained:
        status = "partly explained" if named else "not explained"
    else:
        status = "between"
    out = {"status": status, "unexplained": bool(unexplained), "cost_per_entry": float(cost_per_entry),
           "at_noise": at_noise, "unexplained_above": UNEXPLAINED, "base_model_off": bool(base_model_off)}
    if cost_per_entry > at_noise:
        where = {k: [x for x in conc[k] if x["share"] >= SHARE][:TOP] or conc[k][:1]
                 for k in ("by_channel", "by_run", "by_part")}
        out["where"] = where
        check = [f"{x['name']}: {HINTS[x['name']]}" for x in where["by_channel"] if x["name"] in HINTS]
        top_part = where["by_part"][0]["name"] if where["by_part"] else None
        if top_part and where["by_part"][0]["share"] >= 0.5:
            check.append(PART_HINTS[top_part])
        out["check"] = check
        chans = ", ".join(f"{x['name']} {100 * x['share']:.0f} %" for x in where["by_channel"])
        runs = ", ".join(f"{x['name']} {100 * x['share']:.0f} %" for x in where["by_run"])
        parts = ", ".join(f"{x['name']} {100 * x['share']:.0f} %" for x in where["by_part"])
        lead = ("residual not explained by the catalogue" if unexplained else
                "residual slightly above the noise level")
        out["message"] = (f"{lead} ({cost_per_entry:.2f} squared noise sigmas per residual, noise level "
                          f"{at_noise:g}); it concentrates in {chans}; runs {runs}; part of the runs {parts}")
    else:
        out["message"] = "the residual is at the noise level"
    return out
