"""Plots of hydrodynamic tables (seed 003 Figs. 14-17 style): coefficient versus angle of attack
for several Reynolds numbers, points coloured by the method that filled each cell.
The only hydro module that imports matplotlib."""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np  # noqa: E402

METHOD_COLOURS = {
    "experiment": "tab:red", "cfd": "gold", "jorgensen": "tab:blue", "datcom": "tab:cyan",
    "lifting_line": "tab:orange", "montgomerie_blend": "tab:purple", "flat_plate": "tab:green",
}


def plot_table(table, out_dir, n_re: int = 5, prefix: str | None = None) -> list[Path]:
    """Write one PNG per coefficient (CL, CD, CM vs alpha in degrees) to ``out_dir``.

    ``n_re`` Reynolds rows, evenly spread over the table, are drawn as grey lines; cells are
    dots coloured by provenance, smoothed cells drawn with a black edge.  Returns the paths.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    prefix = prefix or table.name
    rows = np.unique(np.linspace(0, table.re.size - 1, min(n_re, table.re.size)).round().astype(int))
    deg = np.degrees(table.alpha)
    paths = []
    for key in ("CL", "CD", "CM"):
        fig, ax = plt.subplots(figsize=(8, 4.5))
        vals = getattr(table, key)
        seen = set()
        for j in rows:
            ax.plot(deg, vals[j], color="0.6", lw=0.8, zorder=1)
            meth = table.method[j].astype(str)
            for m in np.unique(meth):
                sel = meth == m
                ax.scatter(deg[sel], vals[j, sel], s=6, color=METHOD_COLOURS.get(m, "k"), zorder=2,
                           label=m if m not in seen else None)
                seen.add(m)
            sm = table.smoothed[j]
            if np.any(sm):
                ax.scatter(deg[sm], vals[j, sm], s=14, facecolors="none", edgecolors="k", lw=0.5, zorder=3,
                           label="makima-smoothed" if "smoothed" not in seen else None)
                seen.add("smoothed")
        ax.set_xlabel("angle of attack (deg)")
        ax.set_ylabel(key)
        ax.set_xlim(-180, 180)
        ax.set_title(f"{table.name}: {key}, Re = {table.re[rows[0]]:.3g} .. {table.re[rows[-1]]:.3g}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
        fig.tight_layout()
        p = out_dir / f"{prefix}_{key}.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths


def plot_wing_vs_data(alpha_deg, analytic: dict, data: dict, re: float, path) -> Path:
    """Analytic blend versus experimental polar at one Re (CL and CD on two axes)."""
    fig, axs = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key in zip(axs, ("CL", "CD")):
        ax.plot(data["alpha_deg"], data[key], "k.", ms=3, label="Sheldahl & Klimas (1981)")
        ax.plot(alpha_deg, analytic[key], "-", color="tab:purple", label="lifting line + flat plate")
        ax.set_xlabel("angle of attack (deg)")
        ax.set_ylabel(key)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"NACA 0015, Re = {re:.3g}")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
