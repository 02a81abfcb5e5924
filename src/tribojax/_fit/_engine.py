"""Least squares with uncertainties: optimistix Levenberg–Marquardt plus Jacobian statistics.

Parameters are fitted in unconstrained coordinates θ (log for positive quantities, etc.); a
`transform` maps θ to the physical parameters, and the covariance is carried over by the delta
method. Residuals should already be divided by their uncertainty; if `sigma_known` is False the
common scale is estimated from the residual sum of squares (s² = RSS/(n - p)).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._precision import ensure_x64


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of `least_squares_fit` (NumPy arrays; physical coordinates unless stated).

    Attributes:
        names: parameter names.
        values: fitted parameters.
        std_errors: standard errors (delta method from θ).
        covariance, correlation: p×p matrices.
        theta: the unconstrained optimum.
        residuals: residuals at the optimum (as returned by the residual function).
        singular_values: of the Jacobian in θ, largest first (identifiability).
        converged: optimistix reported success.
        steps: LM steps taken.
        message: optimistix's result message ("" on success).
        fixed: constants held fixed in the fit (set by the caller, e.g. {"M": 1.0}).
        jacobian: ∂residuals/∂θ at the optimum, (n, p) (`least_squares_fit`; None elsewhere).
    """

    names: tuple[str, ...]
    values: np.ndarray
    std_errors: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    theta: np.ndarray
    residuals: np.ndarray
    singular_values: np.ndarray
    converged: bool
    steps: int
    message: str
    fixed: dict = dataclasses.field(default_factory=dict)
    jacobian: np.ndarray | None = None  # ∂residuals/∂θ at the optimum (n, p), when computed

    def as_dict(self) -> dict:
        """Summary as plain Python numbers (non-finite entries mark unidentifiable directions)."""
        return {
            "parameters": dict(zip(self.names, self.values.tolist())),
            "std_errors": dict(zip(self.names, self.std_errors.tolist())),
            "correlation": self.correlation.tolist(),
            "converged": self.converged,
            "steps": self.steps,
            "singular_values": self.singular_values.tolist(),
            "fixed": dict(self.fixed),
        }


def gauss_newton_step_jnp(r, J):
    """The Gauss–Newton step −(JᵀJ)⁺Jᵀr, in units of the standard errors, traceable (JAX).

    Standard errors from s²(JᵀJ)⁺ with s² = rᵀr/(n − p) (the residual scale estimated from the
    fit). Entries ≪ 1: the step still left is far below the statistical uncertainty. Directions
    with singular values below 1e-14 of the largest are dropped; a zero standard error gives inf.
    """
    u, sv, vt = jnp.linalg.svd(J, full_matrices=False)
    keep = sv > sv[0] * 1e-14
    inv = jnp.where(keep, 1.0 / jnp.where(keep, sv, 1.0), 0.0)
    step = -(vt.T @ ((u.T @ r) * inv))
    se = jnp.sqrt(jnp.sum((vt * inv[:, None]) ** 2, axis=0))
    n, p = J.shape
    s = jnp.maximum(jnp.sqrt(r @ r / max(n - p, 1)), 1e-300)
    return jnp.where(se > 0, step / jnp.where(se > 0, se * s, 1.0), jnp.inf)


@eqx.filter_jit
def _solve(residual_fn, theta0, args, solver, max_steps, jac):
    # jitted here so that a module-level `residual_fn` (hashed by identity) is compiled once and
    # a repeated fit with new data in `args` runs warm
    return optx.least_squares(
        residual_fn,
        solver,
        theta0,
        args,
        options=dict(jac=jac),
        max_steps=max_steps,
        throw=False,
    )


@eqx.filter_jit
def _value_and_jacobian(residual_fn, theta, args):
    # one forward pass gives both (the residual rides along as jacfwd's aux)
    def both(th):
        r = residual_fn(th, args)
        return r, r

    J, r = jax.jacfwd(both, has_aux=True)(theta)
    return r, J


def least_squares_fit(
    residual_fn,
    theta0,
    args=None,
    *,
    names,
    transform=lambda theta: theta,
    sigma_known: bool = False,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_steps: int = 500,
    jac: str = "bwd",
    solver=None,
) -> FitResult:
    """Fit θ minimising ½‖residual_fn(θ, args)‖² with optimistix Levenberg–Marquardt.

    Args:
        residual_fn: (θ, args) -> residual vector (already divided by its uncertainty).
        theta0: start, 1-D.
        names: parameter names for the physical vector `transform(θ)`.
        transform: θ -> physical parameter vector (differentiable).
        sigma_known: residuals are in units of their standard deviation (else s² is estimated).
        jac: how LM differentiates the residuals, "bwd" or "fwd" (optimistix option). "bwd" is
            the default because forward linearisation of a residual that contains an optimistix
            root find (the contact load balance) makes lineax reject the Jacobian as non-finite
            in optimistix 0.1.0, although jax.jacfwd of the same residual is finite (a
            `jax.custom_jvp` around the root find avoids it, see `_fit_chain`).
        solver: an optimistix least-squares solver in place of LevenbergMarquardt(rtol, atol).
    The solve is compiled once per `residual_fn` object: pass a module-level function (data in
    `args`) and repeated fits run warm.

    Returns:
        FitResult; `converged` False (and `message` set) when LM did not succeed. Never raises for
        non-convergence: the caller decides.
    """
    ensure_x64()
    theta0 = jnp.asarray(theta0, dtype=jnp.float64)
    if solver is None:
        solver = optx.LevenbergMarquardt(rtol=float(rtol), atol=float(atol))
    sol = _solve(residual_fn, theta0, args, solver, int(max_steps), jac)
    theta = sol.value
    r, J = _value_and_jacobian(residual_fn, theta, args)
    n, p = J.shape
    u, sv, vt = jnp.linalg.svd(J, full_matrices=False)
    # (JᵀJ)^-1 through the SVD; directions with negligible singular values get infinite variance.
    tiny = sv <= sv[0] * 1e-14
    inv_s2 = jnp.where(tiny, jnp.inf, 1.0 / jnp.where(tiny, 1.0, sv) ** 2)
    cov_theta = (vt.T * inv_s2[None, :]) @ vt
    cov_theta = jnp.where(jnp.isnan(cov_theta), jnp.inf, cov_theta)
    scale2 = 1.0 if sigma_known else float(r @ r) / max(n - p, 1)
    cov_theta = cov_theta * scale2
    T = jax.jacfwd(transform)(theta)
    cov = T @ cov_theta @ T.T
    std = jnp.sqrt(jnp.diag(cov))
    corr = cov / jnp.outer(std, std)
    ok = bool(sol.result == optx.RESULTS.successful)
    message = "" if ok else optx.RESULTS[sol.result]
    return FitResult(
        names=tuple(names),
        values=np.asarray(transform(theta)),
        std_errors=np.asarray(std),
        covariance=np.asarray(cov),
        correlation=np.asarray(corr),
        theta=np.asarray(theta),
        residuals=np.asarray(r),
        singular_values=np.asarray(sv),
        converged=ok,
        steps=int(sol.stats["num_steps"]),
        message=str(message),
        jacobian=np.asarray(J),
    )
