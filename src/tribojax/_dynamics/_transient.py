"""Time integration of a `FrictionSystem` to steady state: the independent check of the MHB.

Velocity-Verlet (Störmer) steps of M ẍ + C ẋ + K x + f_c = F(t) at a fixed step, the contacts
advanced by their exact `step` (return mapping) at every new displacement, the damping force taken
at the half-step velocity. Second order in the step for the smooth parts; the contact force is
exact along the piecewise-linear displacement path. No harmonic balance, no FFT, no AFT.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from .._checks import mode_jit
from ._mhb import FrictionSystem


@mode_jit
def integrate_steady(
    system: FrictionSystem,
    omega,
    periods: int = 100,
    steps_per_period: int = 1024,
    x0=None,
    v0=None,
):
    """Integrate from (x0, v0) (default rest) over `periods` periods of ω (rad/s, static counts);
    return the last period's samples x (steps_per_period, N), m, at t_j = j·T/steps."""
    s, ex = system.structure, system.excitation
    n = system.n_dof
    h = 2.0 * jnp.pi / omega / steps_per_period
    Minv = jnp.linalg.inv(s.M)
    amp_c = ex.cosine + omega**2 * (s.M @ ex.base)

    def force(t):
        return ex.static + amp_c * jnp.cos(omega * t) + ex.sine * jnp.sin(omega * t)

    def contact(states, x):
        steps = [c.step(st, x) for c, st in zip(system.contacts, states)]
        return tuple(st for st, _ in steps), sum((f for _, f in steps), jnp.zeros(n))

    x = jnp.zeros(n) if x0 is None else jnp.asarray(x0)
    v = jnp.zeros(n) if v0 is None else jnp.asarray(v0)
    states, fc = contact(tuple(c.initial_state(n) for c in system.contacts), x)
    a = Minv @ (force(0.0) - s.C @ v - s.K @ x - fc)

    def body(carry, k):
        x, v, a, states = carry
        t1 = (k + 1) * h
        v_half = v + 0.5 * h * a
        x = x + h * v_half
        states, fc = contact(states, x)
        a = Minv @ (force(t1) - s.C @ v_half - s.K @ x - fc)
        v = v_half + 0.5 * h * a
        return (x, v, a, states), x

    _, xs = jax.lax.scan(body, (x, v, a, states), jnp.arange(periods * steps_per_period))
    return xs[-steps_per_period - 1 : -1]
