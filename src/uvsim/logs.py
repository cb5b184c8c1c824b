"""Read, validate and write logged runs and datasets (docs/log_format.md).

A *run* is one CSV or Parquet file whose columns are named as in the log
format (``t``, ``x``..``z``, ``qw``..``qz`` or ``roll``/``pitch``/``yaw``,
``u``..``r`` and one kind of inputs).  A *dataset* is a directory with a
``manifest.yaml`` listing run files.  Everything the contract forbids raises
:class:`uvsim.errors.LogFormatError` naming the file, the column and/or the
row; nothing is dropped, clipped or resampled.  Rows are counted from 0 (the
first data row); for CSV files the message also gives the line number.

This module holds the run files' readers and writers (:func:`read_run`, :func:`write_run`),
the dataset directory and its manifest (:class:`Dataset`, :func:`read_dataset`,
:func:`write_dataset`).  The run itself, :class:`Run` (its table validated on construction,
its column accessors, the checks of ``dof``, ``weight`` and ``split``), is in
:mod:`uvsim.logged_run`; the column names and the checks of a run's table are in
:mod:`uvsim.log_columns`.  Both are re-exported here (``from uvsim.logs import Run`` keeps
working).
"""
from __future__ import annotations

import csv
import importlib.util
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from uvsim.errors import LogFormatError
from uvsim.files import load_yaml, not_text
from uvsim.gaps import split_runs
from uvsim.log_columns import (  # noqa: F401  (the column names are part of this module's interface)
    ACCEL_COLUMNS, ATTITUDE_CONSISTENCY_TOL, DEPTH_COLUMN, EULER_COLUMNS, FORCE_COLUMNS, INPUT_KINDS,
    MEASURED_COLUMNS, POSITION_COLUMNS, PWM_RANGE_US, QUAT_COLUMNS, QUAT_NORM_TOL, QUAT_NOTE_TOL, RATE_COLUMNS,
    VELOCITY_COLUMNS, VOLTAGE_COLUMN, FORMAT_COLUMNS)
from uvsim.logged_run import (  # noqa: F401  (re-exported: the run class and its manifest attributes)
    DOFS, MAX_RUN_WEIGHT, SPLITS, Run, _check_choice, _check_closed_loop, _check_weight)
from uvsim.schema import check_keys, require_mapping

MANIFEST = "manifest.yaml"
#: Top-level keys of a manifest: the contract (vehicle, description, runs), the keys that
#: uvsim's own generators and importers write (truth, noise, sources, import) and ``meta``
#: for free-form metadata.
#: Anything else is a typo (``vehicel``, ``run``) and an error with a did-you-mean.
MANIFEST_KEYS = ("vehicle", "description", "runs", "meta", "truth", "noise", "sources", "import")
_RUN_KEYS = ("file", "dof", "weight", "split", "closed_loop")


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


def read_run(path, *, dof=None, weight=1.0, split="train", closed_loop=None, n_thrusters: int | None = None) -> Run:
    """Read and validate one run file (.csv or .parquet).

    Parameters
    ----------
    path : str or Path
    dof, weight, split, closed_loop : manifest attributes of the run (validated).
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
    run = Run(name=path.stem, path=path, data=df, dof=dof, weight=weight, split=split, closed_loop=closed_loop)
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
        _check_closed_loop(entry.get("closed_loop"), where)
        run = read_run(file, dof=entry.get("dof"), weight=entry.get("weight", 1.0),
                       split=entry.get("split", "train"), closed_loop=entry.get("closed_loop"))
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
        if run.closed_loop is not None:
            entry["closed_loop"] = bool(run.closed_loop)
        entries.append(entry)
    doc = {"vehicle": vehicle, "description": description, "runs": entries}
    (path / MANIFEST).write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


#: The public names: the readers and writers here, the run class and its manifest attributes
#: (:mod:`uvsim.logged_run`) and the log format's column names (:mod:`uvsim.log_columns`).
__all__ = [
    "MANIFEST", "MANIFEST_KEYS", "Dataset", "read_run", "read_dataset", "write_run", "write_dataset",
    "DOFS", "SPLITS", "MAX_RUN_WEIGHT", "Run",
    "ACCEL_COLUMNS", "ATTITUDE_CONSISTENCY_TOL", "DEPTH_COLUMN", "EULER_COLUMNS", "FORCE_COLUMNS", "INPUT_KINDS",
    "MEASURED_COLUMNS", "POSITION_COLUMNS", "PWM_RANGE_US", "QUAT_COLUMNS", "QUAT_NORM_TOL", "QUAT_NOTE_TOL",
    "RATE_COLUMNS", "VELOCITY_COLUMNS", "VOLTAGE_COLUMN", "FORMAT_COLUMNS",
]
