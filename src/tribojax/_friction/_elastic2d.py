"""Two-dimensional elastic dry-friction contact: a tangential Jenkins slider whose slip limit is
μ times a unilateral normal spring force (lift-off / separation).

Displacements (m) at the contact: u_t tangential, u_n normal (positive = into the contact, i.e.
compression). Forces (N) transmitted to the structure at those DOFs, resisting the motion:

    f_n = max(k_n·u_n + n0, 0)                          (unilateral normal spring, preload n0)
    f_t = clip(k_t·(u_t − w), −μ f_n, +μ f_n)           (elastic predictor, return to the cone)

with w the slider's anchor position (m), the element's history state. After each step the anchor
is moved so that f_t = k_t·(u_t − w); in separation (f_n = 0) f_t = 0 and the anchor follows u_t.
This is the elastic dry-friction law of the harmonic-balance literature (e.g. Krack & Gross,
"Harmonic Balance for Nonlinear Vibration Problems", 2019: the return-mapping form of Coulomb's
law with a tangential penalty stiffness), exact for a piecewise-linear displacement history.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_range

Scalar = Float[Array, "..."]


class ElasticDryFriction2D(eqx.Module):
    """Elastic dry-friction contact with normal-load variation and separation.

    Fields: k_t (tangential stiffness, N/m, > 0), k_n (normal stiffness, N/m, > 0), mu
    (friction coefficient, > 0), n0 (normal preload at u_n = 0, N, any sign; default 0).
    """

    k_t: Scalar
    k_n: Scalar
    mu: Scalar
    n0: Scalar

    def __init__(self, k_t, k_n, mu, n0=0.0):
        self.k_t = check_range(k_t, "k_t", 0.0, unit="N/m")
        self.k_n = check_range(k_n, "k_n", 0.0, unit="N/m")
        self.mu = check_range(mu, "mu", 0.0)
        self.n0 = check_range(n0, "n0", unit="N")

    def initial_state(self) -> Array:
        """Anchor at the origin: the contact closed at u_t = 0."""
        return jnp.zeros((), dtype=jnp.float64)

    def normal_force(self, u_n) -> Array:
        """f_n = max(k_n u_n + n0, 0) (N)."""
        return jnp.maximum(self.k_n * u_n + self.n0, 0.0)

    def step(self, w, u_t, u_n):
        """One return-mapping step to (u_t, u_n): (new anchor w (m), f_t (N), f_n (N))."""
        f_n = self.normal_force(u_n)
        limit = self.mu * f_n
        f_t = jnp.clip(self.k_t * (u_t - w), -limit, limit)
        return u_t - f_t / self.k_t, f_t, f_n

    def forces(self, u_t, u_n, w0=None):
        """Force histories (f_t, f_n) (N) along displacement samples u_t, u_n (m), from anchor w0
        (default the origin), and the final anchor."""
        w0 = self.initial_state() if w0 is None else w0

        def body(w, inp):
            w, f_t, f_n = self.step(w, inp[0], inp[1])
            return w, (f_t, f_n)

        w, (f_t, f_n) = jax.lax.scan(body, w0, (u_t, u_n))
        return f_t, f_n, w
