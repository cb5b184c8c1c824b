"""Plots of a diagnosis (:func:`uvsim.diagnosis.diagnose`).

* ``validation_runs.png``: for each of the first validation runs, its logged channels
  measured, simulated with the given model and with the corrected one (open loop);
* ``errors_over_time.png``: the error of each logged signal group before / after;
* ``steps.png``: the validation cost of the given model, the baseline and after each
  accepted effect, with every fitted candidate of each step;
* ``residual.png``: where the corrected model's remaining error lies (by channel, run and
  part of the run), the picture behind the report's ``verdict``.

Part of :mod:`uvsim.plotting`, the only package that imports matplotlib.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np

from uvsim.fitting.evaluate import judged_label
from uvsim.signals import UNITS

GROUP_ERR = {"position": "position error [m]", "depth": "depth error [m]", "attitude": "attitude error [rad]",
             "velocity": "velocity error [m/s]", "rates": "rate error [rad/s]", "acceleration": "accel. error [m/s^2]"}


def _series(res, meas, group):
    """(measured (n, k), predicted (n, k), channel names, their columns) of ``group`` from the one
    measure (:func:`uvsim.metrics.channel_series`): the prediction is the free simulation through
    the measurement model (angles on the measured value's branch); NaN where not a sample."""
    from uvsim.metrics import channel_series

    grp = meas.groups[group]
    ser = channel_series(meas, res["pred"])
    n, k = meas.n, len(grp.channels)
    m, p = np.full((n, k), np.nan), np.full((n, k), np.nan)
    for j, c in enumerate(grp.channels):
        if c in ser:
            m[:, j] = np.where(ser[c]["measured"], ser[c]["y"], np.nan)
            p[:, j] = ser[c]["y_hat"]
    return m, p, [c for c, on in zip(grp.channels, grp.logged) if on], np.flatnonzero(grp.logged)


def _judged(diag) -> str:
    """What the verdict compared (the report's ``judged``): the plots show the same predictions."""
    return judged_label(diag.report.get("judged"), "open loop")


def plot_validation_runs(diag, path, max_runs: int = 3) -> Path:
    """Logged channels of the first ``max_runs`` validation runs: measured, given model,
    corrected model (open-loop simulations)."""
    runs = diag.validation[:max_runs]
    meas = [m for m in diag.measurements_validation[:max_runs]]
    rows = max(sum(int(g.logged.sum()) for g in m.groups.values()) for m in meas)
    fig, axes = plt.subplots(rows, len(runs), figsize=(4.6 * len(runs), 1.7 * rows + 0.8), squeeze=False,
                             sharex="col")
    for k, (run, m) in enumerate(zip(runs, meas)):
        b, a = diag.open_loop_before[k], diag.open_loop_after[k]
        i = 0
        for g in m.groups:
            mb, pb, names, cols = _series(b, m, g)
            _, pa, _, _ = _series(a, m, g)
            for name, j in zip(names, cols):
                ax = axes[i, k]
                ax.plot(run.t, mb[:, j], ".", ms=1.5, color="k", label="measured")
                ax.plot(run.t, pb[:, j], color="tab:red", lw=1.0, label="given model")
                ax.plot(run.t, pa[:, j], color="tab:blue", lw=1.0, label="corrected")
                ax.set_ylabel(f"{name} [{UNITS[g]}]", fontsize=8)
                ax.grid(alpha=0.3)
                i += 1
        for ax in axes[i:, k]:
            ax.set_axis_off()
        axes[0, k].set_title(run.name, fontsize=9)
        axes[max(i - 1, 0), k].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"Validation runs, {_judged(diag)}: given model vs corrected ({diag.report['effect']})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def plot_errors(diag, path, max_runs: int = 6) -> Path:
    """Per validation run, the error norm of each logged group over time, before / after."""
    runs = diag.validation[:max_runs]
    meas = diag.measurements_validation[:max_runs]
    groups = [g for g in ("position", "depth", "attitude", "velocity", "rates", "acceleration")
              if any(g in m.groups for m in meas)]
    fig, axes = plt.subplots(len(runs), len(groups), figsize=(3.8 * len(groups), 1.9 * len(runs) + 0.6),
                             squeeze=False, sharex="row")
    for i, (run, m) in enumerate(zip(runs, meas)):
        rb = m.residuals(diag.open_loop_before[i]["pred"])
        ra = m.residuals(diag.open_loop_after[i]["pred"])
        for j, g in enumerate(groups):
            ax = axes[i, j]
            if g not in rb:
                ax.set_axis_off()
                continue
            eb = np.sqrt(np.nansum(rb[g] ** 2, axis=1))
            ea = np.sqrt(np.nansum(ra[g] ** 2, axis=1))
            ok = np.isfinite(rb[g]).any(axis=1)
            ax.plot(run.t[ok], eb[ok], color="tab:red", lw=1.0, label="given model")
            ax.plot(run.t[ok], ea[ok], color="tab:blue", lw=1.0, label="corrected")
            ax.set_ylabel(GROUP_ERR[g], fontsize=8)
            ax.set_title(run.name, fontsize=8)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"Validation errors over time ({_judged(diag)}), effect = {diag.report['effect']} "
                 f"({diag.report['confidence']})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def _step_name(st) -> str:
    """A forward-selection step as the plot labels it: step 0 is the base model's."""
    return "base model" if st["step"] == 0 else f"step {st['step']}"


def plot_steps(diag, path) -> Path:
    """Validation cost per residual of the models along the forward selection, with every
    fitted candidate of each step (green: chosen)."""
    rep = diag.report
    fig, (ax, key) = plt.subplots(1, 2, figsize=(10.5, 4.2), gridspec_kw={"width_ratios": [3, 2]})
    xs, labels = [0], ["given"]
    ys = [rep["validation_cost_per_entry"]["given"]]
    entries = []  # the candidates, numbered on the plot and named in the key beside it (no overprinting)
    for x, st in enumerate(rep["steps"], 1):
        fitted = [c for c in st["candidates"] if "validation_cost_per_entry" in c]
        for j, c in enumerate(fitted):
            col = "tab:green" if c["chosen"] else ("tab:olive" if c["accepted"] else "tab:gray")
            xj = x + 0.12 * (j - 0.5 * (len(fitted) - 1))  # side by side within the step
            ax.plot(xj, c["validation_cost_per_entry"], "o", color=col, ms=9, zorder=3)
            ax.annotate(str(len(entries) + 1), (xj, c["validation_cost_per_entry"]), fontsize=6, color="white",
                        ha="center", va="center", zorder=4)
            entries.append((len(entries) + 1, _step_name(st), c, col))
        if st.get("after_cost_per_entry") is not None:
            xs.append(x)
            ys.append(st["after_cost_per_entry"])
            labels.append(st["chosen"])
    ax.plot(xs, ys, "-s", color="tab:blue", mfc="none", ms=10, label="model after each step", zorder=2)
    ax.axhline(1.0, color="k", ls="--", lw=0.8, label="noise level")
    ax.set_yscale("log")
    ax.set_xticks(range(0, len(rep["steps"]) + 1),
                  ["given"] + [_step_name(st) for st in rep["steps"]])
    ax.set_xlabel("forward-selection step\n(step 0: the base model's thrust curve and damping)")
    ax.set_ylabel("validation cost per residual\n[squared noise sigmas]")
    ax.legend(fontsize=8)
    ax.set_title(f"Diagnosis: {rep['effect']} ({rep['confidence']})", fontsize=10)
    key.axis("off")
    lines = [(f"{i:>2}  {x}: {c['effect']}:{c['variant']}  {c['validation_cost_per_entry']:.3g}"
              + ("  chosen" if c["chosen"] else ("  accepted" if c["accepted"] else "")), col)
             for i, x, c, col in entries[:28]]
    if len(entries) > 28:
        lines.append((f"... and {len(entries) - 28} more (report.json, steps)", "k"))
    for k, (text, col) in enumerate(lines):
        key.text(0.0, 1.0 - k * 0.035, text, transform=key.transAxes, fontsize=7, family="monospace",
                 color=col if col != "tab:gray" else "0.35", va="top")
    key.set_title("candidates (number, step, effect:variant, cost)", fontsize=8, loc="left")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return Path(path)


def plot_residual(diag, path) -> Path:
    """Where the corrected model's open-loop validation error lies (the report's
    ``verdict``, :mod:`uvsim.diagnosis.residual`): shares by channel, run and third of the run."""
    from uvsim.diagnosis.residual import concentration

    conc = concentration(diag.measurements_validation, diag.open_loop_after, diag.validation)
    v = diag.report.get("verdict", {})
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4), gridspec_kw={"width_ratios": [2, 2, 1]})
    for ax, key, title in zip(axes, ("by_channel", "by_run", "by_part"), ("channel", "validation run", "part of run")):
        rows = conc[key][:12]
        ax.barh([r["name"] for r in rows][::-1], [100 * r["share"] for r in rows][::-1], color="tab:purple")
        ax.set_xlabel("share of the open-loop error [%]")
        ax.set_title(f"by {title}", fontsize=9)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3, axis="x")
    fig.suptitle(f"Residual after diagnosis: {v.get('status', '?')} ({v.get('cost_per_entry', float('nan')):.2f} "
                 f"squared noise sigmas per residual; noise level {v.get('at_noise', float('nan')):g})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100, bbox_inches="tight")  # long channel and run names: nothing cut off
    plt.close(fig)
    return Path(path)


def plot_diagnosis(diag, out_dir) -> list[Path]:
    """All diagnosis plots into ``out_dir`` (created); returns the files."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [plot_validation_runs(diag, out / "validation_runs.png"), plot_errors(diag, out / "errors_over_time.png"),
            plot_steps(diag, out / "steps.png"), plot_residual(diag, out / "residual.png")]
