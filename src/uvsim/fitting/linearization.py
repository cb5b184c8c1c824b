"""One linearization of a windowed problem: residuals, Jacobians and each run's pieces of
the normal equations (:class:`RunNormal`), and the reduced system the Levenberg-Marquardt
iteration of :mod:`uvsim.fitting.solver` solves (:func:`reduced_system`; the nuisance
eliminated run by run, that module's docstring).

Jacobians are forward differences: one batched simulation of all windows for the base
point, one per global parameter and one per free node component (every window's
component perturbed at once: windows are independent rows, so each window's residuals
see only their own node; the continuity defects, which involve two windows, are
differentiated from the same simulations piece by piece).  Sensor-bias derivatives need
no simulation.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from uvsim.fitting.objective import FILL, WindowedProblem, robust_residuals
from uvsim.fitting.windows import apply_tangent, tangent_difference

#: Forward-difference steps: scaled parameters (relative) and node components (m, rad, m/s, rad/s).
FD_STEP_Z = 1e-5
FD_STEP_NODE = 1e-5
FD_STEP_BIAS = 1e-6


@dataclass
class RunNormal:
    """One run's contribution to the normal equations at the current point:
    ``rss = r.r``, ``A = Jz^T Jz`` (p, p), ``gz = Jz^T r``, ``D = Jn^T Jn`` (q, q),
    ``B = Jn^T Jz`` (q, p), ``gn = Jn^T r`` (Jz: Jacobian w.r.t. the global parameters,
    Jn: w.r.t. the run's nuisance), the residual sum of squares of each window
    ``window_sse`` (W_r,) and, when requested, the projected score of each window
    ``scores`` (W_r, p) (nuisance profiled out; for the robust covariance)."""

    rss: float
    n: int = 0
    A: np.ndarray | None = None
    gz: np.ndarray | None = None
    D: np.ndarray | None = None
    B: np.ndarray | None = None
    gn: np.ndarray | None = None
    window_sse: np.ndarray | None = None
    scores: np.ndarray | None = None


@dataclass
class RunJacobian:
    """One run's Jacobian with respect to its nuisance, by blocks (the rows of the run's residual
    vector: measurements, continuity defects, node priors, sensor-bias priors;
    :meth:`uvsim.fitting.objective.WindowedProblem.residuals`).  The nuisance is the free node
    components of each window (``k`` per window, window-major) and then the sensor biases.

    ``w_meas`` (m,) the window of each measurement entry; ``dm`` (m, k) its derivatives by its own
    window's node components; ``E``, ``N`` (nw - 1, k, k): defect ``w`` (of window ``w + 1``), entry
    ``i``, by component ``j`` of node ``w`` (through window ``w``'s end state) and of node ``w + 1``;
    ``prior_inv`` (nw k,) the node priors' 1 / sd (``nw`` windows); ``db`` (m, nb) the measurement entries by the
    sensor biases; ``bias_inv`` (nb,) their priors' 1 / sd."""

    nw: int
    w_meas: np.ndarray
    dm: np.ndarray
    E: np.ndarray
    N: np.ndarray
    prior_inv: np.ndarray
    db: np.ndarray
    bias_inv: np.ndarray

    @property
    def k(self) -> int:
        return self.dm.shape[1]

    @property
    def q(self) -> int:
        return self.prior_inv.size + self.bias_inv.size

    def to_sparse(self) -> sparse.csr_matrix:
        """The whole matrix (m, q) (the tests' reference for :func:`structured_normal_pieces`)."""
        m, k, nb, nw = self.dm.shape[0], self.k, self.bias_inv.size, self.nw
        jr, jc, jv = [], [], []
        for j in range(k):
            jr.append(np.arange(m)), jc.append(self.w_meas * k + j), jv.append(self.dm[:, j])
        for j in range(nb):
            jr.append(np.arange(m)), jc.append(np.full(m, nw * k + j)), jv.append(self.db[:, j])
        nd = self.E.shape[0]
        if nd and k:
            wv = np.arange(nd)[:, None, None]
            rows, cols = np.broadcast_arrays(m + wv * k + np.arange(k)[None, :, None], wv * k + np.arange(k)[None, None, :])
            jr += [rows.ravel(), rows.ravel()]
            jc += [cols.ravel(), cols.ravel() + k]
            jv += [self.E.ravel(), self.N.ravel()]
        base = m + nd * k
        jr.append(base + np.arange(self.q)), jc.append(np.arange(self.q))
        jv.append(np.concatenate([self.prior_inv, self.bias_inv]))
        n_rows = base + self.q
        return sparse.csr_matrix((np.concatenate(jv), (np.concatenate(jr), np.concatenate(jc))),
                                 shape=(n_rows, self.q))


def structured_normal_pieces(r, Jz, J: RunJacobian, cluster, scores: bool) -> RunNormal:
    """One run's :class:`RunNormal` from its residuals ``r`` (m_all,), ``Jz`` (m_all, p) and the
    nuisance Jacobian by blocks ``J``, block by block: a window's measurement entries give one
    k x k block of ``Jn^T Jn``, a defect four, a prior one diagonal entry.  On a 2-run 100 Hz log
    this took half the time of the sparse products it replaced (docs/performance.md).  The sums
    are those of the whole matrix's products in another order, equal to round-off
    (``tests/test_hotpath_equivalence.py`` holds them to the dense products of
    :meth:`RunJacobian.to_sparse`).  ``cluster`` (m_all,): the window of each residual entry;
    ``scores``: also the projected window scores (nw, p), nuisance profiled out."""
    k, nb, nw = J.k, J.bias_inv.size, J.nw
    p = Jz.shape[1]
    m = J.w_meas.size
    nk, q = nw * k, J.q
    nd = J.E.shape[0]
    sse = np.bincount(cluster, weights=r * r, minlength=nw)
    D = np.zeros((q, q))
    B = np.zeros((q, p))
    gn = np.zeros(q)
    order = np.argsort(J.w_meas, kind="stable")
    edges = np.searchsorted(J.w_meas[order], np.arange(nw + 1))
    dm, zm, rm = J.dm[order], Jz[:m][order], r[:m][order]
    db = J.db[order]
    for w in range(nw if k else 0):
        a, e = edges[w], edges[w + 1]
        X = dm[a:e]
        blk = slice(w * k, (w + 1) * k)
        D[blk, blk] += X.T @ X
        B[blk] += X.T @ zm[a:e]
        gn[blk] += X.T @ rm[a:e]
        if nb:
            C = X.T @ db[a:e]
            D[blk, nk:] += C
            D[nk:, blk] += C.T
    if nb:
        D[nk:, nk:] += db.T @ db
        B[nk:] += db.T @ zm
        gn[nk:] += db.T @ rm
    if nd and k:
        md = nd * k
        rd, zd = r[m:m + md].reshape(nd, k), Jz[m:m + md].reshape(nd, k, p)
        E, N = J.E, J.N
        EE, NN, EN = (np.einsum("wij,wil->wjl", X, Y) for X, Y in ((E, E), (N, N), (E, N)))
        EZ, NZ = np.einsum("wij,wip->wjp", E, zd), np.einsum("wij,wip->wjp", N, zd)
        Er, Nr = np.einsum("wij,wi->wj", E, rd), np.einsum("wij,wi->wj", N, rd)
        for w in range(nd):
            a, b, c = slice(w * k, (w + 1) * k), slice((w + 1) * k, (w + 2) * k), w
            D[a, a] += EE[c]
            D[b, b] += NN[c]
            D[a, b] += EN[c]
            D[b, a] += EN[c].T
            B[a] += EZ[c]
            B[b] += NZ[c]
            gn[a] += Er[c]
            gn[b] += Nr[c]
    base = m + nd * k
    inv = np.concatenate([J.prior_inv, J.bias_inv])
    idx = np.arange(q)
    D[idx, idx] += inv * inv
    B += inv[:, None] * Jz[base:base + q]
    gn += inv * r[base:base + q]
    D = 0.5 * (D + D.T)  # symmetric to the last bit
    out = RunNormal(float(r @ r), r.size, Jz.T @ Jz, Jz.T @ r, D, B, gn, sse)
    if scores:
        Jt = Jz.copy()
        if q:
            X = np.linalg.solve(D, B)  # D > 0: every nuisance has a prior
            Xn, Xb = X[:nk].reshape(nw, k, p), X[nk:]
            Ym = np.zeros((m, p))
            for w in range(nw if k else 0):
                a, e = edges[w], edges[w + 1]
                Ym[order[a:e]] = dm[a:e] @ Xn[w]
            if nb:
                Ym += J.db @ Xb
            Jt[:m] -= Ym
            if nd and k:
                Jt[m:base] -= (np.einsum("wij,wjp->wip", J.E, Xn[:-1])
                               + np.einsum("wij,wjp->wip", J.N, Xn[1:])).reshape(nd * k, p)
            Jt[base:base + q] -= inv[:, None] * X
        out.scores = _scores(Jt, r, cluster, nw)
    return out


def _scores(Jt, r, cluster, nw: int) -> np.ndarray:
    """(nw, p): the rows of ``Jt * r[:, None]`` summed by window (``cluster``), compiled
    (:mod:`uvsim.kernels.window_sums`, the same values) or by :func:`_window_sums`."""
    from uvsim.kernels import compiled_window_sums

    kernel = compiled_window_sums()
    if kernel is None:
        return _window_sums(Jt * r[:, None], cluster, nw)
    out = np.zeros((nw, Jt.shape[1]))
    kernel(np.ascontiguousarray(Jt), np.ascontiguousarray(r), np.ascontiguousarray(cluster), out)
    return out


def _window_sums(contrib, cluster, nw: int) -> np.ndarray:
    """(nw, p): the rows of ``contrib`` (m, p) summed by window (``cluster``), by
    :func:`numpy.bincount` with weights: the same additions in the same order as ``np.add.at``,
    many times faster."""
    sc = np.empty((nw, contrib.shape[1]))
    for j in range(contrib.shape[1]):
        sc[:, j] = np.bincount(cluster, weights=contrib[:, j], minlength=nw)
    return sc


def _run_meta(prob: WindowedProblem, r: int):
    """Entry -> local window of run r's measurement residuals, and its free comps."""
    rows = prob.meas[r].row_index()
    w_local = prob.lay.own_win[r][rows] - prob.lay.first[r]
    return w_local, np.flatnonzero(prob.free[r])


def linearize(prob: WindowedProblem, z: np.ndarray, nus: list, *, jacobian: bool = True, scores: bool = False):
    """Per run of ``prob``, its :class:`RunNormal` at (z, nus) (residual only when
    ``jacobian`` is False)."""
    p = z.size
    comps = np.flatnonzero(prob.free.any(axis=0))
    D0, biases = prob.assemble(nus)
    Zs = [z]
    Ds = [D0[0]]
    shifted = {}  # parameter set -> position axis along which the model is translation invariant
    if jacobian:
        hz = FD_STEP_Z * np.maximum(1.0, np.abs(z))
        hi = prob.space.z_upper
        sign = np.where(z + hz > hi, -1.0, 1.0)
        hz = hz * sign
        for j in range(p):
            zz = z.copy()
            zz[j] += hz[j]
            Zs.append(zz)
            Ds.append(D0[0])
        for c in comps:
            d = D0[0].copy()
            d[:, c] += FD_STEP_NODE
            if c in prob.shift_axes:
                shifted[len(Zs)] = int(c)
            Zs.append(z)
            Ds.append(d)
    Z = np.array(Zs)
    D = np.array(Ds)
    if shifted:
        # a node moved along an axis no term reads moves the window's whole trajectory by the
        # same amount (position is the integral of the velocity, and nothing else sees it):
        # the base simulation shifted, with no simulation of its own (exact, not a difference)
        sim = [i for i in range(Z.shape[0]) if i not in shifted]
        Ys, As = prob.simulate(Z[sim], D[sim])
        Y = np.empty((Z.shape[0],) + Ys.shape[1:])
        Y[sim] = Ys
        A = None
        if As is not None:
            A = np.empty((Z.shape[0],) + As.shape[1:])
            A[sim] = As
        for i, c in shifted.items():
            Y[i] = Y[0]
            Y[i, ..., c] += FD_STEP_NODE
            if A is not None:
                A[i] = A[0]
    else:
        Y, A = prob.simulate(Z, D)
    blocks = []
    for r in range(len(prob.runs)):
        b = biases[r]
        bb = None if b is None else np.repeat(b, Z.shape[0], 0)
        meas = prob.measurement_residuals(Y, A, r, bb)          # (P, m_meas)
        dfc = prob.defects(Y, D, r)                              # (P, W_r - 1, k)
        pri = prob.priors(D, bb, r)                              # (P, q_r)
        res0 = np.concatenate([meas[0], dfc[0].ravel(), pri[0]])
        if not jacobian:
            with np.errstate(over="ignore"):  # a trial step whose simulation ran away: cost inf, rejected
                blocks.append(RunNormal(float(res0 @ res0), res0.size))
            continue
        full = np.concatenate([meas, dfc.reshape(Z.shape[0], -1), pri], 1)
        Jz = ((full[1:1 + p] - full[0]) / hz[:, None]).T
        w_local, free = _run_meta(prob, r)
        nw = len(prob.lay.bounds[r])
        k = free.size
        q = prob.nuisance_size(r)
        m_meas = meas.shape[1]
        # Jn (m, q) by its blocks (RunJacobian): a measurement entry sees only its own window's
        # node and the sensor biases, a defect two neighbouring nodes, a prior one variable
        dm = np.empty((m_meas, k))
        for j, c in enumerate(free):
            ci = int(np.flatnonzero(comps == c)[0])
            dm[:, j] = (meas[1 + p + ci] - meas[0]) / FD_STEP_NODE
        E = N = np.zeros((0, k, k))
        # defect rows: d_w = node_w (-) end_{w-1}
        if nw > 1:
            # all free components at once: (k perturbed components, nw - 1 defects, k entries)
            w0 = prob.lay.first[r]
            sig = prob.defect_sigma[free]
            ends = prob.end_states(Y, r)[:, :-1, :13]
            ends0 = ends[0]
            node0 = apply_tangent(prob.x_ref[w0 + 1:w0 + nw], D0[0, w0 + 1:w0 + nw])
            d0 = tangent_difference(node0, ends0)[:, free] / sig
            ends_p = ends[[1 + p + int(np.flatnonzero(comps == c)[0]) for c in free]]
            d_end = (tangent_difference(node0[None], ends_p)[..., free] / sig - d0) / FD_STEP_NODE
            dd = np.repeat(D0[0, w0 + 1:w0 + nw][None], k, axis=0)
            dd[np.arange(k), :, free] += FD_STEP_NODE
            node_p = apply_tangent(prob.x_ref[w0 + 1:w0 + nw][None], dd)
            d_node = (tangent_difference(node_p, ends0[None])[..., free] / sig - d0) / FD_STEP_NODE
            # defect w (0..nw-2, of window w + 1), entry i: d/d node w comp j (the end), d/d node w + 1 comp j
            E, N = d_end.transpose(1, 2, 0), d_node.transpose(1, 2, 0)
        w0 = prob.lay.first[r]
        prior_inv = 1.0 / prob.prior_sigma[w0:w0 + nw][:, free].ravel()
        bsd = prob.bias_sd(r)
        db = np.empty((m_meas, bsd.size))
        if bsd.size:
            # every bias moved in turn, all in one batch of parameter sets: each set's prediction
            # is computed alone, so the columns are those of one call per bias
            nb = bsd.size
            yb, ab = prob.run_prediction(Y[:1], None if A is None else A[:1], r)
            b1 = np.repeat(b, nb, axis=0)
            b1[np.arange(nb), np.arange(nb)] += FD_STEP_BIAS
            pred = prob.predict_run(r, np.repeat(yb, nb, axis=0), None if ab is None else np.repeat(ab, nb, axis=0), b1)
            with np.errstate(all="ignore"):
                m1 = robust_residuals(prob.meas[r].normalized(pred, fill=FILL), prob.loss)
            db[:] = ((m1 - meas[0]) / FD_STEP_BIAS).T
        J = RunJacobian(nw, w_local, dm, E, N, prior_inv, db, 1.0 / bsd)
        assert J.q == q, "internal: the nuisance Jacobian's blocks do not add up to the run's nuisance"
        cluster = np.concatenate([w_local, np.repeat(np.arange(1, nw), k), np.repeat(np.arange(nw), k),
                                  np.zeros(bsd.size, int)])
        blocks.append(structured_normal_pieces(res0, Jz, J, cluster, scores))
    return blocks


def reduced_system(blocks, lam: float):
    """Reduced system S dz = rhs plus the per-run pieces for back-substitution."""
    p = blocks[0].A.shape[0] if blocks else 0
    S = np.zeros((p, p))
    rhs = np.zeros(p)
    per = []
    for b in blocks:
        S += b.A + lam * np.diag(np.diag(b.A))
        rhs -= b.gz
        if b.D.shape[0]:
            Dm = b.D + lam * np.diag(np.diag(b.D))
            Dinv_B = np.linalg.solve(Dm, b.B)
            Dinv_g = np.linalg.solve(Dm, b.gn)
            S -= b.B.T @ Dinv_B
            rhs += b.B.T @ Dinv_g
            per.append((Dinv_B, Dinv_g))
        else:
            per.append(None)
    return S, rhs, per
