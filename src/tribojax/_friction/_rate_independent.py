"""Rate-independent friction elements of wu2015: Jenkins macroslip (Eq 1), Mindlin microslip (Eq 2).

Each element is usable two ways:

(a) as a steady hysteresis loop under u = A·cos θ (wu2015's phase convention, docs/reproduction.md):
    θ ∈ [0, π) is the falling branch, starting at u = +A from the loop's peak force; the rising
    branch follows from the loop's odd symmetry f(θ + π) = −f(θ);
(b) in rate form, driven by any displacement history, with the exact update `increment(state, du)`
    of an `AbstractIncrementalElement`.

Units: displacement m, force N, stiffness N/m. A0 = μN/K_d (m) is the critical amplitude.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from .._checks import check_range
from ._element import AbstractIncrementalElement

Scalar = Float[Array, "..."]


class AbstractHysteresisElement(AbstractIncrementalElement):
    """A rate-independent friction element with a closed steady loop under harmonic displacement.

    Contract used by `harmonic_balance`: the falling branch reaches −μN at u = A − slip_span()
    and stays there (gross slip). Concrete elements have the fields `mu` (friction coefficient,
    > 0), `N` (normal load, N, > 0) and `K_d` (tangential contact stiffness, N/m, > 0).
    """

    mu: eqx.AbstractVar[Scalar]
    N: eqx.AbstractVar[Scalar]
    K_d: eqx.AbstractVar[Scalar]
    # the branch has a (θ* − θ)^p singularity at the onset of gross slip (quadrature hint)
    endpoint_singular: ClassVar[bool] = False
    quadrature_order: ClassVar[int] = 16  # Gauss–Legendre points for `harmonic_balance`

    @property
    def slip_force(self) -> Array:
        """μN, the force in gross slip (N)."""
        return self.mu * self.N

    @property
    def A0(self) -> Array:
        """Critical displacement amplitude A0 = μN/K_d (m); Ā = A/A0."""
        return self.mu * self.N / self.K_d

    @abc.abstractmethod
    def slip_span(self) -> Array:
        """Displacement (m) after a reversal at which the branch reaches gross slip (∓μN)."""

    @abc.abstractmethod
    def falling_branch(self, u, A) -> Array:
        """Force (N) on the falling branch of the steady loop of amplitude A (m) at u ∈ [−A, A]."""

    def branch_angle(self, A) -> Array:
        """θ* (rad): where the falling branch enters gross slip; π if it never does.

        cos θ* = 1 − s/A with s = `slip_span()` (wu2015 Eqs 1–2). The arccos is masked at the
        no-slip side (double where), so gradients stay finite at the onset of gross slip.
        """
        c = 1.0 - self.slip_span() / A
        slipping = c > -1.0
        theta = jnp.arccos(jnp.where(slipping, c, 0.0))
        return jnp.where(slipping, theta, jnp.pi)

    def steady_force(self, u, A, direction) -> Array:
        """Steady-loop force (N) at displacement u (m), amplitude A (m), on the branch of the
        sign of `direction` (the velocity's sign: < 0 falling, >= 0 rising)."""
        rising = -self.falling_branch(-u, A)
        return jnp.where(direction < 0, self.falling_branch(u, A), rising)

    def steady_loop(self, theta, A) -> Array:
        """Force (N) at phase θ (rad) of the steady loop under u = A·cos θ (wu2015 Eqs 1–2)."""
        phase = jnp.mod(theta, 2.0 * jnp.pi)
        return self.steady_force(A * jnp.cos(theta), A, jnp.where(phase < jnp.pi, -1.0, 1.0))


def _checked(mu, N, K_d):
    return (
        check_range(mu, "mu", 0.0),
        check_range(N, "N", 0.0, unit="N"),
        check_range(K_d, "K_d", 0.0, unit="N/m"),
    )


class Jenkins(AbstractHysteresisElement):
    """Jenkins (macroslip) element: a spring K_d in series with a Coulomb slider μN.

    Steady loop, wu2015 Eq 1 with its third branch corrected (printed −μN + K_d(u − A); the
    branch through (−A, −μN) is −μN + K_d(u + A)): for Ā = A/A0 > 1 the falling branch is
    f = μN + K_d(u − A) until θ* = arccos(1 − 2/Ā), then −μN. For Ā ≤ 1 the element never slips
    and the loop degenerates to the line f = K_d·u (wu2015's Eq 1 assumes slip).

    Rate form: state z = spring deflection (m); force K_d·z; ż = v unless the slider slides
    (|K_d z| = μN and z·v > 0), then ż = 0.

    Fields: mu (—, > 0), N (normal load, N, > 0), K_d (tangential contact stiffness, N/m, > 0).
    """

    mu: Scalar
    N: Scalar
    K_d: Scalar
    quadrature_order: ClassVar[int] = 10  # the stick branch is a trigonometric polynomial

    def __init__(self, mu, N, K_d):
        self.mu, self.N, self.K_d = _checked(mu, N, K_d)

    def slip_span(self) -> Array:
        return 2.0 * self.A0

    def falling_branch(self, u, A) -> Array:
        """wu2015 Eq 1 (first two branches): min(K_d A, μN) + K_d(u − A), floored at −μN."""
        top = jnp.minimum(self.K_d * A, self.slip_force)
        return jnp.maximum(top + self.K_d * (u - A), -self.slip_force)

    def initial_state(self) -> Array:
        return jnp.zeros((), dtype=jnp.float64)

    def state_rate(self, state, velocity: ArrayLike) -> Array:
        sliding = (self.K_d * jnp.abs(state) >= self.slip_force) & (state * velocity > 0)
        return jnp.where(sliding, 0.0, velocity)

    def force(self, state, velocity: ArrayLike) -> Array:
        return self.K_d * state

    def increment(self, state, du):
        return jnp.clip(state + du, -self.A0, self.A0)

    def state_for_force(self, force) -> Array:
        """The spring deflection (m) whose force is `force` (N), clipped to ±μN."""
        return jnp.clip(jnp.asarray(force, jnp.float64) / self.K_d, -self.A0, self.A0)


def power_unit_bank(n: int, p=1.5, xp=np):
    """Iwan discretisation, in units of A0 (slip limits) and K_d (stiffnesses), of the virgin curve
    φ(x) = μN[1 − (1 − x/Y)^p], Y = p·A0 (initial slope K_d, full slip at Y): p = 3/2 is the
    Mindlin/Koh microslip law (wu2015 Eq 2); p = 2 a bank whose slip limits are spread uniformly
    on (0, 2A0] (a parabolic backbone); other p, power-law spreads of the limits (Iwan 1966,
    Segalman 2005). `xp`: NumPy (constants) or jax.numpy (p traced, differentiable).

    Slip displacements y_j = Y·(1 − (1 − j/n)²), which cluster where φ bends; the stiffnesses make
    the bank's virgin curve the piecewise-linear interpolant of φ at the y_j (Masing branches
    follow, error ~1/n²)."""
    q = 1.0 - (1.0 - np.arange(n + 1) / n) ** 2  # y_j / Y
    phi = 1.0 - (1.0 - xp.asarray(q)) ** p  # virgin curve / μN at y_j
    slopes = (phi[1:] - phi[:-1]) / (p * np.diff(q))  # of the interpolant / K_d, decreasing
    return p * xp.asarray(q[1:]), slopes - xp.concatenate([slopes[1:], xp.zeros(1)])


def mindlin_unit_bank(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The Mindlin bank (`power_unit_bank` at p = 3/2, wu2015 Eq 2) as NumPy constants."""
    return power_unit_bank(n, 1.5)


class IwanBank(eqx.Module):
    """A parallel bank of Jenkins elements (Iwan): slip limits y_j (m), stiffnesses k_j (N/m).

    State: the spring deflections z_j (m). Each spring follows the displacement until its slider
    holds it at ±y_j; the force is Σ k_j z_j. One element (y = μN/K_d, k = K_d) is the Jenkins
    element (wu2015 Eq 1); `IwanBank.mindlin` discretises the Mindlin/Koh element (Eq 2).
    """

    y: Array
    k: Array

    @classmethod
    def mindlin(cls, n: int, A0=1.0, K_d=1.0) -> IwanBank:
        """The Mindlin bank (`mindlin_unit_bank`) for A0 (m) and K_d (N/m)."""
        y, k = mindlin_unit_bank(n)
        return cls(A0 * jnp.asarray(y), K_d * jnp.asarray(k))

    def state_rate(self, z, velocity) -> Array:
        """dz_j/dt (m/s): the velocity, 0 where a slider slides (|z_j| = y_j, moving outward)."""
        sliding = (jnp.abs(z) >= self.y) & (z * velocity > 0)
        return jnp.where(sliding, 0.0, velocity)

    def force(self, z) -> Array:
        """Σ k_j z_j, N."""
        return jnp.sum(self.k * z)

    def increment(self, z, du, limit_scale=1.0) -> Array:
        """Deflections after a displacement step du (m), no reversal inside; slip limits y·s."""
        y = self.y * limit_scale
        return jnp.clip(z + du, -y, y)

    def deflections(self, u, limit_scale=None, z0=None) -> Array:
        """Deflections (len(u), n) driven along the displacement history u (m) from rest, or from
        the deflections `z0` (n, m) at u[0].

        `limit_scale` (len(u), optional): the slip limits at each sample are y·s (a varying
        normal load); exact for a rate-independent bank between samples.
        """
        s = jnp.ones_like(u) if limit_scale is None else limit_scale
        z0 = jnp.zeros_like(self.y) if z0 is None else jnp.asarray(z0)

        def step(z, inp):
            z = self.increment(z, inp[0], inp[1])
            return z, z

        _, zs = jax.lax.scan(step, z0, (jnp.diff(u), s[1:]))
        return jnp.concatenate([z0[None, :], zs])


def _three_halves(p):
    """max(p, 0)^(3/2), double-where masked so that derivatives of every order are finite at 0."""
    positive = p > 0.0
    return jnp.where(positive, jnp.where(positive, p, 1.0) ** 1.5, 0.0)


class Mindlin(AbstractHysteresisElement):
    """Mindlin/Koh microslip element (a sphere on a flat under constant normal load).

    Virgin curve φ(x) = μN[1 − (1 − x/Y)^(3/2)] for 0 ≤ x ≤ Y = 1.5·A0, μN beyond; its initial
    slope is K_d, so A0 = μN/K_d as for Jenkins. Branches follow Masing's rules (doubled virgin
    curve from the last reversal). Steady loop, wu2015 Eq 2 in the simplified Koh form
    f = f* − 2μN[1 − (1 − (A − u)/(3A0))^(3/2)] on the falling branch, floored at −μN.

    Correction to the printed Eq 2 (docs/hysteresis.md): the branches start from the loop's peak
    force f* = μN[1 − (1 − 2Ā/3)^(3/2)] (μN in gross slip, Ā ≥ 1.5, θ* = arccos(1 − 3/Ā)), so the
    loop closes and its damping stays positive.

    Rate form: the Iwan (parallel-Jenkins) discretisation `IwanBank.mindlin` of the virgin curve:
    all Masing branches are interpolated (relative error ~1/n²). The state is the vector of the
    n_iwan spring deflections (m).

    Fields: mu (—, > 0), N (normal load, N, > 0), K_d (initial tangential stiffness, N/m, > 0),
    n_iwan (number of Iwan elements of the rate form, static, >= 2).
    """

    mu: Scalar
    N: Scalar
    K_d: Scalar
    n_iwan: int = eqx.field(static=True)
    endpoint_singular: ClassVar[bool] = True

    def __init__(self, mu, N, K_d, *, n_iwan: int = 256):
        self.mu, self.N, self.K_d = _checked(mu, N, K_d)
        if int(n_iwan) < 2:
            raise ValueError(f"n_iwan = {n_iwan} must be at least 2")
        self.n_iwan = int(n_iwan)

    def slip_span(self) -> Array:
        return 3.0 * self.A0

    def virgin_curve(self, x) -> Array:
        """φ(x) = μN[1 − (1 − x/(1.5 A0))^(3/2)] (N) for a displacement x ≥ 0 (m) from rest."""
        return self.slip_force * (1.0 - _three_halves(1.0 - x / (1.5 * self.A0)))

    def peak_force(self, A) -> Array:
        """f* (N): the steady loop's peak force at amplitude A (m); μN in gross slip."""
        return self.virgin_curve(A)

    def falling_branch(self, u, A) -> Array:
        """wu2015 Eq 2 (Koh form, branch started at f*): f* − 2φ((A − u)/2), floored at −μN."""
        f = self.peak_force(A) - 2.0 * self.virgin_curve(0.5 * (A - u))
        return jnp.maximum(f, -self.slip_force)

    def iwan_bank(self) -> IwanBank:
        """The Iwan discretisation of the rate form: `IwanBank.mindlin(n_iwan, A0, K_d)`."""
        return IwanBank.mindlin(self.n_iwan, self.A0, self.K_d)

    def initial_state(self) -> Array:
        return jnp.zeros(self.n_iwan, dtype=jnp.float64)

    def state_rate(self, state, velocity: ArrayLike) -> Array:
        return self.iwan_bank().state_rate(state, velocity)

    def force(self, state, velocity: ArrayLike) -> Array:
        return self.iwan_bank().force(state)

    def increment(self, state, du):
        return self.iwan_bank().increment(state, du)
