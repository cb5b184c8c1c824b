"""The attitude filter's constant roll / pitch offset as a per-run nuisance with a prior
(issue 21 item 3: "EKF attitude as a measurement with its own noise and lag" and a bias):
data from the independent generator (:mod:`uvsim.scenarios`, lagged roll / pitch beside a
100 Hz gyro), offsets added to the logged angles as a filter's tilt error would be; the fit
finds them, and finds none where there are none."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from uvsim.calibration.report import attitude_bias_flags
from uvsim.fitting import fit, make_space
from uvsim.fitting.objective import ATTITUDE_BIAS_SIGMA
from uvsim.logs import read_dataset
from uvsim.measurements import measurements_for
from uvsim.scenarios import generate, sample_scenario
from uvsim.vehicle import load_vehicle

FREE = ["K_p", "M_q", "K_pp", "M_qq"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    spec = sample_scenario(13, profile="realsensor", n_runs=2, n_validation=1, duration=[10, 12], rate_hz=100.0,
                           perturbation=0.0, n_effects=0, perturb_z_b=False)
    return generate(spec, tmp_path_factory.mktemp("ab") / "ds")


def _runs(path, offsets=None):
    """Training runs of ``path``, with ``offsets`` {run name: (roll, pitch) rad} added to the
    logged angles (a copy; the files are not changed)."""
    out = []
    for r in read_dataset(path).runs:
        if r.split != "train":
            continue
        if offsets:
            d = r.data.copy()
            d["roll"] = d["roll"] + offsets[r.name][0]
            d["pitch"] = d["pitch"] + offsets[r.name][1]
            r = type(r)(r.name, r.path, d, dof=r.dof, split=r.split)
        out.append(r)
    return out


def test_filter_attitude_is_recognized(dataset):
    v = load_vehicle(read_dataset(dataset).vehicle_file)
    m = measurements_for(_runs(dataset)[0], v)
    assert m.has_filter_attitude and m.has_gyro


@pytest.mark.slow
def test_offsets_are_recovered_and_absent_ones_not_invented(dataset):
    v = load_vehicle(read_dataset(dataset).vehicle_file)
    names = [r.name for r in _runs(dataset)]
    offsets = {names[0]: (0.012, -0.02), names[1]: (-0.008, 0.015)}
    space = make_space(v.parameters(), FREE)
    biased = fit(v, _runs(dataset, offsets), space, attitude_bias=True)
    for n in names:
        np.testing.assert_allclose(biased.attitude_bias[n], offsets[n], atol=0.003)
    clean = fit(v, _runs(dataset), space, attitude_bias=True)
    for n in names:
        assert np.max(np.abs(clean.attitude_bias[n])) < 0.003
    assert fit(v, _runs(dataset), space).attitude_bias == {}        # off unless asked for
    # the roll / pitch coefficients the offsets would bend are those of the unbiased data
    for k in FREE:
        assert biased.values[k] == pytest.approx(clean.values[k], rel=0.05)


def test_a_large_offset_is_flagged():
    class R:
        attitude_bias = {"run_a": [0.001, 4 * ATTITUDE_BIAS_SIGMA], "run_b": [0.0, 0.0]}

    flags = attitude_bias_flags(R())
    assert len(flags) == 1 and "run_a" in flags[0] and "pitch" in flags[0] and "x_b" in flags[0]
