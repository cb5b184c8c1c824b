"""Savitzky-Golay on the log's own stamps (issue 48: jittered topside clocks)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import savgol_filter

from uvsim.estimation.savgol import is_uniform, savgol_on_stamps


@pytest.mark.parametrize("deriv", [0, 1, 2])
def test_on_uniform_stamps_it_is_scipy_s_filter(deriv):
    rng = np.random.default_rng(1)
    t = np.arange(0, 12, 0.02)
    x = np.stack([np.sin(1.3 * t) + 0.01 * rng.standard_normal(t.size), 0.1 * t ** 3], 1)
    ours = savgol_on_stamps(t, x, 25, 3, deriv)
    ref = savgol_filter(x, 25, 3, deriv=deriv, delta=0.02, axis=0, mode="interp")
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-9 * np.abs(ref).max())


def test_on_jittered_stamps_it_differentiates_what_a_uniform_filter_gets_wrong():
    """+-15 ms of jitter at 10 Hz: the stamps' own offsets give the derivative to 1e-3; the
    convolution that assumes uniform stamps is off by about 0.1 (of an amplitude of 1)."""
    rng = np.random.default_rng(2)
    t = np.arange(0, 30, 0.1) + rng.uniform(-0.015, 0.015, 300)
    x = np.sin(t)
    assert not is_uniform(t)
    ours = savgol_on_stamps(t, x, 11, 3, 1)[5:-5]
    naive = savgol_filter(x, 11, 3, deriv=1, delta=0.1)[5:-5]
    truth = np.cos(t)[5:-5]
    assert np.abs(ours - truth).max() < 2e-3 < 0.05 < np.abs(naive - truth).max()


def test_exact_on_a_polynomial_of_its_order_anywhere():
    t = np.sort(np.random.default_rng(3).uniform(0, 5, 80))
    x = 2 - t + 0.5 * t ** 2 - 0.1 * t ** 3
    np.testing.assert_allclose(savgol_on_stamps(t, x, 9, 3, 1), -1 + t - 0.3 * t ** 2, atol=1e-9)
    np.testing.assert_allclose(savgol_on_stamps(t, x, 9, 3, 2), 1 - 0.6 * t, atol=1e-8)
