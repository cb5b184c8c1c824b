"""Gaps in logged runs, and the runs' segments between them (docs/log_format.md, "Gaps").

A *gap* is a stretch of a run in which nothing was measured for longer than the sensors'
sampling explains: a logger that stopped for a third of a second, rows deleted from a
file, a converter that wrote the inputs on and left the sensor cells empty.  No method can
use such a stretch as it is: the Savitzky-Golay derivatives of the equation-error screening
need complete signals (:mod:`uvsim.estimation.derivatives`), and a
simulation that runs through it holds the inputs, or follows inputs no measurement checks.
Before this module, a run with a 0.36 s gap silently dropped out of the diagnosis' screening.

:func:`split_run` cuts a run at its gaps into *segments*: runs named ``NAME[1]``,
``NAME[2]``, ... with their own rows (the rows inside a gap, which hold no measurement, are
left out), the run's ``dof``, ``weight`` and ``split``, and a note (:attr:`uvsim.logs.Run.notes`)
that the commands print.  Every :class:`uvsim.logs.Dataset` holds the segments of its runs
(``read_dataset``, the calibration's runs in memory), and ``uvsim simulate`` simulates each
segment from its own first measured state, so calibration, diagnosis (screening included)
and ``simulate --compare`` all see the same segments.

What is a gap (:func:`find_gaps`): the interval between two consecutive rows that carry a
measurement is a gap when it is, for *every* measured column, longer than that column's own
sampling explains (a 10 Hz depth sensor written with empty cells between its samples in a
100 Hz log leaves no gap while the IMU's columns carry on); and the step between two rows is
a gap when it is longer than the rows' own step and the fastest sensor's interval explain
(rows deleted: the inputs are unknown there too).  "Explains" is :func:`interval_limit`:
``GAP_FACTOR`` median intervals, or the median plus ``JITTER_SIGMAS`` robust standard
deviations of the intervals when the time stamps jitter more.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uvsim.errors import LogFormatError
from uvsim.log_columns import MEASURED_COLUMNS, VOLTAGE_COLUMN, _row

#: An interval is a gap beyond this many median intervals of a column: one or two lost
#: samples are a logger's ordinary losses, three are a stop.  The same bound as the
#: importers' per-stream gap report (docs/import_export.md, "Rows, holds and gaps").
GAP_FACTOR = 3.0
#: ... and beyond the median plus this many robust standard deviations (1.4826 MAD) of the
#: intervals, so that jittered time stamps are not cut: a normal jitter exceeds 6 sigma with
#: probability 2e-9 per interval (under 1e-3 for a one-hour log at 100 Hz), while a Linux
#: logger's 1-5 ms jitter at 100 Hz (calibration_structural's ``time_jitter``) can exceed
#: three median intervals.
JITTER_SIGMAS = 6.0
#: A column needs this many samples for its own sampling interval; with fewer it takes no
#: part in deciding what a gap is (its samples still end one).
MIN_SAMPLES = 3
#: A stretch between gaps becomes a segment when every measured column it logs has at least
#: this many samples in it: calibration and diagnosis estimate each column's noise per run from
#: 8 native samples (:func:`uvsim.estimation.noise.noise_sigma`) and stop without them.
#: Shorter stretches are left out and named in the run's note.
MIN_SEGMENT_SAMPLES = 8


@dataclass(frozen=True)
class Gap:
    """One gap of a run: between row ``before`` (the last row before it) and row ``after``
    (the first row after it), at times ``t0`` and ``t1`` (s)."""

    before: int
    after: int
    t0: float
    t1: float

    @property
    def duration(self) -> float:
        return self.t1 - self.t0

    @property
    def empty_rows(self) -> int:
        """Rows inside the gap (they hold inputs but no measurement)."""
        return self.after - self.before - 1


def interval_limit(d: np.ndarray) -> float:
    """The longest interval that sampling intervals ``d`` (s) explain: the larger of
    ``GAP_FACTOR`` x their median and their median + ``JITTER_SIGMAS`` x 1.4826 x MAD."""
    med = float(np.median(d))
    mad = float(np.median(np.abs(d - med)))
    return max(GAP_FACTOR * med, med + JITTER_SIGMAS * 1.4826 * mad)


def _column_rates(t: np.ndarray, finite: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """Per measured column with at least ``MIN_SAMPLES`` samples: (its sample times, the
    longest interval its sampling explains)."""
    out = []
    for j in range(finite.shape[1]):
        s = t[finite[:, j]]
        if s.size >= MIN_SAMPLES:
            out.append((s, interval_limit(np.diff(s))))
    return out


def _measurement_gaps(t: np.ndarray, finite: np.ndarray, rates) -> list[tuple[int, int]]:
    """(before, after) row pairs of consecutive measured rows between which every column
    with a rate misses more than its sampling explains (or has not started, or has ended)."""
    rows = np.flatnonzero(finite.any(axis=1))
    if rows.size < 2 or not rates:
        return []
    a, b = t[rows[:-1]], t[rows[1:]]
    # longer than even the fastest column's sampling explains (a column that ends where another
    # starts is no gap), and for every column inside one of its dropouts or beyond its ends
    gap = (b - a) > min(lim for _, lim in rates)
    for s, limit in rates:
        k = np.searchsorted(s, a, side="right") - 1  # the column's last sample at or before a
        inside = (k >= 0) & (k + 1 < s.size)         # before its first / after its last sample: absent
        span = np.where(inside, s[np.minimum(k + 1, s.size - 1)] - s[np.maximum(k, 0)], np.inf)
        gap &= span > limit
    return [(int(rows[i]), int(rows[i + 1])) for i in np.flatnonzero(gap)]


def _time_gaps(t: np.ndarray, rates) -> list[tuple[int, int]]:
    """(i, i + 1) row pairs whose time step exceeds what the rows' steps and the fastest
    column's sampling explain (rows missing: no inputs either)."""
    d = np.diff(t)
    limit = interval_limit(d)
    if rates:
        limit = max(limit, min(lim for _, lim in rates))
    return [(int(i), int(i) + 1) for i in np.flatnonzero(d > limit)]


def find_gaps(run) -> list[Gap]:
    """The gaps of ``run`` (a :class:`uvsim.logs.Run`), in time order (module docstring).

    Returns
    -------
    list of :class:`Gap`
        Overlapping measurement and time gaps merged; empty for a run without gaps.
    """
    t = run.t
    cols = [c for c in MEASURED_COLUMNS if c in run.data.columns]
    if t.size < 3 or not cols:
        return []
    finite = run.data[cols].notna().to_numpy()
    rates = _column_rates(t, finite)
    pairs = sorted(_measurement_gaps(t, finite, rates) + _time_gaps(t, rates))
    merged: list[list[int]] = []
    for a, b in pairs:
        if merged and a < merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return [Gap(a, b, float(t[a]), float(t[b])) for a, b in merged]


def _describe(g: Gap, run, src: str) -> str:
    """``0.5 s at t = 4.9..5.4 s (rows 50..53 hold no measurement)`` for one gap."""
    off = run.row_offset
    if g.empty_rows:
        rows = (f"{g.empty_rows} row{'s' if g.empty_rows > 1 else ''} from {_row(g.before + 1 + off, src)} "
                "hold no measurement")
    else:
        rows = f"no rows between {_row(g.before + off, src)} and the next"
    return f"{g.duration:.3g} s at t = {g.t0:.6g}..{g.t1:.6g} s ({rows})"


def _segment(run, a: int, b: int, name: str):
    """Rows ``a..b-1`` of ``run`` as a run of their own (validated like any run).  A held
    battery voltage starts the segment with the value that holds at its first row."""
    data = run.data.iloc[a:b].reset_index(drop=True).copy()
    if VOLTAGE_COLUMN in data.columns and np.isnan(data[VOLTAGE_COLUMN].iloc[0]):
        data.loc[0, VOLTAGE_COLUMN] = run.voltage[a]  # the sample that holds there (zero-order hold)
    # the run's own class (uvsim.logged_run.Run), which validates the rows: uvsim.logs imports this module
    seg = type(run)(name=name, path=run.path, data=data, dof=run.dof, weight=run.weight, split=run.split,
                    closed_loop=run.closed_loop)
    seg.empty_columns = list(dict.fromkeys(run.empty_columns + seg.empty_columns))
    seg.row_offset = run.row_offset + a
    seg.segment_of = run.name
    seg.input_delay = run.input_delay
    return seg


def _pieces(run, gaps: list[Gap]) -> list[tuple[int, int]]:
    """(first row, end row) of the stretches before, between and after ``gaps``."""
    starts = [0] + [g.after for g in gaps]
    ends = [g.before + 1 for g in gaps] + [len(run.t)]
    return list(zip(starts, ends))


def _too_few(run, a: int, b: int) -> str:
    """Why rows ``a..b-1`` of ``run`` are too short for a segment (``MIN_SEGMENT_SAMPLES``),
    or ``""``."""
    cols = [c for c in MEASURED_COLUMNS if c in run.data.columns]
    counts = run.data[cols].iloc[a:b].notna().sum().to_numpy()
    few = [c for c, k in zip(cols, counts) if 0 < k < MIN_SEGMENT_SAMPLES]
    if not counts.any():
        return "no measurement"
    if few:
        return (f"fewer than {MIN_SEGMENT_SAMPLES} samples of {', '.join(few)} (calibration and diagnosis estimate "
                f"each column's noise from {MIN_SEGMENT_SAMPLES})")
    return ""


def split_run(run) -> list:
    """``run`` cut at its gaps (:func:`find_gaps`) into segments (module docstring).

    Returns
    -------
    list of :class:`uvsim.logs.Run`
        ``[run]`` itself when it has no gap (or is a segment already); else the segments
        ``NAME[1]``, ``NAME[2]``, ... each carrying the note that says where the run was cut
        and which stretches were left out (no measurement, or a measured column with fewer
        than ``MIN_SEGMENT_SAMPLES`` samples).

    Raises
    ------
    LogFormatError
        When no stretch between the gaps is long enough for a segment: the run would vanish.
    """
    if run.segment_of is not None:
        return [run]
    gaps = find_gaps(run)
    if not gaps:
        return [run]
    src = str(run.path) if run.path is not None else f"run {run.name!r}"
    kept, left = [], []
    for a, b in _pieces(run, gaps):
        short = _too_few(run, a, b)
        if not short:
            kept.append((a, b))
        else:
            left.append(f"t = {run.t[a]:.6g}..{run.t[b - 1]:.6g} s ({b - a} row{'s' if b - a > 1 else ''} from "
                        f"{_row(a + run.row_offset, src)}): {short}")
    what = (f"a gap without measurements of {_describe(gaps[0], run, src)}" if len(gaps) == 1 else
            f"{len(gaps)} gaps without measurements: " + "; ".join(_describe(g, run, src) for g in gaps))
    if not kept:
        raise LogFormatError(f"{src}: {what}; no stretch between them is long enough for a run: "
                             + "; ".join(left))
    names = [f"{run.name}[{k + 1}]" for k in range(len(kept))]
    into = f"split into {len(kept)} segments" if len(kept) > 1 else "cut to one segment"
    note = (f"{src}: {what}: {into} {', '.join(names)}"
            + (f"; left out: {'; '.join(left)}" if left else "")
            + " (docs/log_format.md, 'Gaps')")
    segments = []
    for (a, b), name in zip(kept, names):
        seg = _segment(run, a, b, name)
        seg.notes = list(run.notes) + [note]
        segments.append(seg)
    return segments


def split_runs(runs) -> list:
    """Every run of ``runs`` cut at its gaps (:func:`split_run`), in order."""
    return [seg for run in runs for seg in split_run(run)]
