"""Message streams -> rows of a run on one time base, with a report of what was done.

A log holds several message streams at their own rates (attitude at 10-50 Hz,
pressure at 2-10 Hz, motor outputs at 2-50 Hz ...).  :func:`merge_streams` puts every
sample on a row of one table without interpolating anything:

* samples of different streams closer than ``tol`` seconds (default 5 ms: messages
  written in the same autopilot loop) share a row whose time is the earliest of
  them; the largest such shift is reported per stream;
* every other sample gets a row of its own, so a sensor that did not sample at a
  row's time is NaN there (a missing sample, docs/log_format.md);
* input streams (motor commands) are held from one sample to the next (zero-order
  hold: an ESC keeps its last command), which the report states;
* the battery voltage is left NaN between its samples; the log format holds it
  (:attr:`uvsim.logs.Run.voltage`).

Within a stream, samples must have finite, non-decreasing times; samples that repeat
a time stamp are dropped and counted in the report (never silently).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from uvsim.errors import LogFormatError

#: Default tolerance (s) for putting samples of different streams on one row.
MERGE_TOL_S = 0.005
ROLES = ("measured", "input", "voltage")


@dataclass
class Stream:
    """One message stream mapped to log-format columns.

    Attributes
    ----------
    name : short name used in the report ("attitude", "depth", "motors", ...).
    source : message type or topic, with the fields used (for the manifest).
    t : (n,) sample times on the log's time base, s.
    columns : log-format column -> (n,) values in SI units.
    role : "measured", "input" (held between samples) or "voltage".
    notes : conversions applied (units, offsets), copied into the manifest.
    """

    name: str
    source: str
    t: np.ndarray
    columns: dict
    role: str = "measured"
    notes: list = field(default_factory=list)

    def __post_init__(self):
        if self.role not in ROLES:
            raise ValueError(f"stream {self.name}: role {self.role!r} not in {ROLES}")
        self.t = np.asarray(self.t, float)
        self.columns = {k: np.asarray(v, float) for k, v in self.columns.items()}
        for k, v in self.columns.items():
            if v.shape != self.t.shape:
                raise LogFormatError(f"{self.source}: field for column {k!r} has {v.size} samples for {self.t.size} times")


def clean(stream: Stream, where: str) -> tuple[Stream, dict]:
    """Drop samples with non-finite times or a repeated time stamp (counted), check order."""
    t = stream.t
    rep = {"source": stream.source, "samples_in_log": int(t.size)}
    ok = np.isfinite(t)
    if (~ok).any():
        rep["dropped_nonfinite_time"] = int((~ok).sum())
    order = np.argsort(t[ok], kind="stable")
    tt = t[ok][order]
    if np.any(np.diff(t[ok]) < 0):
        rep["reordered_samples"] = int(np.sum(np.diff(t[ok]) < 0))
    keep = np.ones(tt.size, bool)
    keep[1:] = np.diff(tt) > 0
    if (~keep).any():
        rep["dropped_repeated_timestamp"] = int((~keep).sum())
    cols = {k: v[ok][order][keep] for k, v in stream.columns.items()}
    if not keep.sum():
        raise LogFormatError(f"{where}: {stream.source}: no samples with a valid time stamp")
    out = Stream(stream.name, stream.source, tt[keep], cols, stream.role, list(stream.notes))
    return out, rep


def merge_streams(streams: list[Stream], *, tol: float = MERGE_TOL_S, where: str = "log"
                  ) -> tuple[pd.DataFrame, dict, dict]:
    """Put all samples on rows of one table (see module docstring).

    Returns
    -------
    frame : DataFrame with ``t`` and every stream's columns; input columns are held
        (forward-filled) from their first sample on, everything else NaN between samples.
    report : per stream: source, samples, median rate (Hz), largest row shift (s),
        drops; plus the merge tolerance.
    sample_times : per stream name, its (cleaned) sample times (for gap reports).
    """
    cleaned, report = [], {}
    for s in streams:
        c, rep = clean(s, where)
        cleaned.append(c)
        report[s.name] = rep
    names = [c.name for c in cleaned]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate stream names {names}")
    times = np.concatenate([c.t for c in cleaned])
    sid = np.concatenate([np.full(c.t.size, i) for i, c in enumerate(cleaned)])
    idx = np.concatenate([np.arange(c.t.size) for c in cleaned])
    order = np.lexsort((sid, times))
    row_of = np.empty(times.size, np.intp)
    row_t: list[float] = []
    members: set = set()
    for e in order:  # greedy: a row collects samples within tol of its first, one per stream
        if row_t and times[e] - row_t[-1] <= tol and sid[e] not in members:
            members.add(sid[e])
        else:
            row_t.append(float(times[e]))
            members = {sid[e]}
        row_of[e] = len(row_t) - 1
    row_t_arr = np.array(row_t)
    data = {"t": row_t_arr}
    for i, c in enumerate(cleaned):
        sel = sid == i
        rows = np.empty(c.t.size, np.intp)
        rows[idx[sel]] = row_of[sel]
        shift = c.t - row_t_arr[rows]
        for col, vals in c.columns.items():
            if col in data:
                raise LogFormatError(f"{where}: column {col!r} is mapped from two streams ({c.source} and another)")
            a = np.full(row_t_arr.size, np.nan)
            a[rows] = vals
            data[col] = a
        dt = np.diff(c.t)
        rep = report[c.name]
        rep.update(samples=int(c.t.size), columns=sorted(c.columns), role=c.role,
                   median_rate_hz=float(1.0 / np.median(dt)) if dt.size else None,
                   max_row_shift_s=float(shift.max()) if shift.size else 0.0)
        if c.notes:
            rep["notes"] = list(c.notes)
    frame = pd.DataFrame(data)
    for c in cleaned:
        if c.role == "input":
            frame[list(c.columns)] = frame[list(c.columns)].ffill()
            report[c.name]["held"] = "zero-order hold from each sample to the next (ESC keeps its last command)"
        elif c.role == "voltage":
            report[c.name]["held"] = "NaN between samples; the log format holds the last sample"
    report["_merge"] = {"tolerance_s": tol, "rows": int(row_t_arr.size),
                        "rule": "samples of different streams within tolerance share a row at the earliest "
                                "sample's time; no value is interpolated"}
    return frame, report, {c.name: c.t for c in cleaned}


def gaps(t: np.ndarray, *, factor: float = 3.0, min_gap_s: float = 0.0) -> list[dict]:
    """Intervals longer than ``factor`` x the median sample interval (and ``min_gap_s``):
    ``[{"start": t_i, "duration": dt}]`` on the given time base."""
    t = np.asarray(t, float)
    if t.size < 3:
        return []
    dt = np.diff(t)
    lim = max(factor * float(np.median(dt)), min_gap_s)
    return [{"start": float(t[i]), "duration": float(dt[i])} for i in np.flatnonzero(dt > lim)]
