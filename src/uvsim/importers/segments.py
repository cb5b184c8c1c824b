"""Cut an imported log into runs and write the dataset with its import record.

Runs come from *segments*: the armed intervals of an ArduSub log, the whole bag, or a
segments YAML written by the user::

    segments:                        # times on the log's time base (see the manifest's import.time_base)
      - {start: 206.7, end: 222.7, dof: mixed, split: train, name: manual_1}
      - {start: 230.0, end: 241.5, dof: heave, split: validation}

Keys: ``start``, ``end`` (s, required), ``dof`` (default ``mixed``), ``split`` (default
``train``), ``name`` (default ``<log>_<k>``), ``weight`` (default 1).

Every run's record (in ``manifest.yaml`` under ``import.runs``) states its start on the
log's time base (``t0_s``; the run's ``t`` starts at 0), any time cut at its start
because the motor commands or the battery voltage were not yet known, where the
voltage of its first row was held from, and each stream's gaps.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from uvsim.errors import LogFormatError
from uvsim.files import load_yaml, plain
from uvsim.importers.timeline import gaps
from uvsim.logged_run import DOFS, SPLITS, Run
from uvsim.logs import MANIFEST, MEASURED_COLUMNS, VOLTAGE_COLUMN, write_run

_KEYS = {"start", "end", "dof", "split", "name", "weight"}


@dataclass
class Segment:
    start: float
    end: float
    name: str
    dof: str = "mixed"
    split: str = "train"
    weight: float = 1.0
    origin: str = ""
    closed_loop: bool | None = None   # flown under an autopilot (the manifest's closed_loop); None: not known


def load_segments(path, default_prefix: str) -> list[Segment]:
    """Read a segments YAML (module docstring); errors name the file and ``segments[k]``."""
    path = Path(path)
    doc = load_yaml(path, error=LogFormatError, what="segments file (YAML)")
    items = doc.get("segments") if isinstance(doc, dict) else doc
    if not isinstance(items, list) or not items:
        raise LogFormatError(f"{path}: expected a non-empty list 'segments: [{{start: .., end: ..}}, ...]'")
    out, names = [], set()
    for k, it in enumerate(items):
        where = f"{path}: segments[{k}]"
        if not isinstance(it, dict):
            raise LogFormatError(f"{where}: expected a mapping with start and end (s), got {it!r}")
        unknown = set(it) - _KEYS
        if unknown:
            raise LogFormatError(f"{where}: unknown key(s) {sorted(unknown)}; allowed: {sorted(_KEYS)}")
        try:
            start, end = float(it["start"]), float(it["end"])
        except KeyError as exc:
            raise LogFormatError(f"{where}: missing {exc.args[0]!r} (s, on the log's time base)") from None
        except (TypeError, ValueError):
            raise LogFormatError(f"{where}: start/end must be numbers of seconds, got {it.get('start')!r}, "
                                 f"{it.get('end')!r}") from None
        if not (np.isfinite(start) and np.isfinite(end) and end > start):
            raise LogFormatError(f"{where}: need finite start < end, got {start} .. {end}")
        dof, split = it.get("dof", "mixed"), it.get("split", "train")
        if dof not in DOFS:
            raise LogFormatError(f"{where}: dof {dof!r} is not one of {', '.join(DOFS)}")
        if split not in SPLITS:
            raise LogFormatError(f"{where}: split {split!r} is not one of {', '.join(SPLITS)}")
        weight = it.get("weight", 1.0)
        if isinstance(weight, bool) or not isinstance(weight, (int, float)) or not weight > 0:
            raise LogFormatError(f"{where}: weight {weight!r} must be a positive number")
        name = str(it.get("name", f"{default_prefix}_{k + 1:02d}"))
        if name in names:
            raise LogFormatError(f"{where}: name {name!r} is used twice")
        names.add(name)
        out.append(Segment(start, end, name, dof, split, float(weight), origin=f"{path.name}: segments[{k}]"))
    return out


def cut_run(frame: pd.DataFrame, seg: Segment, input_cols: list[str], sample_times: dict,
            where: str) -> tuple[pd.DataFrame | None, dict]:
    """Rows of ``frame`` in ``[seg.start, seg.end]`` as a run table (``t`` from 0) and its record.

    Returns ``(None, record)`` with ``record["skipped"]`` giving the reason when the
    segment holds no usable run (fewer than 2 rows with known inputs, or nothing measured)."""
    t = frame["t"].to_numpy()
    rec: dict = {"segment": {"start_s": seg.start, "end_s": seg.end, "from": seg.origin}}
    sel = np.flatnonzero((t >= seg.start) & (t <= seg.end))
    known = frame[input_cols].notna().all(axis=1).to_numpy()
    has_v = VOLTAGE_COLUMN in frame.columns
    held_v = frame[VOLTAGE_COLUMN].ffill().to_numpy() if has_v else None
    if has_v:
        known = known & np.isfinite(held_v)
    ok = sel[known[sel]]
    if ok.size < 2:
        reason = ("no motor-command sample at or before the segment" if not known[sel].any()
                  else "fewer than 2 rows with known motor commands")
        rec["skipped"] = f"{reason} ({sel.size} rows in the segment)"
        return None, rec
    first = ok[0]
    if first != sel[0]:
        rec["cut_at_start_s"] = float(t[first] - t[sel[0]])
        rec["cut_reason"] = "motor commands" + (" or battery voltage" if has_v else "") + " not yet logged"
    rows = np.arange(first, sel[-1] + 1)
    df = frame.iloc[rows].reset_index(drop=True).copy()
    if has_v and np.isnan(df.at[0, VOLTAGE_COLUMN]):
        src = int(np.flatnonzero(np.isfinite(frame[VOLTAGE_COLUMN].to_numpy()[: first + 1]))[-1])
        df.at[0, VOLTAGE_COLUMN] = frame.at[src, VOLTAGE_COLUMN]
        rec["voltage_row0_held_from_s"] = float(t[src])
    measured = [c for c in MEASURED_COLUMNS if c in df.columns and df[c].notna().any()]
    if not measured:
        rec["skipped"] = "no measured sample in the segment"
        return None, rec
    empty = [c for c in df.columns if c != "t" and df[c].isna().all()]
    df = df.drop(columns=empty)
    t0 = float(df.at[0, "t"])
    df["t"] = df["t"] - t0
    rec.update(t0_s=t0, rows=int(len(df)), duration_s=float(df["t"].iloc[-1]), columns=[c for c in df.columns if c != "t"])
    if empty:
        rec["columns_without_samples"] = empty
    streams = {}
    for name, ts in sample_times.items():
        inside = ts[(ts >= t0) & (ts <= t0 + rec["duration_s"])]
        entry = {"samples": int(inside.size)}
        g = gaps(inside)
        if g:
            entry["gaps"] = [{"start_s": round(x["start"] - t0, 6), "duration_s": round(x["duration"], 6)} for x in g]
        streams[name] = entry
    rec["streams"] = streams
    return df, rec


def write_imported_dataset(out, runs: list[tuple[Segment, pd.DataFrame]], *, vehicle: str, description: str,
                           record: dict) -> Path:
    """Write the runs (validated by :func:`uvsim.logs.write_run`) and ``manifest.yaml``
    with ``import: record``; returns the directory."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    entries = []
    for seg, df in runs:
        write_run(out / f"{seg.name}.csv", Run(name=seg.name, path=None, data=df, dof=seg.dof,
                                               weight=seg.weight, split=seg.split, closed_loop=seg.closed_loop))
        entries.append({"file": f"{seg.name}.csv", "dof": seg.dof, "weight": seg.weight, "split": seg.split})
        if seg.closed_loop is not None:
            entries[-1]["closed_loop"] = seg.closed_loop
    doc = {"vehicle": vehicle, "description": description, "runs": entries, "import": plain(record)}
    (out / MANIFEST).write_text(yaml.safe_dump(doc, sort_keys=False, width=110))
    return out

