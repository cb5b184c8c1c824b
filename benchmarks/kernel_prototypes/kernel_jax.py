"""JAX prototype: :mod:`equations` traced with jnp scalars as they are (the module's default
helpers ``abs``, ``1.0 * (x < 0)`` and ``x ** 0.5`` accept tracers), time loop ``lax.scan``,
batches ``vmap``, sensitivities ``jvp`` (vmapped over the directions: the primal is computed
once per window), all under ``jit``.  Float64 throughout (``jax_enable_x64``).
"""
from __future__ import annotations

import jax

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_platforms", "cpu")

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import equations as eq  # noqa: E402


def _sim1(y0, F, th, hs):
    """One trajectory: y0 (13,), F (n_t, k), th (n_th,), hs (n_t - 1,) -> (n_t, 13)."""
    k = F.shape[1]

    def body(y, xs):
        f, h = xs
        yn = jnp.stack(eq.rk4_step(y, f, th, k, h))
        return yn, yn

    _, Y = jax.lax.scan(body, y0, (F[:-1], hs))
    return jnp.concatenate([y0[None], Y], 0)


sim1 = jax.jit(_sim1)
sim_batch = jax.jit(jax.vmap(_sim1, in_axes=(0, 0, 0, None)))


def _lin1(y0, F, th, hs, dy0, dth):
    """One window: primal (n_t, 13) and tangents (d, n_t, 13) for d directions."""

    def one(a, b):
        return jax.jvp(lambda y, t: _sim1(y, F, t, hs), (y0, th), (a, b))

    Y, dY = jax.vmap(one)(dy0, dth)
    return Y[0], dY


lin_windows = jax.jit(jax.vmap(_lin1, in_axes=(0, 0, None, None, 0, None)))


def simulate(Y0, F, TH, hs):
    n = F.shape[0]
    return np.asarray(sim_batch(jnp.asarray(Y0), jnp.asarray(F), jnp.asarray(np.broadcast_to(TH, (n, TH.shape[-1]))),
                                jnp.asarray(hs)))


def simulate_one(y0, F, th, hs):
    return np.asarray(sim1(jnp.asarray(y0), jnp.asarray(F), jnp.asarray(th), jnp.asarray(hs)))


def linearize(Y0, F, th, dth, dy0, hs):
    """Y0 (W, 13), F (W, n_t, k), th (n_th,), dth (p, n_th), dy0 (W, q, 13).
    Returns (Y (W, n_t, 13), J (W, p + q, n_t, 13))."""
    W = Y0.shape[0]
    p, q = dth.shape[0], dy0.shape[1]
    dY0 = np.concatenate([np.zeros((W, p, 13)), dy0], 1)
    dTH = np.concatenate([dth, np.zeros((q, th.size))], 0)
    Y, J = lin_windows(jnp.asarray(Y0), jnp.asarray(F), jnp.asarray(th), jnp.asarray(hs), jnp.asarray(dY0),
                       jnp.asarray(dTH))
    return np.asarray(Y), np.asarray(J)
