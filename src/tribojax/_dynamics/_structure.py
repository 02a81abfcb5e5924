"""Linear structures with friction contacts, for the multi-harmonic balance (`_mhb`).

Steady hysteresis: the history is run from the contact's unloaded state at x = 0 through
`cycles` periods and the last is kept. For rate-independent elements one full period with slip
forgets the start, so `cycles = 2` gives the exact periodic loop; in permanent stick the contact
stays anchored at x = 0 (the unloaded position), the physical choice for a joint closed at rest.
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import as_f64
from .._friction._elastic2d import ElasticDryFriction2D
from .._friction._element import AbstractFrictionElement
from .._friction._rate_independent import AbstractHysteresisElement
from ._harmonic import drive


def _square(a, name: str, n: int | None = None) -> Array:
    a = as_f64(a, name)
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {tuple(a.shape)}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} must be {n}×{n} like M, got shape {tuple(a.shape)}")
    if not isinstance(a, jax.core.Tracer) and not np.all(np.isfinite(np.asarray(a))):
        raise ValueError(f"{name} has non-finite entries")
    return a


class Structure(eqx.Module):
    """A linear N-DOF structure M ẍ + C ẋ + K x (M kg, C N s/m, K N/m; N×N, M symmetric positive
    definite). Scalars are read as 1×1 matrices."""

    M: Array
    C: Array
    K: Array

    def __init__(self, M, C, K):
        M = _square(M, "M")
        n = M.shape[0]
        self.C, self.K = _square(C, "C", n), _square(K, "K", n)
        self.M = M
        if isinstance(M, jax.core.Tracer):
            return
        m = np.asarray(M)
        if not np.allclose(m, m.T, rtol=1e-12, atol=0.0):
            raise ValueError("M must be symmetric")
        eig = np.linalg.eigvalsh(m)
        if eig.min() <= 0.0:
            raise ValueError(
                f"M must be positive definite; its smallest eigenvalue is {eig.min():g} kg"
            )

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    def natural_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies (rad/s) of M, K (NumPy, ascending)."""
        m, k = np.asarray(self.M), np.asarray(self.K)
        lam = np.linalg.eigvals(np.linalg.solve(m, k)).real
        return np.sqrt(np.sort(np.clip(lam, 0.0, None)))


class Excitation(eqx.Module):
    """Harmonic forcing F(t) = static + cosine·cos ωt + sine·sin ωt (N, each of length N), plus
    base motion: `base` (m, length N) is the influence vector times the base displacement
    amplitude, x the motion relative to the base, giving the force ω²·M·base·cos ωt."""

    static: Array
    cosine: Array
    sine: Array
    base: Array

    def __init__(self, n_dof: int, static=None, cosine=None, sine=None, base=None):
        def vec(v, name):
            v = jnp.zeros(n_dof) if v is None else as_f64(v, name).reshape(-1)
            if v.shape != (n_dof,):
                raise ValueError(f"{name} must have {n_dof} entries (one per DOF), got {v.size}")
            return v

        self.static = vec(static, "static")
        self.cosine = vec(cosine, "cosine")
        self.sine = vec(sine, "sine")
        self.base = vec(base, "base")


class AbstractContact(eqx.Module):
    """A contact applying a periodic force history to some DOFs of a structure, resisting the
    motion (f_c in M ẍ + C ẋ + K x + f_c = F)."""

    @abc.abstractmethod
    def dofs(self) -> tuple[int, ...]:
        """The DOFs the contact acts on."""

    @abc.abstractmethod
    def forces(self, x: Array, period) -> Array:
        """Force history (n_time, N) in N over one period from displacements x (n_time, N), m."""

    @abc.abstractmethod
    def initial_state(self, n_dof: int):
        """History state of the unloaded contact at x = 0 (for `step`)."""

    @abc.abstractmethod
    def step(self, state, x):
        """Time stepping: (new state, force vector (N,) in N) after moving to displacement x."""


def _periodic_history(u, cycles: int):
    """[0, u, u, ...]: from rest at 0 through `cycles` periods of the samples u (n_time, ...)."""
    return jnp.concatenate([jnp.zeros_like(u[:1]), jnp.tile(u, (cycles,) + (1,) * (u.ndim - 1))])


class FrictionContact(AbstractContact):
    """A friction element acting on x[dof] − x[ref_dof] (ref_dof None: the ground).

    `cycles` (static, >= 2) periods are run; a rate-dependent element (e.g. `LuGre`) is
    integrated by `drive` with RK4 and `substeps` per sample (mind its stability limit).
    """

    element: AbstractFrictionElement
    dof: int = eqx.field(static=True)
    ref_dof: int | None = eqx.field(static=True, default=None)
    cycles: int = eqx.field(static=True, default=2)
    substeps: int = eqx.field(static=True, default=4)

    def dofs(self):
        return (self.dof,) if self.ref_dof is None else (self.dof, self.ref_dof)

    def relative(self, x):
        return x[:, self.dof] - (0.0 if self.ref_dof is None else x[:, self.ref_dof])

    def forces(self, x, period):
        u = self.relative(x)
        n = u.shape[0]
        t = period / n * jnp.arange(-1, self.cycles * n, dtype=jnp.float64)  # rate-dependent only
        f = drive(self.element, _periodic_history(u, self.cycles), t, substeps=self.substeps)
        return self._spread(jnp.zeros_like(x), f[-n:])

    def _spread(self, out, f):
        out = out.at[..., self.dof].add(f)
        if self.ref_dof is not None:
            out = out.at[..., self.ref_dof].add(-f)
        return out

    def initial_state(self, n_dof):
        if not isinstance(self.element, AbstractHysteresisElement):
            raise TypeError("time stepping needs a rate-independent (hysteresis) element")
        return (self.element.initial_state(), jnp.zeros(()))

    def step(self, state, x):
        z, u_old = state
        u = self.relative(x[None])[0]
        z = self.element.increment(z, u - u_old)
        return (z, u), self._spread(jnp.zeros_like(x), self.element.force(z, 0.0))


class DryFrictionContact2D(AbstractContact):
    """An `ElasticDryFriction2D` contact: tangential displacement x[tangential_dof], normal
    displacement x[normal_dof] (positive = compression), both against the ground."""

    element: ElasticDryFriction2D
    tangential_dof: int = eqx.field(static=True)
    normal_dof: int = eqx.field(static=True)
    cycles: int = eqx.field(static=True, default=2)

    def dofs(self):
        return (self.tangential_dof, self.normal_dof)

    def forces(self, x, period):
        n = x.shape[0]
        u_t = _periodic_history(x[:, self.tangential_dof], self.cycles)
        u_n = _periodic_history(x[:, self.normal_dof], self.cycles)
        f_t, f_n, _ = self.element.forces(u_t, u_n)
        out = jnp.zeros_like(x).at[:, self.tangential_dof].add(f_t[-n:])
        return out.at[:, self.normal_dof].add(f_n[-n:])

    def initial_state(self, n_dof):
        return self.element.initial_state()

    def step(self, state, x):
        w, f_t, f_n = self.element.step(state, x[self.tangential_dof], x[self.normal_dof])
        out = jnp.zeros_like(x).at[self.tangential_dof].add(f_t)
        return w, out.at[self.normal_dof].add(f_n)


def check_contacts(contacts, n_dof: int) -> tuple:
    """The contacts as a tuple, each DOF checked to lie in [0, n_dof)."""
    contacts = tuple(contacts)
    for i, c in enumerate(contacts):
        if not isinstance(c, AbstractContact):
            raise TypeError(f"contacts[{i}] is a {type(c).__name__}, not a contact")
        for d in c.dofs():
            if not 0 <= int(d) < n_dof:
                raise ValueError(
                    f"contacts[{i}] acts on DOF {d}, outside the structure's range [0, {n_dof - 1}]"
                )
    return contacts
