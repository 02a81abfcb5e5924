"""Rodas4, a Rosenbrock (linearly implicit) solver for diffrax.

Rodas4 (Hairer & Wanner, Solving Ordinary Differential Equations II, 2nd ed., Sec IV.7, the
coefficients of their RODAS code, ``ro4coe`` with METH = 1; order and stability: `Rodas4`).
With W = I/(γh) − J, J = ∂f/∂y(t₀, y₀) and f_t = ∂f/∂t(t₀, y₀), each of the 6 stages solves

    W K_i = f(t₀ + α_i h, y₀ + Σ_{j<i} a_ij K_j) + Σ_{j<i} (c_ij/h) K_j + γ_i h f_t,

and y₁ = y₀ + Σ m_i K_i, error estimate Σ e_i K_i (here K₆). One Jacobian (`jax.jacfwd`), one
∂f/∂t (`jax.jvp`), one LU and six pairs of triangular solves per step, no Newton iteration: for
small stiff systems much cheaper per step than an ESDIRK (Kvaerno5) with a chord iteration. Up to
`SMALL_N` states the LU is by default unrolled array arithmetic rather than LAPACK, so that XLA:CPU
can compile the whole solve into one kernel where the application asks for it (`Rodas4.lu`,
`tribojax.use_one_kernel`; docs/performance.md, "One kernel per solve").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

# Hairer & Wanner's RODAS, ro4coe (METH = 1): a_ij, c_ij (strictly lower), α_i, γ_i = Σ_j γ_ij.
_GAMMA = 0.25
_A5 = (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950)
_A = (
    (),
    (1.544,),
    (0.9466785280815826, 0.2557011698983284),
    (3.314825187068521, 2.896124015972201, 0.9986419139977817),
    _A5,
    (*_A5, 1.0),
)
_C = (
    (),
    (-5.6688,),
    (-2.430093356833875, -0.2063599157091915),
    (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
    (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
    (
        8.083246795921522,
        -7.981132988064893,
        -31.52159432874371,
        16.31930543123136,
        -6.058818238834054,
    ),
)
_ALPHA = (0.0, 0.386, 0.21, 0.63, 1.0, 1.0)
_GAMMAS = (0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0)
_M = (*_A5, 1.0, 1.0)  # stiffly accurate: y₁ is the last stage's argument plus K₆
# dense output (`RodasInterpolation`): k₁ = Σ d1_i K_i, k₂ = Σ d2_i K_i
_D1 = (
    10.12623508344586,
    -7.487995877610167,
    -34.80091861555747,
    -7.992771707568823,
    1.025137723295662,
    0.0,
)
_D2 = (
    -0.6762803392801253,
    6.087714651680015,
    16.43084320892478,
    24.76722511418386,
    -6.594389125716872,
    0.0,
)


SMALL_N = 8  # states up to which W may be factorised by unrolled elimination (`_lu_small`)


def unrolled_lu(n: int, lu: str = "auto") -> bool:
    """Whether Rodas4 with factorisation `lu` factorises its n×n W by `_lu_small`: "unrolled",
    or "auto" with n ≤ `SMALL_N`. Otherwise LAPACK's getrf/trsm, which rounds differently. Read
    from the solver's field only: the numbers never depend on the environment."""
    return lu == "unrolled" or (lu == "auto" and n <= SMALL_N)


def _lu_small(w):
    """LU of a small W with partial pivoting, unrolled into elementwise array ops: (LU, P) with
    P W = L U (unit L below the diagonal of LU, U on and above it), P a permutation matrix.

    No LAPACK call, so that XLA:CPU compiles the whole ODE loop into one kernel
    (docs/performance.md, "One kernel per solve"); larger systems keep LAPACK's getrf and trsm.
    """
    n = w.shape[0]
    rows = jnp.arange(n)
    eye = jnp.eye(n, dtype=w.dtype)
    a, perm = w, eye
    for k in range(n - 1):
        p = jnp.argmax(jnp.where(rows >= k, jnp.abs(a[:, k]), -1.0))
        ek, ep = (rows == k).astype(w.dtype), (rows == p).astype(w.dtype)
        swap = eye - jnp.outer(ek - ep, ek - ep)  # identity when p == k
        a, perm = swap @ a, swap @ perm
        below = rows > k
        lk = jnp.where(below, a[:, k] / a[k, k], 0.0)
        a = a - jnp.outer(lk, jnp.where(below, a[k, :], 0.0))
        a = jnp.where((rows == k)[None, :] & below[:, None], lk[:, None], a)
    return a, perm


def _lu_solve_small(lu, b, trans=False):
    """x with W x = b (or Wᵀ x = b) from `_lu_small`'s (LU, P), by unrolled substitution."""
    a, perm = lu
    n = a.shape[0]
    u = (lambda i, j: a[j, i]) if trans else (lambda i, j: a[i, j])
    rhs = b if trans else perm @ b
    y: list = [None] * n
    for i in range(n):  # L y = P b, or Uᵀ y = b
        s = rhs[i] - sum((u(i, j) * y[j] for j in range(i)), jnp.zeros_like(rhs[i]))
        y[i] = s / a[i, i] if trans else s
    x: list = [None] * n
    for i in reversed(range(n)):  # U x = y, or Lᵀ x = y
        s = y[i] - sum((u(i, j) * x[j] for j in range(i + 1, n)), jnp.zeros_like(y[i]))
        x[i] = s if trans else s / a[i, i]
    x = jnp.stack(x)
    return perm.T @ x if trans else x


def _combine(coeffs, ks):
    """Σ c_i K_i as one dot product (not a chain of multiply-adds)."""
    n = len(coeffs)
    return jnp.asarray(np.asarray(coeffs)) @ jnp.stack(ks[:n])


class RodasInterpolation(dfx.AbstractLocalInterpolation):
    """Rodas4's dense output on one step: y(θ) = y₀ + θ(Δy + (1 − θ)(k₁ + θ k₂)), θ = (t − t₀)/h
    (Hairer & Wanner's RODAS, order 3)."""

    t0: Array
    t1: Array
    y0: Array
    y1: Array
    k1: Array
    k2: Array

    def _at(self, t):
        th = (t - self.t0) / (self.t1 - self.t0)
        return self.y0 + th * ((self.y1 - self.y0) + (1 - th) * (self.k1 + th * self.k2))

    def evaluate(self, t0, t1=None, left=True):
        del left
        if t1 is None:
            return self._at(t0)
        return self._at(t1) - self._at(t0)


class Rodas4(dfx.AbstractAdaptiveSolver):
    """Rodas4 Rosenbrock solver (Hairer & Wanner, Solving ODEs II, Sec IV.7; RODAS coefficients).

    L-stable, stiffly accurate, order 4(3), 6 stages, dense output of order 3. For ODEs whose state
    is one flat float array (a single `diffrax.ODETerm`). The Jacobian is exact (`jax.jacfwd`), so
    the order holds with any step; ∂f/∂t is evaluated at the step start, so stop steps at kinks of
    a time-dependent forcing (`jump_ts`): diffrax then starts the next step just after the kink.

    Reverse mode: `diffrax.RecursiveCheckpointAdjoint` recomputes the steps with other rounding,
    and the step-size controller then takes other steps than the forward pass: a silently wrong
    gradient (docs/slip.md, why). `simulate_slip` therefore differentiates Rodas4 by forward mode
    in every direction (`ForwardJacobianAdjoint`).
    """

    term_structure: ClassVar = dfx.AbstractTerm
    interpolation_cls: ClassVar[Callable[..., RodasInterpolation]] = RodasInterpolation
    lu: str = eqx.field(static=True, default="auto")
    """W's factorisation: "auto" (unrolled up to `SMALL_N` states, else LAPACK), "unrolled"
    (always), "lapack" (LAPACK's getrf/trsm always). The same in every process: the one-kernel
    option (`tribojax.use_one_kernel`) changes speed, not this choice."""

    def __check_init__(self):
        if self.lu not in ("auto", "unrolled", "lapack"):
            raise ValueError(f"lu = {self.lu!r}: allowed 'auto', 'unrolled' or 'lapack'")

    def order(self, terms):
        return 4

    def error_order(self, terms):
        return 4

    def init(self, terms, t0, t1, y0, args):
        return None

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del solver_state, made_jump
        y0 = jnp.asarray(y0)
        h = t1 - t0

        def f(t, y):
            return terms.vf(t, y, args)

        jac = jax.jacfwd(lambda y: f(t0, y))(y0)
        f0, ft = jax.jvp(lambda t: f(t, y0), (t0,), (jnp.ones_like(t0),))
        w = jnp.eye(y0.shape[0], dtype=y0.dtype) / (_GAMMA * h) - jac
        # one LU of W per step (of W without its tangent); each solve is a custom_linear_solve, so
        # that forward mode gives dK = W⁻¹(d rhs − dW K) with the same LU instead of
        # differentiating the factorisation (as jnp.linalg.solve does)
        if unrolled_lu(y0.shape[0], self.lu):
            lu = _lu_small(jax.lax.stop_gradient(w))
            lu_solve = _lu_solve_small
        else:
            lu = jax.scipy.linalg.lu_factor(jax.lax.stop_gradient(w))
            lu_solve = jax.scipy.linalg.lu_solve

        def solve_w(b):
            return jax.lax.custom_linear_solve(
                lambda x: w @ x,
                b,
                solve=lambda _, r: lu_solve(lu, r),
                transpose_solve=lambda _, r: lu_solve(lu, r, trans=True),
            )

        ks: list[Array] = []
        for i in range(6):
            if i == 0:
                rhs = f0
            else:
                rhs = f(t0 + _ALPHA[i] * h, y0 + _combine(_A[i], ks)) + _combine(_C[i], ks) / h
            if _GAMMAS[i] != 0.0:
                rhs = rhs + (_GAMMAS[i] * h) * ft
            ks.append(solve_w(rhs))
        y1 = y0 + _combine(_M, ks)
        err = ks[5]
        dense_info = dict(y0=y0, y1=y1, k1=_combine(_D1, ks), k2=_combine(_D2, ks))
        return y1, err, dense_info, None, dfx.RESULTS.successful
