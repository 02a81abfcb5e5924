"""Multi-harmonic balance (MHB) of a structure with friction contacts, with alternating
frequency–time (AFT) evaluation of the contact forces.

The displacement is x(t) = a₀ + Σ_k [a_k cos kωt + b_k sin kωt] over a set of harmonics k (any
subset of 0…H). Per DOF the coefficients are stored as X[dof] = [a₀, a₁, b₁, a₂, b₂, …] (a₀ only
if 0 is in the set); X has shape (N, n_coef). With the derivative operator Δ in coefficient space
(ẋ ↔ ω X Δ: the coefficients of d/dt(a cos kθ + b sin kθ) are kω b and −kω a) the balance of the
equations of motion M ẍ + C ẋ + K x + f_c = F is

    R(X, ω) = M X (ωΔ)² + C X (ωΔ) + K X + F_c(X, ω) − F(ω) = 0

(Galerkin projection; Krack & Gross 2019, Eq 2.13), with F_c by AFT at n_time instants of one
period (the method: docs/structures.md); Newton's Jacobian ∂R/∂X is JAX's, exact for the AFT.

Stability: Hill's method. A perturbation e^{λt}q(t) of the periodic solution gives the quadratic
eigenvalue problem (J + λΔ₁ + λ²Δ₂) q = 0 with J = ∂R/∂X, Δ₁ = C ⊗ I + 2ω M ⊗ Δᵀ,
Δ₂ = M ⊗ I; of its eigenvalues the 2N with the smallest |Im λ| approximate the Floquet exponents
(Krack & Gross 2019, Section 3.6). The solution is stable when all have Re λ < 0.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array

from .._export import cached_jit
from .._precision import ensure_x64
from .._results import RESULTS, result_code, result_from_code
from ._structure import Excitation, Structure, check_contacts


def harmonic_layout(harmonics) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For a harmonic set: the harmonic of each coefficient, whether it is a sine, and Δ."""
    layout = [(k, sine) for k in harmonics for sine in ((False, True) if k > 0 else (False,))]
    ks, sine = (np.array(v) for v in zip(*layout))
    delta = np.zeros((ks.size, ks.size))
    c = np.flatnonzero((ks > 0) & ~sine)  # the cosines; their sines follow at c + 1
    delta[c + 1, c], delta[c, c + 1] = ks[c], -ks[c]
    return ks, sine, delta


def _harmonic_set(harmonics, H):
    if harmonics is None:
        if H is None:
            raise ValueError("give the number of harmonics H (>= 1) or a harmonic set")
        if int(H) != H or int(H) < 1:
            raise ValueError(f"H = {H} must be an integer >= 1")
        return tuple(range(int(H) + 1))
    hs = tuple(sorted({int(k) for k in harmonics}))
    if not hs or hs[0] < 0 or max(hs) < 1:
        raise ValueError(f"harmonics = {harmonics} must be integers >= 0 including one >= 1")
    return hs


class FrictionSystem(eqx.Module):
    """A structure with friction contacts under harmonic excitation, discretised by MHB.

    Args:
        structure: the linear `Structure`.
        contacts: a sequence of contacts (`FrictionContact`, `DryFrictionContact2D`).
        excitation: an `Excitation` (default none: give one for a forced response).
        H: harmonics 0…H (>= 1), or `harmonics`: any set of harmonics (>= 0, one of them >= 1).
        n_time: AFT samples per period (static, even, > 2·max harmonic; default the larger of 64
            and 8·max harmonic, rounded up to a power of two).
    """

    structure: Structure
    contacts: tuple
    excitation: Excitation
    harmonics: tuple = eqx.field(static=True)
    n_time: int = eqx.field(static=True)

    def __init__(
        self, structure, contacts=(), excitation=None, *, H=None, harmonics=None, n_time=None
    ):
        ensure_x64()
        if not isinstance(structure, Structure):
            raise TypeError(f"structure must be a Structure, got {type(structure).__name__}")
        self.structure = structure
        self.contacts = check_contacts(contacts, structure.n_dof)
        self.excitation = Excitation(structure.n_dof) if excitation is None else excitation
        self.harmonics = _harmonic_set(harmonics, H)
        h_max = max(self.harmonics)
        if n_time is None:
            n_time = int(2 ** np.ceil(np.log2(max(64, 8 * h_max))))
        if int(n_time) % 2 or int(n_time) <= 2 * h_max:
            raise ValueError(f"n_time = {n_time} must be even and > 2·max harmonic = {2 * h_max}")
        self.n_time = int(n_time)
        ex = self.excitation
        if not any(isinstance(v, jax.core.Tracer) for v in jax.tree.leaves(ex)):
            if 0 not in self.harmonics and np.any(np.asarray(ex.static) != 0):
                raise ValueError("a static force needs harmonic 0 in the harmonic set")
            first = [np.any(np.asarray(v) != 0) for v in (ex.cosine, ex.sine, ex.base)]
            if 1 not in self.harmonics and any(first):
                raise ValueError("a first-harmonic excitation needs harmonic 1 in the harmonic set")

    @property
    def n_dof(self) -> int:
        return self.structure.n_dof

    @property
    def n_coef(self) -> int:
        return harmonic_layout(self.harmonics)[0].size

    def index(self, k: int, sine: bool = False) -> int:
        """Position of a_k (or b_k when `sine`) in a DOF's coefficient vector."""
        ks, sn, _ = harmonic_layout(self.harmonics)
        return int(np.flatnonzero((ks == k) & (sn == sine))[0])

    def time_signal(self, X) -> Array:
        """x at t_j = j·T/n_time, j < n_time (shape (n_time, N)) from coefficients X (N, n_coef)."""
        ks, sine, _ = harmonic_layout(self.harmonics)
        n = self.n_time
        cos_part = jnp.where(jnp.asarray(~sine)[None, :], X, 0.0)
        sin_part = jnp.where(jnp.asarray(sine)[None, :], X, 0.0)
        weight = jnp.asarray(np.where(ks == 0, n, n / 2))[None, :]
        spec = weight * (cos_part - 1j * sin_part)  # a_k − i b_k per coefficient
        full = jnp.zeros((X.shape[0], n // 2 + 1), dtype=jnp.complex128)
        full = full.at[:, jnp.asarray(ks)].add(spec)
        return jnp.fft.irfft(full, n, axis=1).T

    def coefficients(self, x) -> Array:
        """The harmonic coefficients (N, n_coef) of time samples x (n_time, N) (forward FFT)."""
        ks, sine, _ = harmonic_layout(self.harmonics)
        n = self.n_time
        spec = jnp.fft.rfft(x, axis=0).T[:, jnp.asarray(ks)]
        scale = jnp.asarray(np.where(ks == 0, 1.0 / n, 2.0 / n))[None, :]
        return scale * jnp.where(jnp.asarray(sine)[None, :], -spec.imag, spec.real)

    def forcing(self, omega) -> Array:
        """F(ω) in coefficient form (N, n_coef), N."""
        ex, F = self.excitation, jnp.zeros((self.n_dof, self.n_coef))
        if 0 in self.harmonics:
            F = F.at[:, self.index(0)].set(ex.static)
        if 1 in self.harmonics:
            base = omega**2 * (self.structure.M @ ex.base)
            F = F.at[:, self.index(1)].set(ex.cosine + base)
            F = F.at[:, self.index(1, True)].set(ex.sine)
        return F

    def contact_forces(self, X, omega) -> Array:
        """AFT: the contacts' forces in coefficient form (N, n_coef), N."""
        if not self.contacts:
            return jnp.zeros_like(X)
        x = self.time_signal(X)
        period = 2.0 * jnp.pi / omega
        f = sum(c.forces(x, period) for c in self.contacts)
        return self.coefficients(f)

    def residual(self, X, omega) -> Array:
        """R(X, ω) (N, n_coef) in N (see the module docstring)."""
        s = self.structure
        D = omega * jnp.asarray(harmonic_layout(self.harmonics)[2])
        linear = s.M @ X @ (D @ D) + s.C @ X @ D + s.K @ X
        return linear + self.contact_forces(X, omega) - self.forcing(omega)

    def linear_solution(self, omega) -> Array:
        """X of the structure without its contacts (start values), m."""
        s = self.structure
        D = omega * jnp.asarray(harmonic_layout(self.harmonics)[2])
        Z = jnp.kron(s.M, (D @ D).T) + jnp.kron(s.C, D.T) + jnp.kron(s.K, jnp.eye(self.n_coef))
        F = self.forcing(omega)
        return jnp.linalg.solve(Z, F.reshape(-1)).reshape(F.shape)

    def scales(self, omega):
        """(force scale N, displacement scale m) used to make the MHB unknowns and residual O(1)."""
        f = jnp.max(jnp.abs(self.forcing(omega)))
        k = jnp.max(jnp.abs(self.structure.K))
        f = jnp.where(f > 0, f, 1.0)
        return f, f / jnp.where(k > 0, k, 1.0)

    def amplitude(self, X, k: int = 1) -> Array:
        """Amplitude √(a_k² + b_k²) (m) of harmonic k of each DOF (N,); a₀'s magnitude for k = 0."""
        if k == 0:
            return jnp.abs(X[..., self.index(0)])
        return jnp.hypot(X[..., self.index(k)], X[..., self.index(k, True)])


class HBMSolution(eqx.Module):
    """One MHB solution: X (N, n_coef, m), omega (rad/s), result (`RESULTS`), steps (Newton)."""

    X: Array
    omega: Array
    result: RESULTS
    steps: Array

    @property
    def converged(self):
        return self.result == RESULTS.successful


def solve_hbm(
    system: FrictionSystem,
    omega,
    X0=None,
    *,
    rtol=1e-10,
    atol=1e-10,
    max_steps: int = 100,
    solver=None,
) -> HBMSolution:
    """Solve R(X, ω) = 0 at one frequency ω (rad/s, > 0) with optimistix and JAX's Jacobian.

    `solver` (default `optimistix.Dogleg`: Newton steps inside a trust region, which keeps plain
    Newton from cycling between the stick and slip pieces of a friction residual; pass
    `optimistix.Newton(...)` from a close start). Start from X0 (default: the structure without
    its contacts). Differentiable: gradients with respect to any leaf of `system` (μ, N, K_d, M,
    C, K, forcing) and ω follow from the implicit function theorem (optimistix's implicit
    adjoint), not from unrolled iterations. The outcome is in `result` (no exception under jit);
    X is NaN-free but meaningless when it is not successful.
    """
    ensure_x64()
    omega = jnp.asarray(omega, dtype=jnp.float64)
    if not isinstance(omega, jax.core.Tracer) and not float(omega) > 0:
        raise ValueError(f"omega = {float(omega):g} rad/s must be > 0")
    solver = optx.Dogleg(rtol=rtol, atol=atol) if solver is None else solver
    return _solve(system, omega, X0, solver, int(max_steps))


def _scaled_residual(y, args):
    system, omega, f_ref, x_ref = args
    return system.residual(y * x_ref, omega) / f_ref


def _solve(system, omega, X0, solver, max_steps):
    X, code, steps = _solve_arrays(system, omega, X0, solver, max_steps)
    return HBMSolution(X=X, omega=omega, result=result_from_code(code), steps=steps)


@cached_jit
def _solve_arrays(system, omega, X0, solver, max_steps):
    f_ref, x_ref = system.scales(omega)
    y0 = (system.linear_solution(omega) if X0 is None else jnp.asarray(X0)) / x_ref
    # jac="bwd": the (square) Jacobian is materialised once per step by reverse mode, so the
    # trust-region's products J·v, Jᵀ·r and its LU solve are dense algebra, not re-runs of the
    # AFT's history scan (same iterates; about half the time per step)
    sol = optx.root_find(
        _scaled_residual,
        solver,
        y0,
        (system, omega, f_ref, x_ref),
        max_steps=max_steps,
        throw=False,
        options=dict(jac="bwd"),
    )
    result = RESULTS.promote(sol.result)
    X = jnp.where(jnp.isfinite(sol.value), sol.value, 0.0) * x_ref
    result = RESULTS.where(jnp.all(jnp.isfinite(sol.value)), result, RESULTS.nonlinear_divergence)
    return X, result_code(result), sol.stats["num_steps"]


def floquet_exponents(system: FrictionSystem, X, omega, J=None) -> np.ndarray:
    """Hill's approximation of the 2N Floquet exponents (1/s) at a periodic solution X, ω.

    J = ∂R/∂X (flattened, N·n_coef square) is computed unless given. Batched: with J of shape
    (n, N·n_coef, N·n_coef) and ω of shape (n,) (X unused then), the exponents of n solutions of
    the same system in one stacked eigenvalue call, shape (n, 2N).
    """
    c = system.n_coef
    if J is None:
        x = jnp.asarray(X).reshape(-1)
        J = jax.jacfwd(lambda y: system.residual(y.reshape(system.n_dof, c), omega).reshape(-1))(x)
    J = np.asarray(J)
    batched = J.ndim == 3
    J = J if batched else J[None]
    w = np.asarray(omega, dtype=float).reshape(-1)
    m = J.shape[-1]
    M, C = np.asarray(system.structure.M), np.asarray(system.structure.C)
    inv = np.linalg.inv(np.kron(M, np.eye(c)))  # Δ₂⁻¹
    d1_c = inv @ np.kron(C, np.eye(c))  # Δ₁ = C ⊗ I + ω·2 M ⊗ Δᵀ (Δ per unit ω)
    d1_w = inv @ (2.0 * np.kron(M, harmonic_layout(system.harmonics)[2].T))
    A = np.zeros((J.shape[0], 2 * m, 2 * m))
    A[:, :m, m:] = np.eye(m)
    A[:, m:, :m] = -inv @ J
    A[:, m:, m:] = -d1_c - w[:, None, None] * d1_w
    lam = np.linalg.eigvals(A)
    keep = np.argsort(np.abs(lam.imag), axis=-1, kind="stable")[:, : 2 * system.n_dof]
    lam = np.take_along_axis(lam, keep, axis=-1)
    return lam if batched else lam[0]
