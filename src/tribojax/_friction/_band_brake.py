"""A self-energizing band brake with a clearance: the banded rotary friction damper's element.

The device (ARTS-Laboratory, "Dataset-Friction-Damper-with-Backlash", CC BY-SA 4.0; its authors
describe a band brake whose friction is amplified through motion and released at reversal, with
an energized and a backlash regime) is modelled as a play operator with a nonlinear backbone.
Assumptions, stated so they can be checked against its records:

* the state e (m) is the drum's displacement relative to the band's neutral position; a
  displacement step moves e with the drive until the band slips on the drum, at e = e₊ or e₋
  (gross slip), where e stays: the play operator, updated exactly (`increment`);
* across the clearance −g₋ ≤ e ≤ g₊ the band drags lightly: a spring k_g·e;
* past the clearance the band wraps the drum; by the capstan (Euler–Eytelwein) law its tension
  grows as T₀·e^{μφ} with the wrapped angle φ, and φ is taken to grow linearly with the rotation
  past the clearance, so the force rises as k_g·g₊ + A₊(e^{β₊(e − g₊)} − 1) (A₊ ∝ T₀, β₊ = μ dφ/de);
* it saturates at the slip force F₊ (the band slides on the drum), e₊ = g₊ + ln(1 + (F₊ −
  k_g g₊)/A₊)/β₊; the other direction loads the other band end, with its own g₋, A₋, β₋, F₋.

Units: displacement m, force N, stiffness N/m, β 1/m. The force does not depend on the rate.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._checks import check_range
from ._element import AbstractIncrementalElement

Scalar = Float[Array, "..."]


class BandBrake(AbstractIncrementalElement):
    """Band brake with a clearance (module docstring): slip forces `F_pos`, `F_neg` (N, > 0),
    clearances `gap_pos`, `gap_neg` (m, > 0), drag stiffness `k_gap` (N/m, > 0) across the
    clearance, engagement scales `A_pos`, `A_neg` (N, > 0) and rates `beta_pos`, `beta_neg`
    (1/m, > 0) of the exponential (capstan) rise. State: e (m), 0 when unloaded."""

    F_pos: Scalar
    F_neg: Scalar
    gap_pos: Scalar
    gap_neg: Scalar
    k_gap: Scalar
    A_pos: Scalar
    A_neg: Scalar
    beta_pos: Scalar
    beta_neg: Scalar

    def __init__(self, F_pos, F_neg, gap_pos, gap_neg, k_gap, A_pos, A_neg, beta_pos, beta_neg):
        self.F_pos = check_range(F_pos, "F_pos", 0.0, unit="N")
        self.F_neg = check_range(F_neg, "F_neg", 0.0, unit="N")
        self.gap_pos = check_range(gap_pos, "gap_pos", 0.0, unit="m")
        self.gap_neg = check_range(gap_neg, "gap_neg", 0.0, unit="m")
        self.k_gap = check_range(k_gap, "k_gap", 0.0, unit="N/m")
        self.A_pos = check_range(A_pos, "A_pos", 0.0, unit="N")
        self.A_neg = check_range(A_neg, "A_neg", 0.0, unit="N")
        self.beta_pos = check_range(beta_pos, "beta_pos", 0.0, unit="1/m")
        self.beta_neg = check_range(beta_neg, "beta_neg", 0.0, unit="1/m")

    def _side(self, e, gap, A, beta):
        """Force magnitude on one side at engagement e ≥ 0 (m)."""
        past = jnp.maximum(e - gap, 0.0)
        return self.k_gap * jnp.minimum(e, gap) + A * jnp.expm1(beta * past)

    def _saturation(self, gap, A, beta, F):
        """Engagement (m) where a side's force reaches its slip force F."""
        excess = jnp.maximum(F - self.k_gap * gap, 0.0)
        return jnp.where(F > self.k_gap * gap, gap + jnp.log1p(excess / A) / beta, F / self.k_gap)

    def limits(self) -> tuple[Array, Array]:
        """(e₋, e₊): the engagements (m) at which the band slips, e₋ < 0 < e₊."""
        up = self._saturation(self.gap_pos, self.A_pos, self.beta_pos, self.F_pos)
        down = self._saturation(self.gap_neg, self.A_neg, self.beta_neg, self.F_neg)
        return -down, up

    def initial_state(self) -> Array:
        return jnp.zeros((), dtype=jnp.float64)

    def state_for_force(self, force) -> Array:
        """The state e (m) whose force is `force` (N), clipped to the slip forces: a record that
        starts loaded (a residual band tension) starts there. Bisection (the force rises with e)."""
        lo, hi = self.limits()
        target = jnp.clip(jnp.asarray(force, jnp.float64), -self.F_neg, self.F_pos)

        def halve(_, bounds):
            a, b = bounds
            mid = 0.5 * (a + b)
            below = self.force(mid) < target
            return jnp.where(below, mid, a), jnp.where(below, b, mid)

        a, b = jax.lax.fori_loop(0, 80, halve, (lo, hi))
        return 0.5 * (a + b)

    def increment(self, state, du):
        lo, hi = self.limits()
        return jnp.clip(state + du, lo, hi)

    def state_rate(self, state, velocity: ArrayLike) -> Array:
        lo, hi = self.limits()
        sliding = ((state >= hi) & (velocity > 0)) | ((state <= lo) & (velocity < 0))
        return jnp.where(sliding, 0.0, velocity)

    def force(self, state, velocity: ArrayLike = 0.0) -> Array:
        e = jnp.asarray(state)
        up = self._side(jnp.maximum(e, 0.0), self.gap_pos, self.A_pos, self.beta_pos)
        down = self._side(jnp.maximum(-e, 0.0), self.gap_neg, self.A_neg, self.beta_neg)
        return jnp.minimum(up, self.F_pos) - jnp.minimum(down, self.F_neg)
