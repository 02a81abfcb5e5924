"""Harmonic balance of friction elements: first-harmonic K_eq, C_eq and wu2015's K̄, C̄.

Under u = A·cos θ (θ = ωt) the friction force's first harmonic is f_c·cos θ + f_s·sin θ with
f_c = (1/π)∮ f cos θ dθ and f_s = (1/π)∮ f sin θ dθ. wu2015 (Section 5.3; phase convention in
docs/reproduction.md, "wu2015") defines

    K_eq = f_c / A,   C_eq = −f_s / (A ω),   K̄ = K_eq / K_d,   C̄ = π ω C_eq / K_d = W / (K_d A²)

with W = ∮ f du the energy dissipated per cycle. K̄ and C̄ depend on Ā = A/A0 only.

Two routes: `harmonic_balance` integrates the closed steady loop of a Jenkins or Mindlin element
over its falling branch (fixed-order Gauss–Legendre up to the onset of gross slip θ*, closed form
beyond), so it is jit/vmap/grad friendly; `harmonic_response` drives any element in time.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._checks import check_range
from .._friction._element import AbstractFrictionElement, AbstractIncrementalElement
from .._friction._rate_independent import AbstractHysteresisElement
from .._precision import ensure_x64

Scalar = Float[Array, "..."]


class HarmonicCoefficients(eqx.Module):
    """First-harmonic description of a friction loop at one amplitude (batched under vmap).

    Fields: A (amplitude, m), A_bar (A/A0), K_eq (N/m), C_eq (N s/m), K_bar, C_bar
    (dimensionless, wu2015 Section 5.3), W (energy dissipated per cycle, J), f_c, f_s (first
    harmonic cosine and sine amplitudes of the force, N).
    """

    A: Scalar
    A_bar: Scalar
    K_eq: Scalar
    C_eq: Scalar
    K_bar: Scalar
    C_bar: Scalar
    W: Scalar
    f_c: Scalar
    f_s: Scalar


def _coefficients(K_d, A0, A, omega, f_c, f_s) -> HarmonicCoefficients:
    K_eq = f_c / A
    C_eq = -f_s / (A * omega)
    return HarmonicCoefficients(
        A=A,
        A_bar=A / A0,
        K_eq=K_eq,
        C_eq=C_eq,
        K_bar=K_eq / K_d,
        C_bar=jnp.pi * omega * C_eq / K_d,
        W=-jnp.pi * A * f_s,
        f_c=f_c,
        f_s=f_s,
    )


def harmonic_balance(
    element: AbstractHysteresisElement, A, omega=1.0, *, order: int | None = None
) -> HarmonicCoefficients:
    """K_eq, C_eq, K̄, C̄ of a Jenkins or Mindlin element's steady loop at amplitude A.

    Args:
        element: a `Jenkins` or `Mindlin` element (μ, N, K_d are differentiable leaves).
        A: displacement amplitude, m, > 0 (one amplitude; `jax.vmap` over many).
        omega: angular frequency, rad/s, > 0 (enters C_eq only; K̄ and C̄ are independent of it).
        order: Gauss–Legendre points on [0, θ*] (static); default the element's
            `quadrature_order` (Jenkins 10, Mindlin 16: ~1e-13 and ~1e-11 absolute in K̄, C̄).
    Returns:
        `HarmonicCoefficients`.
    Reference: wu2015 Eqs 1–2 (loops) and Section 5.3 (harmonic balance, K̄, C̄).
    """
    ensure_x64()
    if not isinstance(element, AbstractHysteresisElement):
        raise TypeError(
            "harmonic_balance needs a Jenkins or Mindlin element; use harmonic_response for "
            f"other friction elements (got {type(element).__name__})"
        )
    A = check_range(A, "A", 0.0, unit="m")
    omega = check_range(omega, "omega", 0.0, unit="rad/s")
    order = element.quadrature_order if order is None else int(order)
    x, w = (jnp.asarray(v) for v in np.polynomial.legendre.leggauss(order))
    t = 0.5 * (x + 1.0)  # nodes on [0, 1]
    w = 0.5 * w
    theta_star = element.branch_angle(A)
    # Mindlin: θ = θ*(1 − τ²), dθ = 2θ*τ dτ removes the (θ* − θ)^(3/2) endpoint singularity
    if element.endpoint_singular:
        theta = theta_star * (1.0 - t**2)
        weights = 2.0 * theta_star * t * w
    else:
        theta = theta_star * t
        weights = theta_star * w
    f = element.falling_branch(A * jnp.cos(theta), A)
    cos, sin = jnp.cos(theta), jnp.sin(theta)
    # [θ*, π] is gross slip, f = −μN: ∫ −μN cos θ = μN sin θ*, ∫ −μN sin θ = −μN (1 + cos θ*)
    i_c = jnp.sum(weights * f * cos) + element.slip_force * jnp.sin(theta_star)
    i_s = jnp.sum(weights * f * sin) - element.slip_force * (1.0 + jnp.cos(theta_star))
    # odd symmetry f(θ + π) = −f(θ): the full-cycle integrals are twice the half-cycle ones
    f_c = (2.0 / jnp.pi) * i_c
    f_s = (2.0 / jnp.pi) * i_s
    return _coefficients(element.K_d, element.A0, A, omega, f_c, f_s)


def drive(element: AbstractFrictionElement, u, t=None, *, state0=None, substeps: int = 4):
    """Force history (N) of a friction element driven through displacement samples u (m).

    Rate-independent elements (`Jenkins`, `Mindlin`, `BandBrake`: `AbstractIncrementalElement`)
    update exactly with `increment`; `t` is then not needed. Other elements are integrated with
    classical RK4 (`substeps` per sample interval, static) with the displacement interpolated
    linearly between samples (t in s, increasing). The element starts in `state0` (default: its
    unloaded state) at the first sample.
    """
    ensure_x64()
    u = jnp.asarray(u, dtype=jnp.float64)
    state0 = element.initial_state() if state0 is None else state0
    du = jnp.diff(u)
    if isinstance(element, AbstractIncrementalElement):

        def step(state, d):
            new = element.increment(state, d)
            return new, element.force(new, d)

        _, forces = jax.lax.scan(step, state0, du)
        return jnp.concatenate([element.force(state0, 0.0)[None], forces])
    if t is None:
        raise ValueError("drive needs the sample times t for a rate-dependent element")
    t = jnp.asarray(t, dtype=jnp.float64)
    dt = jnp.diff(t)
    v = du / dt

    def step(state, inp):
        t0, h, vel = inp
        new = _rk4(element, state, lambda s: vel, t0, h, substeps)
        return new, element.force(new, vel)

    _, forces = jax.lax.scan(step, state0, (t[:-1], dt, v))
    v0 = v[0] if v.shape[0] else 0.0
    return jnp.concatenate([element.force(state0, v0)[None], forces])


def harmonic_response(
    element: AbstractFrictionElement,
    A,
    omega=1.0,
    *,
    cycles: int = 2,
    steps_per_cycle: int = 4096,
    substeps: int = 1,
    K_d=None,
    A0=None,
):
    """First harmonic of any friction element driven by u = A·cos ωt in the time domain.

    The drive starts from the element's unloaded state at u = 0 (t = −T/4, velocity +Aω), runs
    `cycles` full periods (static), and the first harmonic is taken from the last period by the
    (spectrally exact for periodic data) rectangle rule on `steps_per_cycle` samples. Kinks of a
    rate-independent loop limit the accuracy to O(steps_per_cycle⁻²).

    Rate-independent elements are stepped exactly; others by RK4 at the exact drive velocity
    (`substeps` per sample) — mind the stability limit for stiff elements (h·rate ≲ 2.8).

    Args:
        element: any `AbstractFrictionElement`.
        A: amplitude, m, > 0. omega: rad/s, > 0.
        K_d, A0: normalisation for K̄, C̄ and Ā (default: the element's own `K_d` and `A0`;
            required for elements without them, e.g. K_d = σ0 and A0 = F_s/σ0 for LuGre).
    Returns:
        `HarmonicCoefficients` (the normalised entries use K_d and A0 as above).
    Reference: wu2015 Section 5.3 (first-harmonic balance).
    """
    ensure_x64()
    A = check_range(A, "A", 0.0, unit="m")
    omega = check_range(omega, "omega", 0.0, unit="rad/s")
    if steps_per_cycle % 4:
        raise ValueError(f"steps_per_cycle = {steps_per_cycle} must be a multiple of 4")
    n_quarter = steps_per_cycle // 4
    k = jnp.arange(-n_quarter, cycles * steps_per_cycle + 1, dtype=jnp.float64)
    theta = 2.0 * jnp.pi * k / steps_per_cycle
    t = theta / omega
    u = A * jnp.cos(theta)
    if isinstance(element, AbstractHysteresisElement):
        f = drive(element, u)
    else:
        f = _drive_harmonic(element, A, omega, t, substeps)
    last = slice(-steps_per_cycle - 1, -1)
    f_c = 2.0 * jnp.mean(f[last] * jnp.cos(theta[last]))
    f_s = 2.0 * jnp.mean(f[last] * jnp.sin(theta[last]))
    K_d = element.K_d if K_d is None else jnp.asarray(K_d, dtype=jnp.float64)
    A0 = element.A0 if A0 is None else jnp.asarray(A0, dtype=jnp.float64)
    return _coefficients(K_d, A0, A, omega, f_c, f_s)


def _rk4(element, state, vel, t0, h, substeps):
    """`substeps` classical RK4 steps of the element's state over [t0, t0 + h]; vel(t) in m/s."""
    h = h / substeps

    def one(s, i):
        ts = t0 + i * h
        rate = element.state_rate

        def ax(a, b, c):
            return jax.tree.map(lambda x, y: x + c * y, a, b)

        k1 = rate(s, vel(ts))
        k2 = rate(ax(s, k1, 0.5 * h), vel(ts + 0.5 * h))
        k3 = rate(ax(s, k2, 0.5 * h), vel(ts + 0.5 * h))
        k4 = rate(ax(s, k3, h), vel(ts + h))
        new = jax.tree.map(
            lambda a, b1, b2, b3, b4: a + h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4), s, k1, k2, k3, k4
        )
        return new, None

    if substeps <= 4:  # unrolled: a nested scan of a few steps costs more than its body
        for i in range(substeps):
            state, _ = one(state, float(i))
        return state
    new, _ = jax.lax.scan(one, state, jnp.arange(substeps, dtype=jnp.float64))
    return new


def _drive_harmonic(element, A, omega, t, substeps):
    """RK4 through u = A cos ωt with the exact velocity −Aω sin ωt at every stage."""
    vel = lambda s: -A * omega * jnp.sin(omega * s)  # noqa: E731

    def step(state, inp):
        t0, t1 = inp
        new = _rk4(element, state, vel, t0, t1 - t0, substeps)
        return new, element.force(new, vel(t1))

    state0 = element.initial_state()
    _, forces = jax.lax.scan(step, state0, (t[:-1], t[1:]))
    return jnp.concatenate([element.force(state0, vel(t[0]))[None], forces])
