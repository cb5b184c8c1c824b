"""Read, validate and write logged runs and datasets (docs/log_format.md).

A *run* is one CSV or Parquet file whose columns are named as in the log
format (``t``, ``x``..``z``, ``qw``..``qz`` or ``roll``/``pitch``/``yaw``,
``u``..``r`` and one kind of inputs).  A *dataset* is a directory with a
``manifest.yaml`` listing run files.  Everything the contract forbids raises
:class:`uvsim.errors.LogFormatError` naming the file, the column and/or the
row; nothing is dropped, clipped or resampled.  Rows are counted from 0 (the
first data row); for CSV files the message also gives the line number.
"""
from __future__ import annotations

import copy
import csv
import importlib.util
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from uvsim.errors import LogFormatError
from uvsim.files import load_yaml, not_text
from uvsim.gaps import split_runs
from uvsim.kinematics import euler_to_quat, quat_to_euler
from uvsim.log_columns import (  # noqa: F401  (the column names are part of this module's interface)
    ACCEL_COLUMNS, ATTITUDE_CONSISTENCY_TOL, DEPTH_COLUMN, EULER_COLUMNS, FORCE_COLUMNS, INPUT_KINDS,
    MEASURED_COLUMNS, POSITION_COLUMNS, PWM_RANGE_US, QUAT_COLUMNS, QUAT_NORM_TOL, QUAT_NOTE_TOL, RATE_COLUMNS,
    VELOCITY_COLUMNS, VOLTAGE_COLUMN, FORMAT_COLUMNS, _empty_column_notes, _extra_column_notes, _quaternion_notes,
    _validate)
from uvsim.schema import check_keys, require_mapping

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw", "mixed")
SPLITS = ("train", "validation")
MANIFEST = "manifest.yaml"
#: Top-level keys of a manifest: the contract (vehicle, description, runs), the keys that
#: uvsim's own generators and importers write (truth, noise, sources, import) and ``meta``
#: for free-form metadata.
#: Anything else is a typo (``vehicel``, ``run``) and an error with a did-you-mean.
MANIFEST_KEYS = ("vehicle", "description", "runs", "meta", "truth", "noise", "sources", "import")
_RUN_KEYS = ("file", "dof", "weight", "split")


def _check_choice(value, allowed, what: str, source: str, none_ok: bool = True):
    if value is None and none_ok:
        return None
    if not isinstance(value, str) or value not in allowed:
        raise LogFormatError(f"{source}: {what} {value!r} is not one of {', '.join(allowed)}")
    return value


#: Largest run weight accepted (weights are relative): at a million to one the lighter runs already
#: count below 1e-12 of the cost (weights enter squared), and 1e300 overflowed the squared weighted
#: residuals to inf (numpy overflow warnings, a fit of nothing).
MAX_RUN_WEIGHT = 1e6


def _check_weight(weight, source: str) -> float:
    ok = isinstance(weight, (int, float, np.integer, np.floating)) and not isinstance(weight, bool)
    if not ok or not math.isfinite(float(weight)) or float(weight) <= 0:
        raise LogFormatError(f"{source}: weight {weight!r} must be a positive finite number")
    if float(weight) > MAX_RUN_WEIGHT:
        raise LogFormatError(f"{source}: weight {weight!r} is above {MAX_RUN_WEIGHT:g}; weights are relative (1 is "
                             "every run alike): scale them down")
    return float(weight)


@dataclass
class Run:
    """One logged run, validated on construction.

    ``data`` holds every column as read (float64, index 0..n-1); columns that
    were entirely empty are removed and listed in ``empty_columns``.  NaN in a
    measured signal is a missing sample and is kept.
    """

    name: str
    path: Path | None
    data: pd.DataFrame = field(repr=False)
    dof: str | None = None
    weight: float = 1.0
    split: str = "train"
    empty_columns: list[str] = field(init=False, default_factory=list)
    #: What the reader changed in the data beyond the float64 conversion or did not use (e.g.
    #: quaternions renormalized by more than :data:`QUAT_NOTE_TOL`, columns not in the format,
    #: a run split at a gap: :mod:`uvsim.gaps`); commands print these.
    notes: list[str] = field(init=False, default_factory=list)
    #: Row 0 of this table is row ``row_offset`` of the file (a segment of a run split at a
    #: gap, :mod:`uvsim.gaps`), so that messages name the file's rows.
    row_offset: int = field(init=False, default=0)
    #: The name of the run this one was cut from at a gap (:mod:`uvsim.gaps`); None for a
    #: run as read.
    segment_of: str | None = field(init=False, default=None)
    #: How much later than their time stamps the inputs act in this copy of the run, s
    #: (:func:`uvsim.latency.delay_inputs`; 0: as logged), and the run as logged.
    input_delay: float = field(init=False, default=0.0)
    as_logged: "Run | None" = field(init=False, repr=False, default=None)
    _kind: str = field(init=False, repr=False, default="")
    _input_columns: list[str] = field(init=False, repr=False, default_factory=list)

    def __post_init__(self):
        src = str(self.path) if self.path is not None else f"run {self.name!r}"
        self.path = Path(self.path) if self.path is not None else None
        self.dof = _check_choice(self.dof, DOFS, "dof", src)
        self.split = _check_choice(self.split, SPLITS, "split", src, none_ok=False)
        self.weight = _check_weight(self.weight, src)
        self.data, self.empty_columns, self._kind, self._input_columns = _validate(self.data, src)
        self.notes = (_quaternion_notes(self.data, src) + _extra_column_notes(self.data, self._input_columns, src)
                      + _empty_column_notes(self.empty_columns, src))

    def derived(self, data: pd.DataFrame, *, name: str | None = None) -> "Run":
        """A copy of this run with ``data`` in place of its table, not validated again: for
        tables derived from this run's own validated columns by the library (the inputs
        delayed by interpolation between logged values, :func:`uvsim.latency.delay_inputs`),
        whose columns, kind and finiteness are this run's.  ``name``: the copy's name."""
        if list(data.columns) != list(self.data.columns) or len(data) != len(self.data):
            raise ValueError(f"run {self.name}: a derived table must have this run's columns and length")
        out = copy.copy(self)
        out.data = data
        out.notes = list(self.notes)
        if name is not None:
            out.name = name
        return out

    def _cols(self, names) -> np.ndarray:
        """(n, len(names)) array, NaN for absent columns."""
        out = np.full((len(self.data), len(names)), np.nan)
        for j, c in enumerate(names):
            if c in self.data.columns:
                out[:, j] = self.data[c].to_numpy()
        return out

    def _has(self, names) -> bool:
        return any(c in self.data.columns for c in names)

    @property
    def t(self) -> np.ndarray:
        """Sample times, s, shape (n,)."""
        return self.data["t"].to_numpy()

    @property
    def input_kind(self) -> str:
        """``"force"``, ``"thrust"`` or ``"pwm"``."""
        return self._kind

    @property
    def input_columns(self) -> list[str]:
        """Input column names in the order of :attr:`inputs`."""
        return list(self._input_columns)

    @property
    def inputs(self) -> np.ndarray:
        """Inputs, shape (n, k): X,Y,Z,K,M,N (N, N m) or thrust_i (N) or pwm_i (us)."""
        return self.data[self._input_columns].to_numpy()

    @property
    def n_thrusters(self) -> int | None:
        """Number of thrust/pwm columns; None for force inputs."""
        return None if self._kind == "force" else len(self._input_columns)

    @property
    def has_position(self) -> bool:
        return self._has(POSITION_COLUMNS)

    @property
    def position(self) -> np.ndarray:
        """NED position x, y, z (m), shape (n, 3); NaN columns for absent axes."""
        return self._cols(POSITION_COLUMNS)

    @property
    def has_quaternion(self) -> bool:
        return self._has(QUAT_COLUMNS)

    @property
    def has_euler(self) -> bool:
        return self._has(EULER_COLUMNS)

    @property
    def has_attitude(self) -> bool:
        """True when the run logs any attitude channel (quaternion or any Euler angle)."""
        return self.has_quaternion or self.has_euler

    @property
    def has_full_attitude(self) -> bool:
        """True when the run logs the whole attitude (a quaternion or roll, pitch and yaw)."""
        return self.has_quaternion or all(c in self.data.columns for c in EULER_COLUMNS)

    @property
    def euler_mask(self) -> np.ndarray:
        """(3,) bool: which of roll, pitch, yaw the run logs (all three for a quaternion)."""
        if self.has_quaternion:
            return np.ones(3, bool)
        return np.array([c in self.data.columns for c in EULER_COLUMNS])

    @property
    def has_depth(self) -> bool:
        return DEPTH_COLUMN in self.data.columns

    @property
    def depth(self) -> np.ndarray:
        """Pressure-sensor depth (m, NED z of the sensor), shape (n,); all NaN when absent."""
        return self._cols((DEPTH_COLUMN,))[:, 0]

    @property
    def has_acceleration(self) -> bool:
        return self._has(ACCEL_COLUMNS)

    @property
    def acceleration(self) -> np.ndarray:
        """Accelerometer specific force (m/s^2, body axes, at the IMU), shape (n, 3); NaN when absent."""
        return self._cols(ACCEL_COLUMNS)

    @property
    def quaternion(self) -> np.ndarray:
        """Unit quaternion body->NED (qw, qx, qy, qz), shape (n, 4).

        From the qw..qz columns (normalized, sign as logged) or else from
        roll/pitch/yaw via :func:`uvsim.kinematics.euler_to_quat`.  Rows with
        any component missing are all NaN; all NaN without a full attitude (a
        run with roll and pitch only has no quaternion: use :attr:`euler`)."""
        if self.has_quaternion:
            q = self._cols(QUAT_COLUMNS)
            return q / np.linalg.norm(q, axis=1, keepdims=True)
        if self.has_full_attitude:
            return euler_to_quat(self._cols(EULER_COLUMNS))
        return np.full((len(self.data), 4), np.nan)

    @property
    def euler(self) -> np.ndarray:
        """ZYX Euler angles roll, pitch, yaw (rad), shape (n, 3): the logged
        columns (NaN for angles not logged), or else from the quaternion via
        :func:`uvsim.kinematics.quat_to_euler`."""
        if self.has_euler:
            return self._cols(EULER_COLUMNS)
        if self.has_quaternion:
            return quat_to_euler(self.quaternion)
        return np.full((len(self.data), 3), np.nan)

    @property
    def has_voltage(self) -> bool:
        return VOLTAGE_COLUMN in self.data.columns

    @property
    def voltage(self) -> np.ndarray | None:
        """Battery voltage (V) per row, shape (n,), or None when not logged.  Empty cells
        (no new sample) hold the previous sample (zero-order hold, as inputs are held)."""
        if not self.has_voltage:
            return None
        return self.data[VOLTAGE_COLUMN].ffill().to_numpy()

    @property
    def has_velocity(self) -> bool:
        return self._has(VELOCITY_COLUMNS)

    @property
    def has_rates(self) -> bool:
        return self._has(RATE_COLUMNS)

    @property
    def velocity(self) -> np.ndarray:
        """Body velocities u, v, w (m/s) and rates p, q, r (rad/s), shape (n, 6);
        NaN columns for absent ones."""
        return self._cols(VELOCITY_COLUMNS + RATE_COLUMNS)

    @property
    def measured_columns(self) -> dict[str, list[str]]:
        """Measured columns present, by signal group, e.g. ``{"position": ["z"],
        "attitude": ["qw", "qx", "qy", "qz"], "rates": ["p", "q", "r"]}``."""
        groups = {
            "position": POSITION_COLUMNS,
            "depth": (DEPTH_COLUMN,),
            "attitude": QUAT_COLUMNS + EULER_COLUMNS,
            "velocity": VELOCITY_COLUMNS,
            "rates": RATE_COLUMNS,
            "acceleration": ACCEL_COLUMNS,
        }
        out = {g: [c for c in names if c in self.data.columns] for g, names in groups.items()}
        return {g: cols for g, cols in out.items() if cols}

    def signals(self) -> list[str]:
        """Measured signal groups present, in the order position, depth, attitude,
        velocity, rates, acceleration (the axes are in :attr:`measured_columns`)."""
        return list(self.measured_columns)

    @property
    def extra_columns(self) -> list[str]:
        """Columns that are not part of the log format (kept in ``data``, named in :attr:`notes`)."""
        known = set(FORMAT_COLUMNS) | set(self._input_columns)
        return [c for c in self.data.columns if c not in known]


@dataclass
class Dataset:
    """A directory of runs described by ``manifest.yaml``.  ``meta`` holds any
    manifest keys other than vehicle/description/runs.

    ``runs`` are the runs cut at their gaps (:func:`uvsim.gaps.split_run`): a run with a
    stretch without measurements is here as its segments ``NAME[1]``, ``NAME[2]``, ..., each
    with a note saying so, so that every method that takes a dataset sees the same segments."""

    path: Path
    vehicle: str | None
    description: str
    runs: list[Run]
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        self.runs = split_runs(self.runs)

    @property
    def train(self) -> list[Run]:
        return [r for r in self.runs if r.split == "train"]

    @property
    def validation(self) -> list[Run]:
        return [r for r in self.runs if r.split == "validation"]

    @property
    def vehicle_file(self) -> Path | None:
        """``vehicle`` as a path relative to the dataset directory: when it names a
        .yaml/.yml file, or when a bare name ``NAME`` has ``NAME.yaml``/``NAME.yml``
        beside the manifest (a file beside the data wins over a built-in of the same
        name); None for a built-in name or when absent."""
        if self.vehicle is None:
            return None
        if Path(self.vehicle).suffix.lower() in (".yaml", ".yml"):
            return self.path / self.vehicle
        for ext in (".yaml", ".yml"):
            cand = self.path / f"{self.vehicle}{ext}"
            if cand.is_file():
                return cand
        return None

    def by_dof(self, dof: str) -> list[Run]:
        _check_choice(dof, DOFS, "dof", str(self.path), none_ok=False)
        return [r for r in self.runs if r.dof == dof]


def _have_pyarrow() -> bool:
    return importlib.util.find_spec("pyarrow") is not None


def _need_pyarrow(path: Path, verb: str) -> None:
    if not _have_pyarrow():
        raise LogFormatError(
            f"{path}: {verb} Parquet files needs the optional package pyarrow "
            "(pip install 'uvsim[parquet]' or pip install pyarrow); CSV works without it"
        )


def _csv_header(path: Path) -> list[str]:
    with open(path, newline="", encoding="utf-8") as fh:
        return [h.strip() for h in next(csv.reader(fh), [])]


def read_run(path, *, dof=None, weight=1.0, split="train", n_thrusters: int | None = None) -> Run:
    """Read and validate one run file (.csv or .parquet).

    Parameters
    ----------
    path : str or Path
    dof, weight, split : manifest attributes of the run (validated).
    n_thrusters : int, optional
        If given, the run's thrust_i/pwm_i column count must equal it.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise LogFormatError(f"{path}: run file does not exist (or is not a file)")
    if suffix == ".csv":
        try:
            with open(path, "rb") as fh:
                why = not_text(fh.read(4096))
            if why:
                raise LogFormatError(f"{path}: not a text CSV file ({why}); expected a CSV file with a header "
                                     "row (docs/log_format.md)")
            header = _csv_header(path)
            if len(header) == 1:
                for sep, name in ((";", "semicolon"), ("\t", "tab"), ("|", "vertical bar")):
                    if sep in header[0]:
                        shown = header[0] if len(header[0]) <= 60 else header[0][:60] + "..."
                        raise LogFormatError(f"{path}: the header is one column {shown!r}: the file is "
                                             f"{name}-separated ({sep!r}); expected comma-separated columns "
                                             "(docs/log_format.md; pandas: df.to_csv(path, index=False))")
            dup = sorted({h for h in header if header.count(h) > 1})
            if dup:  # pandas would silently rename the second one to 'x.1'
                raise LogFormatError(f"{path}: column {dup[0]!r} appears more than once")
            # Blank lines are kept as rows so that row i is line i + 2 in messages;
            # blank lines at the end of the file hold nothing and are removed.
            df = pd.read_csv(path, skipinitialspace=True, skip_blank_lines=False)
            filled = np.flatnonzero(df.notna().any(axis=1).to_numpy())
            df = df.iloc[: filled[-1] + 1 if filled.size else 0]
        except LogFormatError:
            raise
        except UnicodeDecodeError as e:
            raise LogFormatError(f"{path}: not a text CSV file (byte {e.start} is not UTF-8); expected a CSV "
                                 "file with a header row (docs/log_format.md)") from None
        except PermissionError:
            raise LogFormatError(f"{path}: permission denied reading the run file") from None
        except (pd.errors.ParserError, pd.errors.EmptyDataError, csv.Error, ValueError) as e:
            raise LogFormatError(f"{path}: cannot parse as CSV: {e}") from None
        except OSError as e:
            raise LogFormatError(f"{path}: cannot read the run file: {e.strerror or e}") from None
    elif suffix == ".parquet":
        _need_pyarrow(path, "reading")
        try:
            df = pd.read_parquet(path, engine="pyarrow")
        except Exception as e:  # pyarrow raises several unrelated types
            raise LogFormatError(f"{path}: cannot read as Parquet: {e}") from e
    else:
        raise LogFormatError(f"{path}: unknown run file type {path.suffix!r}; expected .csv or .parquet")
    run = Run(name=path.stem, path=path, data=df, dof=dof, weight=weight, split=split)
    if n_thrusters is not None and run.n_thrusters != n_thrusters:
        got = "force inputs X..N" if run.n_thrusters is None else f"{run.n_thrusters} {run.input_kind} columns"
        raise LogFormatError(f"{path}: expected {n_thrusters} thrusters (thrust_i or pwm_i columns), found {got}")
    return run


def read_dataset(path) -> Dataset:
    """Read ``manifest.yaml`` in directory ``path`` (or the manifest file
    itself) and every run it lists."""
    path = Path(path)
    manifest = path if path.is_file() else path / MANIFEST
    root = manifest.parent
    if not manifest.is_file():
        raise LogFormatError(f"{manifest}: dataset manifest not found (a dataset is a directory with {MANIFEST})")
    doc = load_yaml(manifest, error=LogFormatError, what="dataset manifest (YAML)")
    if not isinstance(doc, dict):
        raise LogFormatError(f"{manifest}: expected a mapping with keys vehicle, description, runs")
    check_keys(doc, MANIFEST_KEYS, str(manifest), error=LogFormatError,
               hint=" (free-form metadata goes under 'meta:')")
    require_mapping(doc.get("meta"), f"{manifest}: meta", error=LogFormatError)
    entries = doc.get("runs")
    if not isinstance(entries, list) or not entries:
        raise LogFormatError(f"{manifest}: 'runs' must be a non-empty list of {{file: ..., dof: ...}} entries")
    vehicle = doc.get("vehicle")
    if vehicle is not None and not isinstance(vehicle, str):
        raise LogFormatError(f"{manifest}: 'vehicle' must be a vehicle name or file path, got {vehicle!r}")
    description = doc.get("description") or ""
    runs, seen_files, seen_names = [], set(), set()
    for k, entry in enumerate(entries):
        where = f"{manifest}: runs[{k}]"
        if not isinstance(entry, dict) or not isinstance(entry.get("file"), str):
            raise LogFormatError(f"{where}: expected a mapping with a 'file' entry, got {entry!r}")
        check_keys(entry, _RUN_KEYS, where, error=LogFormatError)
        file = root / entry["file"]
        key = file.resolve()
        if key in seen_files:
            raise LogFormatError(f"{where}: file {entry['file']!r} is listed more than once")
        seen_files.add(key)
        if not file.is_file():
            raise LogFormatError(f"{where}: run file {entry['file']!r} does not exist ({file})")
        _check_choice(entry.get("dof"), DOFS, "dof", where)
        _check_choice(entry.get("split", "train"), SPLITS, "split", where, none_ok=False)
        _check_weight(entry.get("weight", 1.0), where)
        run = read_run(file, dof=entry.get("dof"), weight=entry.get("weight", 1.0),
                       split=entry.get("split", "train"))
        if run.name in seen_names:
            raise LogFormatError(f"{where}: run name {run.name!r} (file stem) is used by two files")
        seen_names.add(run.name)
        runs.append(run)
    meta = {k: v for k, v in doc.items() if k not in ("vehicle", "description", "runs")}
    return Dataset(path=root, vehicle=vehicle, description=str(description), runs=runs, meta=meta)


def write_run(path, data: pd.DataFrame | Run) -> Path:
    """Write a run as CSV (or Parquet if ``path`` ends in .parquet).

    A DataFrame is validated first (as :class:`Run`), so what is written can be
    read back.  NaN is written as an empty cell; floats at full precision."""
    path = Path(path)
    run = data if isinstance(data, Run) else Run(name=path.stem, path=None, data=data)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise LogFormatError(f"{path}: unknown run file type {path.suffix!r}; expected .csv or .parquet")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".csv":
        run.data.to_csv(path, index=False)
    else:
        _need_pyarrow(path, "writing")
        run.data.to_parquet(path, index=False, engine="pyarrow")
    return path


def write_dataset(path, runs: list[Run], *, vehicle: str, description: str = "",
                  suffix: str = ".csv") -> Path:
    """Write ``runs`` as ``<name><suffix>`` files plus ``manifest.yaml`` into
    directory ``path`` (created if needed); returns the directory."""
    path = Path(path)
    names = [r.name for r in runs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise LogFormatError(f"{path}: two runs are named {dup[0]!r}; run names become file names")
    if not runs:
        raise LogFormatError(f"{path}: a dataset needs at least one run")
    entries = []
    for run in runs:
        write_run(path / f"{run.name}{suffix}", run)
        entry = {"file": f"{run.name}{suffix}"}
        if run.dof is not None:
            entry["dof"] = run.dof
        entry.update(weight=float(run.weight), split=run.split)
        entries.append(entry)
    doc = {"vehicle": vehicle, "description": description, "runs": entries}
    (path / MANIFEST).write_text(yaml.safe_dump(doc, sort_keys=False))
    return path
