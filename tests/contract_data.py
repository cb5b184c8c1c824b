"""Small copies of the shipped tank dataset and vehicle files for the contract and fuzz tests
(imported by tests/test_contracts.py and tests/test_fuzz.py).

The data are the shipped files themselves (``src/uvsim/data/datasets/bluerov2_tank``,
``src/uvsim/vehicles``), cut to a few seconds so that every command on them takes well
under a second; mutations are applied to these copies as text or numbers.
"""
from __future__ import annotations

from pathlib import Path

import pandas as pd
import yaml

import uvsim

PACKAGE = Path(uvsim.__file__).parent
SHIPPED_DATASET = PACKAGE / "data" / "datasets" / "bluerov2_tank"
SHIPPED_VEHICLE = PACKAGE / "vehicles" / "bluerov2_heavy.yaml"
#: (run file, split) of the small dataset: two surge training runs and one validation run.
TINY_RUNS = (("surge_01.csv", "train"), ("surge_05.csv", "train"), ("surge_09.csv", "validation"))


def shipped_run(name: str = "surge_01.csv", seconds: float = 4.0) -> pd.DataFrame:
    """The first ``seconds`` of a shipped run, exactly as stored (strings kept by re-reading)."""
    df = pd.read_csv(SHIPPED_DATASET / name)
    return df[df["t"] < seconds].reset_index(drop=True)


def write_tiny_dataset(dest: Path, *, seconds: float = 4.0, runs=TINY_RUNS, vehicle: str = "bluerov2_heavy",
                       frames: dict | None = None, manifest_extra: dict | None = None) -> Path:
    """A dataset directory with the first ``seconds`` of ``runs``; ``frames`` replaces a
    run's DataFrame by file name; returns the directory."""
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    entries = []
    for name, split in runs:
        df = (frames or {}).get(name)
        if df is None:
            df = shipped_run(name, seconds)
        df.to_csv(dest / name, index=False)
        entries.append({"file": name, "dof": "surge", "split": split})
    doc = {"vehicle": vehicle, "description": "first seconds of the shipped tank runs", "runs": entries,
           **(manifest_extra or {})}
    (dest / "manifest.yaml").write_text(yaml.safe_dump(doc, sort_keys=False))
    return dest


def shipped_vehicle_text() -> str:
    return SHIPPED_VEHICLE.read_text()
