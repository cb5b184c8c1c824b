"""numba prototype: the functions of :mod:`equations` compiled as they are.

numba cannot take a module as an argument, so the one source is compiled by re-binding its
globals: each function's code object is wrapped in a new function whose globals map the
helper names (``_abs``, ``_neg``, ``_sqrt``, ``rhs``, ``_lin``) to jitted versions.  Two
builds share the text: real arithmetic, and complex-step arithmetic (``_abs`` keeps the
imaginary part's sign with the real part, ``_neg`` reads the real part), whose imaginary
part carries the exact directional derivative of the discrete RK4 map (Squire & Trapp
1998; Martins, Sturdza & Alonso 2003): forward sensitivities with no second copy of the
physics, one complex trajectory per direction.
"""
from __future__ import annotations

import types

import numba
import numpy as np

import equations as eq


def _build(abs_fn, neg_fn):
    g = dict(eq.__dict__)
    g["_abs"] = numba.njit(abs_fn)
    g["_neg"] = numba.njit(neg_fn)
    for name in ("_sqrt", "_lin", "rhs", "rk4_step"):
        f = getattr(eq, name)
        g[name] = numba.njit(types.FunctionType(f.__code__, g, name, f.__defaults__))
    return g["rk4_step"]


def _abs_cs(x):
    return x if x.real >= 0 else -x


def _neg_cs(x):
    return 1.0 if x.real < 0 else 0.0


step_real = _build(lambda x: abs(x), lambda x: 1.0 if x < 0 else 0.0)
step_cs = _build(_abs_cs, _neg_cs)


def _make_loop(step):
    @numba.njit(cache=False)
    def loop(Y0, F, TH, hs, out):
        """Y0 (n, 13), F (n, n_t, k), TH (n, n_th), hs (n_t - 1,); out (n, n_t, 13)."""
        n, n_t, k = F.shape
        for j in range(n):
            y = (Y0[j, 0], Y0[j, 1], Y0[j, 2], Y0[j, 3], Y0[j, 4], Y0[j, 5], Y0[j, 6], Y0[j, 7], Y0[j, 8],
                 Y0[j, 9], Y0[j, 10], Y0[j, 11], Y0[j, 12])
            for c in range(13):
                out[j, 0, c] = y[c]
            th = TH[j]
            for i in range(n_t - 1):
                y = step(y, F[j, i], th, k, hs[i])
                for c in range(13):
                    out[j, i + 1, c] = y[c]
        return out

    return loop


loop_real = _make_loop(step_real)
loop_cs = _make_loop(step_cs)


def simulate(Y0, F, TH, hs):
    n, n_t, _ = F.shape
    out = np.empty((n, n_t, 13))
    return loop_real(np.ascontiguousarray(Y0, float), np.ascontiguousarray(F, float),
                     np.ascontiguousarray(np.broadcast_to(TH, (n, TH.shape[-1])), float), np.asarray(hs, float), out)


H_CS = 1e-30


def linearize(Y0, F, th, dth, dy0, hs):
    """States and exact Jacobian by complex step: Y0 (W, 13) window starts, F (W, n_t, k),
    th (n_th,), dth (p, n_th) parameter directions, dy0 (W, q, 13) state directions.
    Returns (Y (W, n_t, 13), J (W, p + q, n_t, 13))."""
    W, n_t, k = F.shape
    p, q = dth.shape[0], dy0.shape[1]
    d = p + q
    Y0c = np.repeat(Y0[:, None, :], d, 1).astype(complex)
    THc = np.repeat(np.repeat(th[None, None, :], W, 0), d, 1).astype(complex)
    THc[:, :p] += 1j * H_CS * dth[None]
    Y0c[:, p:] += 1j * H_CS * dy0
    out = np.empty((W * d, n_t, 13), complex)
    loop_cs(Y0c.reshape(W * d, 13), np.ascontiguousarray(np.repeat(F, d, 0)), THc.reshape(W * d, -1),
            np.asarray(hs, float), out)
    out = out.reshape(W, d, n_t, 13)
    return out[:, 0].real.copy(), out.imag / H_CS


def linearize_fd(Y0, F, th, dth, dy0, hs, step=1e-6):
    """Forward differences with the compiled kernel (today's method, compiled): 1 + p + q rows per window."""
    W, n_t, k = F.shape
    p, q = dth.shape[0], dy0.shape[1]
    d = p + q
    Y0r = np.repeat(Y0[:, None, :], d + 1, 1)
    THr = np.repeat(np.repeat(th[None, None, :], W, 0), d + 1, 1)
    THr[:, 1:1 + p] += step * dth[None]
    Y0r[:, 1 + p:] += step * dy0
    out = np.empty((W * (d + 1), n_t, 13))
    loop_real(Y0r.reshape(-1, 13), np.ascontiguousarray(np.repeat(F, d + 1, 0)), THr.reshape(W * (d + 1), -1),
              np.asarray(hs, float), out)
    out = out.reshape(W, d + 1, n_t, 13)
    return out[:, 0], (out[:, 1:] - out[:, :1]) / step
