"""The local quadratic fits that give the window-start (node) states from a log
(uvsim.fitting.nodes.local_fit): their values against a closed form, and the answers kept across
calls (a diagnosis builds the same windows for each of its fits) equal to fresh ones."""
from __future__ import annotations

import numpy as np

from uvsim.fitting import nodes


def test_a_quadratic_is_fitted_exactly_and_the_ends_are_one_sided():
    t = np.arange(0.0, 5.0, 0.02)
    x = 0.3 - 1.2 * t + 0.4 * t * t
    t0 = np.array([0.0, 1.0, 2.5, 4.98])
    v, s = nodes.local_fit(t, x, t0, 0.3)
    np.testing.assert_allclose(v, 0.3 - 1.2 * t0 + 0.4 * t0 ** 2, atol=1e-10)
    np.testing.assert_allclose(s, -1.2 + 0.8 * t0, atol=1e-9)


def test_too_few_samples_give_nan():
    t = np.arange(0.0, 1.0, 0.1)
    x = np.where(t < 0.5, np.nan, t)
    v, s = nodes.local_fit(t, x, np.array([0.0, 0.9]), 0.1)
    assert np.isnan(v[0]) and np.isnan(s[0])


def test_kept_answers_equal_fresh_ones_and_are_not_shared(monkeypatch):
    monkeypatch.setattr(nodes, "_local_fits", type(nodes._local_fits)())
    monkeypatch.setattr(nodes, "LOCAL_FIT_CACHE", 3)
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.015, 0.025, 300))
    xs = [rng.normal(size=t.size) for _ in range(5)]
    t0 = t[[0, 50, 120, 299]]
    fresh = [nodes._local_fit(t, x, t0, 0.3, 5) for x in xs]
    for _ in range(2):
        for x, (v0, s0) in zip(xs, fresh):
            v, s = nodes.local_fit(t, x, t0, 0.3)
            np.testing.assert_array_equal(v, v0)
            np.testing.assert_array_equal(s, s0)
            v[:] = 99.0  # a caller's change does not reach the kept answer
    assert len(nodes._local_fits) == 3
    v, _ = nodes.local_fit(t, xs[-1], t0, 0.3)
    np.testing.assert_array_equal(v, fresh[-1][0])
    # another half-width or other times are another fit
    assert not np.array_equal(nodes.local_fit(t, xs[-1], t0, 0.2)[0], fresh[-1][0])
    assert not np.array_equal(nodes.local_fit(t, xs[-1], t0 + 0.1, 0.3)[0], fresh[-1][0])


def test_threads_share_the_kept_fits_safely(monkeypatch):
    from concurrent.futures import ThreadPoolExecutor

    monkeypatch.setattr(nodes, "_local_fits", type(nodes._local_fits)())
    monkeypatch.setattr(nodes, "LOCAL_FIT_CACHE", 2)  # constant eviction
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 6.0, 0.02)
    xs = [rng.normal(size=t.size) for _ in range(6)]
    t0 = t[::60]
    fresh = [nodes._local_fit(t, x, t0, 0.3, 5)[0] for x in xs]

    def one(i):
        return np.array_equal(nodes.local_fit(t, xs[i % 6], t0, 0.3)[0], fresh[i % 6])

    with ThreadPoolExecutor(4) as ex:
        assert all(ex.map(one, range(600)))
    assert len(nodes._local_fits) <= 2
