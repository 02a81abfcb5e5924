"""Rate-independent friction elements of wu2015: Jenkins macroslip (Eq 1), Mindlin microslip (Eq 2).

Each element is usable two ways:

(a) as a steady hysteresis loop under u = A·cos θ (wu2015's phase convention, REPRODUCTION.md):
    θ ∈ [0, π) is the falling branch, starting at u = +A from the loop's peak force; the rising
    branch follows from the loop's odd symmetry f(θ + π) = −f(θ);
(b) as an `AbstractFrictionElement` in rate form, driven by any displacement history. Because the
    elements are rate independent they also provide `increment(state, du)`: the exact state update
    for a displacement step du without a reversal inside it, which the drivers in `_hysteresis`
    use instead of an ODE solver.

Units: displacement m, force N, stiffness N/m. A0 = μN/K_d (m) is the critical amplitude.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import check_range
from ._element import AbstractFrictionElement

Scalar = Float[Array, "..."]


class AbstractHysteresisElement(AbstractFrictionElement):
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

    @abc.abstractmethod
    def increment(self, state, du):
        """State after a displacement step `du` (m) with no reversal inside the step."""

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

    Correction to the printed Eq 2: the branches must start from the loop's peak force
    f* = μN[1 − (1 − 2Ā/3)^(3/2)] (wu2015 defines f* but leaves it out of Eq 2). f* = μN in gross
    slip (Ā ≥ 1.5, θ* = arccos(1 − 3/Ā)); for Ā < 1.5 the printed form (starting at μN) does not
    close and gives negative damping (REPRODUCTION.md).

    Rate form: an Iwan (parallel-Jenkins) discretisation of the virgin curve with `n_iwan`
    elements (static). The slip displacements y_j = Y·(1 − (1 − j/n)²) cluster where φ bends, and
    the stiffnesses make the virgin curve the piecewise-linear interpolant of φ at the y_j, so all
    Masing branches are interpolated too (relative error ~1/n²). The state is the vector of the
    n spring deflections (m).

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

    def _iwan(self):
        """Slip displacements y_j (m) and stiffnesses k_j (N/m) of the Iwan discretisation."""
        j = jnp.arange(self.n_iwan + 1, dtype=jnp.float64) / self.n_iwan
        q = 1.0 - (1.0 - j) ** 2  # y_j / Y, from 0 to 1
        Y = 1.5 * self.A0
        phi = self.slip_force * (1.0 - (1.0 - q) ** 1.5)
        slopes = jnp.diff(phi) / (Y * jnp.diff(q))  # of the interpolant, decreasing
        k = slopes - jnp.concatenate([slopes[1:], jnp.zeros(1)])
        return Y * q[1:], k

    def initial_state(self) -> Array:
        return jnp.zeros(self.n_iwan, dtype=jnp.float64)

    def state_rate(self, state, velocity: ArrayLike) -> Array:
        y, _ = self._iwan()
        sliding = (jnp.abs(state) >= y) & (state * velocity > 0)
        return jnp.where(sliding, 0.0, velocity)

    def force(self, state, velocity: ArrayLike) -> Array:
        _, k = self._iwan()
        return jnp.sum(k * state)

    def increment(self, state, du):
        y, _ = self._iwan()
        return jnp.clip(state + du, -y, y)
