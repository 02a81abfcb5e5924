"""The friction-element interface shared by slip (LuGre) and hysteresis (Jenkins, Mindlin).

An element is the tangential law of one contact in rate form (an internal state, its rate at a
relative velocity, the force it transmits), so the same element can be driven by a diffrax ODE, a
displacement history or a harmonic displacement, and differentiated through either.

Sign convention (used by every element): the relative displacement u and velocity v = du/dt are
those of the driving body with respect to the driven one (wang2022: Δx = x_stage − x_reticle), and
the force is the tangential force transmitted to the driven body, positive in the +u direction.
In stick every element behaves like a spring, so force ≈ stiffness · u for small u.
"""

from __future__ import annotations

import abc

import equinox as eqx
from jaxtyping import Array, ArrayLike, PyTree


class AbstractFrictionElement(eqx.Module):
    """A tangential friction law with internal state, driven by the relative velocity.

    Concrete elements are final `equinox.Module`s whose physical parameters are array leaves
    (so jit, grad and vmap see them). One call computes one operating point; batch with `jax.vmap`.
    """

    @abc.abstractmethod
    def initial_state(self) -> PyTree[Array]:
        """The state of the unloaded contact (no deflection, no history)."""

    @abc.abstractmethod
    def state_rate(self, state: PyTree[Array], velocity: ArrayLike) -> PyTree[Array]:
        """Time derivative of the state at relative velocity `velocity` (m/s).

        Has the same pytree structure as `state`; units are the state's units per second.
        """

    @abc.abstractmethod
    def force(self, state: PyTree[Array], velocity: ArrayLike) -> Array:
        """Tangential force transmitted (N) in `state` at relative velocity `velocity` (m/s)."""


class AbstractIncrementalElement(AbstractFrictionElement):
    """A rate-independent element with an exact state update for a displacement step, which
    `tribojax.drive` uses instead of an ODE solver (Jenkins, Mindlin, the band brake)."""

    @abc.abstractmethod
    def increment(self, state: PyTree[Array], du: ArrayLike) -> PyTree[Array]:
        """State after a displacement step `du` (m) with no reversal inside the step."""
