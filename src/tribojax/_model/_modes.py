"""A damped mode driven by the stage acceleration (exact discretisation) and a 1-D maximiser."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import expm

from .._export import cached_jit


def _transition(M, h):
    """exp(M·h) for every step length h (one matrix exponential when the sampling is uniform)."""
    uniform = jnp.all(jnp.abs(h - h[0]) <= 1e-12 * jnp.abs(h[0]))
    return jax.lax.cond(
        uniform,
        lambda: jnp.broadcast_to(expm(M * h[0]), (h.size, 4, 4)),
        lambda: jax.vmap(lambda hh: expm(M * hh))(h),
    )


@cached_jit  # its trace is stored (tribojax._export): discovery's mode refits call it often
@functools.partial(jax.vmap, in_axes=(None, None, 0, 0))
def oscillator(t, a, omega, zeta):
    """q, q̇ of q̈ + 2ζωq̇ + ω²q = −a(t), a linear between samples (exact discretisation), for
    each (ω, ζ) pair of the vectors `omega`, `zeta`: shape (pairs, n, 2)."""
    A = jnp.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    M = jnp.zeros((4, 4)).at[:2, :2].set(A).at[1, 2].set(-1.0).at[2, 3].set(1.0)
    h = jnp.diff(t)
    E = _transition(M, h)
    slope = jnp.diff(a) / h

    def step(x, inp):
        Ek, ak, sk = inp
        y = Ek @ jnp.concatenate([x, jnp.stack([ak, sk])])
        return y[:2], y[:2]

    _, xs = jax.lax.scan(step, jnp.zeros(2), (E, a[:-1], slope))
    return jnp.concatenate([jnp.zeros((1, 2)), xs])


def golden_max(f, lo, hi, iters=18):
    """Maximiser of a unimodal f on [lo, hi] (golden section)."""
    g = (np.sqrt(5) - 1) / 2
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iters):
        if fc > fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (c, fc) if fc > fd else (d, fd)
