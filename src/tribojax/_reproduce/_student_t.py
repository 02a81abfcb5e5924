"""The Student-t likelihood of residuals, written so that the one least-squares engine fits it.

Residuals r_i (in units of their noise shape) with a Student-t error of ν degrees of freedom and
scale s have the log-likelihood ℓ = Σ_i [ln Γ((ν+1)/2) − ln Γ(ν/2) − ½ ln(νπ) − ln(s σ_i) −
(ν+1)/2 · ln(1 + r_i²/(ν s²))] (Lange, Little & Taylor 1989, J. Am. Stat. Assoc. 84, 881, Eq 1;
ν = inf: the Gaussian). `student_t_ml` maximises it over the model parameters θ and s;
`tribojax._reproduce._robust_fit` applies it to wang2022's measured slips.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
from scipy import optimize, special

from .._results import RESULTS


def student_t_parameters(student_t) -> tuple[float, float]:
    """(1/ν, s) of `student_t` = (ν, s) with ν in (0, inf] and s in (0, inf), or None (the
    Gaussian at s = 1: plain least squares); raises ValueError naming a value out of range."""
    nu, scale = (math.inf, 1.0) if student_t is None else (float(v) for v in student_t)
    if not nu > 0:
        raise ValueError(f"student_t nu = {nu} is outside the allowed range (0, inf]")
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"student_t scale = {scale} is outside the allowed range (0, inf)")
    return (0.0 if math.isinf(nu) else 1.0 / nu), scale


def student_t_residuals(r, scale, inv_nu):
    """ψ_i = sign(r_i)·√((ν+1)·ln(1 + r_i²/(ν s²))): residuals whose sum of squares is the
    Student-t −2 log-likelihood of r at the scale s, up to terms in s alone (Lange, Little &
    Taylor 1989, Eq 1; `inv_nu` = 1/ν, 0 for the Gaussian: ψ = r/s). Least squares on ψ is the
    t maximum likelihood in θ at fixed s. Traceable; ψ/r is smooth and positive, also at r = 0."""
    q = inv_nu * (r / scale) ** 2
    small = q < 1e-12
    q_safe = jnp.where(small, 1.0, q)  # double-where: no 0/0 in the unused branch
    g = jnp.where(small, 1.0 - 0.5 * q, jnp.log1p(q_safe) / q_safe)  # ln(1 + q)/q
    return r / scale * jnp.sqrt((1.0 + inv_nu) * g)


def student_t_residuals_inverse(psi, scale, inv_nu) -> np.ndarray:
    """r from ψ = `student_t_residuals(r, scale, inv_nu)` (NumPy; ψ is odd and increasing)."""
    psi = np.asarray(psi, dtype=float)
    if inv_nu == 0:
        return psi * scale
    return np.sign(psi) * scale * np.sqrt(np.expm1(psi**2 * inv_nu / (1.0 + inv_nu)) / inv_nu)


def student_t_loglik(r, scale, sigma, nu) -> float:
    """ℓ of residuals r (in units of σ) with scale s and shapes σ (nm); ν = inf: Gaussian."""
    r, sigma = np.asarray(r, dtype=float), np.asarray(sigma, dtype=float)
    log_s = np.log(scale * np.abs(sigma))
    if math.isinf(nu):
        return float(np.sum(-0.5 * np.log(2 * np.pi) - log_s - 0.5 * (r / scale) ** 2))
    const = special.gammaln((nu + 1) / 2) - special.gammaln(nu / 2) - 0.5 * np.log(nu * np.pi)
    return float(np.sum(const - log_s - (nu + 1) / 2 * np.log1p((r / scale) ** 2 / nu)))


def em_weights(r, scale, nu) -> np.ndarray:
    """E-step weights u_i = (ν+1)/(ν + r_i²/s²) (1 for the Gaussian)."""
    r = np.asarray(r, dtype=float)
    if math.isinf(nu):
        return np.ones_like(r)
    return (nu + 1.0) / (nu + (r / scale) ** 2)


def _lin_resid(y, model, sigma):
    return (y - np.asarray(model)) / sigma


def _log_resid(y, model, sigma):
    return np.log(np.abs(y / np.asarray(model)))


def t_scale(r, nu) -> float:
    """The maximum-likelihood scale s of residuals r at fixed θ: the root of
    Σ u_i r_i²/s² = n with u_i = (ν+1)/(ν + r_i²/s²) (∂ℓ/∂s = 0; unique, since the sum falls
    from (ν+1)·#{r_i ≠ 0} to 0 as s grows); ν = inf: s² = mean r²."""
    r = np.asarray(r, dtype=float).ravel()
    rms_ = math.sqrt(float(np.mean(r**2)))
    if math.isinf(nu) or rms_ == 0 or not math.isfinite(rms_):  # (NaN: a cell not evaluated)
        return rms_
    r2 = r**2

    def excess(log_s):
        t = r2 * math.exp(-2.0 * log_s)
        return float(np.sum((nu + 1.0) * t / (nu + t))) - r.size

    # the root lies below rms·√((ν+1)/ν), where Σ u r²/s² ≤ (ν+1)/ν·Σ r²/s² = n, and above
    # rms·e⁻⁴⁰, where the sum is ≈ (ν+1)·#{r_i ≠ 0} > n unless most r_i are 0
    lo, hi = math.log(rms_) - 40.0, math.log(rms_ * math.sqrt((nu + 1.0) / nu))
    if excess(lo) <= 0:  # almost every residual is exactly zero
        return rms_
    return math.exp(optimize.brentq(excess, lo, hi, xtol=1e-14, rtol=1e-14))


def student_t_ml(theta_step, y, sigma, nu, first, *, max_iterations=40, tol=1e-3, log=False):
    """Student-t maximum likelihood around a least-squares model by coordinate ascent.

    Each iteration maximises ℓ over θ at the current scale s (one least-squares fit of
    `student_t_residuals`) and then over s at that θ (`t_scale`, exact). It reaches EM's fixed
    point (the same likelihood equations, Lange et al. Eqs 4–5) in fewer fits than EM
    (docs/reproduction.md, robust fit, says why).

    Args:
        theta_step: (s, previous fit) -> (fit, model): the fit of θ at fixed scale s, started
            from the previous fit; the fits need `converged` and `result`.
        y, sigma: data and noise shapes (same shape); r = (y − model)/σ, or ln|y/model| if
            `log` (σ then enters ℓ only, as the Jacobian |y|).
        nu: degrees of freedom (inf: Gaussian, one least-squares fit).
        first: (fit, model) to start from (e.g. the plain least-squares fit).
        max_iterations, tol: stop when one iteration raised ℓ by less than `tol` (nats).
    Returns:
        (fit, r, u, s, history of ℓ, RESULTS member); u are the EM weights at the optimum
        (`em_weights`): J_θᵀ·diag(u)·r = 0 there, the likelihood equations.
    """
    y, sigma = np.asarray(y, dtype=float), np.asarray(sigma, dtype=float)
    fit, model = first
    resid = _log_resid if log else _lin_resid
    r = resid(y, model, sigma)
    scale = t_scale(r, nu)
    history = [student_t_loglik(r, scale, sigma, nu)]
    result = RESULTS.not_converged
    if not math.isfinite(scale):  # the start has a cell the model could not evaluate
        bad = fit.result if not fit.converged else RESULTS.model_failed_at_start
        return fit, r, em_weights(r, scale, nu), scale, tuple(history), bad
    for _ in range(int(max_iterations)):
        fit, model = theta_step(scale, fit)
        if not fit.converged:  # r, s and ℓ stay those of the last fit that converged
            result = fit.result
            break
        r = resid(y, model, sigma)
        scale = t_scale(r, nu)
        history.append(student_t_loglik(r, scale, sigma, nu))
        if abs(history[-1] - history[-2]) < tol:
            result = RESULTS.successful
            break
    return fit, r, em_weights(r, scale, nu), scale, tuple(history), result
