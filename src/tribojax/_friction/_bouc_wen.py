"""The Bouc–Wen hysteresis element in rate form, written as a friction element.

Bouc (1967) and Wen (1976) give the hysteretic displacement z of a smooth elasto-plastic law,

    dz/dt = A·v − β·|v|·|z|^(n−1)·z − γ·v·|z|^n,      F = k·z (+ c·v),

here with A = 1, the restoring force F = K·z (the hysteretic part only: α = 0 in Wen's
F = αKu + (1 − α)Kz, so that F does not depend on the absolute displacement, as for the other
friction elements) and the physical parametrisation β + γ = 1/z_y^n, z_y = F_y/K, β = b/z_y^n,
γ = (1 − b)/z_y^n:

    dz/dt = v·[1 − (b·sgn(v·z) + 1 − b)·|z/z_y|^n].

On loading (v·z > 0) z rises from 0 with slope K and saturates at z_y, so F → F_y (the slip
force); n sets how sharply (n → ∞: the Jenkins element, K in series with a slider F_y). On
unloading the tangent stiffness is K·[1 − (1 − 2b)|z/z_y|^n]: b = 1/2 unloads at K (Masing-like
elastic unloading, the usual choice). Units: v m/s, z m, K N/m, F_y N, c N s/m.
"""

from __future__ import annotations

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._checks import check_range
from ._element import AbstractFrictionElement


def _abs_power(x, n):
    """|x|^n with a double-where mask at 0, so derivatives stay finite for any n > 0."""
    a = jnp.abs(x)
    nz = a > 0.0
    return jnp.where(nz, jnp.where(nz, a, 1.0) ** n, 0.0)


class BoucWen(AbstractFrictionElement):
    """Bouc–Wen friction element (Bouc 1967; Wen 1976, J. Eng. Mech. Div. 102 EM2, Eq 1).

        dz/dt = v·[1 − (b·sgn(v z) + 1 − b)·|z K/F_y|^n],   F = K·z + c·v

    Fields: K (initial stiffness, N/m, > 0), F_y (slip force, N, > 0), n (sharpness of the
    transition to slip, > 0), b (unloading shape β/(β + γ), in [0, 1]; 1/2 unloads at K), c
    (viscous coefficient, N s/m, >= 0). The state is the hysteretic displacement z (m); at
    constant velocity it settles at z = sgn(v)·F_y/K. Driven through a displacement history by
    `tribojax.drive` (RK4): keep h·n·K·|v|/F_y below ≈ 2.8 with h the step.
    """

    K: Array
    F_y: Array
    n: Array
    b: Array
    c: Array

    def __init__(self, K, F_y, n=2.0, b=0.5, c=0.0):
        self.K = check_range(K, "K", 0.0, unit="N/m")
        self.F_y = check_range(F_y, "F_y", 0.0, unit="N")
        self.n = check_range(n, "n", 0.0)
        self.b = check_range(b, "b", 0.0, 1.0, lo_open=False, hi_open=False)
        self.c = check_range(c, "c", 0.0, lo_open=False, unit="N s/m")

    @property
    def z_y(self) -> Array:
        """Yield displacement F_y/K (m): the deflection at which the element slips."""
        return self.F_y / self.K

    def initial_state(self) -> Array:
        return jnp.zeros_like(self.K)

    def state_rate(self, state, velocity: ArrayLike) -> Array:
        """dz/dt (m/s), Wen 1976 Eq 1 with A = 1 in the (K, F_y, n, b) parametrisation."""
        v = jnp.asarray(velocity)
        shape = self.b * jnp.sign(v * state) + 1.0 - self.b
        return v * (1.0 - shape * _abs_power(state / self.z_y, self.n))

    def force(self, state, velocity: ArrayLike) -> Array:
        """F = K·z + c·v, N."""
        return self.K * state + self.c * velocity
