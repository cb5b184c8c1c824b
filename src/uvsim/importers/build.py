"""Streams + segments -> validated run tables and the import record (shared by the importers)."""
from __future__ import annotations

import numpy as np

from uvsim.errors import LogFormatError
from uvsim.importers.segments import Segment, cut_run
from uvsim.importers.timeline import MERGE_TOL_S, merge_streams
from uvsim.log_columns import PWM_RANGE_US
from uvsim.logged_run import Run


def build_runs(streams: list, segments: list[Segment], *, where: str, tol: float = MERGE_TOL_S,
               input_sources: dict | None = None) -> tuple[list, dict]:
    """Merge ``streams``, cut one run per segment and validate each as a log-format run.

    Parameters
    ----------
    streams : :class:`uvsim.importers.timeline.Stream` list (exactly one with role "input").
    segments : where the runs are.
    where : the log file (for messages).
    input_sources : input column -> "MESSAGE.field" named when a command is out of range.

    Returns
    -------
    runs : [(Segment, DataFrame)] for the segments that hold a run.
    record : {"streams": merge report, "runs": {name: record}, "skipped": {name: reason}}.
    """
    frame, report, sample_times = merge_streams(streams, tol=tol, where=where)
    input_cols = [c for s in streams if s.role == "input" for c in s.columns]
    if not input_cols:
        raise LogFormatError(f"{where}: no thruster-command stream; a run needs inputs")
    runs, recs, skipped = [], {}, {}
    for seg in segments:
        df, rec = cut_run(frame, seg, input_cols, sample_times, where)
        if df is None:
            skipped[seg.name] = rec["skipped"]
            continue
        lo, hi = PWM_RANGE_US
        for c in input_cols:
            if not c.startswith("pwm_"):
                continue
            v = df[c].to_numpy()
            bad = np.flatnonzero((v < lo) | (v > hi))
            if bad.size:
                i = int(bad[0])
                src = (input_sources or {}).get(c, c)
                raise LogFormatError(
                    f"{where}: {src} = {v[i]:g} us at t = {rec['t0_s'] + df['t'].iloc[i]:.3f} s (segment {seg.name}) "
                    f"is outside the ESC range {lo:g}..{hi:g} us (0 = output disabled); cut this time out with a "
                    "segments YAML"
                )
        Run(name=seg.name, path=None, data=df, dof=seg.dof, weight=seg.weight, split=seg.split)  # validates
        runs.append((seg, df))
        recs[seg.name] = rec
    record = {"streams": report, "runs": recs}
    if skipped:
        record["skipped_segments"] = skipped
    if not runs:
        raise LogFormatError(f"{where}: no segment holds a run ({'; '.join(f'{k}: {v}' for k, v in skipped.items())})")
    return runs, record


def summary_lines(result: dict) -> list[str]:
    """Human-readable summary printed by the CLI."""
    rec = result["record"]
    lines = [f"dataset {result['dataset']} (vehicle {result['vehicle']}): {len(result['runs'])} run(s)"]
    for name, dur, rows in result["runs"]:
        cols = rec["runs"][name]["columns"]
        lines.append(f"  {name}: {dur:.2f} s, {rows} rows, columns {', '.join(cols)}")
    for name, why in rec.get("skipped_segments", {}).items():
        lines.append(f"  skipped {name}: {why}")
    for name, why in rec.get("optional_streams_missing", {}).items():
        lines.append(f"  stream {name} skipped: {why}")
    for k, s in rec["streams"].items():
        if k.startswith("_"):
            continue
        rate = s.get("median_rate_hz")
        lines.append(f"  stream {k}: {s['source']}, {s['samples']} samples"
                     + (f", {rate:.1f} Hz" if rate else ""))
    if rec.get("flight_modes"):
        ch = rec["flight_modes"]["changes"]
        lines.append(f"  flight modes ({rec['flight_modes']['source']}): "
                     + (", ".join(f"{c['mode']} from {c['t_s']:g} s" for c in ch) if ch else "none reported")
                     + "; each run's closed_loop is in the manifest")
    if rec.get("frame", {}).get("adapted"):
        a = rec["frame"]["adapted"]
        lines.append(f"  vehicle adapted: {a['file']} (flipped {', '.join(a['flipped'])})")
    if rec.get("truncated"):
        lines.append(f"  warning: log truncated: {rec['truncated']}")
    if rec.get("position"):
        lines.append(f"  position: {rec['position']}")
    return lines
