"""The screening's least squares with a fixed base block (uvsim.diagnosis.regression) against
numpy.linalg.lstsq of the whole matrix."""
import numpy as np
import pytest

from uvsim.diagnosis.regression import BaseBlock, ls_step, stepwise


def _problem(seed, nb=6, k=3, m=900):
    rng = np.random.default_rng(seed)
    B = rng.normal(size=(nb, m)) * rng.uniform(0.1, 10.0, size=(nb, 1))  # uneven column scales
    C = rng.normal(size=(k, m)) + 0.5 * B[:k]  # candidate columns correlated with the base
    r = rng.normal(size=m)
    return B, C, r


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_block_solution_is_the_joint_least_squares_solution(seed):
    B, C, r = _problem(seed)
    d, rss = BaseBlock(B).solve(C, r)
    ref, *_ = np.linalg.lstsq(np.vstack([B, C]).T, -r, rcond=None)
    res = r + np.vstack([B, C]).T @ ref
    np.testing.assert_allclose(d, ref, rtol=1e-9, atol=1e-12)
    assert rss == pytest.approx(float(res @ res), rel=1e-10)


def test_a_rank_deficient_base_block_still_gives_the_joint_residual():
    B, C, r = _problem(3)
    B = np.vstack([B, B[0] + 2.0 * B[1]])  # a repeated direction: lstsq's cutoff drops it
    d, rss = BaseBlock(B).solve(C, r)
    A = np.vstack([B, C]).T
    ref, *_ = np.linalg.lstsq(A, -r, rcond=None)
    res_ref, res = r + A @ ref, r + A @ d
    assert rss == pytest.approx(float(res_ref @ res_ref), rel=1e-10)
    assert float(res @ res) == pytest.approx(rss, rel=1e-10)  # d itself attains it
    np.testing.assert_allclose(d[-C.shape[0]:], ref[-C.shape[0]:], rtol=1e-8)  # the candidate's part is unique


def test_an_empty_base_block_is_plain_least_squares():
    _, C, r = _problem(4)
    d, rss = BaseBlock(np.zeros((0, r.size))).solve(C, r)
    ref, *_ = np.linalg.lstsq(C.T, -r, rcond=None)
    np.testing.assert_allclose(d, ref, rtol=1e-12)


def test_ls_step_names_the_values_from_the_start():
    B, C, r = _problem(5, nb=2, k=1)
    vals, rss = ls_step(BaseBlock(B), C[0], r, ["X_u", "Y_v", "thruster_gain_3"], {"X_u": -4.0, "Y_v": -6.0})
    ref, *_ = np.linalg.lstsq(np.vstack([B, C]).T, -r, rcond=None)
    assert vals["X_u"] == pytest.approx(-4.0 + ref[0]) and vals["Y_v"] == pytest.approx(-6.0 + ref[1])
    assert vals["thruster_gain_3"] == pytest.approx(1.0 + ref[2])  # a gain missing from start starts at 1


def test_stepwise_with_a_base_block_picks_what_the_joint_fits_pick():
    rng = np.random.default_rng(6)
    m = 600
    base = rng.normal(size=(3, m))
    J = rng.normal(size=(8, m)) + 0.8 * base[[0, 1, 2, 0, 1, 2, 0, 1]]
    names = ["K_v", "K_vv", "M_u", "M_uu", "N_v", "N_vv", "X_q", "Y_p"]
    r = -(0.9 * base[0] + 0.7 * J[3] - 1.1 * J[6]) + rng.normal(0, 0.05, m)
    picked = stepwise(J, r, names, k=2, base=base)
    assert sorted(picked) == ["M_uu", "X_q"]
    # the same as an exhaustive search over the allowed pairs with lstsq of the whole matrix
    best = min(((i, j) for i in range(8) for j in range(i + 1, 8) if names[i][0] != names[j][0]),
               key=lambda ij: np.sum((r + np.vstack([base, J[list(ij)]]).T
                                      @ np.linalg.lstsq(np.vstack([base, J[list(ij)]]).T, -r, rcond=None)[0]) ** 2))
    assert sorted(picked) == sorted(names[i] for i in best)
