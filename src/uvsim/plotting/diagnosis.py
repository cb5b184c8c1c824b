"""Plots of a diagnosis (:func:`uvsim.diagnosis.diagnose`): residuals before/after over time.

Part of :mod:`uvsim.plotting`, the only package that imports matplotlib.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np  # noqa: E402

DOF = ("X [N]", "Y [N]", "Z [N]", "K [N m]", "M [N m]", "N [N m]")


def plot_output_residuals(diag, path, max_runs: int = 6) -> Path:
    """Position error |p - p_hat| (m) and attitude error angle (rad) over time, before and after,
    for up to ``max_runs`` validation runs."""
    runs = diag.validation[:max_runs]
    fig, axes = plt.subplots(len(runs), 2, figsize=(11, 2.1 * len(runs) + 0.6), squeeze=False, sharex="row")
    for i, run in enumerate(runs):
        b, a = diag.residuals_before[i], diag.residuals_after[i]
        for j, (key, label) in enumerate((("position", "position error [m]"), ("attitude_angle", "attitude error [rad]"))):
            ax = axes[i, j]
            if key not in b:
                ax.text(0.5, 0.5, "not logged", ha="center", va="center", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            eb = b[key] if b[key].ndim == 1 else np.sqrt(np.nansum(b[key] ** 2, axis=1))
            ea = a[key] if a[key].ndim == 1 else np.sqrt(np.nansum(a[key] ** 2, axis=1))
            ax.plot(b["t"], eb, color="tab:red", lw=1.2, label="before (given model)")
            ax.plot(a["t"], ea, color="tab:blue", lw=1.2, label=f"after ({diag.report['effect']})")
            ax.set_ylabel(label, fontsize=8)
            ax.set_title(f"{run.name} ({run.dof or 'run'})", fontsize=9)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(f"Validation residuals before / after: effect = {diag.report['effect']} "
                 f"({diag.report['confidence']})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_force_residuals(diag, path, max_runs: int = 3) -> Path:
    """Inverse-dynamics generalized-force residual (body frame) before/after for up to
    ``max_runs`` validation runs (one column per run, one row per DOF)."""
    runs = diag.validation[:max_runs]
    fig, axes = plt.subplots(6, len(runs), figsize=(4.2 * len(runs), 9), squeeze=False, sharex="col")
    for k, run in enumerate(runs):
        fb, fa = diag.force_before[k], diag.force_after[k]
        for i in range(6):
            ax = axes[i, k]
            ax.plot(fb["t"], fb["body"][:, i], color="tab:red", lw=0.9, label="before")
            ax.plot(fa["t"], fa["body"][:, i], color="tab:blue", lw=0.9, label="after")
            ax.axhline(0, color="k", lw=0.5)
            if k == 0:
                ax.set_ylabel(DOF[i], fontsize=8)
            ax.grid(alpha=0.3)
        axes[0, k].set_title(f"{run.name}" + (f" ({fb['problem']})" if fb["problem"] else ""), fontsize=8)
        axes[-1, k].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Generalized-force residual M (nu_dot_measured - f(eta, nu, u)), body frame", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_candidates(diag, path) -> Path:
    """Validation RMS (noise sigmas) of every candidate, accepted ones highlighted."""
    rows = [c for c in diag.report["candidates"] if "score" in c]
    names = [c["name"] for c in rows]
    vals = [c["validation_rms_noise_sigmas"] for c in rows]
    colors = ["tab:green" if c["accepted"] else ("tab:gray" if c["name"] == "none" else "tab:orange") for c in rows]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.bar(names, vals, color=colors)
    ax.axhline(1.0, color="k", ls="--", lw=0.8, label="noise level")
    ax.set_yscale("log")
    ax.set_ylabel("validation RMS [noise sigmas]")
    for i, c in enumerate(rows):
        ax.text(i, vals[i], f"dBIC {c['score']['delta_bic']:.0f}", ha="center", va="bottom", fontsize=7)
    ax.legend(fontsize=8)
    ax.set_title(f"Candidates (green: accepted); chosen: {diag.report['effect']}", fontsize=10)
    plt.setp(ax.get_xticklabels(), rotation=20, fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def plot_diagnosis(diag, out_dir) -> list[Path]:
    """All diagnosis plots into ``out_dir`` (created); returns the files."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [plot_output_residuals(diag, out / "residuals_over_time.png"),
            plot_force_residuals(diag, out / "force_residuals.png"),
            plot_candidates(diag, out / "candidates.png")]
