"""Runs with gaps (uvsim.gaps): cut into segments for every method, and said.

A stretch without measurements (empty sensor cells, inputs kept, as a logger that stopped
writing its sensors) or without rows (deleted rows: a time jump) used to pass silently: the
equation-error screening of the diagnosis left such a run out without a word, and
calibration and ``simulate`` ran through it.  Now every dataset holds the runs' segments,
each with a note, and the screening names any run it cannot use.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import uvsim
from contract_data import shipped_run, write_tiny_dataset
from uvsim.diagnosis import diagnose
from uvsim.gaps import GAP_FACTOR, find_gaps, split_run
from uvsim.logs import Dataset, Run, read_dataset, read_run
from uvsim.plausibility import check_run
from uvsim.scenarios.sensors import stamps

MEASURED = ["x", "y", "z", "qw", "qx", "qy", "qz"]


def _blank(df: pd.DataFrame, t0: float, t1: float) -> pd.DataFrame:
    """``df`` with every measured cell of the rows t0 <= t < t1 empty (inputs kept)."""
    df = df.copy()
    df.loc[(df.t >= t0) & (df.t < t1), MEASURED] = np.nan
    return df


def _run(df: pd.DataFrame, tmp_path, name="surge_01.csv") -> Run:
    p = tmp_path / name
    df.to_csv(p, index=False)
    return read_run(p, dof="surge", weight=2.0, split="validation", closed_loop=True)


def test_blank_measurements_split_the_run_with_a_note(tmp_path):
    run = _run(_blank(shipped_run("surge_01.csv", 8.0), 4.0, 4.36), tmp_path)  # 0.36 s: 18 rows at 50 Hz
    gaps = find_gaps(run)
    assert len(gaps) == 1 and gaps[0].before == 199 and gaps[0].after == 218 and gaps[0].empty_rows == 18
    segs = split_run(run)
    assert [s.name for s in segs] == ["surge_01[1]", "surge_01[2]"]
    assert [len(s.t) for s in segs] == [200, 400 - 218]           # the 18 empty rows are left out
    assert [s.row_offset for s in segs] == [0, 218] and all(s.segment_of == "surge_01" for s in segs)
    assert all((s.dof, s.weight, s.split, s.path, s.closed_loop) == ("surge", 2.0, "validation", run.path, True)
               for s in segs)
    pd.testing.assert_frame_equal(segs[1].data, run.data.iloc[218:].reset_index(drop=True))
    note = segs[0].notes[-1]
    assert segs[1].notes == segs[0].notes
    for frag in (str(run.path), "a gap without measurements of 0.38 s at t = 3.98..4.36 s",
                 "18 rows from row 200 (line 202 of the file) hold no measurement",
                 "split into 2 segments surge_01[1], surge_01[2]"):
        assert frag in note, note


def test_deleted_rows_split_the_run(tmp_path):
    df = shipped_run("surge_01.csv", 8.0)
    run = _run(df[(df.t < 4.0) | (df.t >= 4.36)].reset_index(drop=True), tmp_path)
    segs = split_run(run)
    assert [len(s.t) for s in segs] == [200, 182]
    assert "no rows between row 199 (line 201 of the file) and the next" in segs[0].notes[-1]
    assert [f.check for f in check_run(run, uvsim.load_vehicle("bluerov2_heavy"))] == []  # below the time-gap check


def test_what_is_not_a_gap():
    """A slow sensor with empty cells between its samples, one channel's dropout while
    another carries on, lost single samples and a logger's jittered stamps are no gaps."""
    rng = np.random.default_rng(5)
    t = np.arange(0, 60, 0.01)
    depth = np.full(t.size, np.nan)
    depth[::10] = 1.0 + 0.01 * rng.normal(size=depth[::10].size)       # 10 Hz in a 100 Hz log
    roll = 0.01 * rng.normal(size=t.size)
    roll[3000:3100] = np.nan                                             # the IMU out for 1 s, depth carries on
    roll[5000] = roll[5101] = roll[5102] = np.nan                        # one or two lost samples
    jittered = stamps(t, 0.005, 100.0, rng)   # the structural benchmark's worst time_jitter (a Linux logger's)
    for tt in (t, jittered):
        run = Run("r", None, pd.DataFrame({"t": tt, "depth": depth, "roll": roll, "X": 0.0, "Y": 0.0, "Z": 0.0,
                                            "K": 0.0, "M": 0.0, "N": 0.0}))
        assert find_gaps(run) == []
    assert np.diff(jittered).max() > GAP_FACTOR * np.median(np.diff(jittered))  # jitter beyond 3 intervals


def test_a_gap_every_channel_shares_is_one():
    t = np.arange(0, 20, 0.01)
    depth = np.full(t.size, np.nan)
    depth[::10] = 1.0
    roll = np.zeros(t.size)
    gap = (t >= 10.0) & (t < 10.6)
    depth[gap], roll[gap] = np.nan, np.nan
    run = Run("r", None, pd.DataFrame({"t": t, "depth": depth, "roll": roll, **{c: 0.0 for c in "XYZKMN"}}))
    (g,) = find_gaps(run)
    assert (g.t0, g.t1) == (pytest.approx(9.99), pytest.approx(10.6))


def test_a_stretch_too_short_for_the_methods_is_left_out_and_named(tmp_path):
    df = shipped_run("surge_01.csv", 4.0)
    run = _run(_blank(df, 3.5, 3.86), tmp_path)                        # 7 rows (3.86..3.98 s) after the gap
    segs = split_run(run)
    assert [s.name for s in segs] == ["surge_01[1]"]
    assert ("cut to one segment surge_01[1]; left out: t = 3.86..3.98 s (7 rows from row 193 (line 195 of the file)): "
            "fewer than 8 samples of x, y, z, qw, qx, qy, qz") in segs[0].notes[-1]


def test_a_segment_starts_with_the_held_voltage(tmp_path):
    df = shipped_run("surge_01.csv", 8.0)
    df["voltage"] = np.where(np.arange(len(df)) % 50 == 0, 15.0 + np.arange(len(df)) / 1000, np.nan)
    run = _run(_blank(df, 4.02, 4.5), tmp_path)
    first = split_run(run)[1]
    assert first.t[0] == pytest.approx(4.5) and first.voltage[0] == run.voltage[np.searchsorted(run.t, 4.5)] == 15.2


def test_plausibility_names_the_file_row_of_a_segment(tmp_path):
    df = _blank(shipped_run("surge_01.csv", 8.0), 4.0, 4.36)
    df.loc[300:, "z"] = 20000.0                                          # in the second segment: millimetres
    segs = split_run(_run(df, tmp_path))
    (f,) = [f for f in check_run(segs[1], uvsim.load_vehicle("bluerov2_heavy")) if f.check == "position-range"]
    assert "column 'z', row 300 (line 302 of the file)" in f.message


def test_every_dataset_holds_the_segments(tmp_path):
    runs = [_run(_blank(shipped_run("surge_01.csv", 8.0), 4.0, 4.36), tmp_path)]
    assert [r.name for r in Dataset(tmp_path, None, "", runs).runs] == ["surge_01[1]", "surge_01[2]"]
    again = Dataset(tmp_path, None, "", Dataset(tmp_path, None, "", runs).runs).runs   # segments are not cut again
    assert [r.name for r in again] == ["surge_01[1]", "surge_01[2]"]


def test_simulate_compare_simulates_each_segment(tmp_path, capsys):
    from uvsim.cli import main

    p = tmp_path / "run.csv"
    _blank(shipped_run("surge_01.csv", 8.0), 4.0, 4.36).to_csv(p, index=False)
    assert main(["simulate", "--vehicle", "bluerov2_heavy", "--run", str(p), "--out", str(tmp_path / "o.csv"),
                 "--compare", "--plot", str(tmp_path / "c.png")]) == 0
    out, err = capsys.readouterr()
    assert "note:" in err and "split into 2 segments run[1], run[2]" in err
    assert "simulated run in 2 segments, each from its own first measured state: 382 samples" in out
    assert "run vs bluerov2_heavy: 382 samples" in out and "in 2 segments (gaps left out)" in out
    sim = read_run(tmp_path / "o.csv")
    assert len(sim.t) == 382 and not np.any((sim.t > 3.98) & (sim.t < 4.36))


@pytest.fixture(scope="module")
def gapped_diagnosis(tmp_path_factory):
    """A diagnosis of a dataset whose first training run has 0.36 s without measurements and
    whose second has one attitude row missing (no gap: the screening cannot differentiate it)."""
    tmp = tmp_path_factory.mktemp("gapped")
    one_nan = shipped_run("surge_05.csv", 8.0)
    one_nan.loc[150, ["qw", "qx", "qy", "qz"]] = np.nan
    ds = write_tiny_dataset(tmp / "ds", seconds=8.0, frames={
        "surge_01.csv": _blank(shipped_run("surge_01.csv", 8.0), 4.0, 4.36), "surge_05.csv": one_nan})
    said = []
    diag = diagnose(ds, "bluerov2_heavy", only=["current"], max_effects=1, top=1, max_iter=3, progress=said.append)
    return ds, diag, said


def test_the_screening_uses_the_segments_of_a_gapped_run(gapped_diagnosis):
    ds, diag, _ = gapped_diagnosis
    assert [r.name for r in read_dataset(ds).runs][:2] == ["surge_01[1]", "surge_01[2]"]
    assert diag.report["runs"]["train"][:2] == ["surge_01[1]", "surge_01[2]"]
    screening = diag.report["steps"][0]["screening"]
    assert screening["available"]
    assert screening["runs"] == ["surge_01[1]", "surge_01[2]"]   # both segments by equation error


def test_the_screening_says_which_run_it_cannot_use(gapped_diagnosis):
    _, diag, said = gapped_diagnosis
    (why,) = diag.report["steps"][0]["screening"]["not_used"].values()
    assert why.startswith("surge_05: attitude: has missing (NaN) samples")
    assert any("equation-error screening on 2 of 3 training run(s); not used: surge_05: attitude" in m for m in said)
