"""Linear least squares of the screening: a candidate's columns beside a fixed base block.

The screening (:meth:`uvsim.diagnosis.selector.Selector.screen`) solves many small least-squares
problems on the equation-error residual (hundreds of thousands of rows): each candidate's
Gauss-Newton step together with the current model's free parameters, and the forward stepwise
pick of the coupled damping terms.  The current parameters' columns (the *base block*, ``B``,
shape (nb, m)) are the same in all of them, so they are factored once (thin SVD) and each
problem is solved on the base block's orthogonal complement (block elimination; Golub & Van
Loan, *Matrix Computations*, 4th ed., sec. 5.3 and 6.2): with ``U S V^T = B^T``,

    min_{d_b, d_c} || B^T d_b + C^T d_c + r ||
    d_c = argmin || (I - U U^T) (C^T d_c + r) ||,     d_b = V S^-1 U^T (-r - C^T d_c),

which costs ``O(m nb k)`` per problem of ``k`` candidate columns instead of an SVD of the
whole ``m x (nb + k)`` matrix (``numpy.linalg.lstsq``).  The residual is the same as the
joint problem's; so are the coefficients when the joint matrix has full column rank.  Singular
values of ``B`` below ``numpy.linalg.lstsq``'s default cutoff (``eps * max(m, nb)`` times the
largest) are dropped, as that function does.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np


class BaseBlock:
    """A fixed block of regressors ``B`` (nb, m), factored once.

    Parameters
    ----------
    B : (nb, m) array; rows are regressors (the layout of
        :meth:`uvsim.fitting.equation_error.EquationError.jacobian`).  ``nb`` may be 0.
    """

    def __init__(self, B: np.ndarray):
        B = np.asarray(B, float)
        self.nb, self.m = B.shape
        if self.nb == 0:
            self.U, self.s, self.Vt = np.zeros((self.m, 0)), np.zeros(0), np.zeros((0, 0))
            return
        U, s, Vt = np.linalg.svd(B.T, full_matrices=False)
        keep = s > np.finfo(float).eps * max(self.m, self.nb) * (s[0] if s.size else 0.0)
        self.U, self.s, self.Vt = U[:, keep], s[keep], Vt[keep]

    def project(self, X: np.ndarray) -> np.ndarray:
        """``X`` (k, m) or (m,) with its component in the span of the base block removed."""
        return X - (X @ self.U) @ self.U.T

    def solve(self, C: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, float]:
        """Least-squares step ``d`` = (d_b (nb,), d_c (k,)) minimizing ``|B^T d_b + C^T d_c + r|``
        for candidate columns ``C`` (k, m), and that minimum's residual sum of squares."""
        C = np.asarray(C, float).reshape(-1, self.m)
        Cp, rp = self.project(C), self.project(r)
        if C.shape[0]:
            d_c, *_ = np.linalg.lstsq(Cp.T, -rp, rcond=None)
        else:
            d_c = np.zeros(0)
        res = rp + Cp.T @ d_c
        d_b = self.Vt.T @ ((self.U.T @ (-r - C.T @ d_c)) / self.s) if self.nb else np.zeros(0)
        return np.concatenate([d_b, d_c]), float(res @ res)


def ls_step(base: BaseBlock, col: np.ndarray, r: np.ndarray, names: Sequence[str], start: Mapping
            ) -> tuple[dict, float]:
    """One Gauss-Newton step on the base block and one more column ``col`` (m,) (per unit of
    each named parameter, base first) from ``start``: (values, residual sum of squares of the
    linearization).  A parameter missing from ``start`` starts at 0, a thruster gain at 1."""
    coef, rss = base.solve(col[None, :], r)
    vals = {n: float(start.get(n, 0.0 if not n.startswith("thruster_gain") else 1.0)) + float(c)
            for n, c in zip(names, coef)}
    return vals, rss


def stepwise(J: np.ndarray, r: np.ndarray, names: Sequence[str], k: int = 2, base: np.ndarray | BaseBlock | None = None
             ) -> list[str]:
    """Forward stepwise selection of ``k`` regressors (rows of ``J``, (n_terms, m)) that,
    together with the ``base`` regressors (always in), best explain ``-r`` (least squares);
    at most one per force row (the first letter)."""
    if not isinstance(base, BaseBlock):
        base = BaseBlock(np.zeros((0, J.shape[1])) if base is None else base)
    Jp, rp = base.project(J), base.project(r)  # the base block eliminated once for every subset
    chosen: list[int] = []
    for _ in range(k):
        best, best_rss = None, np.inf
        for j in range(J.shape[0]):
            if j in chosen or names[j][0] in {names[c][0] for c in chosen}:
                continue
            A = Jp[chosen + [j]].T
            coef, *_ = np.linalg.lstsq(A, -rp, rcond=None)
            res = rp + A @ coef
            rss = float(res @ res)
            if rss < best_rss:
                best, best_rss = j, rss
        if best is None:
            break
        chosen.append(best)
    return [names[j] for j in chosen]
